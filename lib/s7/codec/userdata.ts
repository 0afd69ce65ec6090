/**
 * S7comm userdata PDUs (ROSCTR 7): the CPU services (SZL, clock, block
 * functions, password). Beside the job codec (pdu.ts) and in its style:
 * encoders build the whole frame (TPKT + COTP DT + S7) in one Buffer,
 * decoders take one whole frame, return subarrays of it, and throw only
 * ProtocolError.
 *
 * Parameter part (after the 10-byte header):
 *
 *   00 01 12  head
 *   04 | 08   length of the rest: 4 in a request, 8 in a response and in a
 *             request for the next part of a multi-part answer
 *   11 | 12   method: request / response
 *   tg        type (high nibble: 0 push, 4 request, 8 response) and
 *             function group (low nibble: 3 blocks, 4 CPU (SZL), 5 security, 7 time)
 *   sf        subfunction
 *   seq       sequence number (the CPU's, echoed by a next-part request)
 *   — with length 8 only —
 *   dur       data unit reference
 *   last      last data unit: 00 yes, 01 more parts follow
 *   err err   error code (0 = none)
 *
 * Data part: one item, return code (FF ok, 0A none), transport size
 * (09 octet string), length in bytes, data.
 */
import { PlcError, ProtocolError, ValueError } from '../../errors';
import {
  DataTransportSize,
  LAST_DATA_UNIT,
  MORE_DATA_UNITS,
  Rosctr,
  S7_JOB_HEADER,
  S7_PROTOCOL_ID,
  UserdataMethod,
  UserdataType,
} from '../constants';
import { FRAME_OVERHEAD } from '../../iso/constants';
import { decodeCotp } from '../../iso/cotp';
import { dataLengthBytes, s7Frame } from './pdu';

/** The parameter part of a userdata PDU. */
export interface UserdataParams {
  /** 0x11 request, 0x12 response (UserdataMethod). */
  method: number;
  /** High nibble of the type/group byte: 0 push, 4 request, 8 response (UserdataType). */
  type: number;
  /** Function group (UserdataGroup): 3 blocks, 4 CPU/SZL, 5 security, 7 time. */
  group: number;
  subfunction: number;
  sequence: number;
  /** Present in the 12-byte form only (responses, next-part requests). */
  dataUnitRef?: number;
  /** False when the CPU has more parts of this answer (12-byte form only). */
  lastDataUnit?: boolean;
  /** 0 = no error (12-byte form only); else a SERVICE_ERRORS code. */
  errorCode?: number;
}

/** A decoded userdata PDU. `data` is a subarray of the frame. */
export interface UserdataPdu {
  pduRef: number;
  params: UserdataParams;
  /** 0xFF success, 0x0A "no data / object does not exist". */
  returnCode: number;
  transportSize: number;
  data: Buffer;
}

/** Bytes of the parameter part: 8, or 12 with the data unit fields. */
function paramLength(p: UserdataParams): number {
  return p.dataUnitRef === undefined && p.lastDataUnit === undefined && p.errorCode === undefined ? 8 : 12;
}

/** Userdata frame overhead besides the data: TPKT, COTP, header, 12-byte parameters, item header. */
export const USERDATA_OVERHEAD = FRAME_OVERHEAD + S7_JOB_HEADER + 12 + 4;

/**
 * One userdata frame. `data` undefined sends the empty item `0A 00 00 00`
 * (a request without data, a next-part request, an error answer).
 */
