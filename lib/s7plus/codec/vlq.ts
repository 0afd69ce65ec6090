/**
 * The variable-length integers of S7CommPlus. Seven bits per byte, most
 * significant group first, bit 7 set on every byte but the last. Signed
 * values carry their sign in bit 6 of the first byte (two's complement over
 * the groups). 64-bit values end, after eight 7-bit groups, in a ninth byte
 * of 8 bits. Layout: s7commplus (MIT), vlq.py (after thomas-v2's S7p.cs,
 * facts only). The encoders choose the same length as s7commplus and TIA
 * (golden frames), so requests re-encode byte for byte.
 *
 * Decoders take (buffer, offset) and return the value and the bytes read;
 * they throw only ProtocolError: on truncation and on a value that does not
 * fit its width. Non-minimal encodings (leading 0x80 groups) are accepted.
 */
import { ProtocolError } from '../../errors';

export interface Decoded<T> {
  value: T;
  length: number;
}

function truncated(offset: number): ProtocolError {
  return new ProtocolError(`S7CommPlus: truncated VLQ at offset ${offset}`);
}

/** Bytes the UVLQ32 of `value` takes, the shortest form (as s7commplus and TIA write it); a RangeError outside 0..2^32-1. */
export function uvlq32Length(value: number): number {
  if (!Number.isInteger(value) || value < 0 || value > 0xffffffff) throw new RangeError(`UVLQ32 out of range: ${value}`);
  return value < 0x80 ? 1 : value < 0x4000 ? 2 : value < 0x200000 ? 3 : value < 0x10000000 ? 4 : 5;
}

/**
 * Writes the UVLQ32 of `value` into `out` at `offset` (room for
 * uvlq32Length(value) bytes) and returns the offset after it: the Writer's
 * way, without a Buffer per value (a 50-item request has 300 of them).
 */
export function writeUVlq32(out: Uint8Array, offset: number, value: number): number {
  const n = uvlq32Length(value);
  // value fits 32 bits unsigned, so `>>> 7` shifts it exactly.
  let v = value;
  out[offset + n - 1] = v & 0x7f;
  for (let i = n - 2; i >= 0; i--) {
    v >>>= 7;
    out[offset + i] = (v & 0x7f) | 0x80;
  }
  return offset + n;
}

export function encodeUVlq32(value: number): Buffer {
  const out = Buffer.allocUnsafe(uvlq32Length(value));
  writeUVlq32(out, 0, value);
  return out;
}

export function decodeUVlq32(buf: Buffer, offset: number): Decoded<number> {
  let value = 0;
  for (let i = 0; i < 5; i++) {
    const b = buf[offset + i];
    if (b === undefined) throw truncated(offset);
    value = value * 128 + (b & 0x7f);
    if ((b & 0x80) === 0) {
      if (value > 0xffffffff) throw new ProtocolError(`S7CommPlus: VLQ at offset ${offset} exceeds 32 bits`);
      return { value, length: i + 1 };
    }
  }
  throw new ProtocolError(`S7CommPlus: VLQ at offset ${offset} is longer than 5 bytes`);
}

export function encodeSVlq32(value: number): Buffer {
  if (!Number.isInteger(value) || value < -0x80000000 || value > 0x7fffffff) throw new RangeError(`SVLQ32 out of range: ${value}`);
  let n = 1;
  for (let a = Math.abs(value); a >= 0x40 && n < 5; a = Math.floor(a / 128)) n++;
  const out = Buffer.allocUnsafe(n);
  let v = value;
  for (let i = n - 1; i >= 0; i--) {
    const group = ((v % 128) + 128) % 128;
    out[i] = group | (i === n - 1 ? 0 : 0x80);
    v = (v - group) / 128;
  }
  return out;
}

