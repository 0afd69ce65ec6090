/**
 * The FETCH/WRITE planner: which bytes of which ORG area each job moves.
 * Pure (no sockets, timers or events): tags and values in, byte ranges and
 * jobs out, so the client only sends what is planned here.
 *
 * Bytes are counted from the area's start (C and T: 2 bytes per number).
 * Where the area's unit is a word (C, T, and DB unless the endpoint says
 * dbUnit=byte), a job starts and ends on an even byte.
 */
import { AddressError } from '../errors';
import type { Tag } from '../types';
import { encodeInto, writeSpan } from '../values';
import { MAX_DATA, ORG_BY_AREA, ORG_RANGES, Org, byteLength } from './codec';

/** How the endpoint counts DB addresses on the wire: words (the CP's default) or bytes. */
export type DbUnit = 'word' | 'byte';

/**
 * Tags of one area closer than this are fetched as one job: a CP answers a
 * job in milliseconds, while 1 KiB more data costs under a millisecond.
 */
export const MERGE_GAP = 1024;

/** Where a job's bytes are: the area, its DB number (DB only) and the first byte. */
export interface ByteAddress {
  org: Org;
  dbNumber: number;
  /** Bytes from the area's start (C/T: 2 per number). */
  start: number;
}

/** A byte range of one ORG area, fetched or written as one or more jobs. */
export interface ByteRange extends ByteAddress {
  length: number;
}

/** The bytes of merged tags, with the tags' indexes. */
export interface Range extends ByteRange {
  tags: number[];
}

/** A read's plan: the tags a fetch cannot read, and the ranges that fetch the others. */
export interface ReadPlan {
  /** Indexes of the tags a fetch cannot read (PA, the output modules). */
  unreadable: number[];
  ranges: Range[];
}

/**
 * How one tag's value is written: `direct` bytes on unit boundaries, or
 * `modify` (read-modify-write) of the enclosing units, where `change` puts
 * the value into the fetched bytes at `offset`.
 */
export type WritePlan =
  { kind: 'direct'; at: ByteAddress; data: Buffer } | { kind: 'modify'; range: ByteRange; change: (buf: Buffer, offset: number) => void };

/** Bytes of an area reachable by FETCH/WRITE. */
function areaBytes(org: Org, dbUnit: DbUnit): number {
  const r = ORG_RANGES[org]!;
  if (org === Org.DB) return dbUnit === 'word' ? 2 * (r.maxStart + 1) : 0x10000;
  if (org === Org.C || org === Org.T) return 2 * (r.maxStart + 1);
  return r.maxStart + 1;
}

/** Where a tag lies, [first byte, end) from the area start (C/T: 2 bytes per number). */
export function byteSpan(tag: Tag): [number, number] {
  if (tag.area === 'C' || tag.area === 'T') return [2 * tag.byteOffset, 2 * (tag.byteOffset + tag.count)];
  return [tag.byteOffset, tag.byteOffset + tag.byteLength];
}

/** Bytes must start/end on this boundary for the area's unit. */
function granule(org: Org, dbUnit: DbUnit): number {
  return (org === Org.DB && dbUnit === 'word') || org === Org.C || org === Org.T ? 2 : 1;
}

/** The most bytes one job may carry: the ORG table's length range and the 64 KiB frame limit. */
export function maxJobBytes(org: Org, dbUnit: DbUnit): number {
  const r = ORG_RANGES[org]!;
  const bytes = byteLength(org, r.maxLength, dbUnit);
  return Math.min(bytes, MAX_DATA - (MAX_DATA % 2));
}

/**
 * Refuses, with an AddressError naming the address, a tag FETCH/WRITE cannot
 * reach (the ORG table: docs/protocols.md, "ORG areas and units").
 */
export function checkReach(tag: Tag, dbUnit: DbUnit): void {
  const org = ORG_BY_AREA[tag.area];
  const range = ORG_RANGES[org]!;
  if (org === Org.DB && (tag.dbNumber < 1 || tag.dbNumber > 255)) {
    throw new AddressError(tag.address, `DB${tag.dbNumber} cannot be reached by FETCH/WRITE (ORG 1 takes DB 1..255)`);
  }
  const [start, end] = byteSpan(tag);
  const limit = areaBytes(org, dbUnit);
  if (end > limit) {
    const unit = org === Org.C || org === Org.T ? ` (${range.name} 0..${range.maxStart})` : ` (${range.name} bytes 0..${limit - 1})`;
    throw new AddressError(tag.address, `${start >= limit ? 'starts' : 'ends'} beyond what FETCH/WRITE reaches${unit}`);
  }
}

