/**
 * The planner's byte space: where each tag lives (a span), and the atoms
 * that are never cut (tags whose bytes overlap, read in one piece so a value
 * is never torn between two PLC cycles).
 */
import { PlcError } from '../../errors';
import type { Tag } from '../../types';
import { AREA_CODES, S7Area } from '../constants';

/** Where a tag lives in the planner's byte space: C/T numbers are 2 bytes each. */
export interface Span {
  tag: number;
  group: number;
  area: number;
  dbNumber: number;
  /** 2 for counters/timers (items count numbers), else 1. */
  unit: number;
  start: number;
  end: number;
}

export interface Atom {
  group: number;
  area: number;
  dbNumber: number;
  unit: number;
  start: number;
  end: number;
  spans: Span[];
}

export function isCounterOrTimer(area: number): boolean {
  return area === S7Area.C || area === S7Area.T;
}

export function areaCode(tag: Tag): number {
  const code = AREA_CODES[tag.area];
  if (code === undefined)
    throw new PlcError('INVALID_ADDRESS', `${tag.address}: area ${tag.area} cannot be read over S7`, { tag: tag.address });
  return code;
}

function spanOf(tag: Tag, index: number): Span {
  const area = areaCode(tag);
  const unit = isCounterOrTimer(area) ? 2 : 1;
  const start = tag.byteOffset * unit;
  const length = unit === 2 ? 2 * tag.count : tag.byteLength;
  return { tag: index, group: area * 0x10000 + tag.dbNumber, area, dbNumber: tag.dbNumber, unit, start, end: start + length };
}

export function spansOf(tags: readonly Tag[]): Span[] {
  const spans = tags.map(spanOf);
  spans.sort((a, b) => a.group - b.group || a.start - b.start || b.end - a.end);
  return spans;
}

/** Overlapping tags form one atom; with merge = false every tag is its own atom. */
export function atomsOf(spans: readonly Span[], merge: boolean): Atom[] {
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
