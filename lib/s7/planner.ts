/**
 * The S7 request planner (pure): packs tags into the fewest PDUs the
 * negotiated size allows. Reads: nearby tags of one area are merged into one
 * item when the gap costs less than a new item, items too large for one PDU
 * are split, and items are packed first-fit-decreasing under both limits
 * (request: 12 + 12·n; response: 14 + Σ(4 + len + fill)). Writes: one item
 * per tag (bits as BIT items, which the CPU writes atomically), split and
 * packed likewise (request: 12 + Σ(12 + 4 + len + fill); response: 14 + n).
 */
import type { Tag } from '../types';
import { writeSpan } from '../values';
import { AREA_CODES, DataTransportSize, S7Area, TransportSize } from './constants';
import type { S7Item, S7WriteItem } from './codec';

/** Bytes of S7 header + function + count in a job / an ack-data. */
const REQUEST_BASE = 12;
const RESPONSE_BASE = 14;
const ITEM = 12;
const DATA_HEADER = 4;
/** Merging across a gap is worth it while the gap is smaller than a new item costs (12 + 4 + a fill byte). */
const MERGE_GAP = ITEM + DATA_HEADER + 1;

/** A contiguous byte range of one area, read as one or more items. */
export interface ReadRange {
  area: S7Area;
  dbNumber: number;
  /** Byte offset (C/T: first number). */
  start: number;
  /** Bytes (C/T: 2 per number). */
  length: number;
  /** Indexes into the planned tags. */
  tags: number[];
}

export interface ReadChunk {
  range: number;
  /** Byte offset of this chunk inside its range. */
  offset: number;
  item: S7Item;
  /** Bytes expected back. */
  length: number;
}

export interface ReadPlan {
  ranges: ReadRange[];
  /** PDUs, each a list of chunks. */
  pdus: ReadChunk[][];
}

export interface WriteChunk {
  /** Index of the tag in the write request. */
  tag: number;
  item: S7WriteItem;
}

export interface WritePlan {
  pdus: WriteChunk[][];
}

function areaOf(tag: Tag): S7Area {
  return AREA_CODES[tag.area];
}

function isCounterOrTimer(area: S7Area): boolean {
  return area === S7Area.C || area === S7Area.T;
}

/** Largest data a single read item can return in one PDU. */
export function maxReadItemData(pduSize: number): number {
  return pduSize - RESPONSE_BASE - DATA_HEADER;
}

/** Largest data a single write item can carry in one PDU. */
export function maxWriteItemData(pduSize: number): number {
  return pduSize - REQUEST_BASE - ITEM - DATA_HEADER;
}

/** Merges the tags' byte ranges (same area, gap under the cost of an item, never past one PDU's item). */
export function mergeRanges(tags: readonly Tag[], pduSize: number, merge = true): ReadRange[] {
  const maxItem = maxReadItemData(pduSize);
  const order = tags.map((_, i) => i);
  const key = (t: Tag) => areaOf(t) * 0x10000 + t.dbNumber;
  order.sort((a, b) => key(tags[a]!) - key(tags[b]!) || tags[a]!.byteOffset - tags[b]!.byteOffset);
  const ranges: ReadRange[] = [];
  let current: ReadRange | undefined;
  for (const i of order) {
    const t = tags[i]!;
    const area = areaOf(t);
    const ct = isCounterOrTimer(area);
    const start = ct ? t.byteOffset : t.byteOffset;
    const length = ct ? 2 * t.count : t.byteLength;
    const unit = ct ? 2 : 1; // C/T ranges count numbers, 2 bytes each
    if (current && merge && current.area === area && current.dbNumber === t.dbNumber) {
      const end = current.start + current.length / unit;
      const newEnd = Math.max(end, start + length / unit);
      const gap = (start - end) * unit;
      if (gap <= MERGE_GAP && (newEnd - current.start) * unit <= Math.max(maxItem, current.length)) {
        current.length = (newEnd - current.start) * unit;
        current.tags.push(i);
        continue;
      }
    }
    current = { area, dbNumber: t.dbNumber, start, length, tags: [i] };
    ranges.push(current);
  }
  return ranges;
}

/** Plans a read of `tags` at a PDU size. `merge = false` reads every tag on its own (used to isolate a failing tag). */
export function planRead(tags: readonly Tag[], pduSize: number, merge = true): ReadPlan {
  const ranges = mergeRanges(tags, pduSize, merge);
  const maxItem = maxReadItemData(pduSize);
  const chunks: ReadChunk[] = [];
  ranges.forEach((r, index) => {
    const ct = isCounterOrTimer(r.area);
    // C/T items count numbers; keep chunks on number boundaries.
    const step = ct ? maxItem - (maxItem % 2) : maxItem;
    for (let offset = 0; offset < r.length; offset += step) {
      const length = Math.min(step, r.length - offset);
      const item: S7Item = ct
        ? { area: r.area, dbNumber: 0, transportSize: r.area === S7Area.C ? TransportSize.COUNTER : TransportSize.TIMER, count: length / 2, address: r.start + offset / 2 }
        : { area: r.area, dbNumber: r.dbNumber, transportSize: TransportSize.BYTE, count: length, address: (r.start + offset) * 8 };
      chunks.push({ range: index, offset, item, length });
    }
  });
  return { ranges, pdus: pack(chunks, (c) => c.length, pduSize, 'read') };
}