/** Sorts tags by area and offset, aligns to the area's unit, and merges ranges closer than a round trip is worth. */
export function mergeRanges(tags: readonly Tag[], dbUnit: DbUnit): Range[] {
  const order = tags.map((_, i) => i);
  const key = (t: Tag) => ORG_BY_AREA[t.area] * 0x10000 + t.dbNumber;
  order.sort((a, b) => key(tags[a]!) - key(tags[b]!) || byteSpan(tags[a]!)[0] - byteSpan(tags[b]!)[0]);
  const ranges: Range[] = [];
  let current: Range | undefined;
  for (const i of order) {
    const t = tags[i]!;
    const org = ORG_BY_AREA[t.area];
    const g = granule(org, dbUnit);
    const [s, e] = byteSpan(t);
    const start = s - (s % g);
    const end = e + ((g - (e % g)) % g);
    if (current && current.org === org && current.dbNumber === t.dbNumber) {
      const curEnd = current.start + current.length;
      const newEnd = Math.max(curEnd, end);
      if (start - curEnd <= MERGE_GAP && newEnd - current.start <= Math.max(maxJobBytes(org, dbUnit), current.length)) {
        current.length = newEnd - current.start;
        current.tags.push(i);
        continue;
      }
    }
    current = { org, dbNumber: t.dbNumber, start, length: end - start, tags: [i] };
    ranges.push(current);
  }
  return ranges;
}

/** The fetch ranges of a tag list (they depend on the tags and the endpoint's DB unit only). */
export function planRead(tags: readonly Tag[], dbUnit: DbUnit): ReadPlan {
  const unreadable: number[] = [];
  const readable: number[] = [];
  tags.forEach((tag, i) => (tag.area === 'PA' ? unreadable : readable).push(i));
  const ranges = mergeRanges(
    readable.map((i) => tags[i]!),
    dbUnit,
  ).map((r) => ({ ...r, tags: r.tags.map((k) => readable[k]!) }));
  return { unreadable, ranges };
}

/** A byte range cut into the jobs that carry it, each within maxJobBytes, in order. */
export function splitJobs(range: ByteRange, dbUnit: DbUnit): ByteRange[] {
  const { org, dbNumber, start, length } = range;
  const max = maxJobBytes(org, dbUnit);
  if (length <= max) return [range];
  const jobs: ByteRange[] = [];
  for (let o = 0; o < length; o += max) jobs.push({ org, dbNumber, start: start + o, length: Math.min(max, length - o) });
  return jobs;
}

/** A job's start and length as the request header counts them: in the area's unit (words or bytes; C/T: numbers). */
export function wireUnits(range: ByteRange, dbUnit: DbUnit): { start: number; length: number } {
  const wordUnits = granule(range.org, dbUnit) === 2;
  return { start: wordUnits ? range.start / 2 : range.start, length: wordUnits ? range.length / 2 : range.length };
}

/** The whole units around a changed byte range: what a read-modify-write fetches and writes back. */
export function enclosingUnits(changed: ByteRange, dbUnit: DbUnit): ByteRange {
  const g = granule(changed.org, dbUnit);
  const from = changed.start;
  const to = from + changed.length;
  const start = from - (from % g);
  const end = to + ((g - (to % g)) % g);
  return { org: changed.org, dbNumber: changed.dbNumber, start, length: end - start };
}

/**
 * How to write one validated value: bits and bytes off the area's unit are a
 * read-modify-write, the rest goes out as it is (a STRING only its header and
 * characters, as writeSpan gives them).
 */
export function planWrite(tag: Tag, value: unknown, dbUnit: DbUnit): WritePlan {
  const org = ORG_BY_AREA[tag.area];
  if (tag.type === 'BOOL') {
    const range = { org, dbNumber: tag.dbNumber, start: tag.byteOffset, length: tag.byteLength };
    return { kind: 'modify', range, change: (buf, offset) => encodeInto(tag, value, buf, offset) };
  }
  const span = writeSpan(tag, value);
  if (tag.area === 'C' || tag.area === 'T')
    return { kind: 'direct', at: { org, dbNumber: tag.dbNumber, start: 2 * tag.byteOffset }, data: span.data };
  const g = granule(org, dbUnit);
  const at = { org, dbNumber: tag.dbNumber, start: tag.byteOffset + span.start };
  const data = span.data;
  if (at.start % g === 0 && data.length % g === 0) return { kind: 'direct', at, data };
  return { kind: 'modify', range: { ...at, length: data.length }, change: (buf, offset) => data.copy(buf, offset) };
}
