'use strict';
// The chaos run's PLCs, in their own process: per PLC a simulator (S7 of its
// profile, FETCH/WRITE, a freeport bus over TCP, or an S7-1500 serving
// S7CommPlus over TLS with a certificate of its own) behind a ChaosProxy, and
// its fault schedule played on the shared clock. Every write a PLC applies to
// a write slot is recorded with its value. Driven over IPC by run.js:
//   { op: 'start', seed, plcs, durationMs, t0 } → { ports, fingerprints: [per PLC: S7CommPlus ones, else undefined] }
//   { op: 'status' } → { connections: [per PLC], episodes: [per PLC: { fault, start, end }] }
//   { op: 'records' } → { applied: [per PLC: [[slot, value], ...]], impostorApplied: [the same, at the
//                         PLC with another certificate of a certificate fault] }
//   { op: 'stop' } → exits
const path = require('node:path');
const { plcwire, DIST } = require('../lib/peers');
const { image } = require('../lib/tables');
const { plcTable } = require('../lib/fleet');
const { ChaosProxy } = require('./proxy');
const {
  fleetPlan,
  SLOTS,
  ITEM_DB,
  FREEPORT_STATIC,
  PLUS_SOURCES,
  PLUS_DB,
  PLUS_IMAGE_BYTES,
  plusNamed,
  freeportStatic,
  itemValue,
} = require('./plan');

const plcs = [];
const timers = new Set();

function later(ms, fn) {
  const t = setTimeout(
    () => {
      timers.delete(t);
      fn();
    },
    Math.max(0, ms),
  );
  timers.add(t);
}

/** S7 and FETCH/WRITE memory: DB1 the static table, DB2 the write slots, DB3 the one item of itemError. */
function memoryOf(lib, i) {
  const memory = new lib.PlcMemory({ dataBlocks: { 1: 32768, 2: 4 * SLOTS, [ITEM_DB]: 16 } });
  image(plcTable(100, i)).copy(memory.area('DB', 1));
  memory.area('DB', ITEM_DB).writeInt16BE(itemValue(i), 0);
  return memory;
}

/** Records in `into` every DINT written to the write slots of DB2 in `memory`, as [slot, value]. */
function recordSlots(memory, into) {
  memory.on('write', (a) => {
    if (a.area !== 'DB' || a.dbNumber !== 2) return;
    for (let off = a.offset - (a.offset % 4); off + 4 <= a.offset + a.length; off += 4) {
      if (off >= a.offset && off < 4 * SLOTS) into.push([off / 4, a.data.readInt32BE(off - a.offset)]);
    }
  });
}

/**
 * An S7-1500 serving S7CommPlus over TLS with a certificate of its own (and PUT/GET on the same port). Its
 * memory holds PLC i's values when `values` (the real PLC); zeros otherwise (the impostor of a certificate
 * fault: a client that trusted it silently would read wrong values and write where nobody looks).
 */
async function plusPlc(lib, i, values) {
  const { generateCertificate } = require(path.join(DIST, 'lib/s7plus/transport/cert.js'));
  const cert = await generateCertificate({ commonName: `chaos PLC ${i}${values ? '' : ' (another certificate)'}` });
  const service = new lib.S7PlusService({ sources: PLUS_SOURCES, db: PLUS_DB, tls: { cert: cert.cert, key: cert.key } });
  const line = service.model.dbs.find((d) => d.number === 2);
  const memory = new lib.PlcMemory({ dataBlocks: { 1: PLUS_IMAGE_BYTES, 2: line.length, [ITEM_DB]: 16 } });
  if (values) {
    image(plcTable(100, i)).copy(memory.area('DB', 1), 0, 0, PLUS_IMAGE_BYTES);
    memory.area('DB', ITEM_DB).writeInt16BE(itemValue(i), 0);
    const at = (name) => line.type.members.find((m) => m.name === name);
    for (const t of plusNamed(i)) {
      const m = at(t.name);
      const db = memory.area('DB', 2);
      if (t.type === 'INT') db.writeInt16BE(t.value, m.byte);
      else if (t.type === 'REAL') db.writeFloatBE(t.value, m.byte);
      else if (t.type === 'DINT') db.writeInt32BE(t.value, m.byte);
      else if (t.value) db[m.byte] |= 1 << m.bit;
    }
  }
  const sim = new lib.S7Server({ port: 0, profile: 's7-1500', memory, s7plus: service });
  return { sim, port: await sim.listen(), fingerprint: service.fingerprint, memory };
}

async function startPlc(lib, p) {
  const entry = { p, applied: [], episodes: [], impostorApplied: [] };
  const record = (slot, value) => entry.applied.push([slot, value]);
  if (p.driver.protocol === 'freeport') {
    const stations = {};
    for (let k = 1; k <= SLOTS; k++) stations[k] = Buffer.alloc(4);
    for (const st of FREEPORT_STATIC) {
      const b = Buffer.alloc(4);
      b.writeInt16BE(freeportStatic(p.index, st, 0), 0);
      b.writeInt16BE(freeportStatic(p.index, st, 2), 2);
      stations[st] = b;
    }
    const bus = new lib.FreeportBus({ stations });
    bus.on('request', (req, answered) => {
      if (req.command === 'write' && answered && req.station >= 1 && req.station <= SLOTS) {
        record(req.station - 1, bus.station(req.station).data.readInt32BE(0));
      }
    });
    entry.sim = bus;
    entry.simPort = await bus.listenTcp({ port: 0 });
    entry.connections = () => bus.connectionCount;
  } else if (p.driver.protocol === 's7plus') {
    const plc = await plusPlc(lib, p.index, true);
    recordSlots(plc.memory, entry.applied);
    entry.sim = plc.sim;
    entry.simPort = plc.port;
    entry.fingerprint = plc.fingerprint;
    entry.connections = () => entry.sim.connectionCount;
    // The PLC with another certificate, ready before its fault, so that the swap happens when the fault begins.
    if (p.schedule.some((e) => e.fault === 'certificate')) {
      entry.impostor = await plusPlc(lib, p.index, false);
      recordSlots(entry.impostor.memory, entry.impostorApplied);
    }
  } else {
    const memory = memoryOf(lib, p.index);
    recordSlots(memory, entry.applied);
    if (p.driver.protocol === 's7') {
      entry.sim = new lib.S7Server({ port: 0, memory, ...p.driver.server });
      entry.simPort = await entry.sim.listen();
    } else {
      entry.sim = new lib.FetchWriteServer({ port: 0, memory });
      entry.simPort = (await entry.sim.listen()).fetchPort;
    }
    entry.connections = () => entry.sim.connectionCount;
  }
  entry.proxy = new ChaosProxy(entry.simPort);
  entry.port = await entry.proxy.listen();
  return entry;
}