/**
 * First-fit decreasing under both the request and the response limit.
 * Read: request 12 + 12n, response 14 + Σ(4 + len + fill). Write: request
 * 12 + Σ(16 + len + fill), response 14 + n.
 */
function pack<C>(chunks: C[], lengthOf: (c: C) => number, pduSize: number, kind: 'read' | 'write'): C[][] {
  const sorted = [...chunks].sort((a, b) => lengthOf(b) - lengthOf(a));
  const bins: { chunks: C[]; request: number; response: number; odd: boolean }[] = [];
  for (const c of sorted) {
    const len = lengthOf(c);
    let placed = false;
    for (const bin of bins) {
      // A fill byte is needed after the previous item when its data was odd.
      const fill = bin.odd ? 1 : 0;
      const request = kind === 'read' ? bin.request + ITEM : bin.request + ITEM + DATA_HEADER + len + fill;
      const response = kind === 'read' ? bin.response + DATA_HEADER + len + fill : bin.response + 1;
      if (request <= pduSize && response <= pduSize) {
        bin.chunks.push(c);
        bin.request = request;
        bin.response = response;
        bin.odd = len % 2 === 1;
        placed = true;
        break;
      }
    }
    if (!placed) {
      bins.push({
        chunks: [c],
        request: kind === 'read' ? REQUEST_BASE + ITEM : REQUEST_BASE + ITEM + DATA_HEADER + len,
        response: kind === 'read' ? RESPONSE_BASE + DATA_HEADER + len : RESPONSE_BASE + 1,
        odd: len % 2 === 1,
      });
    }
  }
  return bins.map((b) => b.chunks);
}

/**
 * A lower bound on the PDUs any packing needs to read `tags` at `pduSize`,
 * given the same merged ranges: the response bytes over the payload one PDU
 * carries, and the items over the items one request carries.
 */
export function lowerBoundPdus(tags: readonly Tag[], pduSize: number): number {
  if (tags.length === 0) return 0;
  const ranges = mergeRanges(tags, pduSize);
  const maxItem = maxReadItemData(pduSize);
  let bytes = 0;
  let items = 0;
  for (const r of ranges) {
    const n = Math.ceil(r.length / maxItem);
    items += n;
    bytes += r.length + DATA_HEADER * n;
  }
  const byBytes = Math.ceil(bytes / (pduSize - RESPONSE_BASE));
  const byItems = Math.ceil(items / Math.floor((pduSize - REQUEST_BASE) / ITEM));
  return Math.max(byBytes, byItems);
}

/**
 * Plans a write. Values are encoded here (throws the tag's ValueError, which
 * the client turns into that tag's result before calling).
 */
export function planWrite(items: readonly { tag: Tag; value: unknown }[], pduSize: number): WritePlan {
  const maxData = maxWriteItemData(pduSize);
  const chunks: WriteChunk[] = [];
  items.forEach(({ tag, value }, index) => {
    const area = areaOf(tag);
    if (tag.type === 'BOOL') {
      const bits = tag.isArray ? (value as boolean[]) : [value as boolean];
      bits.forEach((bit, i) => {
        const n = tag.bitOffset + i;
        chunks.push({
          tag: index,
          item: { area, dbNumber: tag.dbNumber, transportSize: TransportSize.BIT, count: 1, address: (tag.byteOffset + (n >> 3)) * 8 + (n & 7), dataTransportSize: DataTransportSize.BIT, data: Buffer.of(bit ? 1 : 0) },
        });
      });
      return;
    }
    const { start, data } = writeSpan(tag, value);
    if (isCounterOrTimer(area)) {
      const ts = area === S7Area.C ? TransportSize.COUNTER : TransportSize.TIMER;
      for (let o = 0; o < data.length; o += maxData - (maxData % 2)) {
        const part = data.subarray(o, o + maxData - (maxData % 2));
        chunks.push({ tag: index, item: { area, dbNumber: 0, transportSize: ts, count: part.length / 2, address: tag.byteOffset + o / 2, dataTransportSize: DataTransportSize.OCTET_STRING, data: part } });
      }
      return;
    }
    for (let o = 0; o < data.length; o += maxData) {
      const part = data.subarray(o, o + maxData);
      chunks.push({
        tag: index,
        item: { area, dbNumber: tag.dbNumber, transportSize: TransportSize.BYTE, count: part.length, address: (tag.byteOffset + start + o) * 8, dataTransportSize: DataTransportSize.BYTE, data: part },
      });
    }
  });
  return { pdus: pack(chunks, (c) => c.item.data.length, pduSize, 'write') };
}
