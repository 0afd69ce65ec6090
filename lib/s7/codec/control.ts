/**
 * The CPU services that travel as jobs (ROSCTR 1) rather than userdata:
 * PLC stop (0x29), the PI service that starts the program (0x28) and block
 * upload (start 0x1D, upload 0x1E, end 0x1F). Same style as pdu.ts: whole
 * frames in one Buffer; decoders throw only ProtocolError.
 *
 *   stop:        29 00 00 00 00 00 | 09 "P_PROGRAM"
 *   start:       28 00 00 00 00 00 00 FD | arg length (2) | arg ("C " = cold) | 09 "P_PROGRAM"
 *   start upload 1D 00 00 00 | upload id (4) | 09 "_0" type, 5 digits, "A"
 *     answer:    1D 00 00 00 | upload id (4) | 07 | load length, 7 ASCII digits
 *   upload:      1E 00 00 00 | upload id (4)
 *     answer:    1E | 01 more / 00 last;  data: length (2) 00 FB, block bytes
 *   end upload:  1F 00 00 00 | upload id (4)   answer: 1F
 */
import { ProtocolError } from '../../errors';
import { ControlFunction, Rosctr, S7_ACK_HEADER, S7_JOB_HEADER, S7_PROTOCOL_ID } from '../constants';
import { FRAME_OVERHEAD } from '../../iso/constants';
import { s7Frame } from './pdu';
import { decodeS7 } from './pdu-decode';

const P_PROGRAM = Buffer.from('P_PROGRAM', 'latin1');
/** PI argument of a cold start. */
export const COLD_START_ARG = Buffer.from('C ', 'latin1');

function frame(rosctr: number, pduRef: number, params: Buffer, data: Buffer = Buffer.alloc(0), error = 0): Buffer {
  const f = s7Frame(rosctr, pduRef, params.length, data.length, error);
  const at = FRAME_OVERHEAD + (rosctr === Rosctr.Ack || rosctr === Rosctr.AckData ? S7_ACK_HEADER : S7_JOB_HEADER);
  params.copy(f, at);
  data.copy(f, at + params.length);
  return f;
}

/** PLC stop job. */
export function encodePlcStop(pduRef = 0): Buffer {
  return frame(Rosctr.Job, pduRef, Buffer.concat([Buffer.of(ControlFunction.PlcStop, 0, 0, 0, 0, 0, P_PROGRAM.length), P_PROGRAM]));
}

/** PI service "P_PROGRAM": start the program; with COLD_START_ARG a cold start, without an argument a (warm/hot) restart. */
export function encodePlcStart(arg: Buffer = Buffer.alloc(0), pduRef = 0): Buffer {
  const head = Buffer.of(ControlFunction.PiService, 0, 0, 0, 0, 0, 0, 0xfd, arg.length >> 8, arg.length & 0xff);
  return frame(Rosctr.Job, pduRef, Buffer.concat([head, arg, Buffer.of(P_PROGRAM.length), P_PROGRAM]));
}

/** The block file name of upload: "_0" + type letter + 5 digits + "A" (the active file system). */
function blockFileName(typeCode: number, number: number): Buffer {
  return Buffer.from(`_0${String.fromCharCode(typeCode)}${String(number).padStart(5, '0')}A`, 'latin1');
}

function uploadHead(func: number, uploadId: number): Buffer {
  const b = Buffer.alloc(8);
  b[0] = func;
  b.writeUInt32BE(uploadId >>> 0, 4);
  return b;
}

export function encodeStartUpload(typeCode: number, number: number, pduRef = 0): Buffer {
  const name = blockFileName(typeCode, number);
  return frame(Rosctr.Job, pduRef, Buffer.concat([uploadHead(ControlFunction.StartUpload, 0), Buffer.of(name.length), name]));
}

export function encodeUpload(uploadId: number, pduRef = 0): Buffer {
  return frame(Rosctr.Job, pduRef, uploadHead(ControlFunction.Upload, uploadId));
}

export function encodeEndUpload(uploadId: number, pduRef = 0): Buffer {
  return frame(Rosctr.Job, pduRef, uploadHead(ControlFunction.EndUpload, uploadId));
}

// ---------------------------------------------------------------- answers (simulator)

/** The ack-data of a control job: its function, and a status byte when `status` is given. */
export function encodeControlAck(pduRef: number, func: number, status?: number, error = 0): Buffer {
  return frame(Rosctr.AckData, pduRef, status === undefined ? Buffer.of(func) : Buffer.of(func, status), undefined, error);
}

export function encodeStartUploadAck(pduRef: number, uploadId: number, loadLength: number): Buffer {
  const len = Buffer.from(String(loadLength).padStart(7, '0'), 'latin1');
  return frame(Rosctr.AckData, pduRef, Buffer.concat([uploadHead(ControlFunction.StartUpload, uploadId), Buffer.of(len.length), len]));
}

export function encodeUploadAck(pduRef: number, chunk: Buffer, more: boolean): Buffer {
  const data = Buffer.alloc(4 + chunk.length);
  data.writeUInt16BE(chunk.length, 0);
  data[2] = 0x00;
  data[3] = 0xfb;
  chunk.copy(data, 4);
  return frame(Rosctr.AckData, pduRef, Buffer.of(ControlFunction.Upload, more ? 1 : 0), data);
}

// ---------------------------------------------------------------- requests (simulator) and answers (client)

