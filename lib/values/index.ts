/**
 * Pure encoders and decoders of every S7 data type (big-endian), shared by
 * all drivers. Validation is strict: a value that does not fit its tag is a
 * ValueError naming the tag (and the element of an array), never a silently
 * truncated write. Decoding never throws on the content of the bytes; only
 * too few bytes is a ProtocolError.
 *
 * JavaScript mapping (JS_TYPES, README "Data types"): integers up to 32 bits,
 * REAL, LREAL → number; LWORD, LINT, ULINT → bigint, LTIME → bigint ns (a
 * safe-integer number is accepted on write); S5TIME, TIME, TIME_OF_DAY,
 * TIMER → number of ms; DATE, DATE_AND_TIME, DTL → Date (UTC fields);
 * COUNTER → number 0–999; CHAR, WCHAR → one-character string; STRING,
 * WSTRING → string.
 */
import { ProtocolError, ValueError } from '../errors';
import type { DataTypeName, PlcScalar, PlcValue } from '../types';
import { BCD_CODECS } from './bcd';
import { decodeBits, encodeBits } from './bits';
import { show, ValueProblem, type ElementCodec } from './checks';
import { NUMBER_CODECS } from './numbers';
import { STRING_CODECS, stringBody } from './strings';
import { TIME_CODECS } from './time';
import { elementByteLength, tagByteLength, type TagShape } from './types-table';

export { describeJsType, elementByteLength, JS_TYPES, tagByteLength, type TagShape } from './types-table';

const CODECS: Readonly<Record<Exclude<DataTypeName, 'BOOL'>, ElementCodec>> = Object.freeze({
  ...NUMBER_CODECS,
  ...STRING_CODECS,
  ...BCD_CODECS,
  ...TIME_CODECS,
});

/** Runs `fn`, turning a ValueProblem into a ValueError that names the tag and, in an array, the element. */
function forTag<T>(tag: TagShape, fn: (element: (i: number) => void) => T): T {
  let index = -1;
  try {
    return fn((i) => (index = i));
  } catch (err) {
    if (!(err instanceof ValueProblem)) throw err;
    throw new ValueError(tag.address, tag.isArray && index >= 0 ? `element ${index}: ${err.message}` : err.message);
  }
}

/**
 * Decodes a tag from `data`, where data[offset] holds the byte at
 * tag.byteOffset; an array when tag.isArray. Any bytes decode (corrupt
 * string lengths are clamped, impossible dates are Invalid Dates); too few
 * bytes is a ProtocolError.
 */
export function decodeTag(tag: TagShape, data: Buffer, offset = 0): PlcValue {
  const need = tagByteLength(tag);
  if (!Number.isInteger(offset) || offset < 0 || data.length - offset < need) {
    throw new ProtocolError(`${tag.address}: ${need} bytes expected, ${Math.max(0, data.length - offset)} received`, {
      tag: tag.address,
    });
  }
  if (tag.type === 'BOOL') {
    const bits = decodeBits(tag, data, offset);
    return tag.isArray ? bits : bits[0]!;
  }
  const codec = CODECS[tag.type];
  if (!tag.isArray) return codec.decode(tag, data, offset);
  const size = elementByteLength(tag.type, tag.stringLength);
  const out: PlcScalar[] = new Array<PlcScalar>(tag.count);
  for (let i = 0; i < tag.count; i++) out[i] = codec.decode(tag, data, offset + i * size);
  return out;
}

/** Decodes a whole tag from `data` at `offset`; the caller has checked that tagByteLength(tag) bytes are there. */
export type TagDecoder = (data: Buffer, offset: number) => PlcValue;

const decoders = new Map<string, TagDecoder>();
const MAX_DECODERS = 4096;

/**
 * decodeTag for one tag, resolved once (the codec, the element size, the
 * BOOL bit) so a poll that decodes the same tags again and again does no
 * lookups. Unlike decodeTag it does not check the length: a read plan has
 * already checked each item's length against the bytes its tags need.
 * Decoders depend on the tag's shape only (type, count, string length, bit)
 * and are shared: a table of 1000 tags holds a handful, not 1000 closures.
 */
export function tagDecoder(tag: TagShape): TagDecoder {
  const key = `${tag.type}|${tag.isArray ? tag.count : ''}|${tag.stringLength}|${tag.type === 'BOOL' ? tag.bitOffset : ''}`;
  let decoder = decoders.get(key);
  if (!decoder) {
    if (decoders.size >= MAX_DECODERS) decoders.clear();
    const shape: TagShape = {
      address: '',
      type: tag.type,
      count: tag.count,
      isArray: tag.isArray,
      stringLength: tag.stringLength,
      bitOffset: tag.bitOffset,
    };
    decoder = makeDecoder(shape);
    decoders.set(key, decoder);
  }
  return decoder;
}

