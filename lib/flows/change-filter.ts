/** Change detection with a deadband: which read outcomes are worth reporting. */
import type { TagOutcome } from './outcome';
import type { PolledTable } from './polled-table';

function toNumber(v: number | bigint): number {
  return typeof v === 'bigint' ? Number(v) : v;
}

/**
 * True when two PLC values differ (numbers: by more than `deadband`; arrays
 * element by element; dates by time; a struct read by name member by member,
 * so a struct whose members all stay within the deadband has not changed).
 */
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
  if (isStruct(after)) {
    if (!isStruct(before)) return true;
    const keys = Object.keys(after);
    if (keys.length !== Object.keys(before).length) return true;
    return keys.some((k) => !Object.prototype.hasOwnProperty.call(before, k) || valueChanged(before[k], after[k], deadband));
  }
  return before !== after;
}

/** A struct's value as the client builds it: a plain object of its members. */
function isStruct(value: unknown): value is Record<string, unknown> {
  return typeof value === 'object' && value !== null && !Array.isArray(value) && !(value instanceof Date);
}

/** A copy of what a value is now: the reported value goes out on a message, and a flow may change it in place. */
function snapshot(value: unknown): unknown {
  if (Array.isArray(value)) return value.map(snapshot);
  if (value instanceof Date) return new Date(value.getTime());
  if (isStruct(value)) return Object.fromEntries(Object.entries(value).map(([k, v]) => [k, snapshot(v)]));
  return value;
}

const UNSEEN = 0;
const GOOD = 1;
const BAD = 2;

/**
 * Remembers the last outcome reported per tag name; keeps the outcomes worth
 * reporting: changed values (beyond the deadband, measured from the last
 * reported value) and changes of quality or error code. `filter` takes
 * outcomes by name; `changedRows` takes a polled table's values by row,
 * looking no name up (the table's slots are resolved once).
 */
export class ChangeFilter {
  readonly deadband: number;
  private readonly slotOf = new Map<string, number>();
  private quality: number[] = [];
  private value: unknown[] = [];
  private code: string[] = [];
  private readonly tableSlots = new WeakMap<PolledTable, number[]>();

  constructor(deadband: unknown = 0) {
    this.deadband = Number(deadband) > 0 ? Number(deadband) : 0;
  }

  filter(list: readonly TagOutcome[]): TagOutcome[] {
    const out: TagOutcome[] = [];
    for (const o of list) {
      const slot = this.slot(o.name);
      if (o.ok ? this.good(slot, o.value) : this.bad(slot, o.error.code)) out.push(o);
    }
    return out;
  }

  /** The rows of `table` worth reporting after a read in which every tag succeeded (`values`: the rows' values in row order). */
  changedRows(table: PolledTable, values: readonly unknown[]): number[] {
    let slots = this.tableSlots.get(table);
    if (!slots) this.tableSlots.set(table, (slots = table.tags.map((t) => this.slot(t.name))));
    const out: number[] = [];
    for (let i = 0; i < slots.length; i++) if (this.good(slots[i]!, values[i])) out.push(i);
    return out;
  }

  clear(): void {
    this.quality.fill(UNSEEN);
    this.value.fill(undefined);
  }

  private slot(name: string): number {
    let slot = this.slotOf.get(name);
    if (slot === undefined) {
      this.slotOf.set(name, (slot = this.slotOf.size));
      this.quality.push(UNSEEN);
      this.value.push(undefined);
      this.code.push('');
    }
    return slot;
  }

  /** Whether a good `value` in `slot` is news; remembers it if so. */
  private good(slot: number, value: unknown): boolean {
    if (this.quality[slot] === GOOD && !valueChanged(this.value[slot], value, this.deadband)) return false;
    this.quality[slot] = GOOD;
    this.value[slot] = snapshot(value);
    return true;
  }

  /** Whether a failure with `code` in `slot` is news; remembers it if so. */
  private bad(slot: number, code: string): boolean {
    if (this.quality[slot] === BAD && this.code[slot] === code) return false;
    this.quality[slot] = BAD;
    this.value[slot] = undefined;
    this.code[slot] = code;
    return true;
  }
}
