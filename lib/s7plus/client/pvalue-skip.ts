/**
 * Where a typed value (flags, type, value) ends, for the handshake's walk of
 * the CreateObject answer. Sizes from s7commplus (MIT), codec.py
 * (skip_typed_value, _pvalue_element_size). The codec's PValue decoder
 * (lib/s7plus/codec/) takes its place once it is merged.
 */
import { ProtocolError } from '../../errors';
import { readVlqU32 } from './frame';

const ARRAY = 0x10;
const FIXED: Readonly<Record<number, number>> = {
  0x00: 0, // NULL
  0x01: 1, // BOOL
  0x02: 1, // USINT
  0x06: 1, // SINT
  0x0a: 1, // BYTE
  0x03: 2, // UINT
  0x07: 2, // INT
  0x0b: 2, // WORD
  0x0c: 4, // DWORD
  0x0e: 4, // REAL
  0x12: 4, // RID
  0x0d: 8, // LWORD
  0x0f: 8, // LREAL
  0x10: 8, // TIMESTAMP
};
/** Numbers sent as VLQs: UDINT, DINT, AID (32 bits); ULINT, LINT, TIMESPAN (64 bits). */
const VLQ32 = new Set([0x04, 0x08, 0x13]);
const VLQ64 = new Set([0x05, 0x09, 0x11]);
const BLOB = 0x14;
const WSTRING = 0x15;
const STRUCT = 0x17;

function vlqEnd(buf: Buffer, at: number, max: number): number {
  for (let i = 0; i < max; i++) {
    const b = buf[at + i];
    if (b === undefined) throw new ProtocolError('S7CommPlus: a value runs past the end of the answer');
    if ((b & 0x80) === 0 || i === max - 1) return at + i + 1;
  }
  return at + max;
}

function within(buf: Buffer, end: number): number {
  if (end > buf.length) throw new ProtocolError('S7CommPlus: a value runs past the end of the answer');
  return end;
}

/** The offset after the typed value that starts at `at` (its flags byte); a ProtocolError for a type it cannot measure. */
export function skipValue(buf: Buffer, at: number, depth = 0): number {
  if (depth > 32) throw new ProtocolError('S7CommPlus: structures nested deeper than 32');
  const flags = buf[at];
  const type = buf[at + 1];
  if (flags === undefined || type === undefined) throw new ProtocolError('S7CommPlus: a value runs past the end of the answer');
  let p = at + 2;
  if (flags & ARRAY) {
    const count = readVlqU32(buf, p);
    p += count.length;
    const size = FIXED[type];
    if (size !== undefined && size > 0) return within(buf, p + count.value * size);
    for (let i = 0; i < count.value; i++) p = vlqEnd(buf, p, VLQ64.has(type) ? 9 : 5);
    return p;
  }
  return skipScalar(buf, p, type, depth);
}

function skipScalar(buf: Buffer, p: number, type: number, depth: number): number {
  const size = FIXED[type];
  if (size !== undefined) return within(buf, p + size);
  if (VLQ32.has(type)) return vlqEnd(buf, p, 5);
  if (VLQ64.has(type)) return vlqEnd(buf, p, 9);
  if (type === WSTRING) {
    const n = readVlqU32(buf, p);
    return within(buf, p + n.length + n.value);
  }
  if (type === BLOB) {
    p += readVlqU32(buf, p).length; // root id
    const n = readVlqU32(buf, p);
    return within(buf, p + n.length + n.value);
  }
  if (type === STRUCT) {
    p = within(buf, p + 4); // struct id
    for (;;) {
      const b = buf[p];
      if (b === undefined) throw new ProtocolError('S7CommPlus: a structure runs past the end of the answer');
      if (b === 0) return p + 1;
      p += readVlqU32(buf, p).length;
      p = skipValue(buf, p, depth + 1);
    }
  }
  throw new ProtocolError(`S7CommPlus: a value of type 0x${type.toString(16)} the client cannot measure`);
}
