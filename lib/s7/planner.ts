/**
 * The S7 request planner (pure): which Read Var / Write Var items go into
 * which PDU at the negotiated PDU size.
 *
 * Sizes (S7 header 10 + function and item count 2; docs/protocols.md, "Sizes and limits"):
 *   read request   12 + 12·items                       ≤ PDU
 *   read response  14 + Σ(4 + len + fill)              ≤ PDU
 *   write request  12 + 12·items + Σ(4 + len + fill)   ≤ PDU
 *   write response 14 + items                          ≤ PDU
 * where fill is one byte after odd-length data, except after the last item.
 *
 * Reads: tags are sorted by area and address; tags whose bytes overlap are
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
import { PlcError, toPlcError } from '../errors';
import type { Tag } from '../types';
import { validateValue, writeSpan } from '../values';
import { AREA_CODES, DataTransportSize, MAX_ITEMS, S7Area, TransportSize } from './constants';

const REQUEST_BASE = 12;
const RESPONSE_BASE = 14;
const REQUEST_ITEM = 12;
const DATA_HEADER = 4;
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

export interface PlanOptions {
  /** false: every tag is its own item (used to isolate a failing tag from good neighbours). Default true. */
  merge?: boolean;
  /** At most this many items per PDU (the peer's limit, e.g. 20 for snap7's server). Default 255, the protocol's. */
  maxItems?: number;
}

/** Bytes one read item can return in a PDU of `pduSize`. */
export function maxReadItemData(pduSize: number): number {
  return pduSize - RESPONSE_BASE - DATA_HEADER;
}

/** Bytes one write item can carry in a PDU of `pduSize`. */
export function maxWriteItemData(pduSize: number): number {
  return pduSize - REQUEST_BASE - REQUEST_ITEM - DATA_HEADER;
}

/** Items one read request can carry. */
export function maxReadItems(pduSize: number, maxItems = MAX_ITEMS): number {
  return Math.max(1, Math.min(maxItems, MAX_ITEMS, Math.floor((pduSize - REQUEST_BASE) / REQUEST_ITEM)));
}

// ------------------------------------------------------------------ geometry

/** Where a tag lives in the planner's byte space: C/T numbers are 2 bytes each. */
interface Span {
  tag: number;
  group: number;
  area: number;
  dbNumber: number;
  /** 2 for counters/timers (items count numbers), else 1. */
  unit: number;
  start: number;
  end: number;
}

interface Atom {
  group: number;
  area: number;
  dbNumber: number;
  unit: number;
  start: number;
  end: number;
  spans: Span[];
}

function isCounterOrTimer(area: number): boolean {
  return area === S7Area.C || area === S7Area.T;
}

function areaCode(tag: Tag): number {
  const code = AREA_CODES[tag.area];
  if (code === undefined) throw new PlcError('INVALID_ADDRESS', `${tag.address}: area ${tag.area} cannot be read over S7`, { tag: tag.address });
  return code;
}

function spanOf(tag: Tag, index: number): Span {
  const area = areaCode(tag);
  const unit = isCounterOrTimer(area) ? 2 : 1;
  const start = tag.byteOffset * unit;
  const length = unit === 2 ? 2 * tag.count : tag.byteLength;
  return { tag: index, group: area * 0x10000 + tag.dbNumber, area, dbNumber: tag.dbNumber, unit, start, end: start + length };
}

function spansOf(tags: readonly Tag[]): Span[] {
  const spans = tags.map(spanOf);
  spans.sort((a, b) => a.group - b.group || a.start - b.start || b.end - a.end);
  return spans;
}

/** Overlapping tags form one atom; with merge = false every tag is its own atom. */
function atomsOf(spans: readonly Span[], merge: boolean): Atom[] {
  const atoms: Atom[] = [];
  let current: Atom | undefined;
  for (const s of spans) {
    if (merge && current && current.group === s.group && s.start < current.end) {
      if (s.end > current.end) current.end = s.end;
      current.spans.push(s);
      continue;
    }
    current = { group: s.group, area: s.area, dbNumber: s.dbNumber, unit: s.unit, start: s.start, end: s.end, spans: [s] };
    atoms.push(current);
  }
  return atoms;
}

// ------------------------------------------------------------------ packing

interface DraftItem {
  group: number;
  area: number;
  dbNumber: number;
  unit: number;
  start: number;
  end: number;
}

interface Bin {
  items: DraftItem[];
  /** 14 + Σ(4 + len) + fills between items, with the last item counted without fill. */
  response: number;
}

