/** Change detection with a deadband: which read outcomes are worth reporting. */
import type { TagOutcome } from './outcome';

function toNumber(v: number | bigint): number {
  return typeof v === 'bigint' ? Number(v) : v;
}

/** True when two PLC values differ (numbers: by more than `deadband`; arrays element by element; dates by time). */
export function valueChanged(before: unknown, after: unknown, deadband: number): boolean {
  if (typeof after === 'number' || typeof after === 'bigint') {
    if (typeof before !== 'number' && typeof before !== 'bigint') return true;
    if (typeof before === 'bigint' && typeof after === 'bigint' && !(deadband > 0)) return before !== after;
    const d = Math.abs(toNumber(after) - toNumber(before));
    return deadband > 0 ? d > deadband : d !== 0 || Number.isNaN(d);
  }
  if (after instanceof Date) return !(before instanceof Date) || before.getTime() !== after.getTime();
  if (Array.isArray(after)) {
    if (!Array.isArray(before) || before.length !== after.length) return true;
    return after.some((v, i) => valueChanged(before[i], v, deadband));
  }
  return before !== after;
}

/**
 * Remembers the last outcome reported per tag name; `filter` keeps the
 * outcomes worth reporting: changed values (beyond the deadband, measured
 * from the last reported value) and changes of quality or error code.
 */
export class ChangeFilter {
  readonly deadband: number;
  private readonly last = new Map<string, TagOutcome>();

  constructor(deadband: unknown = 0) {
    this.deadband = Number(deadband) > 0 ? Number(deadband) : 0;
  }

  filter(list: readonly TagOutcome[]): TagOutcome[] {
    const out: TagOutcome[] = [];
    for (const o of list) {
      const prev = this.last.get(o.name);
      let report: boolean;
      if (!prev) report = true;
      else if (prev.ok !== o.ok) report = true;
      else if (!o.ok) report = !prev.ok && prev.error.code !== o.error.code;
      else report = prev.ok && valueChanged(prev.value, o.value, this.deadband);
      if (report) {
        this.last.set(o.name, o);
        out.push(o);
      }
    }
    return out;
  }

  clear(): void {
    this.last.clear();
  }
}
