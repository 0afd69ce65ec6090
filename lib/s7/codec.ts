/**
 * S7comm codec: pure functions over Buffers. Encoders produce whole frames
 * (TPKT + COTP + S7) in one Buffer; decoders take one whole TPKT frame and
 * throw only ProtocolError on malformed, truncated or hostile input.
 */
import { ProtocolError } from '../errors';
import type { FrameCheck } from '../link/framer';
import {
  COTP_DT_HEADER,
  CotpParam,
  CotpType,
  FRAME_OVERHEAD,
  Rosctr,
  S7Function,
  S7_PROTOCOL_ID,
  TPKT_HEADER,
  TPKT_VERSION,
  lengthInBits,
} from './constants';

// ---------------------------------------------------------------- TPKT

/** Cuts TPKT frames for FrameReader: version 3, length 7..65535 (a COTP header at least). */
export function checkTpkt(buf: Buffer): FrameCheck {
  if (buf.length < TPKT_HEADER) return buf.length > 0 && buf[0] !== TPKT_VERSION ? bad(`TPKT version ${buf[0]}, expected 3`) : { kind: 'need' };
  if (buf[0] !== TPKT_VERSION) return bad(`TPKT version ${buf[0]}, expected 3`);
  const length = buf.readUInt16BE(2);
  if (length < TPKT_HEADER + 3) return bad(`TPKT length ${length} is shorter than a COTP header`);
  return buf.length >= length ? { kind: 'frame', length } : { kind: 'need' };
}

function bad(message: string): FrameCheck {
  return { kind: 'bad', error: new ProtocolError(message) };
}

function tpkt(payloadLength: number): Buffer {
  const frame = Buffer.allocUnsafe(TPKT_HEADER + payloadLength);
  frame[0] = TPKT_VERSION;
  frame[1] = 0;
  frame.writeUInt16BE(frame.length, 2);
  return frame;
}

// ---------------------------------------------------------------- COTP

export interface CotpConnection {
  /** Source reference of the sender. */
  sourceRef: number;
  destinationRef: number;
  callingTsap: number;
  calledTsap: number;
  /** TPDU size code (0x0A = 1024 bytes). */
  tpduSize: number;
}

function encodeCotpConnection(type: CotpType, c: CotpConnection, order: 'tsap-first' | 'size-first'): Buffer {
  const params =
    order === 'tsap-first'
      ? [CotpParam.CallingTsap, 2, c.callingTsap >> 8, c.callingTsap & 0xff, CotpParam.CalledTsap, 2, c.calledTsap >> 8, c.calledTsap & 0xff, CotpParam.TpduSize, 1, c.tpduSize]
      : [CotpParam.TpduSize, 1, c.tpduSize, CotpParam.CallingTsap, 2, c.callingTsap >> 8, c.callingTsap & 0xff, CotpParam.CalledTsap, 2, c.calledTsap >> 8, c.calledTsap & 0xff];
  const frame = tpkt(7 + params.length);
  frame[4] = 6 + params.length; // length indicator: the header after this byte
  frame[5] = type;
  frame.writeUInt16BE(c.destinationRef, 6);
  frame.writeUInt16BE(c.sourceRef, 8);
  frame[10] = 0; // class 0
  for (let i = 0; i < params.length; i++) frame[11 + i] = params[i]!;
  return frame;
}

/** COTP Connection Request (the document's first handshake frame). */
export function encodeConnectionRequest(c: Omit<CotpConnection, 'destinationRef'>): Buffer {
  return encodeCotpConnection(CotpType.CR, { ...c, destinationRef: 0 }, 'tsap-first');
}

/** COTP Connection Confirm, as an S7 CPU sends it (TPDU size first). */
export function encodeConnectionConfirm(c: CotpConnection): Buffer {
  return encodeCotpConnection(CotpType.CC, c, 'size-first');
}