interface Draft {
  bins: Bin[];
  /** Per atom: the items it lies in (one, or the chunks of a split atom), with their bin. */
  placements: { bin: Bin; item: DraftItem }[][];
}

function fillAfter(bin: Bin): number {
  const last = bin.items[bin.items.length - 1];
  return last && (last.end - last.start) % 2 === 1 ? 1 : 0;
}

function pack(atoms: readonly Atom[], pduSize: number, maxItems: number, gapThreshold: number, merge: boolean): Draft {
  const maxItem = maxReadItemData(pduSize);
  const bins: Bin[] = [];
  const placements: Draft['placements'] = [];
  let current: Bin | undefined;

  const openBin = (): Bin => {
    current = { items: [], response: RESPONSE_BASE };
    bins.push(current);
    return current;
  };
  const newItemFits = (bin: Bin, length: number) =>
    bin.items.length < maxItems && bin.response + fillAfter(bin) + DATA_HEADER + length <= pduSize;
  const addItem = (bin: Bin, a: { group: number; area: number; dbNumber: number; unit: number }, start: number, end: number): DraftItem => {
    const item: DraftItem = { group: a.group, area: a.area, dbNumber: a.dbNumber, unit: a.unit, start, end };
    bin.response += fillAfter(bin) + DATA_HEADER + (end - start);
    bin.items.push(item);
    return item;
  };
  /** The last item of the current bin, if `atom` could extend it (same area, ahead of it). */
  const bridgeable = (atom: Atom): DraftItem | undefined => {
    if (!merge || !current) return undefined;
    const last = current.items[current.items.length - 1];
    if (!last || last.group !== atom.group || atom.start < last.end) return undefined;
    return current.response + (atom.end - last.end) <= pduSize ? last : undefined;
  };
  const extend = (item: DraftItem, end: number) => {
    current!.response += end - item.end;
    item.end = end;
  };

  for (const atom of atoms) {
    const length = atom.end - atom.start;
    if (length > maxItem) {
      placements.push(placeHuge(atom));
      continue;
    }
    const last = bridgeable(atom);
    if (last && atom.start - last.end <= gapThreshold) {
      extend(last, atom.end);
      placements.push([{ bin: current!, item: last }]);
      continue;
    }
    const bin = current && newItemFits(current, length) ? current : bins.find((b) => newItemFits(b, length));
    if (bin) {
      placements.push([{ bin, item: addItem(bin, atom, atom.start, atom.end) }]);
      continue;
    }
    if (last) {
      // The PDU ran out of items before bytes: bridging a larger gap still fits.
      extend(last, atom.end);
      placements.push([{ bin: current!, item: last }]);
      continue;
    }
    const fresh = openBin();
    placements.push([{ bin: fresh, item: addItem(fresh, atom, atom.start, atom.end) }]);
  }
  return { bins, placements };

  /** An atom larger than one item: the first chunk fills what the current PDU has left, then full chunks. */
  function placeHuge(atom: Atom): { bin: Bin; item: DraftItem }[] {
    const out: { bin: Bin; item: DraftItem }[] = [];
    const even = (n: number) => n - (n % atom.unit);
    let at = atom.start;
    if (current && current.items.length < maxItems) {
      const room = even(pduSize - current.response - fillAfter(current) - DATA_HEADER);
      if (room >= Math.max(atom.unit, 16)) {
        out.push({ bin: current, item: addItem(current, atom, at, at + room) });
        at += room;
      }
    }
    while (at < atom.end) {
      const length = Math.min(even(maxItem), atom.end - at);
      const bin = (length < even(maxItem) && bins.find((b) => newItemFits(b, length))) || openBin();
      out.push({ bin, item: addItem(bin, atom, at, at + length) });
      at += length;
    }
    return out;
  }
}

/**
 * One step of the bridge-or-split program (SegmentLayout, the lower bound):
 * from `prev` to `next` for atom b after atom a. A state is parity × w +
 * items (the open item's length parity, items used so far, 1 ≤ items ≤
 * kMax); its value is the response bytes so far, the fill bytes of closed
 * items included. Bridging the gap keeps the item count; starting an item
 * (while items < maxItems) pays the open item's fill, a header and the atom.
 * `from`, if given, gets each new state's previous state, negated when the
 * atom started an item.
 */
