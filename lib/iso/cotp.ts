/** COTP (ISO 8073 class 0, as used by RFC 1006): CR, CC, DR, DC, DT, ER TPDUs. */
import { ProtocolError, ValueError } from '../errors';
import { CotpParam, CotpType, TPKT_HEADER } from './constants';
import { assertTpkt, tpktFrame } from './tpkt';

export interface CotpConnection {
  /** Source reference of the sender. */
  sourceRef: number;
  /** The peer's reference (0 in a CR). */
  destinationRef: number;
  /** Parameter 0xC1. */
  callingTsap: number;
  /** Parameter 0xC2: for S7, (connection type << 8) | (rack << 5 | slot). */
  calledTsap: number;
  /** Parameter 0xC0: TPDU size code, bytes = 1 << code (0x0A = 1024). */
  tpduSize: number;
}

/** Parameter order on the wire: circulated CRs send the TSAPs first, S7 CPUs' CC the TPDU size first (docs/protocols.md, "COTP"). */
export type CotpParamOrder = 'tsap-first' | 'size-first';

/**
 * A TSAP as a connection request names it: a 2-byte number (S7's rack/slot
 * TSAPs, 0x0301), or its bytes as sent, of any length up to 255 (S7CommPlus
 * calls the TSAP "SIMATIC-ROOT-HMI", 16 ASCII bytes: s7commplus (MIT),
 * s7commplus/protocol.py, S7COMMPLUS_REMOTE_TSAP).
 */
export type CotpTsap = number | Uint8Array;

/** What a connection request carries: a CotpConnection whose TSAPs may also be byte strings. */
export interface CotpRequest extends Omit<CotpConnection, 'destinationRef' | 'callingTsap' | 'calledTsap'> {
  callingTsap: CotpTsap;
  calledTsap: CotpTsap;
}

/** The bytes of a TSAP parameter's value. */
function tsapBytes(tsap: CotpTsap, what: string): Uint8Array {
  if (typeof tsap !== 'number') {
    if (tsap.length === 0 || tsap.length > 255) throw new ValueError(what, `a TSAP of ${tsap.length} bytes (1 to 255)`);
    return tsap;
  }
  return Uint8Array.of((tsap >> 8) & 0xff, tsap & 0xff);
}

function encodeConnection(type: CotpType, c: CotpRequest & { destinationRef: number }, order: CotpParamOrder): Buffer {
  const calling = tsapBytes(c.callingTsap, 'calling TSAP');
  const called = tsapBytes(c.calledTsap, 'called TSAP');
  const params = 3 + 2 + calling.length + 2 + called.length; // C0 01 xx, C1 len …, C2 len …
  if (6 + params > 0xfe) throw new ValueError('COTP header', `${7 + params} bytes exceed the length indicator's 254`);
  const frame = tpktFrame(7 + params);
  frame[4] = 6 + params; // length indicator: header bytes after this one
  frame[5] = type;
  frame.writeUInt16BE(c.destinationRef & 0xffff, 6);
  frame.writeUInt16BE(c.sourceRef & 0xffff, 8);
  frame[10] = 0; // class 0, no extended formats
  let p = 11;
  const size = () => {
    frame[p] = CotpParam.TpduSize;
    frame[p + 1] = 1;
    frame[p + 2] = c.tpduSize;
    p += 3;
  };
  const tsap = (code: CotpParam, value: Uint8Array) => {
    frame[p] = code;
    frame[p + 1] = value.length;
    frame.set(value, p + 2);
    p += 2 + value.length;
  };
  if (order === 'size-first') size();
  tsap(CotpParam.CallingTsap, calling);
  tsap(CotpParam.CalledTsap, called);
  if (order === 'tsap-first') size();
  return frame;
}

/**
 * COTP Connection Request; default order as in the CR circulated in S7 examples (test/fixtures/s7.ts, DOC).
 * The TSAPs are numbers (2 bytes each) or byte strings (see CotpTsap).
 */
export function encodeConnectionRequest(c: CotpRequest, order: CotpParamOrder = 'tsap-first'): Buffer {
  return encodeConnection(CotpType.CR, { ...c, destinationRef: 0 }, order);
}

/**
 * COTP Connection Confirm; default order as an S7 CPU answers (TPDU size first, as in test/fixtures/s7.ts DOC.connectionConfirm).
 * The TSAPs echo the CR's: numbers (2 bytes) or byte strings (an S7CommPlus CR's).
 */
