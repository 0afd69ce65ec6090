/**
 * Read drafts: PDUs ("bins") of items before they become a plan, and the
 * greedy draft that fills atoms into PDUs in address order, bridging the gap
 * to the previous item when it is at most a threshold, opening a new item
 * otherwise.
 */
import { READ_ITEM, READ_RESPONSE_ITEM_HEADER, VAR_REQUEST_BASE, VAR_RESPONSE_BASE } from '../constants';
import type { Atom } from './atoms';
import { maxReadItemData } from './limits';

export interface DraftItem {
  group: number;
  area: number;
  dbNumber: number;
  unit: number;
  start: number;
  end: number;
}

export interface Bin {
  items: DraftItem[];
  /** 14 + Σ(4 + len) + fills between items, with the last item counted without fill. */
  response: number;
}

export interface Draft {
  bins: Bin[];
  /** Per atom: the items it lies in (one, or the chunks of a split atom), with their bin. */
  placements: { bin: Bin; item: DraftItem }[][];
}

export function fillAfter(bin: Bin): number {
  const last = bin.items[bin.items.length - 1];
  return last && (last.end - last.start) % 2 === 1 ? 1 : 0;
}

export function pack(atoms: readonly Atom[], pduSize: number, maxItems: number, gapThreshold: number, merge: boolean): Draft {
  const maxItem = maxReadItemData(pduSize);
  const bins: Bin[] = [];
  const placements: Draft['placements'] = [];
  let current: Bin | undefined;

  const openBin = (): Bin => {
    current = { items: [], response: VAR_RESPONSE_BASE };
    bins.push(current);
    return current;
  };
  const newItemFits = (bin: Bin, length: number) =>
    bin.items.length < maxItems && bin.response + fillAfter(bin) + READ_RESPONSE_ITEM_HEADER + length <= pduSize;
  const addItem = (bin: Bin, a: { group: number; area: number; dbNumber: number; unit: number }, start: number, end: number): DraftItem => {
    const item: DraftItem = { group: a.group, area: a.area, dbNumber: a.dbNumber, unit: a.unit, start, end };
    bin.response += fillAfter(bin) + READ_RESPONSE_ITEM_HEADER + (end - start);
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
      const room = even(pduSize - current.response - fillAfter(current) - READ_RESPONSE_ITEM_HEADER);
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

export function wireBytes(draft: Draft): number {
  let n = 0;
  for (const b of draft.bins) n += VAR_REQUEST_BASE + READ_ITEM * b.items.length + b.response;
  return n;
}