function makeDecoder(tag: TagShape): TagDecoder {
  if (tag.type === 'BOOL') {
    if (tag.isArray) return (data, offset) => decodeBits(tag, data, offset);
    const at = tag.bitOffset >> 3;
    const mask = 1 << (tag.bitOffset & 7);
    return (data, offset) => (data[offset + at]! & mask) !== 0;
  }
  const decode = CODECS[tag.type].decode;
  if (!tag.isArray) return (data, offset) => decode(tag, data, offset);
  const size = elementByteLength(tag.type, tag.stringLength);
  const count = tag.count;
  return (data, offset) => {
    const out: PlcScalar[] = new Array<PlcScalar>(count);
    for (let i = 0; i < count; i++) out[i] = decode(tag, data, offset + i * size);
    return out;
  };
}

/** The elements of a value: [value] for a scalar; an array of exactly tag.count (CHAR/WCHAR arrays may be given as text). */
function elementsOf(tag: TagShape, value: unknown): readonly unknown[] {
  if (!tag.isArray) return [value];
  if ((tag.type === 'CHAR' || tag.type === 'WCHAR') && typeof value === 'string') {
    if (value.length > tag.count) {
      throw new ValueProblem(`${value.length} characters do not fit ${tag.type}[${tag.count}]`);
    }
    return [...value.padEnd(tag.count, '\u0000')];
  }
  if (!Array.isArray(value)) throw new ValueProblem(`expected an array of ${tag.count} ${tag.type}, got ${show(value)}`);
  if (value.length !== tag.count) throw new ValueProblem(`expected an array of ${tag.count} ${tag.type}, got ${value.length} elements`);
  return value;
}

/** Validates every element and encodes them into a fresh buffer of tagByteLength (not for BOOL). */
function encodeElements(tag: TagShape, value: unknown): Buffer {
  return forTag(tag, (at) => {
    const items = elementsOf(tag, value);
    const codec = CODECS[tag.type as Exclude<DataTypeName, 'BOOL'>];
    const size = elementByteLength(tag.type, tag.stringLength);
    const buf = Buffer.alloc(size * items.length);
    items.forEach((v, i) => {
      at(i);
      codec.encode(tag, v, buf, i * size);
    });
    return buf;
  });
}

function validBits(tag: TagShape, value: unknown): boolean[] {
  return forTag(tag, (at) => {
    const items = elementsOf(tag, value);
    return items.map((v, i) => {
      at(i);
      if (typeof v !== 'boolean') throw new ValueProblem(`expected a boolean for BOOL, got ${show(v)}`);
      return v;
    });
  });
}

/** Validates and encodes a whole tag into a fresh Buffer of tagByteLength bytes. BOOL: the tag's bits set/cleared in zero bytes. */
export function encodeTag(tag: TagShape, value: unknown): Buffer {
  if (tag.type !== 'BOOL') return encodeElements(tag, value);
  const buf = Buffer.alloc(tagByteLength(tag));
  encodeBits(tag, validBits(tag, value), buf, 0);
  return buf;
}

/**
 * Validates and writes a tag's value into `target` at `offset` (the position
 * of tag.byteOffset), for read-modify-write. Nothing is written unless the
 * whole value is valid. BOOL: only the tag's bits change. STRING/WSTRING
 * (and arrays of them): the max-length field the PLC holds stays as it is.
 */
export function encodeInto(tag: TagShape, value: unknown, target: Buffer, offset = 0): void {
  if (tag.type === 'BOOL') {
    encodeBits(tag, validBits(tag, value), target, offset);
    return;
  }
  const encoded = encodeElements(tag, value);
  if (tag.type !== 'STRING' && tag.type !== 'WSTRING') {
    encoded.copy(target, offset);
    return;
  }
  const header = tag.type === 'STRING' ? 1 : 2;
  const size = elementByteLength(tag.type, tag.stringLength);
  for (let at = 0; at < encoded.length; at += size) encoded.copy(target, offset + at + header, at + header, at + size);
}

/**
 * The minimal bytes a write of this value must send, from `start` bytes after
 * tag.byteOffset. A single STRING[n] sends its actual length and characters
 * (start 1), keeping the PLC's declared max-length byte; WSTRING likewise
 * (start 2). Arrays of strings and every other type: start 0, encodeTag.
 * BOOL tags are written bit by bit by the drivers, so BOOL throws.
 */
export function writeSpan(tag: TagShape, value: unknown): { start: number; data: Buffer } {
  if (tag.type === 'BOOL') throw new TypeError(`writeSpan(${tag.address}): BOOL tags are written bit by bit`);
  if (!tag.isArray && (tag.type === 'STRING' || tag.type === 'WSTRING')) return forTag(tag, () => stringBody(tag, value));
  return { start: 0, data: encodeTag(tag, value) };
}

/** Throws ValueError (naming tag.address) when the value does not fit the tag. */
export function validateValue(tag: TagShape, value: unknown): void {
  encodeTag(tag, value);
}
export { shortestFloat32 } from './float32';
