'use strict';
// The client side of the chaos run, as a gateway runs it: one process, one
// client per PLC, each polling its prepared list of tags every `intervalMs`
// (a poll due while the previous one runs is skipped and counted, never
// overlapped) and writing unique values to its write slots, one write in
// flight per slot. Everything a check needs is kept here: poll counts and
// outcomes per PLC, every value read checked as it arrives, every write with
// its outcome, and per PLC the times of its good polls (to see a link back).
const { plcwire } = require('../lib/peers');
const { slotAddress, SLOTS, TIMEOUT_MS, BACKOFF } = require('./plan');

function urlOf(p, port) {
  const params = new URLSearchParams({ timeout: String(TIMEOUT_MS) });
  for (const [k, v] of Object.entries(p.driver.url)) params.set(k, String(v));
  if (p.driver.protocol === 'fetchwrite') return `fetchwrite://127.0.0.1?port=${port}&${params}`;
  const scheme = p.driver.protocol === 'freeport' ? 'freeport+tcp' : 's7';
  return `${scheme}://127.0.0.1:${port}?${params}`;
}

function same(type, expected, actual) {
  if (type === 'REAL') return Math.fround(expected) === actual;
  return expected === actual;
}

/** One PLC's client and everything recorded about it. */
class Station {
  constructor(lib, p, port, opts) {
    this.lib = lib;
    this.p = p;
    this.url = urlOf(p, port);
    this.client = lib.createClient(this.url, { backoff: BACKOFF });
    this.client.on('error', () => undefined);
    this.list = this.client.prepare(p.addresses);
    this.opts = opts;
    this.polls = { due: 0, started: 0, ok: 0, partial: 0, failed: 0, skipped: 0, overlapped: 0 };
    this.healthyPolls = { due: 0, ok: 0 };
    this.busy = 0;
    /** Items that failed in a poll that otherwise answered: { at (the poll's start), item (the itemError one?), text }. */
    this.failures = [];
    /** Every good poll's start and end (for the link-back check). */
    this.good = [];
    this.errorCodes = {};
    this.wrong = [];
    this.writes = [];
    this.slotBusy = new Array(SLOTS).fill(false);
    this.lastAcked = new Array(SLOTS).fill(0);
    this.issued = Array.from({ length: SLOTS }, () => new Set([0]));
    this.read = Array.from({ length: SLOTS }, () => new Set());
    this.seq = 0;
    this.nextSlot = 0;
    this.states = [];
    this.client.on('state', (s) => this.states.push([Date.now(), s]));
  }

  start() {
    this.client.start();
  }

  poll(timing) {
    this.polls.due++;
    if (timing) this.healthyPolls.due++;
    if (this.busy > 0) return void this.polls.skipped++;
    this.busy++;
    if (this.busy > 1) this.polls.overlapped++;
    this.polls.started++;
    const started = Date.now();
    // No stale value: a slot read must hold at least the last value acknowledged before the read began.
    const floor = this.lastAcked.slice();
    this.list.readDetailed().then(
      (results) => {
        this.busy--;
        this.check(results, floor, started, timing);
      },
      (err) => {
        this.busy--;
        this.polls.failed++;
        this.typed(err, 'poll');
      },
    );
  }

  check(results, floor, started, timing) {
    const { addresses, statics, slots, item } = this.p;
    let allOk = true;
    for (const s of statics) {
      const r = results[addresses[s.index]];
      if (r.ok) {
        if (!same(s.type, s.value, r.value)) this.wrongValue(addresses[s.index], s.value, r.value);
      } else {
        allOk = false;
        this.typed(r.error, 'item');
        this.failures.push({ at: started, item: s.index === item, text: `${addresses[s.index]}: ${r.error.code} ${r.error.message}` });
      }
    }
    slots.forEach((index, k) => {
      const r = results[addresses[index]];
      if (!r.ok) {
        allOk = false;
        this.typed(r.error, 'item');
        this.failures.push({ at: started, item: false, text: `${addresses[index]}: ${r.error.code} ${r.error.message}` });
        return;
      }
      if (!this.issued[k].has(r.value)) this.wrongValue(addresses[index], 'a value written', r.value);
      else if (r.value < floor[k]) this.wrongValue(addresses[index], `at least ${floor[k]} (acknowledged before the read)`, r.value);
      this.read[k].add(r.value);
    });
    if (allOk) {
      this.polls.ok++;
      if (timing) this.healthyPolls.ok++;
      this.good.push([started, Date.now()]);
    } else this.polls.partial++;
  }

