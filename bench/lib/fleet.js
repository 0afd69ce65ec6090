'use strict';
// A fleet of simulated PLCs for the scaling benchmarks (bench/many-plcs.js,
// bench/nodered.js): one server process holding N S7 simulators, each on its
// own port with its own memory, and per-PLC tag tables.
//
// PLC i reads the benchmark's scattered table of its size shifted by
// 2 × (i mod 16) bytes, so no two neighbouring PLCs share address strings
// (a client cannot profit from a cache shared between PLCs) while every PLC
// needs the same PDUs.
const { fork } = require('node:child_process');
const path = require('node:path');
const { table, image, DB1_SIZE, STRING_LENGTH } = require('./tables');

const SIZES = { INT: 2, REAL: 4, BOOL: 1, STRING: STRING_LENGTH + 2 };

function addressOf(t) {
  switch (t.type) {
    case 'INT':
      return `DB1,INT${t.offset}`;
    case 'REAL':
      return `DB1,REAL${t.offset}`;
    case 'BOOL':
      return `DB1,X${t.offset}.${t.bit}`;
    case 'STRING':
      return `DB1,S${t.offset}.${STRING_LENGTH}`;
  }
  throw new Error(t.type);
}

const cache = new Map();
/** The tags of PLC `index` (with the values its DB1 holds): `${tags} scattered`, shifted. */
function plcTable(tags, index) {
  const base = cache.get(tags) ?? table(`${tags} scattered`);
  cache.set(tags, base);
  const shift = 2 * (index % 16);
  return base.map((t) => {
    const s = { ...t, offset: t.offset + shift };
    if (s.offset + SIZES[s.type] > DB1_SIZE) throw new Error(`PLC ${index}: ${tags} tags do not fit DB1 shifted by ${shift}`);
    s.address = addressOf(s);
    return s;
  });
}

/** DB1 offsets of PLC `index`'s INT tags: the ones the server changes when asked to (for 'changes' modes). */
function changingOffsets(tags) {
  return tags.filter((t) => t.type === 'INT').map((t) => t.offset);
}

function ask(child, msg) {
  return new Promise((resolve, reject) => {
    const onExit = (code) => reject(new Error(`fleet server exited with ${code}`));
    child.once('exit', onExit);
    child.once('message', (m) => {
      child.off('exit', onExit);
      if (m.ok === false) reject(new Error(m.error));
      else resolve(m);
    });
    child.send(msg);
  });
}

/**
 * Starts `count` simulators (profile S7-1500) in a child process, PLC i's DB1
 * holding plcTable(tags, i). Returns { ports, stats(), change(everyMs), stop() };
 * stats() → { connections: [per PLC], readsPerPlc: [per PLC], reads, writes, cpuUs } (reads and writes
 * are jobs served since start; cpuUs the server process's own CPU time).
 */
async function startFleet(count, tags) {
  const child = fork(path.join(__dirname, '..', 'fleet-server-worker.js'), [], { serialization: 'advanced', stdio: 'inherit' });
  const plcs = [];
  for (let i = 0; i < count; i++) {
    const t = plcTable(tags, i);
    plcs.push({ db1: image(t), changing: changingOffsets(t) });
  }
  let ports;
  try {
    ({ ports } = await ask(child, { op: 'start', plcs }));
  } catch (err) {
    child.kill();
    throw err;
  }
  return {
    ports,
    stats: () => ask(child, { op: 'stats' }),
    /** From now on every `everyMs` ms, one INT tag of each PLC changes (round robin over its INT tags). */
    change: (everyMs) => ask(child, { op: 'change', everyMs }),
    /** Drops every client connection of every PLC (a PLC restart as the clients see it). */
    drop: () => ask(child, { op: 'drop' }),
    stop: () =>
      new Promise((resolve) => {
        if (child.exitCode !== null) return resolve();
        child.once('exit', resolve);
        child.send({ op: 'stop' });
      }),
  };
}

/** Runs bench/fleet-client-worker.js with `job` in a fresh process (see its header); resolves its result or { client, error }. */
function runFleetClient(job, execArgv = []) {
  const child = fork(path.join(__dirname, '..', 'fleet-client-worker.js'), [], { serialization: 'advanced', stdio: 'inherit', execArgv });
  return new Promise((resolve) => {
    const timer = setTimeout(() => {
      child.kill();
      resolve({ client: job.client, error: 'timed out' });
    }, 120_000 + job.durationMs);
    child.once('message', (m) => {
      clearTimeout(timer);
      resolve(m.ok ? m.result : { client: job.client, error: m.error });
    });
    child.once('exit', (code) => {
      clearTimeout(timer);
      resolve({ client: job.client, error: `exited with ${code}` });
    });
    child.send(job);
  });
}

/** Waits until every PLC of `fleet` has no connection left (a client's FIN arrives a little after its process ended); the stats then. */
async function closedStats(fleet, ms = 3000) {
  let s = await fleet.stats();
  const until = Date.now() + ms;
  while (s.connections.some((c) => c !== 0) && Date.now() < until) {
    await new Promise((resolve) => setTimeout(resolve, 100));
    s = await fleet.stats();
  }
  return s;
}

/** p-th percentile of a sorted array. */
function percentile(sorted, p) {
  if (sorted.length === 0) return NaN;
  return sorted[Math.min(sorted.length - 1, Math.floor((p / 100) * sorted.length))];
}

module.exports = { plcTable, startFleet, runFleetClient, closedStats, percentile, ask };
