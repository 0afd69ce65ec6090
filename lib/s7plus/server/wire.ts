/**
 * The few S7CommPlus encodings the simulator writes and reads: the
 * variable-length integers (7 bits a byte, the high bit says "more"; a
 * signed form with its sign in bit 6 of the first byte; a 64-bit form whose
 * ninth byte carries 8 bits) and a bounds-checked reader that throws
 * ProtocolError instead of reading past a hostile frame. Facts: s7commplus
 * (MIT), vlq.py and codec.py. Pure: no I/O.
 */
import { ProtocolError } from '../../errors';

/** Unsigned 32-bit VLQ. */
export function u32(value: number): Buffer {
  const v = value >>> 0;
  let groups = 1;
  while (groups < 5 && v >= 2 ** (7 * groups)) groups++;
  const out = Buffer.alloc(groups);
  for (let i = 0; i < groups; i++) {
    const group = Math.floor(v / 2 ** (7 * (groups - 1 - i))) & 0x7f;
    out[i] = i < groups - 1 ? group | 0x80 : group;
  }
  return out;
}

/** Signed 32-bit VLQ: bit 6 of the first byte is the sign, the rest two's complement. */
export function i32(value: number): Buffer {
  let v = value | 0;
  let abs = v === -0x80000000 ? 0x80000000 : Math.abs(v);
  const bytes = [v & 0x7f];
  while (bytes.length < 5 && abs >= 0x40) {
    abs = Math.floor(abs / 128);
    v >>= 7;
    bytes.push(((v & 0x7f) + 0x80) & 0xff);
  }
  return Buffer.from(bytes.reverse());
}

/** Unsigned 64-bit VLQ (values up to 2^56 - 1 need no special ninth byte; larger ones are not written by the simulator). */
export function u64(value: bigint): Buffer {
  if (value < 0n || value >= 1n << 56n) throw new RangeError(`u64 VLQ ${value} is outside what the simulator writes`);
  const bytes: number[] = [];
  let v = value;
  do {
    bytes.push(Number(v & 0x7fn));
    v >>= 7n;
  } while (v > 0n);
  bytes.reverse();
  for (let i = 0; i < bytes.length - 1; i++) bytes[i]! |= 0x80;
  return Buffer.from(bytes);
}

/** Reads a request field by field; any read past the end is a ProtocolError naming the field. */
export class WireReader {
  constructor(
    readonly buf: Buffer,
    public pos = 0,
  ) {}

  get left(): number {
    return this.buf.length - this.pos;
  }

  private need(n: number, what: string): void {
    if (this.pos + n > this.buf.length)
      throw new ProtocolError(`S7CommPlus request ends inside ${what} (byte ${this.pos} of ${this.buf.length})`);
  }

  byte(what: string): number {
    this.need(1, what);
    return this.buf[this.pos++]!;
  }

  u16(what: string): number {
    this.need(2, what);
    const v = this.buf.readUInt16BE(this.pos);
    this.pos += 2;
    return v;
  }

  u32fixed(what: string): number {
    this.need(4, what);
    const v = this.buf.readUInt32BE(this.pos);
    this.pos += 4;
    return v;
  }

  bytes(n: number, what: string): Buffer {
    this.need(n, what);
    const out = this.buf.subarray(this.pos, this.pos + n);
    this.pos += n;
    return out;
  }

  vlq(what: string): number {
    let value = 0;
    for (let i = 0; i < 5; i++) {
      const b = this.byte(what);
      value = value * 128 + (b & 0x7f);
      if ((b & 0x80) === 0) return value >>> 0 === value ? value : value % 2 ** 32;
    }
    throw new ProtocolError(`S7CommPlus ${what} is a VLQ longer than 5 bytes`);
  }

  vlqSigned(what: string): number {
    let value = 0;
    for (let i = 0; i < 5; i++) {
      let b = this.byte(what);
      if (i === 0 && b & 0x40) {
        b &= 0xbf;
        value = -64;
      } else value *= 128;
      value += b & 0x7f;
      if ((b & 0x80) === 0) return value | 0;
    }
    throw new ProtocolError(`S7CommPlus ${what} is a VLQ longer than 5 bytes`);
  }

  vlq64(what: string): bigint {
    let value = 0n;
    for (let i = 0; i < 9; i++) {
      const b = this.byte(what);
      if (i === 8) return (value << 8n) | BigInt(b);
      value = (value << 7n) | BigInt(b & 0x7f);
      if ((b & 0x80) === 0) return value;
    }
    return value;
  }
}
