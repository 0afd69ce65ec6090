/**
 * S7comm PDUs inside COTP DT: setup communication, Read Var, Write Var and
 * their acks. Encoders build the whole frame (TPKT + COTP DT + S7) in one
 * Buffer; decoders take one whole TPKT frame, return subarrays of it, and
 * throw only ProtocolError.
 */
import { ProtocolError, ValueError } from '../../errors';
import {
  COTP_DT_HEADER,
  CotpType,
  DataTransportSize,
  FRAME_OVERHEAD,
  READ_ITEM,
  Rosctr,
  S7Function,
  S7_ACK_HEADER,
  S7_JOB_HEADER,
  S7_PROTOCOL_ID,
  TPKT_VERSION,
} from '../constants';
import { decodeCotp } from './cotp';
import { tpktFrame } from './tpkt';

/** One S7ANY request item (syntax id 0x10). */
export interface S7Item {
  /** S7Area code (0x84 DB, 0x83 M …). */
  area: number;
  /** Data block number (0 outside DB). */
  dbNumber: number;
  /** TransportSize code of the request item: the unit `count` counts in. */
  transportSize: number;
  /** Elements of transportSize. */
  count: number;
  /** The 24-bit address field: byte offset × 8 + bit (for C/T: the counter/timer number). */
  address: number;
}

/** A Write Var item: the request item plus its data part. */
export interface S7WriteItem extends S7Item {
  /** DataTransportSize code of the data part: 0x03 BIT (length 1 bit), 0x04 BYTE (length in bits), 0x09 OCTET STRING (bytes). */
  dataTransportSize: number;
  data: Buffer;
}

export interface SetupParams {
  maxAmqCalling: number;
  maxAmqCalled: number;
  pduSize: number;
}

/** One data item of a Read Var ack (also the data part of a Write Var job). */
export interface ReadResponseItem {
  /** 0xFF success, else the item's error (ReturnCode). */
  returnCode: number;
  /** DataTransportSize code (0x04 bytes counted in bits, 0x09 octets, 0x03 one bit …). */
  transportSize: number;
  /** The data (a subarray of the frame when decoded). */
  data: Buffer;
}

export type S7Message =
  | { kind: 'setup-request'; pduRef: number; params: SetupParams }
  | { kind: 'read-request'; pduRef: number; items: S7Item[] }
  | { kind: 'write-request'; pduRef: number; items: S7WriteItem[] }
  | { kind: 'setup-ack'; pduRef: number; params: SetupParams }
  | { kind: 'read-ack'; pduRef: number; items: ReadResponseItem[] }
  | { kind: 'write-ack'; pduRef: number; returnCodes: number[] }
  /** An ack or ack-data whose header error class/code is not 0 (headerError() gives the words). */
  | { kind: 'error'; pduRef: number; errorClass: number; errorCode: number; rosctr: number; func?: number }
  /** Any other well-formed S7 PDU (userdata, unknown functions). */
  | { kind: 'other'; pduRef: number; rosctr: number; func?: number };

// ---------------------------------------------------------------- sizes

/** The length field of a data item: bits for BIT (one per byte sent), BYTE/WORD/DWORD and INTEGER, bytes otherwise. */
export function dataLengthField(transportSize: number, bytes: number): number {
  if (transportSize === DataTransportSize.BYTE || transportSize === DataTransportSize.INTEGER) return bytes * 8;
  return bytes;
}

/** Bytes a data item's length field announces. */
export function dataLengthBytes(transportSize: number, field: number): number {
  if (transportSize === DataTransportSize.BYTE || transportSize === DataTransportSize.INTEGER) return (field + 7) >> 3;
  if (transportSize === DataTransportSize.BIT) return field === 0 ? 0 : 1 + ((field - 1) >> 3);
  return field;
}

/** Size of a data part: each item 4 + data bytes, with a fill byte after odd-length data except the last. */
export function dataPartLength(items: readonly { data: Buffer }[]): number {
  let n = 0;
  const last = items.length - 1;
  for (let i = 0; i <= last; i++) {
    const len = items[i]!.data.length;
    n += 4 + len + (len & 1 && i < last ? 1 : 0);
  }
  return n;
}

/** S7 PDU bytes (without TPKT/COTP) of a Read Var job with `items` items. */
export function readRequestPduSize(items: number): number {
  return S7_JOB_HEADER + 2 + READ_ITEM * items;
}

// ---------------------------------------------------------------- encoders

/**
 * Starts a frame: TPKT, COTP DT (EOT), S7 header (an ack's with `error`,
 * class << 8 | code); the parameters start at FRAME_OVERHEAD + the header.
 * The one writer of the S7 header, for jobs, userdata and control jobs alike.
 */
