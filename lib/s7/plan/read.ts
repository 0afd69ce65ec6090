/**
 * Read planning: which Read Var items go into which PDU.
 *
 * Tags are sorted by area and address; tags whose bytes overlap are
 * one "atom" that is never cut (a value is read in one piece, so it is never
 * torn between two PLC cycles) unless it is larger than one item can carry
 * (STRING[254] at PDU 240), then it is cut into chunks and reassembled.
 * Atoms are filled into PDUs in address order, bridging the gap to the
 * previous item when it is small, opening a new item otherwise; several gap
 * thresholds are tried (including the 16 bytes a new item costs). Another
 * draft cuts the atoms into runs, each as long as one PDU holds, laid out
 * exactly (SegmentLayout: bridge or split each gap, fill bytes included).
 * A last draft leaves address order (packCover): the cheapest cover of the
 * atoms by the items fewer PDUs could carry, packed into those PDUs; it is
 * kept only when it needs fewer PDUs. The plan with the fewest PDUs, then the
 * fewest bytes on the wire, wins: plans are cached, so this runs once per tag
 * list.
 */
import type { Tag } from '../../types';
import { READ_ITEM, S7Area, TransportSize, VAR_REQUEST_BASE } from '../constants';
import { atomsOf, spansOf, type Atom } from './atoms';
import { pack, wireBytes, type Draft, type DraftItem } from './draft';
import { packCover } from './draft-cover';
import { packSegments } from './draft-segments';
import { checkPduSize, maxReadItems, type PlanOptions } from './limits';

/** Gap thresholds tried by planRead; 16 = the 12 + 4 bytes a new item costs. */
const GAP_THRESHOLDS = [0, 3, 5, 8, 16, 32, 64, 128];

/** A Read Var item, shaped like the codec's request item (area, dbNumber, transportSize, count, address). */
export interface PlannedReadItem {
  area: number;
  dbNumber: number;
  transportSize: number;
  /** Elements of transportSize (bytes, or counters/timers). */
  count: number;
  /** Bit address (byte × 8) or, for C/T, the first counter/timer number. */
  address: number;
  /** Bytes the PLC returns for this item. */
  length: number;
}

export interface ReadPdu {
  items: PlannedReadItem[];
  /** S7 bytes of the request and of the expected response (without TPKT/COTP). */
  requestSize: number;
  responseSize: number;
}

/** One piece of a tag: `length` bytes at `offset` in an item's data are the tag's bytes from `at`. */
export interface TagSlice {
  pdu: number;
  item: number;
  offset: number;
  length: number;
  at: number;
}

/**
 * Where every tag's pieces lie, flat: tag t's pieces are start[t] …
 * start[t + 1] − 1, each `length` bytes at `offset` in item `item` of PDU
 * `pdu`, being the tag's bytes from `at`. About 24 bytes per tag, for as long
 * as the plan is cached (TagSlice objects in arrays cost ~120).
 */
export interface TagPieces {
  start: Int32Array;
  pdu: Int32Array;
  item: Int32Array;
  offset: Int32Array;
  length: Int32Array;
  at: Int32Array;
}

export interface ReadPlan {
  readonly pduSize: number;
  /** Items per PDU the plan was made for (maxReadItems of its PDU size and item limit). */
  readonly maxItems: number;
  /** false when every tag is its own item (PlanOptions.merge). */
  readonly merged: boolean;
  readonly pdus: ReadPdu[];
  /** Per tag (in the order given): its pieces, in order of `at`; one piece unless the tag was split. */
  readonly pieces: TagPieces;
  /** The pieces as objects per tag (made on first use, for diagnostics). */
  readonly slices: TagSlice[][];
  /** Per tag: the bytes it covers. */
  readonly tagLengths: number[];
}

class PlanOfPieces implements ReadPlan {
  private made: TagSlice[][] | undefined;

  constructor(
    readonly pduSize: number,
    readonly maxItems: number,
    readonly merged: boolean,
    readonly pdus: ReadPdu[],
    readonly pieces: TagPieces,
    readonly tagLengths: number[],
  ) {}

  get slices(): TagSlice[][] {
    return (this.made ??= Array.from({ length: this.tagLengths.length }, (_, t) => slicesOf(this.pieces, t)));
  }
}

/** Tag t's pieces as objects. */
function slicesOf(pieces: TagPieces, t: number): TagSlice[] {
  const out: TagSlice[] = [];
  for (let k = pieces.start[t]!; k < pieces.start[t + 1]!; k++) {
    out.push({ pdu: pieces.pdu[k]!, item: pieces.item[k]!, offset: pieces.offset[k]!, length: pieces.length[k]!, at: pieces.at[k]! });
  }
  return out;
}

