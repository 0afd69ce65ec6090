/**
 * The bridge-or-split program: for atoms in address order, the fewest
 * response bytes of items covering them, per number of items and parity of
 * the open item. The exact layout (draft-segments.ts), the out-of-order
 * draft (draft-cover.ts) and the fill-byte bound (bound.ts) all run it.
 */
import { READ_RESPONSE_ITEM_HEADER } from '../constants';
import type { Atom } from './atoms';

/** One step of the program: atom b after atom a. */
export interface ProgramStep {
  /** The row after atom a. */
  prev: Float64Array;
  a: Atom;
  b: Atom;
  /** Items a state may have at most (a row holds 2 × (most + 1) states). */
  most: number;
  /** Items the states of `prev` can have at most (≤ most): the states beyond are not reached yet. */
  reached: number;
  /** If given, gets each new state's previous state, negated when atom b started an item. */
  from?: Int32Array;
}

/** The first row: atom `a` alone in one item, of a program with at most `most` items. */
export function firstRow(a: Atom, most: number): Float64Array {
  const w = most + 1;
  const row = new Float64Array(2 * w).fill(Infinity);
  const len = a.end - a.start;
  row[(len & 1) * w + 1] = READ_RESPONSE_ITEM_HEADER + len;
  return row;
}

/**
 * One step of the bridge-or-split program (SegmentLayout, the lower bound):
 * the row after atom b from the row after atom a. A state is parity × w +
 * items (the open item's length parity, items used so far, 1 ≤ items ≤
 * most, w = most + 1); its value is the response bytes so far, the fill
 * bytes of closed items included. Bridging the gap keeps the item count;
 * starting an item (while items < most) pays the open item's fill, a header
 * and the atom.
 */
export function bridgeOrSplit(step: ProgramStep): Float64Array {
  const { prev, a, b, most, reached, from } = step;
  const w = most + 1;
  const next = new Float64Array(2 * w).fill(Infinity);
  const len = b.end - b.start;
  const gap = b.start - a.end;
  const bridge = a.group === b.group && gap >= 0;
  for (let p = 0; p < 2; p++) {
    for (let k = 1; k <= reached; k++) {
      const cost = prev[p * w + k]!;
      if (cost === Infinity) continue;
      if (bridge) {
        const q = (p + gap + len) & 1;
        if (cost + gap + len < next[q * w + k]!) {
          next[q * w + k] = cost + gap + len;
          if (from) from[q * w + k] = p * w + k;
        }
      }
      if (k < most) {
        const q = len & 1;
        if (cost + p + READ_RESPONSE_ITEM_HEADER + len < next[q * w + k + 1]!) {
          next[q * w + k + 1] = cost + p + READ_RESPONSE_ITEM_HEADER + len;
          if (from) from[q * w + k + 1] = -(p * w + k);
        }
      }
    }
  }
  return next;
}

/**
 * The bridge-or-split program over all the atoms with at most `most` items:
 * the last row, and with `choices` each step's choices (for startsOf).
 */
export function coverProgram(atoms: readonly Atom[], most: number, choices: boolean): { row: Float64Array; w: number; from: Int32Array[] } {
  const w = most + 1;
  const from: Int32Array[] = choices ? [new Int32Array(2 * w)] : [];
  let row = firstRow(atoms[0]!, most);
  for (let i = 1; i < atoms.length; i++) {
    const back = choices ? new Int32Array(2 * w) : undefined;
    // After atom i − 1 at most i items are open.
    row = bridgeOrSplit({ prev: row, a: atoms[i - 1]!, b: atoms[i]!, most, reached: Math.min(i, most), from: back });
    if (back) from.push(back);
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
