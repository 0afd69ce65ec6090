/**
 * The fewest PDUs any read plan could need: a lower bound the planner's
 * tests and the benchmark hold plans against. Not part of the public API
 * (lib/index.ts); import it from here.
 */
import type { Tag } from '../../types';
import { READ_RESPONSE_ITEM_HEADER, VAR_RESPONSE_BASE } from '../constants';
import { atomsOf, spansOf, type Atom, type Span } from './atoms';
import { checkPduSize, maxReadItemData, maxReadItems, type PlanOptions } from './limits';
import { coverProgram } from './program';

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
    bytes += Math.max(run.tagBytes + READ_RESPONSE_ITEM_HEADER * k, run.end - run.start + k + 3);
  };
  const closeGroup = () => {
    if (group) items += Math.max(1, Math.ceil(group.tagBytes / maxItem));
  };
  for (const s of spans) {
    if (!group || group.id !== s.group) {
      closeGroup();
      group = { id: s.group, tagBytes: 0 };
    }
    if (run && run.group === s.group && s.start - run.end < READ_RESPONSE_ITEM_HEADER) {
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
  const capacity = pduSize - VAR_RESPONSE_BASE;
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
        if (s.start - end > READ_RESPONSE_ITEM_HEADER) gaps.push(s.start - end);
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
    return union + bridged - saved[left]! + READ_RESPONSE_ITEM_HEADER * (groups + left);
  };
}
