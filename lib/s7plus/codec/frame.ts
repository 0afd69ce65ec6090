/**
 * S7CommPlus framing. A message travels as one or more PDUs, each
 * `72 <version> <length:2> <data>`, and ends with the trailer
 * `72 <version> 00 00` after its last PDU; a message longer than a PDU is cut
 * into several and only the last is followed by the trailer. SystemEvent
 * frames (version 0xFE) carry no trailer and may come between the PDUs of
 * another message. Source: s7commplus (MIT), codec.py encode_header,
 * server.py send_app_frame and connection.py _recv_reassembled_payload.
 *
 * The reader takes bytes as they come (TLS records and TCP segments cut
 * anywhere) and returns whole messages; it throws only ProtocolError.
 */
import { ProtocolError } from '../../errors';
import { ProtocolVersion, S7P_PROTOCOL_ID } from '../constants';

export const FRAME_HEADER = 4;
/** The most data one PDU can announce. */
export const MAX_PDU_DATA = 0xffff;

/** One message: its frame version and the data of its PDUs joined. */
export interface S7pMessage {
  version: number;
  data: Buffer;
}

/**
 * The frames of one message: `data` cut into PDUs of at most `maxPdu` bytes,
 * the trailer after the last. A SystemEvent is one frame, without trailer.
 */
export function encodeFrames(version: number, data: Buffer, maxPdu = MAX_PDU_DATA): Buffer {
  if (!Number.isInteger(maxPdu) || maxPdu < 1 || maxPdu > MAX_PDU_DATA) throw new RangeError(`S7CommPlus: PDU size ${maxPdu} out of range`);
  // An empty PDU would read as a trailer.
  if (data.length === 0) throw new RangeError('S7CommPlus: a message has at least one byte');
  if (version === ProtocolVersion.SystemEvent && data.length > MAX_PDU_DATA) throw new RangeError('S7CommPlus: SystemEvent too long');
  const parts: Buffer[] = [];
  for (let at = 0; at < data.length; at += maxPdu) {
    const piece = data.subarray(at, at + maxPdu);
    parts.push(Buffer.of(S7P_PROTOCOL_ID, version, piece.length >> 8, piece.length & 0xff), piece);
  }
  if (version !== ProtocolVersion.SystemEvent) parts.push(Buffer.of(S7P_PROTOCOL_ID, version, 0, 0));
  return Buffer.concat(parts);
}

export interface FrameReaderLimits {
  /** The largest message accepted (bytes of data, all PDUs). Default 16 MiB. */
  maxMessage?: number;
  /** The most PDUs one message may take. Default 4096. */
  maxPdus?: number;
}

const EMPTY = Buffer.alloc(0);

/** Joins PDUs into messages; bytes may arrive cut anywhere. */
export class S7pFrameReader {
  private pending: Buffer = EMPTY;
  private parts: Buffer[] = [];
  private size = 0;
  private version = -1;
  private readonly maxMessage: number;
  private readonly maxPdus: number;

  constructor(limits: FrameReaderLimits = {}) {
    this.maxMessage = limits.maxMessage ?? 16 * 1024 * 1024;
    this.maxPdus = limits.maxPdus ?? 4096;
  }

  /** Bytes held: buffered input and the PDUs of an unfinished message. */
  get buffered(): number {
    return this.pending.length + this.size;
  }

  private fail(message: string): never {
    this.pending = EMPTY;
    this.parts = [];
    this.size = 0;
    this.version = -1;
    throw new ProtocolError(`S7CommPlus: ${message}`);
  }

  push(chunk: Buffer): S7pMessage[] {
    let buf = this.pending.length === 0 ? chunk : Buffer.concat([this.pending, chunk]);
    const out: S7pMessage[] = [];
    while (buf.length >= FRAME_HEADER) {
      if (buf[0] !== S7P_PROTOCOL_ID) this.fail(`frame starts with 0x${buf[0]!.toString(16).padStart(2, '0')}, not 0x72`);
      const version = buf[1]!;
      const length = buf.readUInt16BE(2);
      if (version === ProtocolVersion.SystemEvent) {
        if (buf.length < FRAME_HEADER + length) break;
        out.push({ version, data: Buffer.from(buf.subarray(FRAME_HEADER, FRAME_HEADER + length)) });
        buf = buf.subarray(FRAME_HEADER + length);
        continue;
      }
      if (this.version !== -1 && version !== this.version)
        this.fail(`frame version changed from ${this.version} to ${version} inside a message`);
      if (length === 0) {
        if (this.parts.length === 0) this.fail(`trailer (72 ${version.toString(16).padStart(2, '0')} 00 00) without a frame before it`);
        out.push({ version, data: this.parts.length === 1 ? this.parts[0]! : Buffer.concat(this.parts, this.size) });
        this.parts = [];
        this.size = 0;
        this.version = -1;
        buf = buf.subarray(FRAME_HEADER);
        continue;
      }
      if (this.size + length > this.maxMessage) this.fail(`message longer than ${this.maxMessage} bytes`);
      if (this.parts.length >= this.maxPdus) this.fail(`message of more than ${this.maxPdus} PDUs`);
      if (buf.length < FRAME_HEADER + length) break;
      this.parts.push(Buffer.from(buf.subarray(FRAME_HEADER, FRAME_HEADER + length)));
      this.size += length;
      this.version = version;
      buf = buf.subarray(FRAME_HEADER + length);
    }
    this.pending = buf.length === 0 ? EMPTY : Buffer.from(buf);
    return out;
  }
}
