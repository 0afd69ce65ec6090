/**
 * What a tag covers in PLC memory. A local copy of the element sizes (STEP 7 /
 * TIA Portal "Valid data types") so the parser does not depend on the value
 * codecs: STRING[n] is 2 header bytes + n, WSTRING[n] 2 header words + n words.
 */
import type { DataTypeName } from '../types';

export const MAX_DB_NUMBER = 65535;
/** Byte offsets (and timer/counter numbers) this parser accepts. */
export const MAX_OFFSET = 0xffff;
export const MAX_COUNT = 65535;
export const MAX_STRING_LENGTH = 254;
export const MAX_WSTRING_LENGTH = 16382;

const ELEMENT_BYTES: Readonly<Record<DataTypeName, number>> = Object.freeze({
  BOOL: 1, BYTE: 1, CHAR: 1, SINT: 1, USINT: 1,
  WORD: 2, INT: 2, UINT: 2, WCHAR: 2, S5TIME: 2, DATE: 2, COUNTER: 2, TIMER: 2,
  DWORD: 4, DINT: 4, UDINT: 4, REAL: 4, TIME: 4, TIME_OF_DAY: 4,
  LWORD: 8, LINT: 8, ULINT: 8, LREAL: 8, LTIME: 8, DATE_AND_TIME: 8,
  DTL: 12, STRING: 2, WSTRING: 4,
});

/** Bytes of one element; STRING/WSTRING include their length headers. */
export function elementBytes(type: DataTypeName, stringLength = 0): number {
  if (type === 'STRING') return ELEMENT_BYTES.STRING + stringLength;
  if (type === 'WSTRING') return ELEMENT_BYTES.WSTRING + 2 * stringLength;
  return ELEMENT_BYTES[type];
}

/** Bytes a tag covers from its byte offset; bits: the bytes the bits touch. */
export function tagBytes(type: DataTypeName, count: number, stringLength: number, bitOffset: number): number {
  if (type === 'BOOL') return Math.ceil((bitOffset + count) / 8);
  return elementBytes(type, stringLength) * count;
}

/** Types that start at any byte whatever width letter the address names: strings, and those wider than a double word. */
export function startsAtByte(type: DataTypeName): boolean {
  return type === 'STRING' || type === 'WSTRING' || ELEMENT_BYTES[type] > 4;
}
