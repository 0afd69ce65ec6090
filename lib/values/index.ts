/**
 * Pure encoders and decoders of every S7 data type (big-endian), shared by
 * all drivers. Validation is strict: a value that does not fit its tag is a
 * ValueError naming the tag, never a silently truncated write.
 *
 * JavaScript mapping (README "Data types"): integers up to 32 bits, REAL,
 * LREAL → number; LWORD, LINT, ULINT → bigint, LTIME → bigint nanoseconds;
 * S5TIME, TIME, TIME_OF_DAY, TIMER → number of milliseconds; DATE,
 * DATE_AND_TIME, DTL → Date (fields as UTC); COUNTER → number 0–999; CHAR,
 * WCHAR → one-character string; STRING, WSTRING → string.
 */
import { ProtocolError, ValueError } from '../errors';
import type { DataTypeName, PlcScalar, PlcValue, Tag } from '../types';
import { elementSize } from '../address';

export type TagShape = Pick<Tag, 'address' | 'type' | 'count' | 'isArray' | 'stringLength' | 'bitOffset'>;

/** Bytes of one element: STRING[n] n+2, WSTRING[n] 2n+4, DTL 12 … (BOOL: 1, but see tagByteLength). */
export function elementByteLength(type: DataTypeName, stringLength = 0): number {
  return elementSize(type, stringLength);
}

/** Bytes a tag covers from its byte offset; BOOL arrays: ceil((bitOffset + count) / 8). */
export function tagByteLength(tag: Pick<Tag, 'type' | 'count' | 'stringLength' | 'bitOffset'>): number {
  if (tag.type === 'BOOL') return Math.ceil((tag.bitOffset + tag.count) / 8);
  return elementSize(tag.type, tag.stringLength) * tag.count;
}

/** What each PLC type becomes in JavaScript (for docs and the editor). */
export const JS_TYPES: Readonly<Record<DataTypeName, string>> = Object.freeze({
  BOOL: 'boolean', BYTE: 'number 0..255', WORD: 'number 0..65535', DWORD: 'number 0..4294967295', LWORD: 'bigint 0..2^64-1',
  SINT: 'number -128..127', USINT: 'number 0..255', INT: 'number -32768..32767', UINT: 'number 0..65535',
  DINT: 'number -2^31..2^31-1', UDINT: 'number 0..2^32-1', LINT: 'bigint -2^63..2^63-1', ULINT: 'bigint 0..2^64-1',
  REAL: 'number (float32)', LREAL: 'number', CHAR: 'string of 1 latin-1 character', WCHAR: 'string of 1 UTF-16 unit',
  STRING: 'string (latin-1, up to n characters)', WSTRING: 'string (UTF-16, up to n units)',
  S5TIME: 'number ms 0..9990000', TIME: 'number ms (signed 32-bit)', LTIME: 'bigint ns (signed 64-bit)',
  DATE: 'Date (UTC midnight, 1990-01-01..2168-12-31)', TIME_OF_DAY: 'number ms since midnight',
  DATE_AND_TIME: 'Date (UTC, 1990..2089, ms)', DTL: 'Date (UTC, 1970..2262, ns truncated to ms)',
  COUNTER: 'number 0..999', TIMER: 'number ms 0..9990000',
});

export function describeJsType(type: DataTypeName): string {
  return JS_TYPES[type];
}

const DAY_MS = 86_400_000;
const EPOCH_1990 = Date.UTC(1990, 0, 1);
const S5_BASES = [10, 100, 1000, 10000] as const;
const FLOAT32_MAX = 3.4028234663852886e38;

type Encoder = (tag: TagShape, value: unknown, buf: Buffer, off: number) => void;
type Decoder = (tag: TagShape, buf: Buffer, off: number) => PlcScalar;

function fail(tag: TagShape, problem: string): never {
  throw new ValueError(tag.address, problem);
}

function show(value: unknown): string {
  if (typeof value === 'string') return JSON.stringify(value.length > 40 ? `${value.slice(0, 40)}…` : value);
  if (typeof value === 'bigint') return `${value}n`;
  if (value instanceof Date) return Number.isNaN(value.getTime()) ? 'Invalid Date' : value.toISOString();
  if (Array.isArray(value)) return `an array of ${value.length}`;
  if (value === null) return 'null';
  if (typeof value === 'object') return 'an object';
  return String(value);
}

