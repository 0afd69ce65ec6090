/**
 * Reading S7comm PDUs (pdu.ts writes them): decodeS7 for one whole frame,
 * and the raw readers the hot paths use without decoding a frame (its
 * ROSCTR, PDU reference, item count; a Read Var ack checked and scanned in
 * place). Take one whole TPKT frame, return subarrays of it, throw only
 * ProtocolError (the raw readers answer -1 or false instead).
 */
import { ProtocolError } from '../../errors';
import { READ_ITEM, Rosctr, S7Function, S7_ACK_HEADER, S7_JOB_HEADER, S7_PROTOCOL_ID } from '../constants';
import { COTP_DT_HEADER, CotpType, FRAME_OVERHEAD, TPKT_VERSION } from '../../iso/constants';
import { decodeCotp } from '../../iso/cotp';
import { dataLengthBytes, type ReadResponseItem, type S7Item, type S7Message, type S7WriteItem, type SetupParams } from './pdu';

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
/** Where a job's parameters start in a frame. */
const JOB_PARAMS = FRAME_OVERHEAD + S7_JOB_HEADER;

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
