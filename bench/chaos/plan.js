'use strict';
// The chaos run's plan, the same in both processes: which driver each
// simulated PLC speaks, its tags, and its fault schedule, all drawn from one
// seeded generator (mulberry32), so a seed replays the same run.
//
// DRIVERS is data: a driver is one entry (its simulator kind, profile,
// URL parameters and the faults that apply to it). An S7CommPlus row
// (`s7plus`, S7-1200/1500 over TLS, with its TLS faults) is one more entry
// here, plus its simulator kind in server-worker.js, once that driver lands.
const { plcTable } = require('../lib/fleet');
// mulberry32: small, fast, good enough to draw a schedule from (the benchmark tables' generator).
const { prng } = require('../lib/tables');

/** Every fault of issue #26 (S7comm, FETCH/WRITE and freeport; the TLS ones come with s7plus). */
const FAULTS = {
  reset: 'connection reset (RST on every connection)',
  silence: 'silence: sockets open, no answer',
  slow: 'slow answers (each answer delayed)',
  restart: 'restart: listener gone, back later',
  refused: 'connection refused by the PLC',
  backlog: 'full backlog: connections accepted, never answered',
  half: 'half a frame, then silence',
  garbage: 'garbage instead of an answer',
  itemError: 'an error answer to one item',
  stop: 'CPU in STOP',
};
const ALL = Object.keys(FAULTS);
const NO_CPU_MODE = ALL.filter((f) => f !== 'stop');

/**
 * The drivers of the fleet, PLC i speaking DRIVERS[i mod length]. `server`:
 * the simulator's options; `url`: the client's URL parameters.
 */
const DRIVERS = [
  { id: 's7-1500', protocol: 's7', server: { profile: 's7-1500' }, url: { rack: 0, slot: 1 }, faults: ALL },
  { id: 's7-1200', protocol: 's7', server: { profile: 's7-1200' }, url: { rack: 0, slot: 1 }, faults: ALL },
  {
    id: 's7-1200, 20 items, PDU 240',
    protocol: 's7',
    server: { profile: 's7-1200', maxItems: 20 },
    url: { rack: 0, slot: 1, pdu: 240 },
    faults: ALL,
  },
  { id: 's7-300', protocol: 's7', server: { profile: 's7-300' }, url: { rack: 0, slot: 2, pdu: 240 }, faults: ALL },
  {
    id: 's7-300, 20 items',
    protocol: 's7',
    server: { profile: 's7-300', maxItems: 20 },
    url: { rack: 0, slot: 2, pdu: 240 },
    faults: ALL,
  },
  { id: 's7-400', protocol: 's7', server: { profile: 's7-400' }, url: { rack: 0, slot: 2, pdu: 480 }, faults: ALL },
  { id: 's7-200', protocol: 's7', server: { profile: 's7-200' }, url: { localTsap: '1000', remoteTsap: '1001', pdu: 240 }, faults: ALL },
  { id: 'logo', protocol: 's7', server: { profile: 'logo' }, url: { localTsap: '0100', remoteTsap: '0200', pdu: 240 }, faults: ALL },
  { id: 'fetchwrite', protocol: 'fetchwrite', server: {}, url: {}, faults: NO_CPU_MODE },
  { id: 'freeport+tcp', protocol: 'freeport', server: {}, url: { retries: 0, gap: 0 }, faults: NO_CPU_MODE },
];

/** The client's request timeout and backoff (every URL carries the timeout). */
const TIMEOUT_MS = 2000;
const BACKOFF = { initialDelay: 100, maxDelay: 2000, factor: 2, jitter: 0.2 };
/** A link must be back (a good poll) this long after its fault ended: a timeout, the longest backoff wait, slack for a loaded machine. */
const RECOVERY_MS = TIMEOUT_MS + BACKOFF.maxDelay * (1 + BACKOFF.jitter) + 1500;

/** Write slots: DINTs the simulator records (S7/FETCH/WRITE: DB2; freeport: stations 1..8). */
const SLOTS = 8;
/** The data block of the one item that answers an error during an itemError fault. */
const ITEM_DB = 3;
const STATIC_TAGS = 91;
const FREEPORT_STATIC = [9, 10, 11, 12];

function slotAddress(protocol, k) {
  return protocol === 'freeport' ? `ST${k + 1},DINT0` : `DB2,DINT${4 * k}`;
}

