/**
 * The headers of S7CommPlus messages (the data of a frame, see frame.ts):
 *
 *     request   31 <reserved:2> <function:2> <reserved:2> <sequence:2> <session id:4> <transport flags:1>   14 bytes
 *     response  32 <reserved:2> <function:2> <reserved:2> <sequence:2> <transport flags:1>                   10 bytes
 *
 * A response carries no session id. Source: s7commplus (MIT), codec.py
 * encode_request_header and server.py _build_response_header; golden frames.
 *
 * The integrity id (sessions of frame version 2 and up) is a UVLQ counter, one
 * for reads and one for writes (READ_FUNCTIONS in ../constants). In a request
 * it sits just before the body's closing fill (CreateObject: between the
 * request set and the object); in a response s7commplus's server appends it
 * after the body. Source: s7commplus (MIT), connection.py _send_request and
 * server.py _process_request; golden frames (the kq/IntegrityId bytes).
 */
import { ProtocolError } from '../../errors';
import { DataType, Ids, Opcode } from '../constants';
import { Reader, Writer } from './bytes';
import { readPValue, scalar, writePValue, type PValue } from './pvalue';

export const REQUEST_HEADER = 14;
export const RESPONSE_HEADER = 10;

export interface RequestHeader {
  functionCode: number;
  sequence: number;
  sessionId: number;
  transportFlags: number;
}

export interface ResponseHeader {
  functionCode: number;
  sequence: number;
  transportFlags: number;
  /** 0x32, or 0x02 from some older firmware. */
  opcode?: number;
}

/** A request: its header, its body, and the integrity id when the session carries one. */
export interface Request<T> {
  header: RequestHeader;
  body: T;
  integrityId?: number;
}

export interface Response<T> {
  header: ResponseHeader;
  body: T;
  integrityId?: number;
}

/** Whether the decoders expect an integrity id (a session of frame version 2 or up, after its setup). */
export interface DecodeOptions {
  integrity: boolean;
}

export function writeRequestHeader(w: Writer, h: RequestHeader): void {
  w.u8(Opcode.Request).u16(0).u16(h.functionCode).u16(0).u16(h.sequence).u32(h.sessionId).u8(h.transportFlags);
}

export function writeResponseHeader(w: Writer, h: ResponseHeader): void {
  w.u8(h.opcode ?? Opcode.Response)
    .u16(0)
    .u16(h.functionCode)
    .u16(0)
    .u16(h.sequence)
    .u8(h.transportFlags);
}

function functionName(code: number): string {
  return `0x${code.toString(16).padStart(4, '0')}`;
}

/** Reads a request header; `fn`: the function the caller decodes (a mismatch is a ProtocolError). */
export function readRequestHeader(r: Reader, fn?: number): RequestHeader {
  const opcode = r.u8('opcode');
  if (opcode !== Opcode.Request) throw new ProtocolError(`S7CommPlus: expected a request (0x31), found opcode 0x${opcode.toString(16)}`);
  r.u16('reserved');
  const functionCode = r.u16('function code');
  r.u16('reserved');
  const h: RequestHeader = {
    functionCode,
    sequence: r.u16('sequence number'),
    sessionId: r.u32('session id'),
    transportFlags: r.u8('transport flags'),
  };
  if (fn !== undefined && functionCode !== fn)
    throw new ProtocolError(`S7CommPlus: expected function ${functionName(fn)}, found ${functionName(functionCode)}`);
  return h;
}

/** Reads a response header; `fn`: the function of the request it answers. */
export function readResponseHeader(r: Reader, fn?: number): ResponseHeader {
  const opcode = r.u8('opcode');
  if (opcode !== Opcode.Response && opcode !== Opcode.Response2)
    throw new ProtocolError(`S7CommPlus: expected a response (0x32), found opcode 0x${opcode.toString(16)}`);
  r.u16('reserved');
  const functionCode = r.u16('function code');
  r.u16('reserved');
  const h: ResponseHeader = { functionCode, sequence: r.u16('sequence number'), transportFlags: r.u8('transport flags') };
  if (opcode !== Opcode.Response) h.opcode = opcode;
  if (fn !== undefined && functionCode !== fn)
    throw new ProtocolError(`S7CommPlus: the answer to function ${functionName(fn)} is function ${functionName(functionCode)}`);
  return h;
}