export function decodeSVlq32(buf: Buffer, offset: number): Decoded<number> {
  let value = 0;
  for (let i = 0; i < 5; i++) {
    const b = buf[offset + i];
    if (b === undefined) throw truncated(offset);
    value = i === 0 && b & 0x40 ? -64 + (b & 0x3f) : value * 128 + (b & 0x7f);
    if ((b & 0x80) === 0) {
      if (value < -0x80000000 || value > 0x7fffffff) throw new ProtocolError(`S7CommPlus: signed VLQ at offset ${offset} exceeds 32 bits`);
      return { value, length: i + 1 };
    }
  }
  throw new ProtocolError(`S7CommPlus: VLQ at offset ${offset} is longer than 5 bytes`);
}

const U64_MAX = 0xffffffffffffffffn;
const BIG_56 = 1n << 56n;

export function encodeUVlq64(value: bigint): Buffer {
  if (value < 0n || value > U64_MAX) throw new RangeError(`UVLQ64 out of range: ${value}`);
  if (value >= BIG_56) {
    // Nine bytes: the top 56 bits in eight 7-bit groups, then the low 8 bits whole.
    const out = Buffer.allocUnsafe(9);
    out[8] = Number(value & 0xffn);
    let v = value >> 8n;
    for (let i = 7; i >= 0; i--) {
      out[i] = Number(v & 0x7fn) | 0x80;
      v >>= 7n;
    }
    return out;
  }
  let n = 1;
  for (let v = value; v >= 0x80n; v >>= 7n) n++;
  const out = Buffer.allocUnsafe(n);
  let v = value;
  for (let i = n - 1; i >= 0; i--) {
    out[i] = Number(v & 0x7fn) | (i === n - 1 ? 0 : 0x80);
    v >>= 7n;
  }
  return out;
}

export function decodeUVlq64(buf: Buffer, offset: number): Decoded<bigint> {
  let value = 0n;
  for (let i = 0; i < 8; i++) {
    const b = buf[offset + i];
    if (b === undefined) throw truncated(offset);
    value = (value << 7n) | BigInt(b & 0x7f);
    if ((b & 0x80) === 0) return { value, length: i + 1 };
  }
  const last = buf[offset + 8];
  if (last === undefined) throw truncated(offset);
  return { value: (value << 8n) | BigInt(last), length: 9 };
}

const S64_MIN = -(1n << 63n);
const S64_MAX = (1n << 63n) - 1n;
const S_BIG_55 = (1n << 55n) - 1n;

export function encodeSVlq64(value: bigint): Buffer {
  if (value < S64_MIN || value > S64_MAX) throw new RangeError(`SVLQ64 out of range: ${value}`);
  const abs = value < 0n ? -value : value;
  if (abs > S_BIG_55) {
    const out = Buffer.allocUnsafe(9);
    out[8] = Number(value & 0xffn);
    let v = value >> 8n;
    for (let i = 7; i >= 0; i--) {
      out[i] = Number(v & 0x7fn) | 0x80;
      v >>= 7n;
    }
    return out;
  }
  let n = 1;
  for (let a = abs; a >= 0x40n && n < 8; a >>= 7n) n++;
  const out = Buffer.allocUnsafe(n);
  let v = value;
  for (let i = n - 1; i >= 0; i--) {
    out[i] = Number(v & 0x7fn) | (i === n - 1 ? 0 : 0x80);
    v >>= 7n;
  }
  return out;
}

export function decodeSVlq64(buf: Buffer, offset: number): Decoded<bigint> {
  let value = 0n;
  for (let i = 0; i < 8; i++) {
    const b = buf[offset + i];
    if (b === undefined) throw truncated(offset);
    value = i === 0 && b & 0x40 ? BigInt(-64 + (b & 0x3f)) : (value << 7n) | BigInt(b & 0x7f);
    if ((b & 0x80) === 0) return { value, length: i + 1 };
  }
  const last = buf[offset + 8];
  if (last === undefined) throw truncated(offset);
  return { value: (value << 8n) | BigInt(last), length: 9 };
}
