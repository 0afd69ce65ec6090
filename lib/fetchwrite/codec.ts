/**
 * FETCH/WRITE codec (CP 343/443 and S5 CPs): the 16-byte request header,
 * the fetch response and write acknowledgement headers, exactly as the
 * SIMATIC NET NCM S7 manual's FETCH/WRITE tables give them (docs/protocols.md,
 * "FETCH/WRITE over TCP"). Pure functions;
 * decoders throw only ProtocolError.
 */
import { PlcError, ProtocolError, type PlcErrorCode } from '../errors';
import type { FrameCheck } from '../link/framer';
import type { AreaName } from '../types';

export const HEADER = 16;
/** A frame carries at most 64 KiB of data. */
export const MAX_DATA = 0xffff;

export enum OpCode {
  WriteRequest = 0x03,
  WriteAck = 0x04,
  FetchRequest = 0x05,
  FetchResponse = 0x06,
}

export enum Org {
  DB = 0x01,
  M = 0x02,
  I = 0x03,
  Q = 0x04,
  PEPA = 0x05,
  C = 0x06,
  T = 0x07,
}

export const ORG_BY_AREA: Readonly<Record<AreaName, Org>> = Object.freeze({
  DB: Org.DB,
  M: Org.M,
  I: Org.I,
  Q: Org.Q,
  PE: Org.PEPA,
  PA: Org.PEPA,
  C: Org.C,
  T: Org.T,
});

/**
 * The ORG table (docs/protocols.md, "ORG areas and units"): how each ORG
 * area counts its start and length, and the largest start and length a job
 * may name (DB: in words). The table permits a length of exactly 1 for
 * counters and timers, so C/T ranges are fetched one cell per job.
 */
export const ORG_RANGES: Readonly<Record<number, { name: string; unit: 'word' | 'byte'; maxStart: number; maxLength: number }>> =
  Object.freeze({
    [Org.DB]: { name: 'DB', unit: 'word', maxStart: 2047, maxLength: 2048 },
    [Org.M]: { name: 'M', unit: 'byte', maxStart: 255, maxLength: 256 },
    [Org.I]: { name: 'I', unit: 'byte', maxStart: 127, maxLength: 128 },
    [Org.Q]: { name: 'Q', unit: 'byte', maxStart: 127, maxLength: 128 },
    // The ORG table's 0–255 is the S5 I/O range; S7 CPUs put analog modules from byte 256 up (PIW256),
    // and the start field is 16 bits, so any byte address is allowed here (docs/protocols.md, corrections).
    [Org.PEPA]: { name: 'PE/PA', unit: 'byte', maxStart: 0xffff, maxLength: 256 },
    [Org.C]: { name: 'C', unit: 'word', maxStart: 255, maxLength: 1 },
    [Org.T]: { name: 'T', unit: 'word', maxStart: 255, maxLength: 1 },
  });

export interface FwRequest {
  op: OpCode.FetchRequest | OpCode.WriteRequest;
  org: number;
  dbNumber: number;
  /** In the area's unit (DB: words by default, bytes with dbUnit=byte). */
  start: number;
  /** In the area's unit. */
  length: number;
  /** Write only. */
  data?: Buffer;
}

export interface FwResponse {
  op: OpCode.FetchResponse | OpCode.WriteAck;
  error: number;
  data: Buffer;
}

/** A request header (and the data of a write) in one Buffer. */
export function encodeRequest(r: FwRequest): Buffer {
  if (!isU(r.org, 0xff) || !isU(r.dbNumber, 0xff) || !isU(r.start, 0xffff) || !isU(r.length, 0xffff)) {
    throw new PlcError(
      'INVALID_ADDRESS',
      `FETCH/WRITE job out of the header's range: ORG ${r.org}, DB ${r.dbNumber}, start ${r.start}, length ${r.length}`,
    );
  }
  const data = r.op === OpCode.WriteRequest ? (r.data ?? Buffer.alloc(0)) : Buffer.alloc(0);
  const frame = Buffer.allocUnsafe(HEADER + data.length);
  frame[0] = 0x53; // 'S'
  frame[1] = 0x35; // '5'
  frame[2] = HEADER;
  frame[3] = 0x01;
  frame[4] = 0x03;
  frame[5] = r.op;
  frame[6] = 0x03;
  frame[7] = 0x08;
  frame[8] = r.org;
  frame[9] = r.dbNumber;
  frame.writeUInt16BE(r.start, 10);
  frame.writeUInt16BE(r.length, 12);
  frame[14] = 0xff;
  frame[15] = 0x02;
  data.copy(frame, HEADER);
  return frame;
}

