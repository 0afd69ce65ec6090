/**
 * The S7 tag model as a driver's TagSyntax (lib/link/driver.ts): parsing,
 * and the areas and spans write allow-lists match. S7 and FETCH/WRITE use it
 * (FETCH/WRITE with its own reach checks on top).
 */
import type { TagSyntax } from '../link/driver';
import type { Tag } from '../types';
import { parseAddress } from './parse';

/** Allow-list entries naming a whole area: "DB10", "M", "PE" (a DB number without leading zeros). */
const AREA_ENTRY = /^(DB\d+|[IQMCT]|PE|PA)$/;

function areaOf(tag: Tag): string {
  return tag.area === 'DB' ? `DB${tag.dbNumber}` : tag.area;
}

/** Where a tag lies inside its area, as every driver's tags say it. */
type Span = Pick<Tag, 'type' | 'byteOffset' | 'bitOffset' | 'count' | 'byteLength'>;

const firstBit = (t: Span) => t.byteOffset * 8 + (t.type === 'BOOL' ? t.bitOffset : 0);
const bitLength = (t: Span) => (t.type === 'BOOL' ? t.count : t.byteLength * 8);

/** True when `inner`'s bits lie wholly inside `outer`'s (both in the same area). */
export function spanContains(outer: Span, inner: Span): boolean {
  return firstBit(inner) >= firstBit(outer) && firstBit(inner) + bitLength(inner) <= firstBit(outer) + bitLength(outer);
}

export const S7_TAG_SYNTAX: TagSyntax<Tag> = Object.freeze({
  parse: (address: string) => parseAddress(address),
  areaOf,
  allowArea: (entry: string) => (AREA_ENTRY.test(entry) ? entry.replace(/^DB0+(?=\d)/, 'DB') : undefined),
  contains(outer: Tag, inner: Tag): boolean {
    return areaOf(outer) === areaOf(inner) && spanContains(outer, inner);
  },
});