function bridgeOrSplit(prev: Float64Array, next: Float64Array, w: number, kMax: number, maxItems: number, a: Atom, b: Atom, from?: Int32Array): void {
  const len = b.end - b.start;
  const gap = b.start - a.end;
  const bridge = a.group === b.group && gap >= 0;
  for (let p = 0; p < 2; p++) {
    for (let k = 1; k <= kMax; k++) {
      const cost = prev[p * w + k]!;
      if (cost === Infinity) continue;
      if (bridge) {
        const q = (p + gap + len) & 1;
        if (cost + gap + len < next[q * w + k]!) {
          next[q * w + k] = cost + gap + len;
          if (from) from[q * w + k] = p * w + k;
        }
      }
      if (k < maxItems) {
        const q = len & 1;
        if (cost + p + DATA_HEADER + len < next[q * w + k + 1]!) {
          next[q * w + k + 1] = cost + p + DATA_HEADER + len;
          if (from) from[q * w + k + 1] = -(p * w + k);
        }
      }
    }
  }
}

/**
 * The bridge-or-split program over all the atoms with at most `most` items:
 * the last row, and with `choices` each step's choices (for startsOf).
 */
function coverProgram(atoms: readonly Atom[], most: number, choices: boolean): { row: Float64Array; w: number; from: Int32Array[] } {
  const w = most + 1;
  const from: Int32Array[] = choices ? [new Int32Array(2 * w)] : [];
  let row = new Float64Array(2 * w).fill(Infinity);
  const first = atoms[0]!.end - atoms[0]!.start;
  row[(first & 1) * w + 1] = DATA_HEADER + first;
  for (let i = 1; i < atoms.length; i++) {
    const next = new Float64Array(2 * w).fill(Infinity);
    const back = choices ? new Int32Array(2 * w) : undefined;
    // After atom i − 1 at most i items are open.
    bridgeOrSplit(row, next, w, Math.min(i, most), most, atoms[i - 1]!, atoms[i]!, back);
    if (back) from.push(back);
    row = next;
  }
  return { row, w, from };
}

/** Which atoms start an item, following the program's choices back from the state `end` after the last step. */
function startsOf(from: readonly Int32Array[], end: number): boolean[] {
  const starts: boolean[] = new Array<boolean>(from.length).fill(false);
  let state = end;
  for (let s = from.length - 1; s > 0; s--) {
    const f = from[s]![state]!;
    starts[s] = f < 0;
    state = Math.abs(f);
  }
  starts[0] = true;
  return starts;
}

/**
 * The cheapest items for each run of atoms i..j that one PDU can answer,
 * grown one atom at a time: an exact dynamic program over the gaps (bridge
 * it, or start a new item) whose state is the items used so far and the
 * parity of the open item, because an odd-length item costs a fill byte
 * unless it is the last. A new item is forced where the area changes.
 * Each step costs O(maxItems), so growing a run to the PDU's end is linear.
 */
class SegmentLayout {
  /** Per step (atom i + s) and state (parity × (maxItems + 1) + items): response bytes so far, fills of closed items included. */
  private readonly rows: Float64Array[] = [];
  /** Per step and state: the previous state, negated when the atom started a new item. */
  private readonly from: Int32Array[] = [];
  private readonly width: number;

  constructor(
    private readonly atoms: readonly Atom[],
    private readonly i: number,
    private readonly maxItems: number,
    private readonly pduSize: number,
  ) {
    this.width = maxItems + 1;
    const row = new Float64Array(2 * this.width).fill(Infinity);
    const len = atoms[i]!.end - atoms[i]!.start;
    row[(len & 1) * this.width + 1] = DATA_HEADER + len;
    this.rows.push(row);
    this.from.push(new Int32Array(2 * this.width));
  }

  /** The last atom laid out so far. */
  get j(): number {
    return this.i + this.rows.length - 1;
  }

  /** Adds atom j + 1; false (and nothing changes) when the run would no longer fit one PDU. */
  grow(): boolean {
    const w = this.width;
    const row = new Float64Array(2 * w).fill(Infinity);
    const from = new Int32Array(2 * w);
    bridgeOrSplit(this.rows[this.rows.length - 1]!, row, w, this.maxItems, this.maxItems, this.atoms[this.j]!, this.atoms[this.j + 1]!, from);
    if (this.best(row) === undefined) return false;
    this.rows.push(row);
    this.from.push(from);
    return true;
  }

  /** The state of `row` with the fewest wire bytes (answer + 12 request bytes per item) that fits the PDU. */
  private best(row: Float64Array): number | undefined {
    const w = this.width;
    let state: number | undefined;
    let wire = Infinity;
    for (let s = 0; s < 2 * w; s++) {
      const response = RESPONSE_BASE + row[s]!;
      const k = s % w;
      if (response > this.pduSize || REQUEST_BASE + REQUEST_ITEM * k > this.pduSize) continue;
      if (response + REQUEST_ITEM * k < wire) {
        wire = response + REQUEST_ITEM * k;
        state = s;
      }
    }
    return state;
  }

