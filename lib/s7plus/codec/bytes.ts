/**
 * A cursor over a received buffer and a growing output buffer, for the
 * S7CommPlus codec. The reader throws only ProtocolError, naming what it was
 * reading and where.
 */
import { ProtocolError } from '../../errors';
import {
  decodeSVlq32,
  decodeSVlq64,
  decodeUVlq32,
  decodeUVlq64,
  encodeSVlq32,
  encodeSVlq64,
  encodeUVlq64,
  uvlq32Length,
  writeUVlq32,
} from './vlq';

export class Reader {
  offset: number;

  constructor(
    readonly buf: Buffer,
    offset = 0,
    readonly end = buf.length,
  ) {
    this.offset = offset;
  }

  get remaining(): number {
    return this.end - this.offset;
  }

  private need(n: number, what: string): void {
    if (this.offset + n > this.end)
      throw new ProtocolError(`S7CommPlus: truncated ${what} at offset ${this.offset} (${n} bytes needed, ${this.remaining} left)`);
  }

  /** The next byte, not consumed (undefined at the end). */
  peek(): number | undefined {
    return this.offset < this.end ? this.buf[this.offset] : undefined;
  }

  u8(what = 'byte'): number {
    this.need(1, what);
    return this.buf[this.offset++]!;
  }

  u16(what = 'UInt16'): number {
    this.need(2, what);
    const v = this.buf.readUInt16BE(this.offset);
    this.offset += 2;
    return v;
  }

  u32(what = 'UInt32'): number {
    this.need(4, what);
    const v = this.buf.readUInt32BE(this.offset);
    this.offset += 4;
    return v;
  }

  u64(what = 'UInt64'): bigint {
    this.need(8, what);
    const v = this.buf.readBigUInt64BE(this.offset);
    this.offset += 8;
    return v;
  }

  bytes(n: number, what = 'bytes'): Buffer {
    this.need(n, what);
    const out = this.buf.subarray(this.offset, this.offset + n);
    this.offset += n;
    return out;
  }

  private vlq<T>(decode: (b: Buffer, o: number) => { value: T; length: number }): T {
    const view = this.end === this.buf.length ? this.buf : this.buf.subarray(0, this.end);
    const { value, length } = decode(view, this.offset);
    this.offset += length;
    return value;
  }

  uvlq32(): number {
    return this.vlq(decodeUVlq32);
  }
  svlq32(): number {
    return this.vlq(decodeSVlq32);
  }
  uvlq64(): bigint {
    return this.vlq(decodeUVlq64);
  }
  svlq64(): bigint {
    return this.vlq(decodeSVlq64);
  }

  /** The end must be reached: `what` names the message for the error. */
  done(what: string): void {
    if (this.offset !== this.end)
      throw new ProtocolError(`S7CommPlus: ${this.end - this.offset} unexpected bytes after the ${what} at offset ${this.offset}`);
  }
}

export class Writer {
  private buf = Buffer.allocUnsafe(64);
  private len = 0;

  private room(n: number): void {
    if (this.len + n <= this.buf.length) return;
    const next = Buffer.allocUnsafe(Math.max(this.buf.length * 2, this.len + n));
    this.buf.copy(next, 0, 0, this.len);
    this.buf = next;
  }

  u8(v: number): this {
    this.room(1);
    this.buf[this.len++] = v & 0xff;
    return this;
  }
  u16(v: number): this {
    this.room(2);
    this.buf.writeUInt16BE(v & 0xffff, this.len);
    this.len += 2;
    return this;
  }
  u32(v: number): this {
    this.room(4);
    this.buf.writeUInt32BE(v >>> 0, this.len);
    this.len += 4;
    return this;
  }
  u64(v: bigint): this {
    this.room(8);
    this.buf.writeBigUInt64BE(BigInt.asUintN(64, v), this.len);
    this.len += 8;
    return this;
  }
  bytes(b: Uint8Array): this {
    this.room(b.length);
    this.buf.set(b, this.len);
    this.len += b.length;
    return this;
  }
  uvlq32(v: number): this {
    this.room(uvlq32Length(v));
    this.len = writeUVlq32(this.buf, this.len, v);
    return this;
  }
  svlq32(v: number): this {
    return this.bytes(encodeSVlq32(v));
  }
  uvlq64(v: bigint): this {
    return this.bytes(encodeUVlq64(v));
  }
  svlq64(v: bigint): this {
    return this.bytes(encodeSVlq64(v));
  }

  get length(): number {
    return this.len;
  }

  toBuffer(): Buffer {
    return Buffer.from(this.buf.subarray(0, this.len));
  }
}