function integer(tag: TagShape, value: unknown, min: number, max: number): number {
  let n: number;
  if (typeof value === 'number') n = value;
  else if (typeof value === 'bigint') n = Number(value);
  else return fail(tag, `expected a number for ${tag.type}, got ${show(value)}`);
  if (!Number.isInteger(n)) return fail(tag, `${show(value)} is not an integer (${tag.type})`);
  if (n < min || n > max) return fail(tag, `${show(value)} is out of range for ${tag.type} (${min}..${max})`);
  return n;
}

function big(tag: TagShape, value: unknown, min: bigint, max: bigint): bigint {
  let n: bigint;
  if (typeof value === 'bigint') n = value;
  else if (typeof value === 'number') {
    if (!Number.isSafeInteger(value)) return fail(tag, `${show(value)} is not a safe integer; pass a bigint for ${tag.type}`);
    n = BigInt(value);
  } else return fail(tag, `expected a bigint or integer for ${tag.type}, got ${show(value)}`);
  if (n < min || n > max) return fail(tag, `${show(value)} is out of range for ${tag.type} (${min}..${max})`);
  return n;
}

function num(tag: TagShape, value: unknown): number {
  if (typeof value !== 'number') return fail(tag, `expected a number for ${tag.type}, got ${show(value)}`);
  return value;
}

function date(tag: TagShape, value: unknown): Date {
  if (!(value instanceof Date)) return fail(tag, `expected a Date for ${tag.type}, got ${show(value)}`);
  if (Number.isNaN(value.getTime())) return fail(tag, `Invalid Date for ${tag.type}`);
  return value;
}

function bcd(n: number): number {
  return ((Math.floor(n / 10) % 10) << 4) | n % 10;
}

function fromBcd(byte: number): number {
  return (byte >> 4) * 10 + (byte & 0x0f);
}

function encodeS5Time(tag: TagShape, value: unknown): number {
  const ms = integer(tag, value, 0, 9_990_000);
  for (let base = 0; base < 4; base++) {
    const units = ms / S5_BASES[base]!;
    if (Number.isInteger(units) && units <= 999) {
      return (base << 12) | (Math.floor(units / 100) << 8) | (Math.floor(units / 10) % 10 << 4) | units % 10;
    }
  }
  return fail(tag, `${ms} ms cannot be represented exactly in ${tag.type} (3 BCD digits × 10 ms, 100 ms, 1 s or 10 s); round it`);
}

function decodeS5Time(word: number): number {
  const base = S5_BASES[(word >> 12) & 0x03]!;
  const digit = (n: number) => Math.min(n, 9); // a non-BCD nibble from the PLC is clamped, never thrown on
  return (digit((word >> 8) & 0x0f) * 100 + digit((word >> 4) & 0x0f) * 10 + digit(word & 0x0f)) * base;
}