  /** The items of the run laid out so far, and per atom the index of its item. */
  items(): { items: DraftItem[]; itemOf: number[]; response: number } {
    const last = this.rows.length - 1;
    const end = this.best(this.rows[last]!)!;
    const response = RESPONSE_BASE + this.rows[last]![end]!;
    const starts = startsOf(this.from, end);
    const items: DraftItem[] = [];
    const itemOf: number[] = [];
    for (let s = 0; s <= last; s++) {
      const a = this.atoms[this.i + s]!;
      if (starts[s]) items.push({ group: a.group, area: a.area, dbNumber: a.dbNumber, unit: a.unit, start: a.start, end: a.end });
      else items[items.length - 1]!.end = a.end;
      itemOf.push(items.length - 1);
    }
    return { items, itemOf, response };
  }
}

/** Contiguous runs of atoms in address order, each as long as one PDU holds, each laid out exactly (optimal among such plans). */
function packSegments(atoms: readonly Atom[], pduSize: number, maxItems: number): Draft {
  const maxItem = maxReadItemData(pduSize);
  const bins: Bin[] = [];
  const placements: Draft['placements'] = [];
  let i = 0;
  while (i < atoms.length) {
    const atom = atoms[i]!;
    if (atom.end - atom.start > maxItem) {
      const even = (n: number) => n - (n % atom.unit);
      const pieces: { bin: Bin; item: DraftItem }[] = [];
      for (let at = atom.start; at < atom.end; ) {
        const length = Math.min(even(maxItem), atom.end - at);
        const item: DraftItem = { group: atom.group, area: atom.area, dbNumber: atom.dbNumber, unit: atom.unit, start: at, end: at + length };
        const bin: Bin = { items: [item], response: RESPONSE_BASE + DATA_HEADER + length };
        bins.push(bin);
        pieces.push({ bin, item });
        at += length;
      }
      placements.push(pieces);
      i++;
      continue;
    }
    const run = new SegmentLayout(atoms, i, maxItems, pduSize);
    while (run.j + 1 < atoms.length && atoms[run.j + 1]!.end - atoms[run.j + 1]!.start <= maxItem && run.grow());
    const best = run.items();
    const j = run.j;
    const bin: Bin = { items: best.items, response: best.response };
    bins.push(bin);
    for (let k = i; k <= j; k++) placements.push([{ bin, item: best.items[best.itemOf[k - i]!]! }]);
    i = j + 1;
  }
  return { bins, placements };
}

/** Largest program (atoms × states) packCover runs; beyond it the other drafts decide. */
const COVER_STATES = 2_000_000;
/** Swaps or moves packCover tries to bring every PDU within its size. */
const COVER_STEPS = 1000;

/**
 * A draft that need not follow address order, for tables where neither the
 * bytes nor the items of a PDU run out first everywhere: the atoms are
 * covered by the items with the fewest response bytes that `pdus` PDUs can
 * carry (the fill-byte bound's program, with its choices kept), then the
 * items are packed into `pdus` PDUs, largest first into the lightest PDU with
 * room, and balanced by swaps. Tried for each count below `fewerThan` that
 * the bytes allow; undefined when none works, when an atom needs more than
 * one item, or when the table is too large for the program.
 */
function packCover(atoms: readonly Atom[], pduSize: number, maxItems: number, fewerThan: number): Draft | undefined {
  const n = atoms.length;
  const maxItem = maxReadItemData(pduSize);
  if (n === 0 || fewerThan <= 1 || atoms.some((a) => a.end - a.start > maxItem)) return undefined;
  const most = Math.min(n, (fewerThan - 1) * maxItems);
  if (n * 2 * (most + 1) > COVER_STATES) return undefined;
  const { row, w, from } = coverProgram(atoms, most, true);
  const capacity = pduSize - RESPONSE_BASE;
  // The cover's bytes with its last item's fill byte (a PDU's last item saves one, counted per PDU below).
  const bytes = (s: number) => row[s]! + (s >= w ? 1 : 0);
  for (let pdus = 1; pdus < fewerThan; pdus++) {
    let end = -1;
    for (let s = 0; s < 2 * w; s++) {
      const k = s % w;
      if (k === 0 || k > pdus * maxItems || row[s] === Infinity) continue;
      if (end < 0 || bytes(s) < bytes(end)) end = s;
    }
    if (end < 0 || bytes(end) - pdus > pdus * capacity) continue;
    const draft = packRuns(atoms, coverRuns(atoms, from, end, maxItem), pdus, maxItems, capacity);
    if (draft) return draft;
  }
  return undefined;
}

