/** The canonical IEC form of a tag: what the editor shows and what parses back to the same tag. */
import type { AreaName, DataTypeName, Tag } from '../types';
import { elementBytes, startsAtByte } from './sizes';

export type TagLocation = Pick<Tag, 'area' | 'dbNumber' | 'byteOffset' | 'bitOffset' | 'type' | 'count' | 'isArray' | 'stringLength'>;

const AREA_PREFIX: Readonly<Record<AreaName, string>> = Object.freeze({
  I: 'I',
  Q: 'Q',
  M: 'M',
  DB: 'DB',
  PE: 'PI',
  PA: 'PQ',
  C: 'C',
  T: 'T',
});
/** Types an IEC width letter names without an override. */
const NATURAL_WIDTH: Partial<Record<DataTypeName, string>> = Object.freeze({ BYTE: 'B', WORD: 'W', DWORD: 'D' });
const WIDTH_OF_SIZE: Readonly<Record<number, string>> = Object.freeze({ 1: 'B', 2: 'W', 4: 'D' });

function typeSpec(tag: TagLocation): string {
  const base = tag.type === 'STRING' || tag.type === 'WSTRING' ? `${tag.type}[${tag.stringLength}]` : tag.type;
  return tag.isArray ? `${base}[${tag.count}]` : base;
}

/**
 * Canonical IEC form, e.g. `DB1.DBD4:REAL`, `M0.1`, `DB1.DBB0:CHAR[10]`,
 * `PIW256`, `T3`. The override is left out when the width letter already
 * names the type; arrays, strings and 8/12-byte types sit on a B address.
 */
export function formatAddress(tag: TagLocation): string {
  if (tag.area === 'C' || tag.area === 'T') return `${tag.area}${tag.byteOffset}${tag.isArray ? `:${typeSpec(tag)}` : ''}`;
  const prefix = tag.area === 'DB' ? `DB${tag.dbNumber}.DB` : AREA_PREFIX[tag.area];
  if (tag.type === 'BOOL') {
    const spec = tag.isArray ? `:${typeSpec(tag)}` : '';
    return `${prefix}${tag.area === 'DB' ? 'X' : ''}${tag.byteOffset}.${tag.bitOffset}${spec}`;
  }
  const natural = NATURAL_WIDTH[tag.type];
  if (!tag.isArray && natural) return `${prefix}${natural}${tag.byteOffset}`;
  const width = tag.isArray || startsAtByte(tag.type) ? 'B' : WIDTH_OF_SIZE[elementBytes(tag.type)]!;
  return `${prefix}${width}${tag.byteOffset}:${typeSpec(tag)}`;
}
