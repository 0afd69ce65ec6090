/**
 * The bridge-or-split program: for atoms in address order, the fewest
 * response bytes of items covering them, per number of items and parity of
 * the open item. The exact layout (draft-segments.ts), the out-of-order
 * draft (draft-cover.ts) and the fill-byte bound (bound.ts) all run it.
 */
import { READ_RESPONSE_ITEM_HEADER } from '../constants';
import type { Atom } from './atoms';

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
export function bridgeOrSplit(prev: Float64Array, next: Float64Array, w: number, kMax: number, maxItems: number, a: Atom, b: Atom, from?: Int32Array): void {
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
        if (cost + p + READ_RESPONSE_ITEM_HEADER + len < next[q * w + k + 1]!) {
          next[q * w + k + 1] = cost + p + READ_RESPONSE_ITEM_HEADER + len;
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
export function coverProgram(atoms: readonly Atom[], most: number, choices: boolean): { row: Float64Array; w: number; from: Int32Array[] } {
  const w = most + 1;
  const from: Int32Array[] = choices ? [new Int32Array(2 * w)] : [];
  let row = new Float64Array(2 * w).fill(Infinity);
  const first = atoms[0]!.end - atoms[0]!.start;
  row[(first & 1) * w + 1] = READ_RESPONSE_ITEM_HEADER + first;
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
export function startsOf(from: readonly Int32Array[], end: number): boolean[] {
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