/** Starts episode `e` of PLC `entry` now; returns how to end it. */
function begin(entry, e) {
  const { sim, proxy } = entry;
  const protocol = entry.p.driver.protocol;
  switch (e.fault) {
    case 'reset':
      proxy.reset();
      return () => undefined;
    case 'silence':
      proxy.setMode('silent');
      return () => proxy.setMode('pass');
    case 'slow':
      proxy.setMode('slow', e.delayMs);
      return () => proxy.setMode('pass');
    case 'half':
      proxy.setMode('half');
      return () => proxy.setMode('pass');
    case 'garbage':
      proxy.setMode('garbage');
      return () => undefined;
    case 'backlog':
      proxy.setMode('backlog');
      proxy.reset();
      return () => proxy.setMode('pass');
    case 'restart': {
      const gone = proxy.gone();
      return () => gone.then(() => proxy.back());
    }
    case 'refused':
      if (protocol === 'freeport') {
        proxy.setMode('refuse');
        proxy.reset();
        return () => proxy.setMode('pass');
      }
      sim.faults.refuseConnections = true;
      sim.faults.dropConnections();
      return () => (sim.faults.refuseConnections = false);
    case 'tlsAlert':
      proxy.setMode('alert');
      return () => undefined;
    case 'recordReset':
      proxy.setMode('recordReset');
      return () => undefined;
    case 'certificate': {
      // The PLC restarts with another certificate: the same port, the impostor behind it.
      const swapped = (async () => {
        await proxy.gone();
        proxy.target = entry.impostor.port;
        await proxy.back();
      })();
      return async () => {
        await swapped;
        await proxy.gone();
        proxy.target = entry.simPort;
        await proxy.back();
      };
    }
    case 'itemError':
      if (protocol === 's7plus') {
        sim.memory.deleteDataBlock(ITEM_DB);
        return () => {
          sim.memory.createDataBlock(ITEM_DB, 16);
          sim.memory.area('DB', ITEM_DB).writeInt16BE(itemValue(entry.p.index), 0);
        };
      }
      if (protocol === 's7') {
        sim.faults.missingDb = ITEM_DB;
        return () => (sim.faults.missingDb = undefined);
      }
      if (protocol === 'fetchwrite') {
        const memory = sim.memory;
        memory.deleteDataBlock(ITEM_DB);
        return () => {
          memory.createDataBlock(ITEM_DB, 16);
          memory.area('DB', ITEM_DB).writeInt16BE(itemValue(entry.p.index), 0);
        };
      }
      sim.station(FREEPORT_STATIC[FREEPORT_STATIC.length - 1]).silent = true;
      return () => (sim.station(FREEPORT_STATIC[FREEPORT_STATIC.length - 1]).silent = false);
    case 'stop':
      sim.stop('command');
      return () => sim.start('warm');
  }
  throw new Error(`unknown fault ${e.fault}`);
}

function schedule(entry, t0) {
  for (const e of entry.p.schedule) {
    later(t0 + e.at - Date.now(), () => {
      const record = { fault: e.fault, start: Date.now(), end: undefined };
      entry.episodes.push(record);
      const end = begin(entry, e);
      later(e.duration, async () => {
        await end();
        record.end = Date.now();
      });
    });
  }
}

async function start(msg) {
  const lib = plcwire();
  const fleet = fleetPlan(msg);
  for (const p of fleet) plcs.push(await startPlc(lib, p));
  for (const entry of plcs) schedule(entry, msg.t0);
  return { ports: plcs.map((e) => e.port), fingerprints: plcs.map((e) => e.fingerprint) };
}

async function stop() {
  for (const t of timers) clearTimeout(t);
  timers.clear();
  await Promise.all(plcs.map((e) => e.proxy.close()));
  await Promise.all(plcs.map((e) => e.sim.close()));
  await Promise.all(plcs.map((e) => e.impostor?.sim.close()));
}

process.on('message', async (msg) => {
  try {
    if (msg.op === 'start') process.send({ ok: true, ...(await start(msg)) });
    else if (msg.op === 'status') {
      process.send({ ok: true, connections: plcs.map((e) => e.connections()), episodes: plcs.map((e) => e.episodes) });
    } else if (msg.op === 'records') {
      process.send({ ok: true, applied: plcs.map((e) => e.applied), impostorApplied: plcs.map((e) => e.impostorApplied) });
    } else if (msg.op === 'stop') {
      await stop();
      process.exit(0);
    }
  } catch (err) {
    process.send({ ok: false, error: String((err && err.stack) || err) });
  }
});
process.on('disconnect', () => process.exit(0));