/** Plans a read of `tags` (in the order given) at a negotiated PDU size. Throws only for an unusable PDU size or area. */
export function planRead(tags: readonly Tag[], pduSize: number, options: PlanOptions = {}): ReadPlan {
  checkPduSize(pduSize);
  const merge = options.merge ?? true;
  const maxItems = maxReadItems(pduSize, options.maxItems);
  const atoms = atomsOf(spansOf(tags), merge);
  let best: Draft | undefined;
  let bestBytes = Infinity;
  const drafts = (merge ? GAP_THRESHOLDS : [-1]).map((gap) => () => pack(atoms, pduSize, maxItems, gap, merge));
  if (merge) drafts.push(() => packSegments(atoms, pduSize, maxItems));
  for (const make of drafts) {
    const draft = make();
    const bytes = wireBytes(draft);
    if (!best || draft.bins.length < best.bins.length || (draft.bins.length === best.bins.length && bytes < bestBytes)) {
      best = draft;
      bestBytes = bytes;
    }
  }
  // Out of address order, only where that needs fewer PDUs than the best so far.
  if (merge && best) best = packCover(atoms, pduSize, maxItems, best.bins.length) ?? best;
  return finish(tags, pduSize, maxItems, merge, atoms, best ?? { bins: [], placements: [] });
}

function finish(tags: readonly Tag[], pduSize: number, maxItems: number, merge: boolean, atoms: readonly Atom[], draft: Draft): ReadPlan {
  const where = new Map<DraftItem, { pdu: number; item: number }>();
  const pdus: ReadPdu[] = draft.bins.map((bin, pdu) => ({
    items: bin.items.map((d, item) => {
      where.set(d, { pdu, item });
      return readItem(d);
    }),
    requestSize: VAR_REQUEST_BASE + READ_ITEM * bin.items.length,
    responseSize: bin.response,
  }));
  const perTag: TagSlice[][] = tags.map(() => []);
  const tagLengths: number[] = new Array<number>(tags.length).fill(0);
  let count = 0;
  atoms.forEach((atom, a) => {
    const pieces = draft.placements[a]!;
    for (const span of atom.spans) {
      tagLengths[span.tag] = span.end - span.start;
      for (const { item } of pieces) {
        const from = Math.max(span.start, item.start);
        const to = Math.min(span.end, item.end);
        if (from >= to) continue;
        const at = where.get(item)!;
        perTag[span.tag]!.push({ pdu: at.pdu, item: at.item, offset: from - item.start, length: to - from, at: from - span.start });
        count++;
      }
    }
  });
  const pieces: TagPieces = {
    start: new Int32Array(tags.length + 1),
    pdu: new Int32Array(count),
    item: new Int32Array(count),
    offset: new Int32Array(count),
    length: new Int32Array(count),
    at: new Int32Array(count),
  };
  let k = 0;
  perTag.forEach((list, t) => {
    pieces.start[t] = k;
    for (const p of list) {
      pieces.pdu[k] = p.pdu;
      pieces.item[k] = p.item;
      pieces.offset[k] = p.offset;
      pieces.length[k] = p.length;
      pieces.at[k] = p.at;
      k++;
    }
  });
  pieces.start[tags.length] = k;
  return new PlanOfPieces(pduSize, maxItems, merge, pdus, pieces, tagLengths);
}

function readItem(d: DraftItem): PlannedReadItem {
  const length = d.end - d.start;
  if (d.unit === 2) {
    const transportSize = d.area === S7Area.C ? TransportSize.COUNTER : TransportSize.TIMER;
    return { area: d.area, dbNumber: 0, transportSize, count: length / 2, address: d.start / 2, length };
  }
  return { area: d.area, dbNumber: d.dbNumber, transportSize: TransportSize.BYTE, count: length, address: d.start * 8, length };
}

/**
 * A tag's bytes from the items' answers: `data[pdu][item]` is the data of
 * that item. Returns the buffer and the offset of the tag's first byte in it
 * (no copy unless the tag was split across items).
 */
export function tagData(plan: ReadPlan, tag: number, data: readonly (readonly (Buffer | undefined)[])[]): { data: Buffer; offset: number } {
  const p = plan.pieces;
  const first = p.start[tag]!;
  const end = p.start[tag + 1]!;
  if (end - first === 1) return { data: data[p.pdu[first]!]![p.item[first]!]!, offset: p.offset[first]! };
  const out = Buffer.alloc(plan.tagLengths[tag]!);
  for (let k = first; k < end; k++) data[p.pdu[k]!]![p.item[k]!]!.copy(out, p.at[k]!, p.offset[k]!, p.offset[k]! + p.length[k]!);
  return { data: out, offset: 0 };
}
