/**
 * What every S7 data type occupies in PLC memory and what it becomes in
 * JavaScript. Sizes from the S7 type definitions (STEP 7 / TIA Portal help,
 * "Valid data types"): STRING[n] is 2 header bytes + n, WSTRING[n] is
 * 2 header words + n words, DTL 12 bytes.
 */
import type { DataTypeName, Tag } from '../types';

/** The parts of a tag the value codecs need. */
export type TagShape = Pick<Tag, 'address' | 'type' | 'count' | 'isArray' | 'stringLength' | 'bitOffset'>;

const ELEMENT_BYTES: Readonly<Record<DataTypeName, number>> = Object.freeze({
  BOOL: 1,
  BYTE: 1,
  CHAR: 1,
  SINT: 1,
  USINT: 1,
  WORD: 2,
  INT: 2,
  UINT: 2,
  WCHAR: 2,
  S5TIME: 2,
  DATE: 2,
  COUNTER: 2,
  TIMER: 2,
  DWORD: 4,
  DINT: 4,
  UDINT: 4,
  REAL: 4,
  TIME: 4,
  TIME_OF_DAY: 4,
  LWORD: 8,
  LINT: 8,
  ULINT: 8,
  LREAL: 8,
  LTIME: 8,
  DATE_AND_TIME: 8,
  DTL: 12,
  STRING: 2, // + n characters
  WSTRING: 4, // + n UTF-16 units of 2 bytes
});

/** Bytes of one element: BOOL 1 (a bit, see tagByteLength), STRING[n] n+2, WSTRING[n] 2n+4, DTL 12, DATE_AND_TIME 8 … */
export function elementByteLength(type: DataTypeName, stringLength = 0): number {
  if (type === 'STRING') return ELEMENT_BYTES.STRING + stringLength;
  if (type === 'WSTRING') return ELEMENT_BYTES.WSTRING + 2 * stringLength;
  return ELEMENT_BYTES[type];
}

/** Bytes a tag covers from its byteOffset; BOOL (arrays too): Math.ceil((bitOffset + count) / 8). */
export function tagByteLength(tag: Pick<Tag, 'type' | 'count' | 'stringLength' | 'bitOffset'>): number {
  if (tag.type === 'BOOL') return Math.ceil((tag.bitOffset + tag.count) / 8);
  return elementByteLength(tag.type, tag.stringLength) * tag.count;
}

/** What a value of each PLC type is in JavaScript (README "Data types", the editor's help). Arrays are JS arrays of these. */
export const JS_TYPES: Readonly<Record<DataTypeName, string>> = Object.freeze({
  BOOL: 'boolean',
  BYTE: 'number 0..255',
  WORD: 'number 0..65535',
  DWORD: 'number 0..4294967295',
  LWORD: 'bigint 0..2^64-1 (a safe-integer number is accepted on write)',
  SINT: 'number -128..127',
  USINT: 'number 0..255',
  INT: 'number -32768..32767',
  UINT: 'number 0..65535',
  DINT: 'number -2147483648..2147483647',
  UDINT: 'number 0..4294967295',
  LINT: 'bigint -2^63..2^63-1 (a safe-integer number is accepted on write)',
  ULINT: 'bigint 0..2^64-1 (a safe-integer number is accepted on write)',
  REAL: 'number (float32; NaN and ±Infinity allowed, finite values beyond ±3.4e38 rejected)',
  LREAL: 'number (float64)',
  CHAR: 'string of 1 latin-1 character',
  WCHAR: 'string of 1 UTF-16 code unit',
  STRING: 'string of up to n latin-1 characters',
  WSTRING: 'string of up to n UTF-16 code units',
  S5TIME: 'number of ms 0..9990000 (exact in one of the 10 ms/100 ms/1 s/10 s bases)',
  TIME: 'number of ms -2147483648..2147483647',
  LTIME: 'bigint of ns (signed 64-bit; a safe-integer number is accepted on write)',
  DATE: 'Date at UTC midnight 1990-01-01..2168-12-31',
  TIME_OF_DAY: 'number of ms since midnight 0..86399999',
  DATE_AND_TIME: 'Date (UTC fields, ms) 1990-01-01..2089-12-31',
  DTL: 'Date (UTC fields; ns read as whole ms) 1970-01-01..2262-04-11',
  COUNTER: 'number 0..999',
  TIMER: 'number of ms 0..9990000 (S5TIME format)',
});

/** E.g. describeJsType('INT') → 'number -32768..32767'. */
export function describeJsType(type: DataTypeName): string {
  return JS_TYPES[type];
}