function isU(n: number, max: number): boolean {
  return Number.isInteger(n) && n >= 0 && n <= max;
}

/** A fetch response or write acknowledgement (what the CP sends). */
export function encodeResponse(op: OpCode.FetchResponse | OpCode.WriteAck, error: number, data: Buffer = Buffer.alloc(0)): Buffer {
  const body = op === OpCode.FetchResponse && error === 0 ? data : Buffer.alloc(0);
  const frame = Buffer.alloc(HEADER + body.length);
  frame[0] = 0x53;
  frame[1] = 0x35;
  frame[2] = HEADER;
  frame[3] = 0x01;
  frame[4] = 0x03;
  frame[5] = op;
  frame[6] = 0x0f;
  frame[7] = 0x03;
  frame[8] = error;
  frame[9] = 0xff;
  frame[10] = 0x07;
  body.copy(frame, HEADER);
  return frame;
}

function checkCommon(buf: Buffer, what: string): void {
  if (buf[0] !== 0x53 || buf[1] !== 0x35)
    throw new ProtocolError(`${what}: system id ${buf.subarray(0, 2).toString('hex')}, expected "S5"`);
  if (buf[2] !== HEADER) throw new ProtocolError(`${what}: header length ${buf[2]}, expected 16`);
  if (buf[3] !== 0x01 || buf[4] !== 0x03) throw new ProtocolError(`${what}: bad op code field`);
}

/** Decodes a response frame cut by checkResponse(): the header, and the data after it. */
export function decodeResponse(frame: Buffer): FwResponse {
  if (frame.length < HEADER) throw new ProtocolError(`FETCH/WRITE response of ${frame.length} bytes is shorter than its header`);
  checkCommon(frame, 'response');
  const op = frame[5]!;
  if (op !== OpCode.FetchResponse && op !== OpCode.WriteAck)
    throw new ProtocolError(`response op code 0x${op.toString(16).padStart(2, '0')}, expected 06 or 04`);
  if (frame[6] !== 0x0f || frame[7] !== 0x03) throw new ProtocolError('response: bad ack field');
  if (frame[9] !== 0xff || frame[10] !== 0x07) throw new ProtocolError('response: bad empty field');
  return { op, error: frame[8]!, data: frame.subarray(HEADER) };
}

/** Decodes a request (for the simulator); `data` is what follows the header in the frame. */
export function decodeRequest(frame: Buffer): FwRequest {
  if (frame.length < HEADER) throw new ProtocolError(`FETCH/WRITE request of ${frame.length} bytes is shorter than its header`);
  checkCommon(frame, 'request');
  const op = frame[5]!;
  if (op !== OpCode.FetchRequest && op !== OpCode.WriteRequest)
    throw new ProtocolError(`request op code 0x${op.toString(16).padStart(2, '0')}, expected 05 or 03`);
  if (frame[6] !== 0x03 || frame[7] !== 0x08) throw new ProtocolError('request: bad ORG field');
  if (frame[14] !== 0xff || frame[15] !== 0x02) throw new ProtocolError('request: bad empty field');
  return {
    op,
    org: frame[8]!,
    dbNumber: frame[9]!,
    start: frame.readUInt16BE(10),
    length: frame.readUInt16BE(12),
    ...(op === OpCode.WriteRequest ? { data: frame.subarray(HEADER) } : {}),
  };
}

/** Bytes a request's length stands for (DB in word units and C/T: 2 per unit). */
export function byteLength(org: number, length: number, dbUnit: 'word' | 'byte'): number {
  if (org === Org.DB) return dbUnit === 'word' ? 2 * length : length;
  if (org === Org.C || org === Org.T) return 2 * length;
  return length;
}

/**
 * The CP's error byte (the S5 CP status numbers of the handling blocks' ANZW:
 * 02, 03 and 06 are the ones a FETCH/WRITE peer sends in practice).
 * Unknown codes keep their number.
 */
