/**
 * What a tag covers in PLC memory: the sizes come from the value codecs'
 * table (lib/values/types-table.ts, which depends on nothing here), and the
 * limits of what this parser accepts.
 */
import type { DataTypeName } from '../types';
import { elementByteLength, tagByteLength } from '../values/types-table';

export const MAX_DB_NUMBER = 65535;
/** Byte offsets (and timer/counter numbers) this parser accepts. */
export const MAX_OFFSET = 0xffff;
export const MAX_COUNT = 65535;
export const MAX_STRING_LENGTH = 254;
export const MAX_WSTRING_LENGTH = 16382;

/** Bytes of one element; STRING/WSTRING include their length headers (the value codecs' table). */
export const elementBytes = elementByteLength;

/** Bytes a tag covers from its byte offset; bits: the bytes the bits touch. */
export function tagBytes(type: DataTypeName, count: number, stringLength: number, bitOffset: number): number {
  return tagByteLength({ type, count, stringLength, bitOffset });
}

/** Types that start at any byte whatever width letter the address names: strings, and those wider than a double word. */
export function startsAtByte(type: DataTypeName): boolean {
  return type === 'STRING' || type === 'WSTRING' || elementByteLength(type) > 4;
}
