/**
 * The request frames a session sends and the response header it reads,
 * pure: the request header with the sequence number and the IntegrityId
 * spliced in as the PLC expects it. Layouts from s7commplus (MIT), connection.py
 * (_send_request, _frame_request); the frame header, the end marker, the
 * VLQ and the reassembly of split answers are the codec's (../codec/frame.ts,
 * ../codec/vlq.ts).
 */
import { ProtocolError } from '../../errors';
import { encodeFrames } from '../codec/frame';
import { encodeUVlq32 } from '../codec/vlq';
import { Opcode } from '../constants';

/** Bytes of a request header (opcode, reserved, function, reserved, sequence, session id, flags) and of a response header (no session id). */
const REQUEST_HEADER = 14;
const RESPONSE_HEADER = 10;

export interface RequestFrame {
  version: number;
  fn: number;
  seq: number;
  sessionId: number;
  flags: number;
  /** What follows the 14-byte header. */
  payload: Buffer;
  /** The IntegrityId, or undefined when the session sends none (before session setup, plain V1). */
  integrityId?: number | undefined;
  /** The payload's trailing bytes the IntegrityId goes before (4: the trailing u32 of most requests; 5 for Explore). */
  integrityTail?: number;
}

/** A whole request frame: header, request header, payload with its IntegrityId, and the end marker. */
export function requestFrame(r: RequestFrame): Buffer {
  const head = Buffer.alloc(REQUEST_HEADER);
  head[0] = Opcode.Request;
  head.writeUInt16BE(r.fn, 3);
  head.writeUInt16BE(r.seq, 7);
  head.writeUInt32BE(r.sessionId >>> 0, 9);
  head[13] = r.flags;
  let body: Buffer[] = [r.payload];
  if (r.integrityId !== undefined) {
    const id = encodeUVlq32(r.integrityId);
    const tail = r.integrityTail ?? 4;
    body =
      r.payload.length >= tail
        ? [r.payload.subarray(0, r.payload.length - tail), id, r.payload.subarray(r.payload.length - tail)]
        : [id, r.payload];
  }
  return encodeFrames(r.version, Buffer.concat([head, ...body]));
}

/** The response header's fields (opcode, function, sequence number) and what follows it. */
export interface Response {
  opcode: number;
  fn: number;
  seq: number;
  payload: Buffer;
}

/** A message's response header; a ProtocolError when it is too short for one. */
export function responseOf(data: Buffer): Response {
  if (data.length < RESPONSE_HEADER) throw new ProtocolError(`S7CommPlus: an answer of ${data.length} bytes has no response header`);
  return { opcode: data[0]!, fn: data.readUInt16BE(3), seq: data.readUInt16BE(7), payload: data.subarray(RESPONSE_HEADER) };
}