/** The cover's items as runs of atoms, from the program's choices; a run is cut where it would outgrow one item. */
function coverRuns(atoms: readonly Atom[], from: readonly Int32Array[], end: number, maxItem: number): { first: number; last: number }[] {
  const starts = startsOf(from, end);
  const runs: { first: number; last: number }[] = [];
  for (let i = 0; i < atoms.length; i++) {
    const open = runs[runs.length - 1];
    if (!starts[i] && open && atoms[i]!.end - atoms[open.first]!.start <= maxItem) open.last = i;
    else runs.push({ first: i, last: i });
  }
  return runs;
}

/** Runs packed into `pdus` PDUs of at most maxItems items and `capacity` response bytes each, or undefined. */
function packRuns(atoms: readonly Atom[], runs: readonly { first: number; last: number }[], pdus: number, maxItems: number, capacity: number): Draft | undefined {
  const r = runs.length;
  if (r > pdus * maxItems) return undefined;
  const len = runs.map((run) => atoms[run.last]!.end - atoms[run.first]!.start);
  const weight = len.map((l) => DATA_HEADER + l + (l & 1));
  const binOf = new Int32Array(r);
  const load = new Float64Array(pdus);
  const count = new Int32Array(pdus);
  const odd = new Int32Array(pdus);
  const put = (x: number, b: number, sign: 1 | -1) => {
    load[b] += sign * weight[x]!;
    count[b] += sign;
    odd[b] += sign * (len[x]! & 1);
    if (sign > 0) binOf[x] = b;
  };
  // A PDU's bytes over its capacity (≤ 0 fits): its last item is an odd one if it has one, saving that fill byte.
  const over = (b: number, dLoad = 0, dOdd = 0) => load[b]! + dLoad - (odd[b]! + dOdd > 0 ? 1 : 0) - capacity;
  for (const x of runs.map((_, i) => i).sort((a, b) => weight[b]! - weight[a]!)) {
    let best = -1;
    for (let b = 0; b < pdus; b++) if (count[b]! < maxItems && (best < 0 || load[b]! < load[best]!)) best = b;
    put(x, best, 1);
  }
  for (let step = 0; step < COVER_STEPS; step++) {
    let a = -1;
    for (let b = 0; b < pdus; b++) if (over(b) > 0 && (a < 0 || over(b) > over(a))) a = b;
    if (a < 0) return draftOf(atoms, runs, binOf, pdus);
    // The move or swap that takes the most off PDU a without overfilling another.
    let bestX = -1;
    let bestY = -1;
    let bestLeft = over(a);
    for (let x = 0; x < r; x++) {
      if (binOf[x] !== a) continue;
      const ox = len[x]! & 1;
      for (let b = 0; b < pdus; b++) {
        if (b === a || count[b]! >= maxItems || over(b, weight[x]!, ox) > 0) continue;
        const left = Math.max(0, over(a, -weight[x]!, -ox));
        if (left < bestLeft) [bestX, bestY, bestLeft] = [x, -1 - b, left];
      }
      for (let y = 0; y < r; y++) {
        const b = binOf[y]!;
        const d = weight[x]! - weight[y]!;
        if (b === a || d <= 0) continue;
        const oy = len[y]! & 1;
        if (over(b, d, ox - oy) > 0) continue;
        const left = Math.max(0, over(a, -d, oy - ox));
        if (left < bestLeft) [bestX, bestY, bestLeft] = [x, y, left];
      }
    }
    if (bestX < 0) return undefined;
    if (bestY < 0) {
      put(bestX, a, -1);
      put(bestX, -1 - bestY, 1);
    } else {
      const b = binOf[bestY]!;
      put(bestX, a, -1);
      put(bestY, b, -1);
      put(bestX, b, 1);
      put(bestY, a, 1);
    }
  }
  return undefined;
}