export function s7Frame(rosctr: number, pduRef: number, paramLength: number, dataLength: number, error = 0): Buffer {
  const ack = rosctr === Rosctr.Ack || rosctr === Rosctr.AckData;
  const header = ack ? S7_ACK_HEADER : S7_JOB_HEADER;
  const frame = tpktFrame(COTP_DT_HEADER + header + paramLength + dataLength);
  frame[4] = 2;
  frame[5] = CotpType.DT;
  frame[6] = 0x80;
  frame[7] = S7_PROTOCOL_ID;
  frame[8] = rosctr;
  frame[9] = 0;
  frame[10] = 0;
  frame.writeUInt16BE(pduRef & 0xffff, 11);
  frame.writeUInt16BE(paramLength, 13);
  frame.writeUInt16BE(dataLength, 15);
  if (ack) frame.writeUInt16BE(error, 17);
  return frame;
}

/** Offset of the parameters in a frame built by s7Frame. */
const JOB_PARAMS = FRAME_OVERHEAD + S7_JOB_HEADER;
const ACK_PARAMS = FRAME_OVERHEAD + S7_ACK_HEADER;

function writeSetup(frame: Buffer, o: number, p: SetupParams): void {
  frame[o] = S7Function.Setup;
  frame[o + 1] = 0;
  frame.writeUInt16BE(p.maxAmqCalling & 0xffff, o + 2);
  frame.writeUInt16BE(p.maxAmqCalled & 0xffff, o + 4);
  frame.writeUInt16BE(p.pduSize & 0xffff, o + 6);
}

/** Setup communication job (docs/protocols.md, "Setup communication"). */
export function encodeSetupCommunication(pduRef: number, p: SetupParams): Buffer {
  const frame = s7Frame(Rosctr.Job, pduRef, 8, 0);
  writeSetup(frame, JOB_PARAMS, p);
  return frame;
}

/** Setup communication ack-data: the negotiated values, as the PLC answers. */
export function encodeSetupAck(pduRef: number, p: SetupParams): Buffer {
  const frame = s7Frame(Rosctr.AckData, pduRef, 8, 0);
  writeSetup(frame, ACK_PARAMS, p);
  return frame;
}

function writeItem(frame: Buffer, o: number, item: S7Item): void {
  frame[o] = 0x12; // variable specification
  frame[o + 1] = 0x0a; // length of the rest of the item
  frame[o + 2] = 0x10; // syntax id S7ANY
  frame[o + 3] = item.transportSize;
  frame.writeUInt16BE(item.count & 0xffff, o + 4);
  frame.writeUInt16BE(item.dbNumber & 0xffff, o + 6);
  frame[o + 8] = item.area;
  frame[o + 9] = (item.address >>> 16) & 0xff;
  frame[o + 10] = (item.address >>> 8) & 0xff;
  frame[o + 11] = item.address & 0xff;
}

/** Read Var job with many items, one Buffer. */
export function encodeReadRequest(pduRef: number, items: readonly S7Item[]): Buffer {
  checkCount(items.length);
  const frame = s7Frame(Rosctr.Job, pduRef, 2 + READ_ITEM * items.length, 0);
  frame[JOB_PARAMS] = S7Function.ReadVar;
  frame[JOB_PARAMS + 1] = items.length;
  for (let i = 0; i < items.length; i++) writeItem(frame, JOB_PARAMS + 2 + READ_ITEM * i, items[i]!);
  return frame;
}

/** Writes data items (return code/reserved, transport size, length, data, fill) from `p`. */
function writeDataItems(
  frame: Buffer,
  p: number,
  items: readonly { data: Buffer }[],
  code: (i: number) => number,
  size: (i: number) => number,
): void {
  const last = items.length - 1;
  for (let i = 0; i <= last; i++) {
    const data = items[i]!.data;
    const returnCode = code(i);
    const ts = returnCode === 0xff || returnCode === 0 ? size(i) : 0;
    frame[p] = returnCode;
    frame[p + 1] = ts;
    frame.writeUInt16BE(dataLengthField(ts, data.length), p + 2);
    data.copy(frame, p + 4);
    p += 4 + data.length;
    if (data.length & 1 && i < last) frame[p++] = 0;
  }
}