const ENCODERS: Readonly<Record<DataTypeName, Encoder>> = {
  BOOL: () => {
    throw new Error('BOOL is encoded bitwise');
  },
  BYTE: (t, v, b, o) => void b.writeUInt8(integer(t, v, 0, 0xff), o),
  USINT: (t, v, b, o) => void b.writeUInt8(integer(t, v, 0, 0xff), o),
  SINT: (t, v, b, o) => void b.writeInt8(integer(t, v, -128, 127), o),
  WORD: (t, v, b, o) => void b.writeUInt16BE(integer(t, v, 0, 0xffff), o),
  UINT: (t, v, b, o) => void b.writeUInt16BE(integer(t, v, 0, 0xffff), o),
  INT: (t, v, b, o) => void b.writeInt16BE(integer(t, v, -32768, 32767), o),
  DWORD: (t, v, b, o) => void b.writeUInt32BE(integer(t, v, 0, 0xffffffff), o),
  UDINT: (t, v, b, o) => void b.writeUInt32BE(integer(t, v, 0, 0xffffffff), o),
  DINT: (t, v, b, o) => void b.writeInt32BE(integer(t, v, -2147483648, 2147483647), o),
  LWORD: (t, v, b, o) => void b.writeBigUInt64BE(big(t, v, 0n, 0xffffffffffffffffn), o),
  ULINT: (t, v, b, o) => void b.writeBigUInt64BE(big(t, v, 0n, 0xffffffffffffffffn), o),
  LINT: (t, v, b, o) => void b.writeBigInt64BE(big(t, v, -(2n ** 63n), 2n ** 63n - 1n), o),
  REAL: (t, v, b, o) => {
    const n = num(t, v);
    if (Number.isFinite(n) && Math.abs(n) > FLOAT32_MAX) fail(t, `${n} overflows REAL (max ±${FLOAT32_MAX})`);
    b.writeFloatBE(n, o);
  },
  LREAL: (t, v, b, o) => void b.writeDoubleBE(num(t, v), o),
  CHAR: (t, v, b, o) => {
    if (typeof v !== 'string' || v.length !== 1) fail(t, `expected one character for CHAR, got ${show(v)}`);
    const code = v.charCodeAt(0);
    if (code > 0xff) fail(t, `${show(v)} is not a latin-1 character (CHAR)`);
    b[o] = code;
  },
  WCHAR: (t, v, b, o) => {
    if (typeof v !== 'string' || v.length !== 1) fail(t, `expected one UTF-16 character for WCHAR, got ${show(v)}`);
    b.writeUInt16BE(v.charCodeAt(0), o);
  },
  STRING: (t, v, b, o) => {
    const s = latin1(t, v);
    b[o] = t.stringLength;
    b[o + 1] = s.length;
    b.fill(0, o + 2, o + 2 + t.stringLength);
    b.write(s, o + 2, 'latin1');
  },
  WSTRING: (t, v, b, o) => {
    const s = utf16(t, v);
    b.writeUInt16BE(t.stringLength, o);
    b.writeUInt16BE(s.length, o + 2);
    b.fill(0, o + 4, o + 4 + 2 * t.stringLength);
    for (let i = 0; i < s.length; i++) b.writeUInt16BE(s.charCodeAt(i), o + 4 + 2 * i);
  },
  S5TIME: (t, v, b, o) => void b.writeUInt16BE(encodeS5Time(t, v), o),
  TIMER: (t, v, b, o) => void b.writeUInt16BE(encodeS5Time(t, v), o),
  TIME: (t, v, b, o) => void b.writeInt32BE(integer(t, v, -2147483648, 2147483647), o),
  LTIME: (t, v, b, o) => void b.writeBigInt64BE(big(t, v, -(2n ** 63n), 2n ** 63n - 1n), o),
  TIME_OF_DAY: (t, v, b, o) => void b.writeUInt32BE(integer(t, v, 0, DAY_MS - 1), o),
  DATE: (t, v, b, o) => {
    const ms = date(t, v).getTime() - EPOCH_1990;
    if (ms % DAY_MS !== 0) fail(t, `${show(v)} is not a UTC midnight (DATE has no time of day)`);
    const days = ms / DAY_MS;
    if (days < 0 || days > 0xffff) fail(t, `${show(v)} is out of range for DATE (1990-01-01..2169-06-06)`);
    b.writeUInt16BE(days, o);
  },
  DATE_AND_TIME: (t, v, b, o) => {
    const d = date(t, v);
    const year = d.getUTCFullYear();
    if (year < 1990 || year > 2089) fail(t, `${show(v)} is out of range for DATE_AND_TIME (1990..2089)`);
    const ms = d.getUTCMilliseconds();
    b[o] = bcd(year % 100);
    b[o + 1] = bcd(d.getUTCMonth() + 1);
    b[o + 2] = bcd(d.getUTCDate());
    b[o + 3] = bcd(d.getUTCHours());
    b[o + 4] = bcd(d.getUTCMinutes());
    b[o + 5] = bcd(d.getUTCSeconds());
    b[o + 6] = bcd(Math.floor(ms / 10));
    b[o + 7] = ((ms % 10) << 4) | (d.getUTCDay() + 1);
  },
  DTL: (t, v, b, o) => {
    const d = date(t, v);
    const year = d.getUTCFullYear();
    if (year < 1970 || year > 2262) fail(t, `${show(v)} is out of range for DTL (1970..2262)`);
    b.writeUInt16BE(year, o);
    b[o + 2] = d.getUTCMonth() + 1;
    b[o + 3] = d.getUTCDate();
    b[o + 4] = d.getUTCDay() + 1;
    b[o + 5] = d.getUTCHours();
    b[o + 6] = d.getUTCMinutes();
    b[o + 7] = d.getUTCSeconds();
    b.writeUInt32BE(d.getUTCMilliseconds() * 1_000_000, o + 8);
  },
  COUNTER: (t, v, b, o) => {
    const n = integer(t, v, 0, 999);
    b.writeUInt16BE((Math.floor(n / 100) << 8) | bcd(n % 100), o);
  },
};

function latin1(t: TagShape, v: unknown): string {
  if (typeof v !== 'string') return fail(t, `expected a string for STRING[${t.stringLength}], got ${show(v)}`);
  if (v.length > t.stringLength) fail(t, `${v.length} characters do not fit STRING[${t.stringLength}]`);
  // eslint-disable-next-line no-control-regex
  if (/[^\u0000-\u00ff]/.test(v)) fail(t, `${show(v)} has characters outside latin-1; use WSTRING`);
  return v;
}