export function encodeUserdata(pduRef: number, p: UserdataParams, data?: Buffer, returnCode = 0xff): Buffer {
  const plen = paramLength(p);
  const empty = data === undefined;
  const dlen = 4 + (empty ? 0 : data.length);
  if (dlen > 0xffff) throw new ValueError('userdata', `${dlen} bytes do not fit an S7 PDU`);
  const frame = s7Frame(Rosctr.UserData, pduRef, plen, dlen);
  let o = FRAME_OVERHEAD + S7_JOB_HEADER;
  frame[o] = 0x00;
  frame[o + 1] = 0x01;
  frame[o + 2] = 0x12;
  frame[o + 3] = plen - 4;
  frame[o + 4] = p.method;
  frame[o + 5] = ((p.type & 0x0f) << 4) | (p.group & 0x0f);
  frame[o + 6] = p.subfunction;
  frame[o + 7] = p.sequence;
  if (plen === 12) {
    frame[o + 8] = p.dataUnitRef ?? 0;
    frame[o + 9] = p.lastDataUnit === false ? MORE_DATA_UNITS : LAST_DATA_UNIT;
    frame.writeUInt16BE(p.errorCode ?? 0, o + 10);
  }
  o += plen;
  if (empty) {
    frame[o] = 0x0a;
    frame[o + 1] = DataTransportSize.NULL;
    frame[o + 2] = 0;
    frame[o + 3] = 0;
    return frame;
  }
  frame[o] = returnCode;
  frame[o + 1] = DataTransportSize.OCTET_STRING;
  frame.writeUInt16BE(data.length, o + 2);
  data.copy(frame, o + 4);
  return frame;
}

/**
 * Whether a whole frame is a userdata PDU the CPU sent unasked (type push:
 * alarm and diagnostic indications of group 4, cyclic data of group 2), so
 * the session hands it to its push listeners instead of matching an answer.
 * Looks at the bytes only; the listener decodes.
 */
export function isUserdataPush(frame: Buffer): boolean {
  const at = FRAME_OVERHEAD;
  const params = at + S7_JOB_HEADER;
  return (
    frame.length > params + 8 &&
    frame[at] === S7_PROTOCOL_ID &&
    frame[at + 1] === Rosctr.UserData &&
    frame[params + 2] === 0x12 &&
    frame[params + 5]! >> 4 === UserdataType.Push
  );
}

/** A first request (8-byte parameters) of a group and subfunction, with its data (or none). */
export function encodeUserdataRequest(group: number, subfunction: number, data?: Buffer): Buffer {
  return encodeUserdata(0, { method: UserdataMethod.Request, type: UserdataType.Request, group, subfunction, sequence: 0 }, data);
}

/** The request for the next part of a multi-part answer: the CPU's sequence number and data unit reference echoed. */
export function encodeUserdataNext(group: number, subfunction: number, sequence: number, dataUnitRef: number): Buffer {
  return encodeUserdata(0, {
    method: UserdataMethod.Response,
    type: UserdataType.Request,
    group,
    subfunction,
    sequence,
    dataUnitRef,
    lastDataUnit: true,
    errorCode: 0,
  });
}

/** What a response carries besides group and subfunction. */
export interface UserdataAnswer {
  sequence?: number;
  dataUnitRef?: number;
  /** False when more parts follow. Default true. */
  last?: boolean;
  /** A SERVICE_ERRORS code; the data is then the empty item. */
  errorCode?: number;
  data?: Buffer;
}

/** A CPU's response (12-byte parameters). Errors and answers without data carry `0A 00 00 00`. */
export function encodeUserdataResponse(pduRef: number, group: number, subfunction: number, a: UserdataAnswer = {}): Buffer {
  const errorCode = a.errorCode ?? 0;
  return encodeUserdata(
    pduRef,
    {
      method: UserdataMethod.Response,
      type: UserdataType.Response,
      group,
      subfunction,
      sequence: a.sequence ?? 0,
      dataUnitRef: a.dataUnitRef ?? 0,
      lastDataUnit: a.last ?? true,
      errorCode,
    },
    errorCode === 0 ? a.data : undefined,
  );
}