/** Opcode, function and sequence of a message without decoding its body (for routing answers to requests). */
export function peekMessage(data: Buffer): { opcode: number; functionCode?: number; sequence?: number } {
  const opcode = data[0];
  if (opcode === undefined) throw new ProtocolError('S7CommPlus: empty message');
  if (opcode === Opcode.Notification || data.length < RESPONSE_HEADER) return { opcode };
  return { opcode, functionCode: data.readUInt16BE(3), sequence: data.readUInt16BE(7) };
}

/** A request's integrity id where the options expect one (undefined otherwise). */
export function readIntegrity(r: Reader, opts: DecodeOptions): number | undefined {
  return opts.integrity ? r.uvlq32() : undefined;
}

/** The zero fill that closes most bodies: `n` bytes, which must be there (their value is not checked). */
export function readFill(r: Reader, n: number): void {
  r.bytes(n, 'closing fill');
}

/**
 * The end of a response: s7commplus's server appends the integrity id after
 * the body; what else a PLC sends there is not read.
 */
export function readResponseTail(r: Reader, opts: DecodeOptions): number | undefined {
  return opts.integrity && r.remaining > 0 ? r.uvlq32() : undefined;
}

/** Finishes a response: the body's fill (if any), then the integrity id. */
export function writeResponseTail(w: Writer, fill: number, integrityId: number | undefined): Buffer {
  for (let i = 0; i < fill; i++) w.u8(0);
  if (integrityId !== undefined) w.uvlq32(integrityId);
  return w.toBuffer();
}

/**
 * The ObjectQualifier closing Get/SetMultiVariables and the substreamed
 * requests: struct id 1256 (UInt32), then ParentRID (RID), CompositionAID
 * (AID) and KeyQualifier (UDInt) as (UVLQ key, PValue), ending at key 0.
 * Source: s7commplus (MIT), codec.py encode_object_qualifier; golden frames
 * (the symbolic write). The frame-version-1 form (a fixed 4-byte KeyQualifier,
 * no end) is not supported.
 */
export interface ObjectQualifier {
  parentRid: number;
  compositionAid: number;
  keyQualifier: number;
}

export function writeObjectQualifier(w: Writer, q: ObjectQualifier): void {
  w.u32(Ids.ObjectQualifier);
  const members: [number, PValue][] = [
    [Ids.ParentRID, scalar(DataType.RID, q.parentRid)],
    [Ids.CompositionAID, scalar(DataType.AID, q.compositionAid)],
    [Ids.KeyQualifier, scalar(DataType.UDInt, q.keyQualifier)],
  ];
  for (const [key, value] of members) {
    w.uvlq32(key);
    writePValue(w, value);
  }
  w.uvlq32(0);
}

export function readObjectQualifier(r: Reader): ObjectQualifier {
  const at = r.offset;
  const id = r.u32('ObjectQualifier');
  if (id !== Ids.ObjectQualifier) throw new ProtocolError(`S7CommPlus: expected the ObjectQualifier (1256) at offset ${at}, found ${id}`);
  const q: ObjectQualifier = { parentRid: 0, compositionAid: 0, keyQualifier: 0 };
  for (let key = r.uvlq32(); key !== 0; key = r.uvlq32()) {
    const v = readPValue(r).value;
    const n = typeof v === 'number' ? v : 0;
    if (key === Ids.ParentRID) q.parentRid = n;
    else if (key === Ids.CompositionAID) q.compositionAid = n;
    else if (key === Ids.KeyQualifier) q.keyQualifier = n;
  }
  return q;
}

export const NO_QUALIFIER: ObjectQualifier = { parentRid: 0, compositionAid: 0, keyQualifier: 0 };