/** A decoded control job or its answer. */
export type ControlMessage =
  | { kind: 'stop'; pduRef: number }
  | { kind: 'start'; pduRef: number; cold: boolean; service: string }
  | { kind: 'start-upload'; pduRef: number; blockType: number; number: number }
  | { kind: 'upload'; pduRef: number; uploadId: number }
  | { kind: 'end-upload'; pduRef: number; uploadId: number }
  | { kind: 'control-ack'; pduRef: number; func: number; status: number | undefined; error: number }
  | { kind: 'start-upload-ack'; pduRef: number; uploadId: number; loadLength: number }
  | { kind: 'upload-ack'; pduRef: number; more: boolean; chunk: Buffer };

/** Where the function byte of a job sits in a frame with the plain COTP DT header. */
const JOB_FUNC = FRAME_OVERHEAD + S7_JOB_HEADER;

/** True when a frame is a job (ROSCTR 1) of one of the control functions (a cheap test; decodeControl checks the rest). */
export function isControlJob(frame: Buffer): boolean {
  if (frame.length <= JOB_FUNC || frame[7] !== S7_PROTOCOL_ID || frame[8] !== Rosctr.Job) return false;
  const f = frame[JOB_FUNC]!;
  return (
    f === ControlFunction.PlcStop || f === ControlFunction.PiService || (f >= ControlFunction.StartUpload && f <= ControlFunction.EndUpload)
  );
}

/** Decodes a control job (simulator) or the ack-data answering one (client). Throws ProtocolError. */
export function decodeControl(frame: Buffer): ControlMessage {
  const m = decodeS7(frame);
  const at = FRAME_OVERHEAD;
  const rosctr = frame[at + 1]!;
  const ack = rosctr === Rosctr.AckData || rosctr === Rosctr.Ack;
  const header = ack ? S7_ACK_HEADER : S7_JOB_HEADER;
  const plen = frame.readUInt16BE(at + 6);
  const p = frame.subarray(at + header, at + header + plen);
  const data = frame.subarray(at + header + plen);
  const pduRef = m.pduRef;
  if (ack) {
    const error = m.kind === 'error' ? (m.errorClass << 8) | m.errorCode : 0;
    if (p.length === 0) return { kind: 'control-ack', pduRef, func: 0, status: undefined, error };
    const func = p[0]!;
    if (error === 0 && func === ControlFunction.StartUpload) {
      if (p.length < 9 || p.length !== 9 + p[8]!)
        throw new ProtocolError(`start upload answer: ${p.length} parameter bytes do not match its length string`);
      const text = p.subarray(9).toString('latin1');
      if (!/^[0-9]+$/.test(text)) throw new ProtocolError(`start upload answer: block length "${text}" is not a number`);
      return { kind: 'start-upload-ack', pduRef, uploadId: p.readUInt32BE(4), loadLength: Number(text) };
    }
    if (error === 0 && func === ControlFunction.Upload) {
      if (p.length !== 2) throw new ProtocolError(`upload answer: ${p.length} parameter bytes, expected 2`);
      if (data.length < 4) throw new ProtocolError(`upload answer: ${data.length} data bytes, expected at least 4`);
      const len = data.readUInt16BE(0);
      if (4 + len !== data.length) throw new ProtocolError(`upload answer announces ${len} bytes, ${data.length - 4} present`);
      return { kind: 'upload-ack', pduRef, more: p[1] !== 0, chunk: data.subarray(4) };
    }
    if (p.length > 2) throw new ProtocolError(`control answer: ${p.length} parameter bytes, expected 1 or 2`);
    return { kind: 'control-ack', pduRef, func, status: p[1], error };
  }
  if (m.kind !== 'other' || rosctr !== Rosctr.Job || p.length === 0) throw new ProtocolError(`not a control job (${m.kind})`);
  const func = p[0]!;
  if (func === ControlFunction.PlcStop) {
    if (p.length < 7 || p.length !== 7 + p[6]!)
      throw new ProtocolError(`PLC stop: ${p.length} parameter bytes do not match its service name`);
    return { kind: 'stop', pduRef };
  }
  if (func === ControlFunction.PiService) {
    if (p.length < 11) throw new ProtocolError(`PI service of ${p.length} parameter bytes is too short`);
    const argLen = p.readUInt16BE(8);
    const nameAt = 10 + argLen;
    if (nameAt >= p.length || nameAt + 1 + p[nameAt]! !== p.length)
      throw new ProtocolError('PI service: argument and service name lengths do not match the parameters');
    const arg = p.subarray(10, nameAt);
    return { kind: 'start', pduRef, cold: arg.equals(COLD_START_ARG), service: p.subarray(nameAt + 1).toString('latin1') };
  }
  if (p.length < 8) throw new ProtocolError(`upload job of ${p.length} parameter bytes is too short`);
  const uploadId = p.readUInt32BE(4);
  if (func === ControlFunction.StartUpload) {
    if (p.length !== 9 + p[8]! || p[8] !== 9) throw new ProtocolError('start upload: the block file name is not 9 characters');
    const name = p.subarray(9).toString('latin1');
    const match = /^_0(.)([0-9]{5})(.)$/.exec(name);
    if (!match) throw new ProtocolError(`start upload: "${name}" is not a block file name`);
    return { kind: 'start-upload', pduRef, blockType: match[1]!.charCodeAt(0), number: Number(match[2]) };
  }
  if (p.length !== 8) throw new ProtocolError(`upload job: ${p.length} parameter bytes, expected 8`);
  return func === ControlFunction.Upload ? { kind: 'upload', pduRef, uploadId } : { kind: 'end-upload', pduRef, uploadId };
}