/** The draft of packed runs: items in address order within a PDU, but an odd-length one last (it needs no fill byte). */
function draftOf(atoms: readonly Atom[], runs: readonly { first: number; last: number }[], binOf: Int32Array, pdus: number): Draft {
  const members: number[][] = Array.from({ length: pdus }, () => []);
  runs.forEach((_, x) => members[binOf[x]!]!.push(x));
  const bins: Bin[] = [];
  const placements: Draft['placements'] = new Array(atoms.length);
  for (const list of members) {
    if (list.length === 0) continue;
    const odd = list.findIndex((x) => (atoms[runs[x]!.last]!.end - atoms[runs[x]!.first]!.start) & 1);
    if (odd >= 0) list.push(...list.splice(odd, 1));
    const bin: Bin = { items: [], response: RESPONSE_BASE };
    for (const x of list) {
      const { first, last } = runs[x]!;
      const a = atoms[first]!;
      const item: DraftItem = { group: a.group, area: a.area, dbNumber: a.dbNumber, unit: a.unit, start: a.start, end: atoms[last]!.end };
      bin.response += fillAfter(bin) + DATA_HEADER + (item.end - item.start);
      bin.items.push(item);
      for (let i = first; i <= last; i++) placements[i] = [{ bin, item }];
    }
    bins.push(bin);
  }
  return { bins, placements };
}