/** Decodes a whole userdata frame; throws ProtocolError on anything malformed, truncated or inconsistent. */
export function decodeUserdata(frame: Buffer): UserdataPdu {
  const cotp = decodeCotp(frame);
  if (cotp.type !== 'DT') throw new ProtocolError(`expected COTP data, got ${cotp.type}`);
  const pdu = cotp.payload;
  if (pdu.length < S7_JOB_HEADER) throw new ProtocolError(`S7 PDU of ${pdu.length} bytes is too short`);
  if (pdu[0] !== S7_PROTOCOL_ID) throw new ProtocolError(`S7 protocol id 0x${pdu[0]!.toString(16)}, expected 0x32`);
  if (pdu[1] !== Rosctr.UserData) throw new ProtocolError(`expected a userdata PDU (ROSCTR 7), got ROSCTR ${pdu[1]}`);
  const plen = pdu.readUInt16BE(6);
  const dlen = pdu.readUInt16BE(8);
  if (S7_JOB_HEADER + plen + dlen !== pdu.length) {
    throw new ProtocolError(`S7 lengths (header 10 + parameters ${plen} + data ${dlen}) do not match the PDU (${pdu.length})`);
  }
  return decodeUserdataParts(pdu.readUInt16BE(4), pdu.subarray(S7_JOB_HEADER, S7_JOB_HEADER + plen), pdu.subarray(S7_JOB_HEADER + plen));
}

/** The parameter and data parts of a userdata PDU whose header lengths were checked. */
export function decodeUserdataParts(pduRef: number, p: Buffer, d: Buffer): UserdataPdu {
  if (p.length !== 8 && p.length !== 12) throw new ProtocolError(`userdata parameters of ${p.length} bytes, expected 8 or 12`);
  if (p[0] !== 0x00 || p[1] !== 0x01 || p[2] !== 0x12) throw new ProtocolError('userdata parameter head is not 00 01 12');
  if (p[3] !== p.length - 4) throw new ProtocolError(`userdata parameter length byte ${p[3]} does not match its ${p.length} bytes`);
  const params: UserdataParams = { method: p[4]!, type: p[5]! >> 4, group: p[5]! & 0x0f, subfunction: p[6]!, sequence: p[7]! };
  if (p.length === 12) {
    if (p[9]! > MORE_DATA_UNITS) throw new ProtocolError(`userdata "last data unit" byte 0x${p[9]!.toString(16)}, expected 00 or 01`);
    params.dataUnitRef = p[8]!;
    params.lastDataUnit = p[9] === LAST_DATA_UNIT;
    params.errorCode = p.readUInt16BE(10);
  }
  if (d.length < 4) throw new ProtocolError(`userdata data part of ${d.length} bytes, expected at least 4`);
  const returnCode = d[0]!;
  const transportSize = d[1]!;
  const len = dataLengthBytes(transportSize, d.readUInt16BE(2));
  // A request whose item announces more than the S7 header's data length holds is read by the header:
  // Apache PLC4X 0.13.1 asks for SZL 0x0011 with an item that announces 12 bytes and carries the 4 of
  // SZL ID and index (its default CPU identification), and CPUs answer it. Answers stay exact.
  const request = params.method === UserdataMethod.Request && params.type === UserdataType.Request;
  if (4 + len !== d.length && !(request && 4 + len > d.length)) {
    throw new ProtocolError(`userdata data item announces ${len} bytes, ${d.length - 4} present`);
  }
  return { pduRef, params, returnCode, transportSize, data: d.subarray(4) };
}

/**
 * The password as the security function sends it: padded with spaces to 8
 * characters; bytes 0 and 1 XOR 0x55, each later byte XOR 0x55 and the
 * encoded byte two places before.
 */
export function encodePassword(password: string): Buffer {
  if (typeof password !== 'string' || password.length === 0 || password.length > 8 || !/^[\x20-\x7e]+$/.test(password)) {
    throw new PlcError('INVALID_VALUE', 'a PLC password is 1 to 8 printable ASCII characters');
  }
  const plain = Buffer.from(password.padEnd(8, ' '), 'latin1');
  const out = Buffer.alloc(8);
  for (let i = 0; i < 8; i++) out[i] = i < 2 ? plain[i]! ^ 0x55 : plain[i]! ^ 0x55 ^ out[i - 2]!;
  return out;
}

/** The 8 password bytes as sent, back to the text (padded with spaces). */
export function decodePassword(b: Buffer): string {
  const out = Buffer.alloc(8);
  for (let i = 0; i < 8; i++) out[i] = i < 2 ? b[i]! ^ 0x55 : b[i]! ^ 0x55 ^ b[i - 2]!;
  return out.toString('latin1');
}
