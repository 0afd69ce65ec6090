/**
 * S7comm PDUs inside COTP DT: setup communication, Read Var, Write Var and
 * their acks. Encoders build the whole frame (TPKT + COTP DT + S7) in one
 * Buffer. The decoders, which take one whole TPKT frame, return subarrays
 * of it and throw only ProtocolError, are in pdu-decode.ts.
 */
import { ValueError } from '../../errors';
import { DataTransportSize, READ_ITEM, Rosctr, S7Function, S7_ACK_HEADER, S7_JOB_HEADER, S7_PROTOCOL_ID } from '../constants';
import { COTP_DT_HEADER, CotpType, FRAME_OVERHEAD } from '../../iso/constants';
import { tpktFrame } from '../../iso/tpkt';

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
