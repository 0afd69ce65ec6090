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

/** PLC `p`'s URL at `port`; an S7CommPlus PLC's with its certificate pinned (`fingerprint`). */
function urlOf(p, port, fingerprint) {
  const params = new URLSearchParams({ timeout: String(TIMEOUT_MS) });
  for (const [k, v] of Object.entries(p.driver.url)) params.set(k, String(v));
  if (p.driver.protocol === 'fetchwrite') return `fetchwrite://127.0.0.1?port=${port}&${params}`;
  if (p.driver.protocol === 's7plus') params.set('fingerprint', fingerprint);
  const scheme = { freeport: 'freeport+tcp', s7plus: 's7plus' }[p.driver.protocol] ?? 's7';
  return `${scheme}://127.0.0.1:${port}?${params}`;
}

function same(type, expected, actual) {
  if (type === 'REAL') return Math.fround(expected) === actual;
  return expected === actual;
}

/**
 * A growable column of numbers in typed-array chunks: the run's own records
 * stay a few bytes per write or failure, so the heap figure is the library's.
 */
class Column {
  constructor(Type) {
    this.Type = Type;
    this.chunks = [];
    this.length = 0;
  }

  push(v) {
    if (this.length % 65536 === 0) this.chunks.push(new this.Type(65536));
    this.chunks[this.chunks.length - 1][this.length++ % 65536] = v;
  }

  get(i) {
    return this.chunks[Math.floor(i / 65536)][i % 65536];
  }

  set(i, v) {
    this.chunks[Math.floor(i / 65536)][i % 65536] = v;
  }
}

const PENDING = 0;
const ACKED = 1;
const REJECTED = 2;

/**
 * One PLC's client and everything recorded about it. Write n (1, 2, …) of
 * PLC i carries the value i × 1,000,000 + n, so a value names its write.
 */
class Station {
  constructor(lib, p, port, fingerprint) {
    this.lib = lib;
    this.p = p;
    this.url = urlOf(p, port, fingerprint);
    this.name = p.driver.protocol === 'fetchwrite' ? `127.0.0.1:${port}` : this.url.split('?')[0];
    this.client = lib.createClient(this.url, { backoff: BACKOFF });
    /** When the client refused a certificate that is not the pinned one (CERTIFICATE_UNTRUSTED). */
    this.refusals = [];
    this.client.on('error', (err) => {
      if (err && err.code === 'CERTIFICATE_UNTRUSTED') this.refusals.push(Date.now());
    });
    this.list = this.client.prepare(p.addresses);
    this.polls = { due: 0, started: 0, ok: 0, partial: 0, failed: 0, skipped: 0, overlapped: 0 };
    this.healthyPolls = { due: 0, ok: 0 };
    this.busy = 0;
    /** Items that failed in a poll that otherwise answered: when the answer came, and whether it was the itemError item. */
    this.failAt = new Column(Float64Array);
    this.failItem = new Column(Uint8Array);
    this.failTexts = [];
    /** Runs of good polls, [start of the first, start of the last] (for the link-back check). */
    this.runs = [];
    this.inRun = false;
    this.errorCodes = {};
    this.wrong = [];
    /** Per write n - 1: its slot, its outcome, whether its value was read. */
    this.writeSlot = new Column(Int8Array);
    this.outcome = new Column(Uint8Array);
    this.seenRead = new Column(Uint8Array);
    this.rejectedCodes = {};
    this.badRejections = [];
    this.slotBusy = new Array(SLOTS).fill(false);
    this.lastAcked = new Array(SLOTS).fill(0);
    this.seq = 0;
    this.nextSlot = 0;
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
        this.inRun = false;
        this.typed(err, 'poll');
      },
    );
  }

  /** The write whose value `v` is, if PLC i wrote it to slot k; 0 for the slot's initial 0; -1 when none. */
  writeOf(v, k) {
    if (v === 0) return 0;
    const n = v - this.p.index * 1_000_000;
    return Number.isInteger(n) && n >= 1 && n <= this.seq && this.writeSlot.get(n - 1) === k ? n : -1;
  }

  check(results, floor, started, timing) {
    const { addresses, statics, slots, item } = this.p;
    let allOk = true;
    const failed = (index, error) => {
      allOk = false;
      this.typed(error, 'item');
      this.failAt.push(Date.now());
      this.failItem.push(index === item ? 1 : 0);
      if (this.failTexts.length < 3) this.failTexts.push(`${addresses[index]}: ${error.code} ${error.message}`);
    };
    for (const s of statics) {
      const r = results[addresses[s.index]];
      if (!r.ok) failed(s.index, r.error);
      else if (!same(s.type, s.value, r.value)) this.wrongValue(addresses[s.index], s.value, r.value);
    }
    slots.forEach((index, k) => {
      const r = results[addresses[index]];
      if (!r.ok) return failed(index, r.error);
      const n = this.writeOf(r.value, k);
      if (n < 0) this.wrongValue(addresses[index], 'a value written', r.value);
      else if (r.value < floor[k]) this.wrongValue(addresses[index], `at least ${floor[k]} (acknowledged before the read)`, r.value);
      if (n > 0) this.seenRead.set(n - 1, 1);
    });
    if (allOk) {
      this.polls.ok++;
      if (timing) this.healthyPolls.ok++;
      if (this.inRun) this.runs[this.runs.length - 1][1] = started;
      else this.runs.push([started, started]);
      this.inRun = true;
    } else {
      this.polls.partial++;
      this.inRun = false;
    }
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
    const n = ++this.seq;
    const value = this.p.index * 1_000_000 + n;
    this.writeSlot.push(k);
    this.outcome.push(PENDING);
    this.seenRead.push(0);
    const address = slotAddress(this.p.driver.protocol, k);
    this.client.write({ [address]: value }).then(
      () => {
        this.outcome.set(n - 1, ACKED);
        this.lastAcked[k] = Math.max(this.lastAcked[k], value);
        this.slotBusy[k] = false;
      },
      (err) => {
        this.outcome.set(n - 1, REJECTED);
        const typed = err instanceof this.lib.PlcError;
        const code = typed ? err.code : 'untyped';
        this.rejectedCodes[code] = (this.rejectedCodes[code] ?? 0) + 1;
        const text = String(err && err.message);
        // The tag itself, not only the PLC: a gateway's log must say which write failed (issue #26).
        const named = text.includes(address) && err.tag === address;
        if (!typed || !named) this.badRejections.push({ n, address, value, typed, named, code, message: text });
        this.slotBusy[k] = false;
      },
    );
  }

  get inFlight() {
    return this.busy + this.slotBusy.filter(Boolean).length;
  }
}

/** Starts a client per PLC of `fleet` (ports: the proxies'; fingerprints: the S7CommPlus PLCs' certificates); returns the stations. */
function openStations(fleet, ports, fingerprints) {
  const lib = plcwire();
  const stations = fleet.map((p, i) => new Station(lib, p, ports[i], fingerprints[i]));
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

module.exports = { openStations, drive, urlOf, PENDING, ACKED, REJECTED };