/** COTP Disconnect Request with a reason (e.g. 0x80 normal, 0x85? see ISO 8073). */
export function encodeDisconnectRequest(destinationRef: number, sourceRef: number, reason = 0x00): Buffer {
  const frame = tpkt(7);
  frame[4] = 6;
  frame[5] = CotpType.DR;
  frame.writeUInt16BE(destinationRef, 6);
  frame.writeUInt16BE(sourceRef, 8);
  frame[10] = reason;
  return frame;
}

export type CotpMessage =
  | ({ type: 'CR' | 'CC' } & CotpConnection)
  | { type: 'DR' | 'DC'; destinationRef: number; sourceRef: number; reason: number }
  | { type: 'DT'; last: boolean; payload: Buffer }
  | { type: 'ER'; destinationRef: number; cause: number };

/** Decodes the COTP part of one TPKT frame. */
export function decodeCotp(frame: Buffer): CotpMessage {
  if (frame.length < TPKT_HEADER + 2) throw new ProtocolError(`COTP: frame of ${frame.length} bytes is too short`);
  if (frame[0] !== TPKT_VERSION || frame.readUInt16BE(2) !== frame.length) throw new ProtocolError('COTP: not one whole TPKT frame');
  const li = frame[4]!;
  if (TPKT_HEADER + 1 + li > frame.length) throw new ProtocolError(`COTP: length indicator ${li} runs past the frame`);
  const type = frame[5]! & 0xf0;
  if (type === CotpType.DT) {
    if (li < 2) throw new ProtocolError('COTP DT: header too short');
    return { type: 'DT', last: (frame[6]! & 0x80) !== 0, payload: frame.subarray(TPKT_HEADER + 1 + li) };
  }
  if (li < 6) throw new ProtocolError(`COTP 0x${type.toString(16)}: header too short`);
  const destinationRef = frame.readUInt16BE(6);
  const sourceRef = frame.readUInt16BE(8);
  if (type === CotpType.CR || type === CotpType.CC) {
    const c: CotpConnection = { sourceRef, destinationRef, callingTsap: -1, calledTsap: -1, tpduSize: 0 };
    let p = 11;
    const end = TPKT_HEADER + 1 + li;
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
  if (type === CotpType.DR || type === CotpType.DC) {
    return { type: type === CotpType.DR ? 'DR' : 'DC', destinationRef, sourceRef, reason: li >= 6 && frame.length > 10 ? frame[10]! : 0 };
  }
  if (type === CotpType.ER) return { type: 'ER', destinationRef, cause: frame.length > 8 ? frame[8]! : 0 };
  throw new ProtocolError(`COTP: unexpected TPDU type 0x${type.toString(16)}`);
}

// ---------------------------------------------------------------- S7 PDUs

export interface S7Item {
  /** S7Area code. */
  area: number;
  dbNumber: number;
  /** TransportSize code of the request item. */
  transportSize: number;
  /** Elements of transportSize. */
  count: number;
  /** Bit address: byte offset × 8 + bit (for C/T: the number). */
  address: number;
}

export interface S7WriteItem extends S7Item {
  /** DataTransportSize code of the data part. */
  dataTransportSize: number;
  data: Buffer;
}

export interface SetupParams {
  maxAmqCalling: number;
  maxAmqCalled: number;
  pduSize: number;
}

/** Starts a frame: TPKT, COTP DT (last), S7 header. Returns the buffer; the caller fills from `offset`. */
function s7Frame(rosctr: Rosctr, pduRef: number, paramLength: number, dataLength: number, errorBytes: boolean): { frame: Buffer; offset: number } {
  const header = errorBytes ? 12 : 10;
  const frame = tpkt(COTP_DT_HEADER + header + paramLength + dataLength);
  frame[4] = 2;
  frame[5] = CotpType.DT;
  frame[6] = 0x80;
  frame[7] = S7_PROTOCOL_ID;
  frame[8] = rosctr;
  frame.writeUInt16BE(0, 9);
  frame.writeUInt16BE(pduRef & 0xffff, 11);
  frame.writeUInt16BE(paramLength, 13);
  frame.writeUInt16BE(dataLength, 15);
  if (errorBytes) frame.writeUInt16BE(0, 17);
  return { frame, offset: FRAME_OVERHEAD + header };
}

/** Setup communication job (the document's second handshake frame). */
export function encodeSetupCommunication(pduRef: number, p: SetupParams): Buffer {
  const { frame, offset } = s7Frame(Rosctr.Job, pduRef, 8, 0, false);
  writeSetup(frame, offset, p);
  return frame;
}

/** Setup communication ack-data (what the PLC answers). */
export function encodeSetupAck(pduRef: number, p: SetupParams): Buffer {
  const { frame, offset } = s7Frame(Rosctr.AckData, pduRef, 8, 0, true);
  writeSetup(frame, offset, p);
  return frame;
}

function writeSetup(frame: Buffer, o: number, p: SetupParams): void {
  frame[o] = S7Function.Setup;
  frame[o + 1] = 0;
  frame.writeUInt16BE(p.maxAmqCalling, o + 2);
  frame.writeUInt16BE(p.maxAmqCalled, o + 4);
  frame.writeUInt16BE(p.pduSize, o + 6);
}

function writeItem(frame: Buffer, o: number, item: S7Item): void {
  frame[o] = 0x12;
  frame[o + 1] = 0x0a;
  frame[o + 2] = 0x10;
  frame[o + 3] = item.transportSize;
  frame.writeUInt16BE(item.count, o + 4);
  frame.writeUInt16BE(item.dbNumber, o + 6);
  frame[o + 8] = item.area;
  frame[o + 9] = (item.address >> 16) & 0xff;
  frame.writeUInt16BE(item.address & 0xffff, o + 10);
}

/** Read Var job with many items, in one Buffer. */
export function encodeReadRequest(pduRef: number, items: readonly S7Item[]): Buffer {
  const { frame, offset } = s7Frame(Rosctr.Job, pduRef, 2 + 12 * items.length, 0, false);
  frame[offset] = S7Function.ReadVar;
  frame[offset + 1] = items.length;
  for (let i = 0; i < items.length; i++) writeItem(frame, offset + 2 + 12 * i, items[i]!);
  return frame;
}

/** Bytes of the data part of items: 4-byte header + data, a fill byte after odd-length data except the last. */
function dataPartLength(lengths: readonly number[]): number {
  let n = 0;
  for (let i = 0; i < lengths.length; i++) {
    n += 4 + lengths[i]!;
    if (lengths[i]! % 2 === 1 && i < lengths.length - 1) n++;
  }
  return n;
}

/** Write Var job with many items, in one Buffer. */
export function encodeWriteRequest(pduRef: number, items: readonly S7WriteItem[]): Buffer {
  const dataLength = dataPartLength(items.map((i) => i.data.length));
  const { frame, offset } = s7Frame(Rosctr.Job, pduRef, 2 + 12 * items.length, dataLength, false);
  frame[offset] = S7Function.WriteVar;
  frame[offset + 1] = items.length;
  for (let i = 0; i < items.length; i++) writeItem(frame, offset + 2 + 12 * i, items[i]!);
  let p = offset + 2 + 12 * items.length;
  for (let i = 0; i < items.length; i++) {
    const item = items[i]!;
    frame[p] = 0;
    frame[p + 1] = item.dataTransportSize;
    frame.writeUInt16BE(lengthInBits(item.dataTransportSize) ? item.data.length * 8 : item.data.length, p + 2);
    if (item.dataTransportSize === 0x03) frame.writeUInt16BE(1, p + 2); // one bit
    item.data.copy(frame, p + 4);
    p += 4 + item.data.length;
    if (item.data.length % 2 === 1 && i < items.length - 1) frame[p++] = 0;
  }
  return frame;
}

export interface ReadResponseItem {
  returnCode: number;
  /** DataTransportSize code (0x04 bytes in bits, 0x09 octets, 0x03 bit …). */
  transportSize: number;
  data: Buffer;
}

/** Read Var ack-data (what the PLC answers). */
export function encodeReadResponse(pduRef: number, items: readonly ReadResponseItem[]): Buffer {
  const dataLength = dataPartLength(items.map((i) => i.data.length));
  const { frame, offset } = s7Frame(Rosctr.AckData, pduRef, 2, dataLength, true);
  frame[offset] = S7Function.ReadVar;
  frame[offset + 1] = items.length;
  let p = offset + 2;
  for (let i = 0; i < items.length; i++) {
    const item = items[i]!;
    frame[p] = item.returnCode;
    frame[p + 1] = item.returnCode === 0xff ? item.transportSize : 0;
    const len = item.data.length;
    frame.writeUInt16BE(item.returnCode !== 0xff ? 0 : item.transportSize === 0x03 ? len : lengthInBits(item.transportSize) ? len * 8 : len, p + 2);
    item.data.copy(frame, p + 4);
    p += 4 + len;
    if (len % 2 === 1 && i < items.length - 1) frame[p++] = 0;
  }
  return frame;
}

/** Write Var ack-data: one return code per item. */
export function encodeWriteResponse(pduRef: number, returnCodes: readonly number[]): Buffer {
  const { frame, offset } = s7Frame(Rosctr.AckData, pduRef, 2, returnCodes.length, true);
  frame[offset] = S7Function.WriteVar;
  frame[offset + 1] = returnCodes.length;
  for (let i = 0; i < returnCodes.length; i++) frame[offset + 2 + i] = returnCodes[i]!;
  return frame;
}

/** An ack (ROSCTR 2) with a header error and no parameters: how a CPU refuses a job. */
export function encodeErrorAck(pduRef: number, errorClass: number, errorCode: number): Buffer {
  const { frame } = s7Frame(Rosctr.Ack, pduRef, 0, 0, true);
  frame[17] = errorClass;
  frame[18] = errorCode;
  return frame;
}

export type S7Message =
  | { kind: 'setup-request'; pduRef: number; params: SetupParams }
  | { kind: 'read-request'; pduRef: number; items: S7Item[] }
  | { kind: 'write-request'; pduRef: number; items: S7WriteItem[] }
  | { kind: 'setup-ack'; pduRef: number; params: SetupParams }
  | { kind: 'read-ack'; pduRef: number; items: ReadResponseItem[] }
  | { kind: 'write-ack'; pduRef: number; returnCodes: number[] }
  | { kind: 'error'; pduRef: number; errorClass: number; errorCode: number; rosctr: number; func?: number }
  | { kind: 'other'; pduRef: number; rosctr: number; func?: number };

/**
 * Decodes one whole TPKT frame carrying a COTP DT with an S7 PDU. Data in
 * the result are subarrays of `frame` (no copies). Throws ProtocolError only.
 */
export function decodeS7(frame: Buffer): S7Message {
  const cotp = decodeCotp(frame);
  if (cotp.type !== 'DT') throw new ProtocolError(`expected COTP data, got ${cotp.type}`);
  const pdu = cotp.payload;
  if (pdu.length < 10) throw new ProtocolError(`S7 PDU of ${pdu.length} bytes is too short`);
  if (pdu[0] !== S7_PROTOCOL_ID) throw new ProtocolError(`S7 protocol id 0x${pdu[0]!.toString(16)}, expected 0x32`);
  const rosctr = pdu[1]!;
  const pduRef = pdu.readUInt16BE(4);
  const paramLength = pdu.readUInt16BE(6);
  const dataLength = pdu.readUInt16BE(8);
  const withError = rosctr === Rosctr.Ack || rosctr === Rosctr.AckData;
  const header = withError ? 12 : 10;
  if (pdu.length < header) throw new ProtocolError(`S7 ack of ${pdu.length} bytes is too short`);
  if (header + paramLength + dataLength !== pdu.length) {
    throw new ProtocolError(`S7 lengths (header ${header} + parameters ${paramLength} + data ${dataLength}) do not match the PDU (${pdu.length})`);
  }
  const params = pdu.subarray(header, header + paramLength);
  const data = pdu.subarray(header + paramLength);
  const func = params.length > 0 ? params[0] : undefined;
  if (withError) {
    const errorClass = pdu[10]!;
    const errorCode = pdu[11]!;
    if (errorClass !== 0 || errorCode !== 0) return { kind: 'error', pduRef, errorClass, errorCode, rosctr, ...(func === undefined ? {} : { func }) };
  }
  if (rosctr === Rosctr.Job) {
    if (func === S7Function.Setup) return { kind: 'setup-request', pduRef, params: decodeSetup(params) };
    if (func === S7Function.ReadVar) return { kind: 'read-request', pduRef, items: decodeItems(params) };
    if (func === S7Function.WriteVar) {
      const items = decodeItems(params);
      const parts = decodeDataItems(data, items.length);
      return {
        kind: 'write-request',
        pduRef,
        items: items.map((item, i) => ({ ...item, dataTransportSize: parts[i]!.transportSize, data: parts[i]!.data })),
      };
    }
  } else if (rosctr === Rosctr.AckData) {
    if (func === S7Function.Setup) return { kind: 'setup-ack', pduRef, params: decodeSetup(params) };
    if (func === S7Function.ReadVar) {
      const count = itemCount(params);
      return { kind: 'read-ack', pduRef, items: decodeDataItems(data, count) };
    }
    if (func === S7Function.WriteVar) {
      const count = itemCount(params);
      if (data.length !== count) throw new ProtocolError(`write ack: ${count} items but ${data.length} return codes`);
      return { kind: 'write-ack', pduRef, returnCodes: [...data] };
    }
  }
  return { kind: 'other', pduRef, rosctr, ...(func === undefined ? {} : { func }) };
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
  if (params.length !== 2 + 12 * count) throw new ProtocolError(`${count} items need ${2 + 12 * count} parameter bytes, got ${params.length}`);
  const items: S7Item[] = [];
  for (let i = 0; i < count; i++) {
    const o = 2 + 12 * i;
    if (params[o] !== 0x12 || params[o + 1] !== 0x0a || params[o + 2] !== 0x10) {
      throw new ProtocolError(`item ${i + 1}: not an S7ANY address (12 0A 10)`);
    }
    items.push({
      transportSize: params[o + 3]!,
      count: params.readUInt16BE(o + 4),
      dbNumber: params.readUInt16BE(o + 6),
      area: params[o + 8]!,
      address: (params[o + 9]! << 16) | params.readUInt16BE(o + 10),
    });
  }
  return items;
}

function decodeDataItems(data: Buffer, count: number): ReadResponseItem[] {
  const items: ReadResponseItem[] = [];
  let p = 0;
  for (let i = 0; i < count; i++) {
    if (p + 4 > data.length) throw new ProtocolError(`data item ${i + 1} of ${count} is missing`);
    const returnCode = data[p]!;
    const transportSize = data[p + 1]!;
    const raw = data.readUInt16BE(p + 2);
    const len = transportSize === 0x03 ? raw : lengthInBits(transportSize) ? Math.ceil(raw / 8) : raw;
    if (p + 4 + len > data.length) throw new ProtocolError(`data item ${i + 1}: ${len} bytes announced, ${data.length - p - 4} present`);
    items.push({ returnCode, transportSize, data: data.subarray(p + 4, p + 4 + len) });
    p += 4 + len;
    if (len % 2 === 1 && i < count - 1) p++;
  }
  // Some peers pad the last item too; more than one byte left over is not S7.
  if (data.length - p > 1) throw new ProtocolError(`${data.length - p} stray bytes after the data items`);
  return items;
}