function wireBytes(draft: Draft): number {
  let n = 0;
  for (const b of draft.bins) n += REQUEST_BASE + REQUEST_ITEM * b.items.length + b.response;
  return n;
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
    requestSize: REQUEST_BASE + REQUEST_ITEM * bin.items.length,
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

function checkPduSize(pduSize: number): void {
  if (!Number.isInteger(pduSize) || pduSize < 64 || pduSize > 0xffff) {
    throw new PlcError('INVALID_VALUE', `unusable S7 PDU size ${pduSize} (expected 64..65535)`);
  }
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

/**
 * The fewest PDUs any plan could read `tags` in at `pduSize` — a bin-packing
 * lower bound, the largest of a bytes bound, an items bound and a fill-byte
 * bound (evenBytesWithItems), tags may be split anywhere in all three:
 * - bytes: every response carries at most PDU − 14 bytes of items. Per run of
 *   tags whose gaps are under 4 bytes (bridging a larger gap never saves
 *   bytes), with T tag bytes over a span S: at least k = ceil(T / max item)
 *   items, so at least max(T + 4k, S + k + 3) bytes (each gap left out costs
 *   an item header instead).
 * - items: per area, ceil(tag bytes / max item) items, at most
 *   maxReadItems(pduSize) per request.
 */
export function lowerBoundPdus(tags: readonly Tag[], pduSize: number, options: Pick<PlanOptions, 'maxItems'> = {}): number {
  checkPduSize(pduSize);
  if (tags.length === 0) return 0;
  const maxItem = maxReadItemData(pduSize);
  const spans = spansOf(tags);
  let bytes = 0;
  let items = 0;
  let run: { group: number; start: number; end: number; tagBytes: number } | undefined;
  let group: { id: number; tagBytes: number } | undefined;
  const closeRun = () => {
    if (!run) return;
    const k = Math.ceil(run.tagBytes / maxItem);
    bytes += Math.max(run.tagBytes + DATA_HEADER * k, run.end - run.start + k + 3);
  };
  const closeGroup = () => {
    if (group) items += Math.max(1, Math.ceil(group.tagBytes / maxItem));
  };
  for (const s of spans) {
    if (!group || group.id !== s.group) {
      closeGroup();
      group = { id: s.group, tagBytes: 0 };
    }
    if (run && run.group === s.group && s.start - run.end < DATA_HEADER) {
      // Count only bytes not already covered (overlapping tags).
      const added = Math.max(0, s.end - Math.max(s.start, run.end));
      run.tagBytes += added;
      group.tagBytes += added;
      if (s.end > run.end) run.end = s.end;
      continue;
    }
    closeRun();
    run = { group: s.group, start: s.start, end: s.end, tagBytes: s.end - s.start };
    group.tagBytes += s.end - s.start;
  }
  closeRun();
  closeGroup();
  const capacity = pduSize - RESPONSE_BASE;
  const perPdu = maxReadItems(pduSize, options.maxItems);
  let n = Math.max(Math.ceil(bytes / capacity), Math.ceil(items / perPdu));
  // Both limits at once: n PDUs carry at most n·perPdu items, so at most that many gaps can be left out.
  const least = bytesWithItems(spans);
  while (least(n * perPdu) > n * capacity) n++;
  // Fill bytes: every item but the last of its PDU takes an even number of bytes.
  const even = evenBytesWithItems(atomsOf(spans, true));
  if (even) while (even[Math.min(even.length - 1, n * perPdu)]! - n > n * capacity) n++;
  return n;
}

/** Atoms beyond which evenBytesWithItems (quadratic) is not run and the bound goes without it. */
const EVEN_BOUND_ATOMS = 4000;

/**
 * The fewest response bytes Σ (4 + len, rounded up to even) of items
 * covering the atoms, per number of items allowed (index m: at most m
 * items): a dynamic program over the gaps (bridge it or start an item),
 * with the open item's parity as state. A PDU's items cost that less at
 * most one byte (its last item needs no fill), which lowerBoundPdus
 * subtracts. Any plan's items, trimmed to the atoms they cover and merged
 * where they share an atom, are such a cover costing no more.
 */
function evenBytesWithItems(atoms: readonly Atom[]): Float64Array | undefined {
  const n = atoms.length;
  if (n === 0 || n > EVEN_BOUND_ATOMS) return undefined;
  // As many items as atoms: no limit (the bound is taken per item count).
  const { row, w } = coverProgram(atoms, n, false);
  const least = new Float64Array(w).fill(Infinity);
  for (let m = 1; m < w; m++) least[m] = Math.min(least[m - 1]!, row[m]!, row[w + m]! + 1);
  return least;
}

/**
 * The fewest response bytes (Σ 4 + len) any plan needs when it may use at
 * most m items: one item per area at least, and each further item can leave
 * out one gap; leaving out the largest gaps over 4 bytes saves the most.
 */
function bytesWithItems(spans: readonly Span[]): (m: number) => number {
  let union = 0;
  let groups = 0;
  const gaps: number[] = [];
  let prev: Span | undefined;
  let end = 0;
  for (const s of spans) {
    if (!prev || prev.group !== s.group) {
      groups++;
      union += s.end - s.start;
      end = s.end;
    } else {
      if (s.start > end) {
        if (s.start - end > DATA_HEADER) gaps.push(s.start - end);
        else union += s.start - end;
      }
      union += Math.max(0, s.end - Math.max(s.start, end));
      end = Math.max(end, s.end);
    }
    prev = s;
  }
  gaps.sort((a, b) => b - a);
  const bridged = gaps.reduce((a, b) => a + b, 0);
  const saved = [0];
  for (const g of gaps) saved.push(saved[saved.length - 1]! + g);
  return (m) => {
    const left = Math.max(0, Math.min(m - groups, gaps.length));
    return union + bridged - saved[left]! + DATA_HEADER * (groups + left);
  };
}

// ------------------------------------------------------------------ plan cache

/**
 * Remembers read plans by tag list: the same list (the same array, or the
 * same addresses in the same order) at the same PDU size and options (item
 * limit, merge) is not planned again. Bounded: the oldest plan goes when
 * `capacity` is reached.
 */
export class ReadPlanCache {
  private readonly byArray = new WeakMap<readonly Tag[], ReadPlan>();
  private readonly byKey = new Map<string, { tags: readonly Tag[]; plan: ReadPlan; options: PlanOptions }[]>();
  private count = 0;
  hits = 0;
  misses = 0;

  constructor(readonly capacity = 64) {}

  get(tags: readonly Tag[], pduSize: number, options: PlanOptions = {}): ReadPlan {
    const same = this.byArray.get(tags);
    if (same && same.pduSize === pduSize && same.maxItems === maxReadItems(pduSize, options.maxItems) && same.merged === (options.merge ?? true)) {
      this.hits++;
      return same;
    }
    const key = cacheKey(tags, pduSize, options);
    const bucket = this.byKey.get(key);
    const found = bucket?.find((e) => sameTags(e.tags, tags));
    if (found) {
      this.hits++;
      this.byArray.set(tags, found.plan);
      return found.plan;
    }
    this.misses++;
    const plan = planRead(tags, pduSize, options);
    if (this.count >= this.capacity) {
      this.byKey.clear();
      this.count = 0;
    }
    const entry = { tags: [...tags], plan, options };
    if (bucket) bucket.push(entry);
    else this.byKey.set(key, [entry]);
    this.count++;
    this.byArray.set(tags, plan);
    return plan;
  }

  clear(): void {
    this.byKey.clear();
    this.count = 0;
  }
}

function cacheKey(tags: readonly Tag[], pduSize: number, options: PlanOptions): string {
  const first = tags[0]?.address ?? '';
  const last = tags[tags.length - 1]?.address ?? '';
  return `${pduSize}|${options.merge ?? true}|${options.maxItems ?? ''}|${tags.length}|${first}|${last}`;
}

function sameTags(a: readonly Tag[], b: readonly Tag[]): boolean {
  if (a.length !== b.length) return false;
  for (let i = 0; i < a.length; i++) if (a[i] !== b[i] && a[i]!.address !== b[i]!.address) return false;
  return true;
}

// ------------------------------------------------------------------ writes

/** A Write Var item, shaped like the codec's write item. */
export interface PlannedWriteItem {
  area: number;
  dbNumber: number;
  transportSize: number;
  count: number;
  address: number;
  dataTransportSize: number;
  data: Buffer;
}

export interface WritePdu {
  items: PlannedWriteItem[];
  /** Per item: the index of its tag in the write. */
  tags: number[];
  requestSize: number;
  responseSize: number;
}

export interface WritePlan {
  pduSize: number;
  pdus: WritePdu[];
  /** Per tag: the ValueError that kept it out of the plan, if any. */
  errors: (PlcError | undefined)[];
}

/**
 * Plans a write. Each tag becomes its own items: bits as BIT items, one per
 * bit (the CPU writes a single bit atomically; no read-modify-write, so
 * neighbouring bits are never clobbered); STRING/WSTRING from the current
 * length byte(s) on (writeSpan: the PLC's declared max length stays); data
 * larger than one PDU is cut into chunks. Items are packed first-fit
 * decreasing. A value that does not fit its tag is reported in `errors` and
 * not sent.
 */
export function planWrite(writes: readonly { tag: Tag; value: unknown }[], pduSize: number, options: Pick<PlanOptions, 'maxItems'> = {}): WritePlan {
  checkPduSize(pduSize);
  const maxData = maxWriteItemData(pduSize);
  const maxItems = Math.min(options.maxItems ?? MAX_ITEMS, MAX_ITEMS, pduSize - RESPONSE_BASE);
  const pieces: { tag: number; item: PlannedWriteItem }[] = [];
  const errors: (PlcError | undefined)[] = writes.map(() => undefined);
  writes.forEach(({ tag, value }, index) => {
    try {
      pieces.push(...writeItems(tag, value, maxData).map((item) => ({ tag: index, item })));
    } catch (err) {
      errors[index] = toPlcError(err, 'INVALID_VALUE');
    }
  });
  pieces.sort((a, b) => b.item.data.length - a.item.data.length);
  const bins: { pdu: WritePdu; lastOdd: boolean }[] = [];
  for (const p of pieces) {
    const len = p.item.data.length;
    let bin = bins.find(
      (b) => b.pdu.items.length < maxItems && b.pdu.requestSize + REQUEST_ITEM + (b.lastOdd ? 1 : 0) + DATA_HEADER + len <= pduSize,
    );
    if (!bin) {
      bin = { pdu: { items: [], tags: [], requestSize: REQUEST_BASE, responseSize: RESPONSE_BASE }, lastOdd: false };
      bins.push(bin);
    }
    bin.pdu.requestSize += REQUEST_ITEM + (bin.lastOdd ? 1 : 0) + DATA_HEADER + len;
    bin.pdu.responseSize += 1;
    bin.pdu.items.push(p.item);
    bin.pdu.tags.push(p.tag);
    bin.lastOdd = len % 2 === 1;
  }
  return { pduSize, pdus: bins.map((b) => b.pdu), errors };
}

function writeItems(tag: Tag, value: unknown, maxData: number): PlannedWriteItem[] {
  const area = areaCode(tag);
  validateValue(tag, value);
  if (tag.type === 'BOOL') {
    const bits = tag.isArray ? (value as readonly boolean[]) : [value as boolean];
    return bits.map((bit, i) => {
      const n = tag.bitOffset + i;
      return {
        area,
        dbNumber: tag.dbNumber,
        transportSize: TransportSize.BIT,
        count: 1,
        address: (tag.byteOffset + (n >> 3)) * 8 + (n & 7),
        dataTransportSize: DataTransportSize.BIT,
        data: Buffer.of(bit ? 1 : 0),
      };
    });
  }
  const { start, data } = writeSpan(tag, value);
  const items: PlannedWriteItem[] = [];
  if (isCounterOrTimer(area)) {
    const step = maxData - (maxData % 2);
    const transportSize = area === S7Area.C ? TransportSize.COUNTER : TransportSize.TIMER;
    for (let o = 0; o < data.length; o += step) {
      const part = data.subarray(o, o + step);
      items.push({ area, dbNumber: 0, transportSize, count: part.length / 2, address: tag.byteOffset + o / 2, dataTransportSize: DataTransportSize.OCTET_STRING, data: part });
    }
    return items;
  }
  for (let o = 0; o < data.length; o += maxData) {
    const part = data.subarray(o, o + maxData);
    items.push({
      area,
      dbNumber: tag.dbNumber,
      transportSize: TransportSize.BYTE,
      count: part.length,
      address: (tag.byteOffset + start + o) * 8,
      dataTransportSize: DataTransportSize.BYTE,
      data: part,
    });
  }
  return items;
}