function utf16(t: TagShape, v: unknown): string {
  if (typeof v !== 'string') return fail(t, `expected a string for WSTRING[${t.stringLength}], got ${show(v)}`);
  if (v.length > t.stringLength) fail(t, `${v.length} UTF-16 units do not fit WSTRING[${t.stringLength}]`);
  return v;
}

const DECODERS: Readonly<Record<DataTypeName, Decoder>> = {
  BOOL: () => {
    throw new Error('BOOL is decoded bitwise');
  },
  BYTE: (_t, b, o) => b.readUInt8(o),
  USINT: (_t, b, o) => b.readUInt8(o),
  SINT: (_t, b, o) => b.readInt8(o),
  WORD: (_t, b, o) => b.readUInt16BE(o),
  UINT: (_t, b, o) => b.readUInt16BE(o),
  INT: (_t, b, o) => b.readInt16BE(o),
  DWORD: (_t, b, o) => b.readUInt32BE(o),
  UDINT: (_t, b, o) => b.readUInt32BE(o),
  DINT: (_t, b, o) => b.readInt32BE(o),
  LWORD: (_t, b, o) => b.readBigUInt64BE(o),
  ULINT: (_t, b, o) => b.readBigUInt64BE(o),
  LINT: (_t, b, o) => b.readBigInt64BE(o),
  REAL: (_t, b, o) => b.readFloatBE(o),
  LREAL: (_t, b, o) => b.readDoubleBE(o),
  CHAR: (_t, b, o) => String.fromCharCode(b[o]!),
  WCHAR: (_t, b, o) => String.fromCharCode(b.readUInt16BE(o)),
  // The actual-length byte is clamped to the declared and the PLC's maximum: a
  // corrupt length never reads past the string.
  STRING: (t, b, o) => b.toString('latin1', o + 2, o + 2 + Math.min(b[o + 1]!, b[o]! || t.stringLength, t.stringLength)),
  WSTRING: (t, b, o) => {
    const n = Math.min(b.readUInt16BE(o + 2), b.readUInt16BE(o) || t.stringLength, t.stringLength);
    let s = '';
    for (let i = 0; i < n; i++) s += String.fromCharCode(b.readUInt16BE(o + 4 + 2 * i));
    return s;
  },
  S5TIME: (_t, b, o) => decodeS5Time(b.readUInt16BE(o)),
  TIMER: (_t, b, o) => decodeS5Time(b.readUInt16BE(o)),
  TIME: (_t, b, o) => b.readInt32BE(o),
  LTIME: (_t, b, o) => b.readBigInt64BE(o),
  TIME_OF_DAY: (_t, b, o) => b.readUInt32BE(o),
  DATE: (_t, b, o) => new Date(EPOCH_1990 + b.readUInt16BE(o) * DAY_MS),
  DATE_AND_TIME: (_t, b, o) => {
    const yy = fromBcd(b[o]!);
    const year = yy >= 90 ? 1900 + yy : 2000 + yy;
    const ms = fromBcd(b[o + 6]!) * 10 + (b[o + 7]! >> 4);
    return new Date(Date.UTC(year, fromBcd(b[o + 1]!) - 1, fromBcd(b[o + 2]!), fromBcd(b[o + 3]!), fromBcd(b[o + 4]!), fromBcd(b[o + 5]!), ms));
  },
  DTL: (_t, b, o) =>
    new Date(Date.UTC(b.readUInt16BE(o), b[o + 2]! - 1, b[o + 3]!, b[o + 5]!, b[o + 6]!, b[o + 7]!, Math.floor(b.readUInt32BE(o + 8) / 1_000_000))),
  COUNTER: (_t, b, o) => {
    const w = b.readUInt16BE(o);
    return Math.min((w >> 8) & 0x0f, 9) * 100 + Math.min((w >> 4) & 0x0f, 9) * 10 + Math.min(w & 0x0f, 9);
  },
};

/**
 * Decodes a tag from `data`, where data[offset] is the byte at tag.byteOffset.
 * Throws ProtocolError (never anything else) when `data` is too short.
 */