  wrongValue(address, expected, actual) {
    if (this.wrong.length < 20) this.wrong.push(`${address}: expected ${expected}, read ${JSON.stringify(actual)}`);
    else this.wrong.push('…');
  }

  typed(err, what) {
    const code = err instanceof this.lib.PlcError ? err.code : `untyped ${what}: ${String(err && err.message)}`;
    this.errorCodes[code] = (this.errorCodes[code] ?? 0) + 1;
  }

  write() {
    const k = this.nextSlot;
    this.nextSlot = (k + 1) % SLOTS;
    if (this.slotBusy[k]) return;
    this.slotBusy[k] = true;
    const value = this.p.index * 1_000_000 + ++this.seq;
    this.issued[k].add(value);
    const address = slotAddress(this.p.driver.protocol, k);
    const w = { slot: k, value, address, issued: Date.now(), outcome: 'pending' };
    this.writes.push(w);
    this.client.write({ [address]: value }).then(
      () => {
        w.outcome = 'acked';
        this.lastAcked[k] = Math.max(this.lastAcked[k], value);
        this.slotBusy[k] = false;
      },
      (err) => {
        w.outcome = 'rejected';
        w.typed = err instanceof this.lib.PlcError;
        w.code = err && err.code;
        const text = String(err && err.message);
        w.named = text.includes(address) || text.includes(this.p.driver.protocol === 'fetchwrite' ? '127.0.0.1' : this.url.split('?')[0]);
        w.message = text;
        this.slotBusy[k] = false;
      },
    );
  }

  get inFlight() {
    return this.busy + this.slotBusy.filter(Boolean).length;
  }
}

/** Starts a client per PLC of `fleet` (ports: the proxies'); returns the stations. */
function openStations(fleet, ports, opts) {
  const lib = plcwire();
  const stations = fleet.map((p, i) => new Station(lib, p, ports[i], opts));
  for (const s of stations) s.start();
  return stations;
}

/**
 * Runs polls and writes from `t0` until `t0 + durationMs` (shared clock), spread
 * over the interval; resolves when every poll and write settled (or after 20 s).
 */
async function drive(stations, { t0, durationMs, intervalMs, writeEveryMs, warmMs }) {
  const n = stations.length;
  const end = t0 + durationMs;
  const timers = new Set();
  const every = (s, offset, period, fn) => {
    let next = t0 + offset;
    const tick = () => {
      timers.delete(t);
      if (Date.now() >= end) return;
      fn();
      next += period;
      t = setTimeout(tick, Math.max(0, next - Date.now()));
      timers.add(t);
    };
    let t = setTimeout(tick, Math.max(0, next - Date.now()));
    timers.add(t);
  };
  stations.forEach((s, i) => {
    every(s, (i * intervalMs) / n, intervalMs, () => s.poll(s.p.healthy && Date.now() >= t0 + warmMs));
    every(s, (i * writeEveryMs) / n + 7, writeEveryMs, () => s.write());
  });
  await new Promise((resolve) => setTimeout(resolve, Math.max(0, end - Date.now())));
  for (const t of timers) clearTimeout(t);
  const deadline = Date.now() + 20_000;
  while (stations.some((s) => s.inFlight > 0) && Date.now() < deadline) await new Promise((r) => setTimeout(r, 20));
}

module.exports = { openStations, drive };