/** Write Var job with many items, one Buffer. BIT items carry one byte (0/1) with length 1 bit. */
export function encodeWriteRequest(pduRef: number, items: readonly S7WriteItem[]): Buffer {
  checkCount(items.length);
  const paramLength = 2 + READ_ITEM * items.length;
  const frame = s7Frame(Rosctr.Job, pduRef, paramLength, dataPartLength(items));
  frame[JOB_PARAMS] = S7Function.WriteVar;
  frame[JOB_PARAMS + 1] = items.length;
  for (let i = 0; i < items.length; i++) writeItem(frame, JOB_PARAMS + 2 + READ_ITEM * i, items[i]!);
  writeDataItems(
    frame,
    JOB_PARAMS + paramLength,
    items,
    () => 0,
    (i) => items[i]!.dataTransportSize,
  );
  return frame;
}

/** Read Var ack-data. A failed item (return code ≠ 0xFF) is sent as 4 bytes with size 0 and no data. */
export function encodeReadResponse(pduRef: number, items: readonly ReadResponseItem[]): Buffer {
  checkCount(items.length);
  const frame = s7Frame(Rosctr.AckData, pduRef, 2, dataPartLength(items));
  frame[ACK_PARAMS] = S7Function.ReadVar;
  frame[ACK_PARAMS + 1] = items.length;
  writeDataItems(
    frame,
    ACK_PARAMS + 2,
    items,
    (i) => items[i]!.returnCode,
    (i) => items[i]!.transportSize,
  );
  return frame;
}

/** Write Var ack-data: one return code per item. */
export function encodeWriteResponse(pduRef: number, returnCodes: readonly number[]): Buffer {
  checkCount(returnCodes.length);
  const frame = s7Frame(Rosctr.AckData, pduRef, 2, returnCodes.length);
  frame[ACK_PARAMS] = S7Function.WriteVar;
  frame[ACK_PARAMS + 1] = returnCodes.length;
  for (let i = 0; i < returnCodes.length; i++) frame[ACK_PARAMS + 2 + i] = returnCodes[i]!;
  return frame;
}

/**
 * A refused job: ack (ROSCTR 2) with the header error and no parameters, or,
 * with `func`, an ack-data echoing the function with 0 items (as S7-1200/1500
 * answer a Read/Write Var when PUT/GET is off).
 */
export function encodeErrorAck(pduRef: number, errorClass: number, errorCode: number, func?: number): Buffer {
  const withFunc = func !== undefined;
  const frame = s7Frame(withFunc ? Rosctr.AckData : Rosctr.Ack, pduRef, withFunc ? 2 : 0, 0);
  frame[17] = errorClass;
  frame[18] = errorCode;
  if (withFunc) {
    frame[ACK_PARAMS] = func;
    frame[ACK_PARAMS + 1] = 0;
  }
  return frame;
}

/** An ack without parameters refusing a whole job with a header error given as class << 8 | code (0x8104, 0x8500 …). */
export function encodeHeaderErrorAck(pduRef: number, error: number): Buffer {
  return encodeErrorAck(pduRef, error >> 8, error & 0xff);
}

function checkCount(n: number): void {
  if (n > 255) throw new ValueError('item count', `an S7 job carries at most 255 items, got ${n}`);
}

// ---------------------------------------------------------------- decoders

/**
 * Decodes one whole TPKT frame carrying a COTP DT with an S7 PDU: jobs (for
 * the simulator) and acks (for the client). Data are subarrays of `frame`.
 * Throws ProtocolError only, on anything malformed, truncated or inconsistent.
 */
