/**
 * A life-sign exchange with the PLC program (a handshake timer): the PC
 * writes a counter or toggling bit every interval, and watches a value the
 * PLC keeps changing; no change within `timeout` means the partner is lost.
 * Pure logic with an injected clock; the heartbeat node drives it.
 */

/** Largest value of a life-sign counter per data type; it wraps to 0 after that. */
export const LIFE_SIGN_COUNTER_MAX: Readonly<Record<string, number>> = Object.freeze({
  BYTE: 0xff,
  USINT: 0xff,
  SINT: 0x7f,
  CHAR: 0xff,
  WORD: 0xffff,
  UINT: 0xffff,
  INT: 0x7fff,
  DWORD: 0xffffffff,
  UDINT: 0xffffffff,
  DINT: 0x7fffffff,
});

export type LifeSignMode = 'counter' | 'toggle';
export type LifeSignEvent = 'alive' | 'lost' | 'restored';
export type LifeSignState = 'waiting' | 'alive' | 'lost';

/** The next life sign to write after `previous` (a counter wraps at its type's maximum; INT when unknown). */
export function nextLifeSign(mode: LifeSignMode, previous: unknown, type: string): number | boolean {
  if (mode === 'toggle') return type === 'BOOL' ? !previous : previous ? 0 : 1;
  const max = LIFE_SIGN_COUNTER_MAX[type] ?? 0x7fff;
  const n = Number(previous) || 0;
  return n >= max ? 0 : n + 1;
}

export interface LifeSignReport {
  event: LifeSignEvent;
  state: LifeSignState;
  changes: number;
  losses: number;
  age: number;
  value: unknown;
}

/** Watches the PLC's life sign: waiting → alive → lost (once) → restored. */
export class LifeSignWatch {
  readonly timeout: number;
  private readonly now: () => number;
  state: LifeSignState = 'waiting';
  changes = 0;
  losses = 0;
  /** The last value seen, as a comparable key (bigints, dates and arrays turned into primitives). */
  value: unknown = undefined;
  private readonly started: number;
  private lastChange: number | undefined = undefined;
  private seen = false;

  constructor(options: { timeout: number; now?: () => number }) {
    this.timeout = options.timeout;
    this.now = options.now || Date.now;
    this.started = this.now();
  }

  /** Ms since the watched value last changed (or since the watch started). */
  get age(): number {
    return this.now() - (this.lastChange ?? this.started);
  }

  /** A value read from the PLC; returns 'alive' or 'restored' when that is news. */
  observe(value: unknown): 'alive' | 'restored' | undefined {
    const key = valueKey(value);
    if (!this.seen) {
      this.seen = true;
      this.value = key;
      return undefined;
    }
    if (key === this.value) return undefined;
    this.value = key;
    this.changes++;
    this.lastChange = this.now();
    if (this.state === 'alive') return undefined;
    const event = this.state === 'lost' ? 'restored' : 'alive';
    this.state = 'alive';
    return event;
  }

  /** Returns 'lost' once, when the value has not changed for longer than the timeout. */
  check(): 'lost' | undefined {
    if (this.state === 'lost' || this.age <= this.timeout) return undefined;
    this.state = 'lost';
    this.losses++;
    return 'lost';
  }

  /** What the heartbeat node sends with an event. */
  report(event: LifeSignEvent): LifeSignReport {
    return { event, state: this.state, changes: this.changes, losses: this.losses, age: this.age, value: this.value };
  }
}

function valueKey(v: unknown): unknown {
  if (typeof v === 'bigint') return `${v}n`;
  if (v instanceof Date) return v.getTime();
  if (Array.isArray(v)) return JSON.stringify(v.map(valueKey));
  return v;
}
