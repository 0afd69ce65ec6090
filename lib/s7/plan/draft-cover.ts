/**
 * The out-of-order draft (packCover): the cheapest cover of the atoms by the
 * items fewer PDUs could carry, packed into those PDUs. planRead keeps it
 * only when it needs fewer PDUs than the address-order drafts.
 */
import { READ_RESPONSE_ITEM_HEADER, VAR_RESPONSE_BASE } from '../constants';
import type { Atom } from './atoms';
import { fillAfter, type Bin, type Draft, type DraftItem } from './draft';
import { maxReadItemData } from './limits';
import { coverProgram, startsOf } from './program';

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
export function packCover(atoms: readonly Atom[], pduSize: number, maxItems: number, fewerThan: number): Draft | undefined {
  const n = atoms.length;
  const maxItem = maxReadItemData(pduSize);
  if (n === 0 || fewerThan <= 1 || atoms.some((a) => a.end - a.start > maxItem)) return undefined;
  const most = Math.min(n, (fewerThan - 1) * maxItems);
  if (n * 2 * (most + 1) > COVER_STATES) return undefined;
  const { row, w, from } = coverProgram(atoms, most, true);
  const capacity = pduSize - VAR_RESPONSE_BASE;
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
function packRuns(
  atoms: readonly Atom[],
  runs: readonly { first: number; last: number }[],
  pdus: number,
  maxItems: number,
  capacity: number,
): Draft | undefined {
  const r = runs.length;
  if (r > pdus * maxItems) return undefined;
  const len = runs.map((run) => atoms[run.last]!.end - atoms[run.first]!.start);
  const weight = len.map((l) => READ_RESPONSE_ITEM_HEADER + l + (l & 1));
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
  const placements: Draft['placements'] = new Array<Draft['placements'][number]>(atoms.length);
  for (const list of members) {
    if (list.length === 0) continue;
    const odd = list.findIndex((x) => (atoms[runs[x]!.last]!.end - atoms[runs[x]!.first]!.start) & 1);
    if (odd >= 0) list.push(...list.splice(odd, 1));
    const bin: Bin = { items: [], response: VAR_RESPONSE_BASE };
    for (const x of list) {
      const { first, last } = runs[x]!;
      const a = atoms[first]!;
      const item: DraftItem = { group: a.group, area: a.area, dbNumber: a.dbNumber, unit: a.unit, start: a.start, end: atoms[last]!.end };
      bin.response += fillAfter(bin) + READ_RESPONSE_ITEM_HEADER + (item.end - item.start);
      bin.items.push(item);
      for (let i = first; i <= last; i++) placements[i] = [{ bin, item }];
    }
    bins.push(bin);
  }
  return { bins, placements };
}