export function decodeS7(frame: Buffer): S7Message {
  const cotp = decodeCotp(frame);
  if (cotp.type !== 'DT') throw new ProtocolError(`expected COTP data, got ${cotp.type}`);
  if (!cotp.last) throw new ProtocolError('fragmented COTP data (no EOT) is not used by S7 and not supported');
  const pdu = cotp.payload;
  if (pdu.length < S7_JOB_HEADER) throw new ProtocolError(`S7 PDU of ${pdu.length} bytes is too short`);
  if (pdu[0] !== S7_PROTOCOL_ID) throw new ProtocolError(`S7 protocol id 0x${pdu[0]!.toString(16)}, expected 0x32`);
  const rosctr = pdu[1]!;
  const pduRef = pdu.readUInt16BE(4);
  const paramLength = pdu.readUInt16BE(6);
  const dataLength = pdu.readUInt16BE(8);
  const ack = rosctr === Rosctr.Ack || rosctr === Rosctr.AckData;
  const header = ack ? S7_ACK_HEADER : S7_JOB_HEADER;
  if (pdu.length < header) throw new ProtocolError(`S7 ack of ${pdu.length} bytes is too short`);
  if (header + paramLength + dataLength !== pdu.length) {
    throw new ProtocolError(
      `S7 lengths (header ${header} + parameters ${paramLength} + data ${dataLength}) do not match the PDU (${pdu.length})`,
    );
  }
  const params = pdu.subarray(header, header + paramLength);
  const data = pdu.subarray(header + paramLength);
  const func = params.length > 0 ? params[0] : undefined;
  if (ack && (pdu[10] !== 0 || pdu[11] !== 0)) {
    const e = { kind: 'error' as const, pduRef, errorClass: pdu[10]!, errorCode: pdu[11]!, rosctr };
    return func === undefined ? e : { ...e, func };
  }
  if (rosctr === Rosctr.Job) {
    if (func === S7Function.Setup) return { kind: 'setup-request', pduRef, params: decodeSetup(params) };
    if (func === S7Function.ReadVar) {
      if (dataLength !== 0) throw new ProtocolError(`read request with ${dataLength} data bytes`);
      return { kind: 'read-request', pduRef, items: decodeItems(params) };
    }
    if (func === S7Function.WriteVar) {
      const items = decodeItems(params) as S7WriteItem[];
      const parts = decodeDataItems(data, items.length);
      for (let i = 0; i < items.length; i++) {
        items[i]!.dataTransportSize = parts[i]!.transportSize;
        items[i]!.data = parts[i]!.data;
      }
      return { kind: 'write-request', pduRef, items };
    }
  } else if (rosctr === Rosctr.AckData) {
    if (func === S7Function.Setup) return { kind: 'setup-ack', pduRef, params: decodeSetup(params) };
    if (func === S7Function.ReadVar) return { kind: 'read-ack', pduRef, items: decodeDataItems(data, itemCount(params), true) };
    if (func === S7Function.WriteVar) {
      const count = itemCount(params);
      if (data.length !== count) throw new ProtocolError(`write ack: ${count} items but ${data.length} return codes`);
      return { kind: 'write-ack', pduRef, returnCodes: Array.from(data) };
    }
  }
  return func === undefined ? { kind: 'other', pduRef, rosctr } : { kind: 'other', pduRef, rosctr, func };
}

/** Where the S7 header starts in a frame with the plain 3-byte COTP DT header (TPKT 4 + LI, code, EOT). */
const PLAIN_S7_AT = FRAME_OVERHEAD;

/** The ROSCTR of the S7 PDU in a frame with the plain 3-byte COTP DT header (header byte 1). */
export function s7Rosctr(frame: Buffer): number {
  return frame[PLAIN_S7_AT + 1]!;
}

/** The PDU reference of the S7 PDU in a frame with the plain 3-byte COTP DT header (header bytes 4–5). */
export function s7PduRef(frame: Buffer): number {
  return (frame[PLAIN_S7_AT + 4]! << 8) | frame[PLAIN_S7_AT + 5]!;
}

/** Sets the PDU reference of a frame with the plain 3-byte COTP DT header (a job is sent with its own). */
export function setPduRef(frame: Buffer, ref: number): void {
  frame[PLAIN_S7_AT + 4] = (ref >> 8) & 0xff;
  frame[PLAIN_S7_AT + 5] = ref & 0xff;
}

/** The item count of a Read/Write Var job (its second parameter byte). */
export function jobItemCount(frame: Buffer): number {
  return frame[JOB_PARAMS + 1]!;
}

/**
 * The PDU reference of a frame carrying the last (EOT) COTP DT with a
 * 3-byte header and an S7 PDU whose lengths add up, or −1 for any other
 * frame (decodeS7 then says what it is, or what is wrong with it). Makes no
 * objects: the client routes each answer to its job with it, and the job
 * decodes the rest.
 */
export function s7AnswerRef(frame: Buffer): number {
  const at = PLAIN_S7_AT;
  if (
    frame.length < at + S7_JOB_HEADER ||
    frame[4] !== COTP_DT_HEADER - 1 ||
    (frame[5]! & 0xf0) !== CotpType.DT ||
    (frame[6]! & 0x80) === 0
  )
    return -1;
  if (frame[0] !== TPKT_VERSION || ((frame[2]! << 8) | frame[3]!) !== frame.length || frame[at] !== S7_PROTOCOL_ID) return -1;
  const rosctr = frame[at + 1]!;
  const header = rosctr === Rosctr.Ack || rosctr === Rosctr.AckData ? S7_ACK_HEADER : S7_JOB_HEADER;
  if (frame.length < at + header) return -1;
  const paramLength = (frame[at + 6]! << 8) | frame[at + 7]!;
  const dataLength = (frame[at + 8]! << 8) | frame[at + 9]!;
  if (at + header + paramLength + dataLength !== frame.length) return -1;
  return (frame[at + 4]! << 8) | frame[at + 5]!;
}

