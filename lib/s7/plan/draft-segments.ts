/**
 * The exact-layout draft: atoms cut into runs in address order, each run as
 * long as one PDU holds, each laid out exactly (bridge or split each gap,
 * fill bytes included).
 */
import { READ_ITEM, READ_RESPONSE_ITEM_HEADER, VAR_REQUEST_BASE, VAR_RESPONSE_BASE } from '../constants';
import type { Atom } from './atoms';
import type { Bin, Draft, DraftItem } from './draft';
import { maxReadItemData } from './limits';
import { bridgeOrSplit, firstRow, startsOf } from './program';

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
    this.rows.push(firstRow(atoms[i]!, maxItems));
    this.from.push(new Int32Array(2 * this.width));
  }

  /** The last atom laid out so far. */
  get j(): number {
    return this.i + this.rows.length - 1;
  }

  /** Adds atom j + 1; false (and nothing changes) when the run would no longer fit one PDU. */
  grow(): boolean {
    const from = new Int32Array(2 * this.width);
    const prev = this.rows[this.rows.length - 1]!;
    const row = bridgeOrSplit({
      prev,
      a: this.atoms[this.j]!,
      b: this.atoms[this.j + 1]!,
      most: this.maxItems,
      reached: this.maxItems,
      from,
    });
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
      const response = VAR_RESPONSE_BASE + row[s]!;
      const k = s % w;
      if (response > this.pduSize || VAR_REQUEST_BASE + READ_ITEM * k > this.pduSize) continue;
      if (response + READ_ITEM * k < wire) {
        wire = response + READ_ITEM * k;
        state = s;
      }
    }
    return state;
  }

  /** The items of the run laid out so far, and per atom the index of its item. */
  items(): { items: DraftItem[]; itemOf: number[]; response: number } {
    const last = this.rows.length - 1;
    const end = this.best(this.rows[last]!)!;
    const response = VAR_RESPONSE_BASE + this.rows[last]![end]!;
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
export function packSegments(atoms: readonly Atom[], pduSize: number, maxItems: number): Draft {
  const maxItem = maxReadItemData(pduSize);
  const bins: Bin[] = [];
  const placements: Draft['placements'] = [];
  let i = 0;
  while (i < atoms.length) {
    const atom = atoms[i]!;
    if (atom.end - atom.start > maxItem) {
      const even = (n: number) => n - (n % atom.unit);
      const pieces: { bin: Bin; item: DraftItem }[] = [];
      for (let at = atom.start; at < atom.end;) {
        const length = Math.min(even(maxItem), atom.end - at);
        const item: DraftItem = {
          group: atom.group,
          area: atom.area,
          dbNumber: atom.dbNumber,
          unit: atom.unit,
          start: at,
          end: at + length,
        };
        const bin: Bin = { items: [item], response: VAR_RESPONSE_BASE + READ_RESPONSE_ITEM_HEADER + length };
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