/**
 * PLC i's poll list: { addresses, statics: [{ index, type, value }], slots: [index of slot k],
 * item: index of the item that an itemError fault fails }.
 */
function tagsOf(protocol, i) {
  const addresses = [];
  const statics = [];
  let item;
  if (protocol === 'freeport') {
    for (const st of FREEPORT_STATIC) {
      for (const off of [0, 2]) {
        statics.push({ index: addresses.length, type: 'INT', value: freeportStatic(i, st, off) });
        addresses.push(`ST${st},INT${off}`);
      }
    }
    item = addresses.length - 1;
  } else {
    for (const t of plcTable(100, i).slice(0, STATIC_TAGS)) {
      statics.push({ index: addresses.length, type: t.type, value: t.value });
      addresses.push(t.address);
    }
    item = addresses.length;
    statics.push({ index: item, type: 'INT', value: itemValue(i) });
    addresses.push(`DB${ITEM_DB},INT0`);
  }
  const slots = [];
  for (let k = 0; k < SLOTS; k++) {
    slots.push(addresses.length);
    addresses.push(slotAddress(protocol, k));
  }
  return { addresses, statics, slots, item };
}

function itemValue(i) {
  return 1000 + i;
}

function freeportStatic(i, station, offset) {
  return ((i * 131 + station * 17 + offset * 7) % 30000) - 15000;
}

/**
 * Milliseconds of an episode of `fault` and its parameter, drawn from `rnd`.
 * Slow answers come up to 4 s late, twice the timeout; on a freeport bus at
 * most 1.5 timeouts late: its default frame does not say which station
 * answers, and the master drains the line one timeout after a timeout, so a
 * reply later than two timeouts would be taken for the next request's (a
 * limit of the protocol, lib/freeport/README.md), which no master can tell.
 */
function drawEpisode(fault, rnd, protocol) {
  const between = (lo, hi) => Math.round(lo + rnd() * (hi - lo));
  switch (fault) {
    case 'reset':
    case 'garbage':
      return { duration: 0 };
    case 'slow':
      return { duration: between(2000, 8000), delayMs: between(200, protocol === 'freeport' ? 1.5 * TIMEOUT_MS : 2 * TIMEOUT_MS) };
    case 'silence':
      return { duration: between(1000, 6000) };
    case 'restart':
      return { duration: between(500, 5000) };
    case 'half':
      return { duration: between(1000, 3000) };
    default:
      return { duration: between(1000, 5000) };
  }
}

/**
 * The fleet: per PLC its driver, tags and fault schedule (episodes
 * { fault, at, duration, ... } in ms from the run's start). A quarter of the
 * PLCs stay healthy all along: their poll rate is the measure that a faulty
 * PLC never slows the others. Every episode ends RECOVERY_MS plus 3 s before
 * the end, so every link must be back when the run ends. `calm`: no faults
 * at all (the same load without chaos, to compare).
 */
function fleetPlan({ seed, plcs, durationMs, calm = false }) {
  const rnd = prng(seed);
  const warm = Math.min(5000, durationMs / 10);
  const lastEnd = durationMs - RECOVERY_MS - 3000;
  const fleet = [];
  for (let i = 0; i < plcs; i++) {
    const driver = DRIVERS[i % DRIVERS.length];
    const healthy = rnd() < 0.25 || calm;
    const schedule = [];
    let t = warm + rnd() * 4000;
    for (let more = !healthy; more;) {
      const fault = driver.faults[Math.floor(rnd() * driver.faults.length)];
      const e = { fault, at: Math.round(t), ...drawEpisode(fault, rnd, driver.protocol) };
      more = e.at + e.duration <= lastEnd;
      if (more) schedule.push(e);
      t = e.at + e.duration + RECOVERY_MS + rnd() * 6000;
    }
    fleet.push({ index: i, driver, healthy: schedule.length === 0, schedule, ...tagsOf(driver.protocol, i) });
  }
  return fleet;
}

module.exports = {
  prng,
  FAULTS,
  DRIVERS,
  TIMEOUT_MS,
  BACKOFF,
  RECOVERY_MS,
  SLOTS,
  ITEM_DB,
  FREEPORT_STATIC,
  fleetPlan,
  freeportStatic,
  itemValue,
  slotAddress,
};