/** Per item of a read: return code, where its data starts in the answer frame, and its length (filled by scanReadAck). */
export interface ReadItemTable {
  code: Uint8Array;
  start: Int32Array;
  length: Int32Array;
}

/**
 * The client's read hot path: when `frame` is a well-formed Read Var
 * ack-data of `count` items without a header error, fills `table` at
 * base … base + count − 1 (data offsets are into `frame`) and returns true.
 * Returns false for any other frame, well-formed or not: decodeS7 then
 * decodes it or throws the ProtocolError. Accepts exactly what decodeS7
 * accepts for a read ack, without making an object or a subarray per item.
 */
export function scanReadAck(frame: Buffer, count: number, table: ReadItemTable, base: number): boolean {
  const at = PLAIN_S7_AT;
  if (s7AnswerRef(frame) < 0 || frame[at + 1] !== Rosctr.AckData) return false;
  const params = at + S7_ACK_HEADER;
  if (frame[at + 10] !== 0 || frame[at + 11] !== 0 || ((frame[at + 6]! << 8) | frame[at + 7]!) !== 2) return false;
  if (frame[params] !== S7Function.ReadVar || frame[params + 1] !== count) return false;
  const end = frame.length;
  let p = params + 2;
  for (let i = 0; i < count; i++) {
    if (p + 4 > end) return false;
    const code = frame[p]!;
    const len = code !== 0xff ? 0 : dataLengthBytes(frame[p + 1]!, (frame[p + 2]! << 8) | frame[p + 3]!);
    if (p + 4 + len > end) return false;
    table.code[base + i] = code;
    table.start[base + i] = p + 4;
    table.length[base + i] = len;
    p += 4 + len;
    if (len & 1 && i < count - 1) p++;
  }
  return end - p <= 1;
}

function itemCount(params: Buffer): number {
  if (params.length !== 2) throw new ProtocolError(`ack parameters of ${params.length} bytes, expected 2`);
  return params[1]!;
}

function decodeSetup(params: Buffer): SetupParams {
  if (params.length !== 8) throw new ProtocolError(`setup communication parameters of ${params.length} bytes, expected 8`);
  return { maxAmqCalling: params.readUInt16BE(2), maxAmqCalled: params.readUInt16BE(4), pduSize: params.readUInt16BE(6) };
}

function decodeItems(params: Buffer): S7Item[] {
  if (params.length < 2) throw new ProtocolError('request parameters too short');
  const count = params[1]!;
  if (params.length !== 2 + READ_ITEM * count)
    throw new ProtocolError(`${count} items need ${2 + READ_ITEM * count} parameter bytes, got ${params.length}`);
  const items: S7Item[] = new Array<S7Item>(count);
  for (let i = 0; i < count; i++) {
    const o = 2 + READ_ITEM * i;
    if (params[o] !== 0x12 || params[o + 1] !== 0x0a || params[o + 2] !== 0x10) {
      throw new ProtocolError(`item ${i + 1}: not an S7ANY address (12 0A 10)`);
    }
    items[i] = {
      area: params[o + 8]!,
      dbNumber: params.readUInt16BE(o + 6),
      transportSize: params[o + 3]!,
      count: params.readUInt16BE(o + 4),
      address: (params[o + 9]! << 16) | (params[o + 10]! << 8) | params[o + 11]!,
    };
  }
  return items;
}

/**
 * `answer`: items of a read answer. A failed item there carries no data,
 * whatever its length field says: CPUs send length 0, snap7's server sends
 * `05 00 00 04` and no bytes (its S7 data length counts 4 bytes for the item).
 */
function decodeDataItems(data: Buffer, count: number, answer = false): ReadResponseItem[] {
  const items: ReadResponseItem[] = new Array<ReadResponseItem>(count);
  let p = 0;
  for (let i = 0; i < count; i++) {
    if (p + 4 > data.length) throw new ProtocolError(`data item ${i + 1} of ${count} is missing`);
    const returnCode = data[p]!;
    const transportSize = data[p + 1]!;
    const len = answer && returnCode !== 0xff ? 0 : dataLengthBytes(transportSize, (data[p + 2]! << 8) | data[p + 3]!);
    if (p + 4 + len > data.length) throw new ProtocolError(`data item ${i + 1}: ${len} bytes announced, ${data.length - p - 4} present`);
    items[i] = { returnCode, transportSize, data: data.subarray(p + 4, p + 4 + len) };
    p += 4 + len;
    if (len & 1 && i < count - 1) p++;
  }
  // Some peers pad the last odd item too; more than that is not S7.
  if (data.length - p > 1) throw new ProtocolError(`${data.length - p} stray bytes after the data items`);
  return items;
}
