/**
 * The frames a session sends and the messages it receives, pure: the frame
 * header (0x72, version, length) and its end marker, the request header
 * with the sequence number and the IntegrityId spliced in as the PLC
 * expects it, and the cutter that reassembles a response the PLC split
 * over several PDUs. Layouts from s7commplus (MIT), connection.py
 * (_send_request, _frame_request, _recv_reassembled_payload) and codec.py
 * (encode_header, decode_header); the VLQ from vlq.py (encode_uint32_vlq).
 */
import { ProtocolError } from '../../errors';
import { Opcode, PROTOCOL_ID, REQUEST_HEADER, RESPONSE_HEADER, Version } from './ids';

/** An unsigned 32-bit VLQ: 7 bits a byte, most significant group first, the high bit on every byte but the last. */
export function vlqU32(value: number): Buffer {
  const groups: number[] = [value & 0x7f];
  for (let v = Math.floor(value / 128); v > 0; v = Math.floor(v / 128)) groups.unshift((v & 0x7f) | 0x80);
  return Buffer.from(groups);
}

/** Reads an unsigned 32-bit VLQ at `offset`: its value and the bytes it took; a ProtocolError past the end or beyond 5 bytes. */
export function readVlqU32(buf: Buffer, offset: number): { value: number; length: number } {
  let value = 0;
  for (let i = 0; i < 5; i++) {
    const b = buf[offset + i];
    if (b === undefined) throw new ProtocolError('S7CommPlus: a number runs past the end of the answer');
    value = value * 128 + (b & 0x7f);
    if ((b & 0x80) === 0) {
      if (value > 0xffffffff) throw new ProtocolError('S7CommPlus: a 32-bit number is out of range');
      return { value, length: i + 1 };
    }
  }
  throw new ProtocolError('S7CommPlus: a 32-bit number is longer than 5 bytes');
}

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
  const head = Buffer.alloc(4 + REQUEST_HEADER);
  head[0] = PROTOCOL_ID;
  head[1] = r.version;
  head[4] = Opcode.REQUEST;
  head.writeUInt16BE(r.fn, 7);
  head.writeUInt16BE(r.seq, 11);
  head.writeUInt32BE(r.sessionId >>> 0, 13);
  head[17] = r.flags;
  let body: Buffer[] = [r.payload];
  if (r.integrityId !== undefined) {
    const id = vlqU32(r.integrityId);
    const tail = r.integrityTail ?? 4;
    body =
      r.payload.length >= tail
        ? [r.payload.subarray(0, r.payload.length - tail), id, r.payload.subarray(r.payload.length - tail)]
        : [id, r.payload];
  }
  const length = REQUEST_HEADER + body.reduce((n, b) => n + b.length, 0);
  if (length > 0xffff) throw new ProtocolError(`S7CommPlus: a request of ${length} bytes does not fit one frame`);
  head.writeUInt16BE(length, 2);
  return Buffer.concat([head, ...body, endMarker(r.version)]);
}

/** The header of length 0 that ends a message. */
function endMarker(version: number): Buffer {
  return Buffer.from([PROTOCOL_ID, version, 0, 0]);
}

/** A message from the PLC: the data of its PDUs joined, and the version of its frames. */
export interface Message {
  version: number;
  data: Buffer;
}

/** The most a reassembled message may hold (a whole Explore of a large program stays far below). */
const MAX_MESSAGE = 16 * 1024 * 1024;

/**
 * Cuts a byte stream into messages: PDUs (0x72, version, length, data) whose
 * data are joined until the end marker (length 0). A SystemEvent (version
 * 0xFE) is a message of its own, wherever it comes. Anything else (a wrong
 * protocol id, a version change inside a message, a message past 16 MiB)
 * is a ProtocolError: the stream is lost.
 */
export class MessageCutter {
  private pending: Buffer = Buffer.alloc(0);
  private parts: Buffer[] = [];
  private partsLength = 0;
  private partsVersion = -1;

  /** Feeds a chunk; returns the messages it completed. */
  push(chunk: Buffer): Message[] {
    this.pending = this.pending.length === 0 ? chunk : Buffer.concat([this.pending, chunk]);
    const out: Message[] = [];
    let at = 0;
    while (this.pending.length - at >= 4) {
      if (this.pending[at] !== PROTOCOL_ID) {
        throw new ProtocolError(`S7CommPlus: a frame starts with 0x${this.pending[at]!.toString(16).padStart(2, '0')}, not 0x72`);
      }
      const version = this.pending[at + 1]!;
      const length = this.pending.readUInt16BE(at + 2);
      if (this.pending.length - at < 4 + length) break;
      const data = this.pending.subarray(at + 4, at + 4 + length);
      at += 4 + length;
      if (version === Version.SYSTEM_EVENT) {
        out.push({ version, data: Buffer.from(data) });
        continue;
      }
      if (this.partsVersion !== -1 && version !== this.partsVersion) {
        throw new ProtocolError(`S7CommPlus: the frame version changed from ${this.partsVersion} to ${version} inside one message`);
      }
      if (length === 0) {
        if (this.partsVersion === -1) continue; // an end marker with nothing before it ends nothing
        out.push({ version, data: this.parts.length === 1 ? this.parts[0]! : Buffer.concat(this.parts) });
        this.parts = [];
        this.partsLength = 0;
        this.partsVersion = -1;
        continue;
      }
      this.partsVersion = version;
      this.parts.push(Buffer.from(data));
      this.partsLength += length;
      if (this.partsLength > MAX_MESSAGE) throw new ProtocolError(`S7CommPlus: a message grew past ${MAX_MESSAGE} bytes`);
    }
    this.pending = at === this.pending.length ? Buffer.alloc(0) : Buffer.from(this.pending.subarray(at));
    return out;
  }
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
