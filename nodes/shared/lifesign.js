'use strict';
/**
 * A life-sign exchange with the PLC program (a handshake timer):
 * the PC writes a counter or toggling bit every interval, and watches a value
 * the PLC keeps changing; no change within `timeout` means the partner is lost.
 * Pure logic with an injected clock; the heartbeat node drives it.
 */

/** Largest value of a life-sign counter per data type; it wraps to 0 after that. */
const COUNTER_MAX = Object.freeze({
  BYTE: 0xff, USINT: 0xff, SINT: 0x7f, CHAR: 0xff,
  WORD: 0xffff, UINT: 0xffff, INT: 0x7fff,
  DWORD: 0xffffffff, UDINT: 0xffffffff, DINT: 0x7fffffff,
});

/** The next life sign to write after `previous`. */
function nextLifeSign(mode, previous, type) {
  if (mode === 'toggle') return type === 'BOOL' ? !previous : previous ? 0 : 1;
  const max = COUNTER_MAX[type] ?? 0x7fff;
  const n = Number(previous) || 0;
  return n >= max ? 0 : n + 1;
}

class LifeSignWatch {
  /** @param {{ timeout: number, now?: () => number }} options */
  constructor(options) {
    this.timeout = options.timeout;
    this.now = options.now || Date.now;
    this.state = 'waiting';
    this.started = this.now();
    this.lastChange = undefined;
    this.value = undefined;
    this.seen = false;
    this.changes = 0;
    this.losses = 0;
  }

  /** Ms since the watched value last changed (or since the watch started). */
  get age() {
    return this.now() - (this.lastChange ?? this.started);
  }

  /** A value read from the PLC; returns 'alive' or 'restored' when that is news. */
  observe(value) {
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
  check() {
    if (this.state === 'lost' || this.age <= this.timeout) return undefined;
    this.state = 'lost';
    this.losses++;
    return 'lost';
  }

  /** What the node sends with an event. */
  report(event) {
    return { event, state: this.state, changes: this.changes, losses: this.losses, age: this.age, value: this.value };
  }
}

function valueKey(v) {
  if (typeof v === 'bigint') return `${v}n`;
  if (v instanceof Date) return v.getTime();
  if (Array.isArray(v)) return JSON.stringify(v.map(valueKey));
  return v;
}

module.exports = { LifeSignWatch, nextLifeSign, COUNTER_MAX };
