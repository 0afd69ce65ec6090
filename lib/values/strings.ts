/**
 * Characters and strings. CHAR and STRING hold latin-1 bytes; WCHAR and
 * WSTRING hold UTF-16BE code units. STRING[n] is [max length byte, actual
 * length byte, n bytes]; WSTRING[n] is [max u16, actual u16, n units].
 */
import { reject, show, type CodecTable } from './checks';
import type { TagShape } from './types-table';

const NOT_LATIN1 = /[^\u0000-\u00ff]/; // eslint-disable-line no-control-regex

/** A STRING[n] value: a string of at most n latin-1 characters. */
function latin1String(tag: TagShape, value: unknown): string {
  const limit = `STRING[${tag.stringLength}]`;
  if (typeof value !== 'string') return reject(`expected a string for ${limit}, got ${show(value)}`);
  if (value.length > tag.stringLength) reject(`${value.length} characters do not fit ${limit} (at most ${tag.stringLength})`);
  if (NOT_LATIN1.test(value)) reject(`${show(value)} has characters outside latin-1, which ${limit} cannot hold; use WSTRING`);
  return value;
}

/** A WSTRING[n] value: a string of at most n UTF-16 code units. */
function utf16String(tag: TagShape, value: unknown): string {
  const limit = `WSTRING[${tag.stringLength}]`;
  if (typeof value !== 'string') return reject(`expected a string for ${limit}, got ${show(value)}`);
  if (value.length > tag.stringLength) {
    reject(`${value.length} UTF-16 units do not fit ${limit} (at most ${tag.stringLength})`);
  }
  return value;
}

function writeUtf16(s: string, buf: Buffer, off: number): void {
  for (let i = 0; i < s.length; i++) buf.writeUInt16BE(s.charCodeAt(i), off + 2 * i);
}

function readUtf16(buf: Buffer, off: number, units: number): string {
  let s = '';
  for (let i = 0; i < units; i++) s += String.fromCharCode(buf.readUInt16BE(off + 2 * i));
  return s;
}

/**
 * The characters a string header promises, clamped: never more than the
 * declared length nor the PLC's own max-length field (a zero max, as in a
 * never-initialised DB, is ignored). A corrupt length never reads past the
 * string and never throws.
 */
function clampLength(actual: number, plcMax: number, declared: number): number {
  return Math.min(actual, plcMax || declared, declared);
}

export const STRING_CODECS: CodecTable<'CHAR' | 'WCHAR' | 'STRING' | 'WSTRING'> = {
  CHAR: {
    encode: (_t, v, b, o) => {
      if (typeof v !== 'string' || v.length !== 1) reject(`expected one character for CHAR, got ${show(v)}`);
      if (NOT_LATIN1.test(v)) reject(`${show(v)} is not a latin-1 character (CHAR); use WCHAR`);
      b[o] = v.charCodeAt(0);
    },
    decode: (_t, b, o) => String.fromCharCode(b[o]!),
  },
  WCHAR: {
    encode: (_t, v, b, o) => {
      if (typeof v !== 'string' || v.length !== 1) {
        reject(
          `expected one UTF-16 code unit for WCHAR, got ${show(v)}${typeof v === 'string' && v.length === 2 ? ' (a surrogate pair)' : ''}`,
        );
      }
      b.writeUInt16BE(v.charCodeAt(0), o);
    },
    decode: (_t, b, o) => String.fromCharCode(b.readUInt16BE(o)),
  },
  STRING: {
    encode: (t, v, b, o) => {
      const s = latin1String(t, v);
      b[o] = t.stringLength;
      b[o + 1] = s.length;
      b.fill(0, o + 2, o + 2 + t.stringLength);
      b.write(s, o + 2, 'latin1');
    },
    decode: (t, b, o) => b.toString('latin1', o + 2, o + 2 + clampLength(b[o + 1]!, b[o]!, t.stringLength)),
  },
  WSTRING: {
    encode: (t, v, b, o) => {
      const s = utf16String(t, v);
      b.writeUInt16BE(t.stringLength, o);
      b.writeUInt16BE(s.length, o + 2);
      b.fill(0, o + 4, o + 4 + 2 * t.stringLength);
      writeUtf16(s, b, o + 4);
    },
    decode: (t, b, o) => readUtf16(b, o + 4, clampLength(b.readUInt16BE(o + 2), b.readUInt16BE(o), t.stringLength)),
  },
};

/** Bytes a single STRING/WSTRING write sends after the PLC's max-length field: actual length and characters. */
export function stringBody(tag: TagShape, value: unknown): { start: number; data: Buffer } {
  if (tag.type === 'STRING') {
    const s = latin1String(tag, value);
    const data = Buffer.alloc(1 + s.length);
    data[0] = s.length;
    data.write(s, 1, 'latin1');
    return { start: 1, data };
  }
  const s = utf16String(tag, value);
  const data = Buffer.alloc(2 + 2 * s.length);
  data.writeUInt16BE(s.length, 0);
  writeUtf16(s, data, 2);
  return { start: 2, data };
}