export function encodeConnectionConfirm(c: CotpRequest & { destinationRef: number }, order: CotpParamOrder = 'size-first'): Buffer {
  return encodeConnection(CotpType.CC, c, order);
}

/** COTP Disconnect Request (ISO 8073 §13.5): reason 0x80 normal, 0x81 congestion, 0x85 unknown TSAP... (class 0 uses 0..4, 0x80+). */
export function encodeDisconnectRequest(destinationRef: number, sourceRef: number, reason = 0x00): Buffer {
  const frame = tpktFrame(7);
  frame[4] = 6;
  frame[5] = CotpType.DR;
  frame.writeUInt16BE(destinationRef & 0xffff, 6);
  frame.writeUInt16BE(sourceRef & 0xffff, 8);
  frame[10] = reason & 0xff;
  return frame;
}

/** COTP TPDU Error (ISO 8073 §13.12): reject cause 0 unspecified, 1 invalid parameter code, 2 invalid TPDU type, 3 invalid parameter value. */
export function encodeCotpError(destinationRef: number, cause: number): Buffer {
  const frame = tpktFrame(5);
  frame[4] = 4;
  frame[5] = CotpType.ER;
  frame.writeUInt16BE(destinationRef & 0xffff, 6);
  frame[8] = cause & 0xff;
  return frame;
}

export type CotpMessage =
  | ({ type: 'CR' | 'CC' } & CotpConnection)
  | { type: 'DR' | 'DC'; destinationRef: number; sourceRef: number; reason: number }
  | { type: 'DT'; last: boolean; payload: Buffer }
  | { type: 'ER'; destinationRef: number; cause: number };

/** Decodes the COTP part of one whole TPKT frame. DT payloads are subarrays of `frame`. Throws ProtocolError only. */
export function decodeCotp(frame: Buffer): CotpMessage {
  assertTpkt(frame, 'COTP');
  const li = frame[4]!;
  const end = TPKT_HEADER + 1 + li;
  if (li < 2) throw new ProtocolError(`COTP: length indicator ${li} is too short`);
  if (end > frame.length) throw new ProtocolError(`COTP: length indicator ${li} runs past the frame`);
  const type = frame[5]! & 0xf0;
  if (type === CotpType.DT) return { type: 'DT', last: (frame[6]! & 0x80) !== 0, payload: frame.subarray(end) };
  if (type === CotpType.ER) {
    if (li < 4) throw new ProtocolError('COTP ER: header too short');
    return { type: 'ER', destinationRef: frame.readUInt16BE(6), cause: frame[8]! };
  }
  if (type !== CotpType.CR && type !== CotpType.CC && type !== CotpType.DR && type !== CotpType.DC) {
    throw new ProtocolError(`COTP: unexpected TPDU type 0x${type.toString(16)}`);
  }
  if (li < 6) throw new ProtocolError(`COTP 0x${type.toString(16)}: header too short`);
  const destinationRef = frame.readUInt16BE(6);
  const sourceRef = frame.readUInt16BE(8);
  if (type === CotpType.DR || type === CotpType.DC) {
    return { type: type === CotpType.DR ? 'DR' : 'DC', destinationRef, sourceRef, reason: type === CotpType.DR ? frame[10]! : 0 };
  }
  const c: CotpConnection = { sourceRef, destinationRef, callingTsap: -1, calledTsap: -1, tpduSize: 0 };
  let p = 11;
  while (p < end) {
    if (p + 2 > end) throw new ProtocolError('COTP: truncated parameter');
    const code = frame[p]!;
    const len = frame[p + 1]!;
    if (p + 2 + len > end) throw new ProtocolError(`COTP: parameter 0x${code.toString(16)} runs past the header`);
    if (code === CotpParam.TpduSize && len === 1) c.tpduSize = frame[p + 2]!;
    else if (code === CotpParam.CallingTsap && len === 2) c.callingTsap = frame.readUInt16BE(p + 2);
    else if (code === CotpParam.CalledTsap && len === 2) c.calledTsap = frame.readUInt16BE(p + 2);
    p += 2 + len;
  }
  return { type: type === CotpType.CR ? 'CR' : 'CC', ...c };
}

/** The TPDU type of a whole frame's COTP header (CotpType: DT, DR …), without checking the rest. */
export function cotpTpduType(frame: Buffer): number {
  return frame[TPKT_HEADER + 1]! & 0xf0;
}

/** The reason of a COTP disconnect request (0 when the frame is too short to carry one). */
export function disconnectReason(frame: Buffer): number {
  return frame[TPKT_HEADER + 6] ?? 0;
}