const ERRORS: Readonly<Record<number, [PlcErrorCode, string]>> = Object.freeze({
  0x01: ['PLC_ERROR', 'wrong job type (error 01)'],
  0x02: ['OBJECT_DOES_NOT_EXIST', 'area does not exist (error 02: e.g. the data block is not loaded)'],
  0x03: ['ADDRESS_OUT_OF_RANGE', 'area too small (error 03: start or length beyond its end)'],
  0x04: ['PLC_ERROR', 'timeout in the PLC (error 04: QVZ, I/O not present)'],
  0x05: ['PLC_ERROR', 'error in the status word (error 05)'],
  0x06: ['TYPE_NOT_SUPPORTED', 'invalid ORG format (error 06: ORG id, DB number or length not allowed)'],
  0x07: ['PLC_ERROR', 'no free data buffer in the CP (error 07)'],
  0x08: ['PLC_ERROR', 'no free transport connection (error 08)'],
  0x09: ['PLC_ERROR', 'error on the remote side (error 09)'],
  0x0a: ['PLC_ERROR', 'connection error (error 0A)'],
});

/** A typed error for a non-zero error byte; `context` names the job ("s7://… fetch of DB1 0+4"). */
export function errorFor(code: number, context: string): PlcError {
  const known = ERRORS[code];
  const hex = code.toString(16).padStart(2, '0').toUpperCase();
  if (known) return new PlcError(known[0], `${context}: the CP answered ${known[1]}`, { plcCode: code });
  return new PlcError('PLC_ERROR', `${context}: the CP answered error ${hex} (unknown code)`, { plcCode: code });
}

/** What the client waits for on one connection: a job's answer and the data bytes a fetch returns. */
export interface ResponseExpectation {
  op: OpCode.FetchRequest | OpCode.WriteRequest;
  /** Bytes of data a successful fetch carries (0 for a write). */
  dataBytes: number;
}

/**
 * FrameCheck for the client's FrameReader. FETCH/WRITE answers carry no
 * length, so the reader is told what the pending job expects: 16 bytes, plus
 * the fetched data when the error byte is 0. Bytes with no job pending, or a
 * header that is not the expected answer, are 'bad' (the link is dropped).
 */
export function checkResponse(buffered: Buffer, expected: ResponseExpectation | undefined): FrameCheck {
  if (!expected) return { kind: 'bad', error: new ProtocolError(`${buffered.length} bytes from the CP while no job was pending`) };
  if (buffered.length < HEADER) {
    // Reject a wrong start early rather than waiting for 16 bytes that may never come.
    const prefix = Buffer.from([0x53, 0x35, HEADER, 0x01, 0x03]);
    const n = Math.min(buffered.length, prefix.length);
    if (!buffered.subarray(0, n).equals(prefix.subarray(0, n)))
      return {
        kind: 'bad',
        error: new ProtocolError(`answer does not start with "S5" 10 01 03: ${buffered.subarray(0, n).toString('hex')}`),
      };
    return { kind: 'need' };
  }
  let header: FwResponse;
  try {
    header = decodeResponse(buffered.subarray(0, HEADER));
  } catch (err) {
    return { kind: 'bad', error: err as ProtocolError };
  }
  const want = expected.op === OpCode.FetchRequest ? OpCode.FetchResponse : OpCode.WriteAck;
  if (header.op !== want) {
    return {
      kind: 'bad',
      error: new ProtocolError(`answer op code 0x${hex2(header.op)} does not match the job (expected 0x${hex2(want)})`),
    };
  }
  const length = header.op === OpCode.FetchResponse && header.error === 0 ? HEADER + expected.dataBytes : HEADER;
  return buffered.length >= length ? { kind: 'frame', length } : { kind: 'need' };
}

/** FrameCheck for the simulator: a request header, plus the data of a write (its length from the header's units). */
export function checkRequest(buffered: Buffer, dbUnit: 'word' | 'byte'): FrameCheck {
  if (buffered.length < HEADER) return { kind: 'need' };
  let req: FwRequest;
  try {
    req = decodeRequest(buffered.subarray(0, HEADER));
  } catch (err) {
    return { kind: 'bad', error: err as ProtocolError };
  }
  const length = req.op === OpCode.WriteRequest ? HEADER + byteLength(req.org, req.length, dbUnit) : HEADER;
  return buffered.length >= length ? { kind: 'frame', length } : { kind: 'need' };
}

function hex2(n: number): string {
  return n.toString(16).padStart(2, '0');
}