export function decodeTag(tag: TagShape, data: Buffer, offset = 0): PlcValue {
  const need = tagByteLength(tag);
  if (offset < 0 || data.length - offset < need) {
    throw new ProtocolError(`${tag.address}: ${need} bytes expected, ${Math.max(0, data.length - offset)} received`);
  }
  if (tag.type === 'BOOL') {
    const bits: boolean[] = [];
    for (let i = 0; i < tag.count; i++) {
      const n = tag.bitOffset + i;
      bits.push((data[offset + (n >> 3)]! & (1 << (n & 7))) !== 0);
    }
    return tag.isArray ? bits : bits[0]!;
  }
  const decode = DECODERS[tag.type];
  const size = elementSize(tag.type, tag.stringLength);
  if (!tag.isArray) return decode(tag, data, offset);
  const out: PlcScalar[] = new Array(tag.count);
  for (let i = 0; i < tag.count; i++) out[i] = decode(tag, data, offset + i * size);
  return out;
}

function elements(tag: TagShape, value: unknown): unknown[] {
  if (!tag.isArray) return [value];
  // A CHAR/WCHAR array may be given as text.
  if ((tag.type === 'CHAR' || tag.type === 'WCHAR') && typeof value === 'string') {
    if (value.length > tag.count) fail(tag, `${value.length} characters do not fit ${tag.type}[${tag.count}]`);
    return [...value.padEnd(tag.count, '\u0000')];
  }
  if (!Array.isArray(value)) return fail(tag, `expected an array of ${tag.count} ${tag.type}, got ${show(value)}`);
  if (value.length !== tag.count) fail(tag, `expected ${tag.count} elements, got ${value.length}`);
  return value;
}

/**
 * Validates and writes the tag's value into `target` at `offset` (the position
 * of tag.byteOffset). Nothing is written unless the whole value is valid.
 * BOOL: only the tag's bits change. STRING/WSTRING: the max-length header the
 * PLC holds stays as it is.
 */
export function encodeInto(tag: TagShape, value: unknown, target: Buffer, offset = 0): void {
  const items = elements(tag, value);
  if (tag.type === 'BOOL') {
    for (const v of items) if (typeof v !== 'boolean') fail(tag, `expected a boolean for BOOL, got ${show(v)}`);
    items.forEach((v, i) => {
      const n = tag.bitOffset + i;
      const at = offset + (n >> 3);
      target[at] = v ? target[at]! | (1 << (n & 7)) : target[at]! & ~(1 << (n & 7));
    });
    return;
  }
  const encoded = encodeElements(tag, items);
  const keepHeader = !tag.isArray && (tag.type === 'STRING' || tag.type === 'WSTRING');
  const skip = keepHeader ? (tag.type === 'STRING' ? 1 : 2) : 0;
  encoded.copy(target, offset + skip, skip);
}

function encodeElements(tag: TagShape, items: readonly unknown[]): Buffer {
  const size = elementSize(tag.type, tag.stringLength);
  const buf = Buffer.alloc(size * items.length);
  const encode = ENCODERS[tag.type];
  items.forEach((v, i) => encode(tag, v, buf, i * size));
  return buf;
}

/** Validates and encodes a whole tag into a fresh Buffer of tagByteLength bytes (BOOL: the tag's bits in zero bytes). */
export function encodeTag(tag: TagShape, value: unknown): Buffer {
  const buf = Buffer.alloc(tagByteLength(tag));
  if (tag.type === 'BOOL') encodeInto(tag, value, buf, 0);
  else encodeElements(tag, elements(tag, value)).copy(buf);
  return buf;
}

/**
 * The bytes a write of this value must send, from `start` bytes after
 * tag.byteOffset. A scalar STRING[n] sends its actual length and characters
 * only (start 1), so the PLC's declared max-length byte is kept; WSTRING
 * likewise (start 2). BOOL is written bit by bit by the drivers.
 */
export function writeSpan(tag: TagShape, value: unknown): { start: number; data: Buffer } {
  if (tag.type === 'BOOL') throw new Error('writeSpan: BOOL tags are written bit by bit');
  if (!tag.isArray && tag.type === 'STRING') {
    const s = latin1(tag, value);
    const data = Buffer.alloc(1 + s.length);
    data[0] = s.length;
    data.write(s, 1, 'latin1');
    return { start: 1, data };
  }
  if (!tag.isArray && tag.type === 'WSTRING') {
    const s = utf16(tag, value);
    const data = Buffer.alloc(2 + 2 * s.length);
    data.writeUInt16BE(s.length, 0);
    for (let i = 0; i < s.length; i++) data.writeUInt16BE(s.charCodeAt(i), 2 + 2 * i);
    return { start: 2, data };
  }
  return { start: 0, data: encodeTag(tag, value) };
}

/** Throws ValueError when the value does not fit the tag. */
export function validateValue(tag: TagShape, value: unknown): void {
  encodeTag(tag, value);
}
