'use strict';
// The chaos run's plan, the same in both processes: which driver each
// simulated PLC speaks, its tags, and its fault schedule, all drawn from one
// seeded generator (mulberry32), so a seed replays the same run.
//
// DRIVERS is data: a driver is one entry (its simulator kind, profile,
// URL parameters and the faults that apply to it), the S7CommPlus row
// (an S7-1500 over TLS, with its TLS faults) among them.
const { plcTable } = require('../lib/fleet');
// mulberry32: small, fast, good enough to draw a schedule from (the benchmark tables' generator).
const { prng } = require('../lib/tables');

/** Every fault of issue #26; the last three only where S7CommPlus runs over TLS. */
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
  tlsAlert: 'a fatal TLS alert in mid-session, then the PLC closes',
  recordReset: 'half a TLS record, then RST',
  certificate: 'a restart with another certificate (refused, never trusted), then the right one back',
};
const TLS_ONLY = ['tlsAlert', 'recordReset', 'certificate'];
const ALL = Object.keys(FAULTS).filter((f) => !TLS_ONLY.includes(f));
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
  // S7CommPlus over TLS, the certificate pinned: a standard DB by address, an optimized DB by name. The TLS
  // faults are drawn as often as all the others together, so that a short run sees them.
  {
    id: 's7-1500 S7CommPlus/TLS',
    protocol: 's7plus',
    server: { profile: 's7-1500' },
    url: {},
    faults: [...ALL, ...TLS_ONLY.flatMap((f) => [f, f, f])],
  },
];

/** The client's request timeout and backoff (every URL carries the timeout). */
const TIMEOUT_MS = 2000;
const BACKOFF = { initialDelay: 100, maxDelay: 2000, factor: 2, jitter: 0.2 };
/** A link must be back (a good poll) this long after its fault ended: a timeout, the longest backoff wait, slack for a loaded machine. */
const RECOVERY_MS = TIMEOUT_MS + BACKOFF.maxDelay * (1 + BACKOFF.jitter) + 1500;

/** Write slots: DINTs the simulator records (S7/FETCH/WRITE: DB2; freeport: stations 1..8; S7CommPlus: "Line".slot[k] of the optimized DB2). */
const SLOTS = 8;
/** The data block of the one item that answers an error during an itemError fault. */
const ITEM_DB = 3;
const STATIC_TAGS = 91;
const FREEPORT_STATIC = [9, 10, 11, 12];

/**
 * The S7CommPlus PLC's program: DB1 "Image" standard (the static table's bytes, read by address), DB2 "Line"
 * optimized (the write slots and four statics, by name), DB3 "Item" standard (the item that an itemError fault
 * fails, by address).
 */
const PLUS_SOURCES = [
  {
    name: 'Image.db',
    content: `DATA_BLOCK "Image"\n{ S7_Optimized_Access := 'FALSE' }\nVERSION : 0.1\nNON_RETAIN\n   STRUCT\n      raw : Array[0..3071] of Byte;\n   END_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n`,
  },
  {
    name: 'Line.db',
    content: `DATA_BLOCK "Line"\n{ S7_Optimized_Access := 'TRUE' }\nVERSION : 0.1\nNON_RETAIN\n   STRUCT\n      slot : Array[0..${SLOTS - 1}] of DInt;\n      speed : Int;\n      level : Real;\n      count : DInt;\n      running : Bool;\n   END_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n`,
  },
  {
    name: 'Item.db',
    content: `DATA_BLOCK "Item"\n{ S7_Optimized_Access := 'FALSE' }\nVERSION : 0.1\nNON_RETAIN\n   STRUCT\n      v : Int;\n   END_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n`,
  },
];
const PLUS_DB = { Image: 1, Line: 2, Item: ITEM_DB };
/** Bytes of DB1 "Image": the static table's tags lie below (bench/lib/fleet.js plcTable, shifted by up to 30). */
const PLUS_IMAGE_BYTES = 3072;
/** The S7CommPlus PLC's statics by name in the optimized block, PLC i's values. */
function plusNamed(i) {
  return [
    { name: 'speed', address: '"Line".speed', type: 'INT', value: 100 + i },
    { name: 'level', address: '"Line".level', type: 'REAL', value: i + 0.5 },
    { name: 'count', address: '"Line".count', type: 'DINT', value: 70_000 + i },
    { name: 'running', address: '"Line".running', type: 'BOOL', value: i % 2 === 1 },
  ];
}
/** Tags by address in the S7CommPlus PLC's standard DB1 (with the 4 names, the item and the 8 slots: 100). */
const PLUS_BY_ADDRESS = 87;

function slotAddress(protocol, k) {
  if (protocol === 'freeport') return `ST${k + 1},DINT0`;
  return protocol === 's7plus' ? `"Line".slot[${k}]` : `DB2,DINT${4 * k}`;
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
    const plus = protocol === 's7plus';
    for (const t of plcTable(100, i).slice(0, plus ? PLUS_BY_ADDRESS : STATIC_TAGS)) {
      statics.push({ index: addresses.length, type: t.type, value: t.value });
      addresses.push(t.address);
    }
    if (plus) {
      for (const t of plusNamed(i)) {
        statics.push({ index: addresses.length, type: t.type, value: t.value });
        addresses.push(t.address);
      }
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
    case 'tlsAlert':
    case 'recordReset':
      return { duration: 0 };
    case 'certificate':
      // Long enough for the client to try again (and refuse again) at least once at the longest backoff.
      return { duration: between(3000, 6000) };
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
  PLUS_SOURCES,
  PLUS_DB,
  PLUS_IMAGE_BYTES,
  plusNamed,
  fleetPlan,
  freeportStatic,
  itemValue,
  slotAddress,
};
