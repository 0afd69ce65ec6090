'use strict';
// `npm run chaos -- --nodered`: the same fleet, faults and writes through a
// real Node-RED (nodered-worker.js): per PLC a connection, a read node
// polling its tags and a write node for its write slots; Catch and Status
// nodes for the whole tab. Half-way through, a full redeploy. Measured at the
// end: per PLC and fault episode how often Status left "connected" and how
// often Catch heard of it (once per episode is the aim), nodes left not
// connected, connections at the simulators after the redeploy and at the
// end, writes exactly once or rejected naming their tag, values read.
const { fork } = require('node:child_process');
const os = require('node:os');
const path = require('node:path');
const { ask } = require('../lib/fleet');
const { fleetPlan, slotAddress, SLOTS, TIMEOUT_MS } = require('./plan');
const { urlOf } = require('./clients');

/** The flow: per PLC conn<i>, read<i>, write<i>; one Catch, one Status, one chaos-record. */
function chaosFlow(fleet, ports, fingerprints, intervalMs) {
  const flow = [
    { id: 'tab', type: 'tab', label: 'chaos' },
    { id: 'rec', type: 'chaos-record', z: 'tab', x: 600, y: 100 },
    { id: 'catch', type: 'catch', z: 'tab', scope: null, uncaught: false, wires: [['rec']], x: 100, y: 100 },
    { id: 'status', type: 'status', z: 'tab', scope: null, wires: [['rec']], x: 100, y: 200 },
  ];
  fleet.forEach((p, i) => {
    flow.push({ id: `conn${i}`, type: 'plcwire-connection', name: `plc${i}`, url: urlOf(p, ports[i], fingerprints[i]) });
    flow.push({
      id: `read${i}`,
      type: 'plcwire-read',
      z: 'tab',
      name: `plc${i}`,
      connection: `conn${i}`,
      interval: intervalMs,
      output: 'object',
      deadband: 0,
      tags: p.addresses.map((address, k) => ({ name: `t${k}`, address })),
      wires: [['rec']],
      x: 300,
      y: 100,
    });
    flow.push({
      id: `write${i}`,
      type: 'plcwire-write',
      z: 'tab',
      name: `plc${i}`,
      connection: `conn${i}`,
      tags: Array.from({ length: SLOTS }, (_, k) => ({ name: `slot${k}`, address: slotAddress(p.driver.protocol, k) })),
      wires: [['rec']],
      x: 300,
      y: 200,
    });
  });
  return flow;
}

function forked(file) {
  const child = fork(path.join(__dirname, file), [], { serialization: 'advanced', stdio: 'inherit' });
  const exited = new Promise((resolve) => child.once('exit', resolve));
  return {
    child,
    ask: (msg) => ask(child, msg),
    stop: async () => {
      if (child.exitCode === null) child.send({ op: 'stop' });
      await Promise.race([exited, new Promise((r) => setTimeout(r, 20_000))]);
      if (child.exitCode === null) child.kill();
    },
  };
}

const wait = (ms) => new Promise((r) => setTimeout(r, Math.max(0, ms)));

/** Polls `fn` every 200 ms until it returns true or `ms` passed; resolves whether it did. */
async function eventually(fn, ms) {
  const until = Date.now() + ms;
  for (;;) {
    if (await fn()) return true;
    if (Date.now() > until) return false;
    await wait(200);
  }
}

async function runNodeRed(o, log = console.log) {
  log(
    `chaos through Node-RED: seed ${o.seed}, ${o.plcs} PLCs, ${o.durationMs / 1000} s, polls every ${o.intervalMs} ms, a write per PLC every ${o.writeEveryMs} ms, a full redeploy half-way`,
  );
  const fleet = fleetPlan({ seed: o.seed, plcs: o.plcs, durationMs: o.durationMs, calm: o.calm });
  const plcs = forked('server-worker.js');
  const red = forked('nodered-worker.js');
  const load = { start: os.loadavg()[0], highest: os.loadavg()[0], end: 0 };
  const sampleLoad = setInterval(() => (load.highest = Math.max(load.highest, os.loadavg()[0])), 5000);
  try {
    const { version } = await red.ask({ op: 'start' });
    const plus = fleet.filter((p) => p.driver.protocol === 's7plus').length;
    const t0 = Date.now() + 4000 + o.plcs * 20 + plus * 400;
    o.t0 = t0;
    const { ports, fingerprints } = await plcs.ask({ op: 'start', seed: o.seed, plcs: o.plcs, durationMs: o.durationMs, calm: o.calm, t0 });
    const flow = chaosFlow(fleet, ports, fingerprints, o.intervalMs);
    const expect = fleet.map((p) => p.statics.map((s) => [`t${s.index}`, s.type, s.value]));
    const first = await red.ask({ op: 'deploy', flow, expect });
    await red.ask({ op: 'drive', plcs: o.plcs, t0, durationMs: o.durationMs, writeEveryMs: o.writeEveryMs });
    // The full redeploy half-way, faults going on.
    await wait(t0 + o.durationMs / 2 - Date.now());
    const redeployAt = Date.now();
    const second = await red.ask({ op: 'deploy', flow });
    // Five seconds on: no PLC with two connections (the old nodes' links closed, the new ones opened once).
    await wait(5000);
    const after = (await plcs.ask({ op: 'status' })).connections;
    await wait(t0 + o.durationMs - Date.now());
    // Every fault has ended (plan.js: RECOVERY_MS and 3 s before the end); Node-RED's own backoff (up to 30 s) may take longer.
    const back = await eventually(
      async () => (await red.ask({ op: 'states', plcs: o.plcs })).states.every((s) => s === 'connected'),
      35_000,
    );
    const status = await plcs.ask({ op: 'status' });
    const { states } = await red.ask({ op: 'states', plcs: o.plcs });
    await wait(Math.max(2 * o.writeEveryMs, 2 * TIMEOUT_MS));
    const results = await red.ask({ op: 'results' });
    const { applied, impostorApplied } = await plcs.ask({ op: 'records' });
    load.end = os.loadavg()[0];
    load.highest = Math.max(load.highest, load.end);
    return evaluateNodeRed({
      o,
      fleet,
      version,
      deployMs: [first.deployMs, second.deployMs],
      redeployAt,
      after,
      back,
      status,
      states,
      results,
      applied,
      impostorApplied,
      load,
    });
  } finally {
    clearInterval(sampleLoad);
    await red.stop();
    await plcs.stop();
  }
}

/** For each PLC's episodes, from its start to the next one's (or the run's end): Status left "connected" how often, Catch heard how often. */
function perEpisode(o, fleet, status, record) {
  const end = o.t0 + o.durationMs;
  const byPlc = fleet.map(() => ({ statuses: [], errors: [] }));
  for (const s of record.statuses) if (s.type === 'plcwire-read' && byPlc[s.plc]) byPlc[s.plc].statuses.push(s);
  for (const e of record.errors) if (e.type !== 'plcwire-write' && byPlc[e.plc]) byPlc[e.plc].errors.push(e);
  const episodes = [];
  fleet.forEach((p, i) => {
    const eps = status.episodes[i];
    // The moments the read node's status left green (connected, every tag good).
    const left = [];
    let green = false;
    for (const s of byPlc[i].statuses) {
      const isGreen = s.fill === 'green';
      if (green && !isGreen) left.push(s.t);
      green = isGreen;
    }
    eps.forEach((e, k) => {
      const to = k + 1 < eps.length ? eps[k + 1].start : end;
      const inside = (t) => t >= e.start && t < to;
      const caught = byPlc[i].errors.filter((x) => inside(x.t));
      episodes.push({
        plc: i,
        fault: e.fault,
        status: left.filter(inside).length,
        catch: caught.length,
        caught: caught.map((x) => `${x.type} ${x.code ?? ''} ${x.message.slice(0, 140)}`),
      });
    });
  });
  return episodes;
}

function evaluateNodeRed(r) {
  const { o, fleet, status, results, applied, impostorApplied } = r;
  const { record, writes } = results;
  const failed = [];
  const fail = (text) => failed.length < 40 && failed.push(text);
  // Writes: exactly once, or rejected through Catch naming the tag.
  const t = { writes: 0, acked: 0, rejected: 0, cut: 0, lost: 0, twice: 0, phantom: 0, pending: 0, unnamed: 0, inDoubt: 0 };
  fleet.forEach((p, i) => {
    const w = writes[i] ?? { seq: 0, slots: [], outcomes: [] };
    const counts = new Map();
    for (const [slot, value] of applied[i]) {
      const n = value - i * 1_000_000;
      if (n >= 1 && n <= w.seq && w.slots[n - 1] === slot) counts.set(n, (counts.get(n) ?? 0) + 1);
      else if (value !== 0) {
        t.phantom++;
        fail(`PLC ${i}: the PLC applied ${value} to slot ${slot}, never written there`);
      }
    }
    for (let n = 1; n <= w.seq; n++) {
      const times = counts.get(n) ?? 0;
      const outcome = w.outcomes[n - 1];
      t.writes++;
      if (outcome === 1) {
        t.acked++;
        if (times === 0) {
          t.lost++;
          fail(`PLC ${i}: write ${n} acknowledged, never applied`);
        }
      } else if (outcome === 2) {
        t.rejected++;
        if (times === 1) t.inDoubt++;
      } else if (outcome === 4) t.cut++;
      else if (outcome === 3) {
        t.twice++;
        fail(`PLC ${i}: write ${n} both acknowledged and rejected`);
      } else {
        t.pending++;
        fail(`PLC ${i}: write ${n} never settled (neither sent on nor caught)`);
      }
      if (times > 1) {
        t.twice++;
        fail(`PLC ${i}: write ${n} applied ${times} times`);
      }
    }
    if (impostorApplied[i].length > 0) fail(`PLC ${i}: ${impostorApplied[i].length} writes applied by the PLC with another certificate`);
  });
  for (const e of record.errors) {
    if (e.type === 'plcwire-write' && !/slot\d/.test(e.message)) {
      t.unnamed++;
      fail(`PLC ${e.plc}: a write rejected without naming its tag: ${e.message}`);
    }
  }
  // Catch and Status per fault episode.
  const episodes = perEpisode(o, fleet, status, record);
  const seen = (key) => episodes.filter((e) => e[key] > 0);
  const once = (key) => episodes.filter((e) => e[key] === 1);
  const unseen = {};
  for (const e of episodes) if (e.status === 0 && e.catch === 0) unseen[e.fault] = (unseen[e.fault] ?? 0) + 1;
  const most = (key) => episodes.reduce((m, e) => Math.max(m, e[key]), 0);
  // Links, connections.
  const notConnected = r.states.map((s, i) => [i, s]).filter(([, s]) => s !== 'connected');
  for (const [i, s] of notConnected) fail(`PLC ${i} (${fleet[i].driver.id}): its connection node is ${s} at the end`);
  const doubled = r.after.map((n, i) => [i, n]).filter(([, n]) => n > 1);
  for (const [i, n] of doubled) fail(`PLC ${i}: ${n} connections at the simulator 5 s after the full redeploy`);
  const connections = status.connections.reduce((a, b) => a + b, 0);
  status.connections.forEach((n, i) => n !== 1 && fail(`PLC ${i}: ${n} connections at the simulator at the end`));
  const healthy = fleet.filter((p) => p.healthy);
  const due = Math.floor(o.durationMs / o.intervalMs);
  const achieved = healthy.reduce((a, p) => a + (record.reads[p.index] ?? 0), 0) / Math.max(1, healthy.length * due);
  if (record.wrong.length > 0) for (const w of record.wrong.slice(0, 5)) fail(`wrong value: ${w}`);
  const row = (check, measured, limit, ok, skipped = false) => ({ check, measured: String(measured), limit, ok, skipped });
  const rows = [
    row(
      'writes acknowledged, applied exactly once',
      `${t.acked} of ${t.writes}`,
      'lost 0, twice 0, unsettled 0',
      !t.lost && !t.twice && !t.pending,
    ),
    row('writes rejected to Catch naming the tag', `${t.rejected}`, 'unnamed 0', t.unnamed === 0),
    row('writes applied that were never written', `${t.phantom}`, '0', t.phantom === 0),
    row('values read that the PLC did not hold', `${record.wrong.length}`, '0', record.wrong.length === 0),
    row(
      'fault episodes Status saw (left connected)',
      `${seen('status').length} of ${episodes.length}, once: ${once('status').length}, most ${most('status')}`,
      'the aim: once each',
      true,
      true,
    ),
    row(
      'fault episodes Catch saw',
      `${seen('catch').length} of ${episodes.length}, once: ${once('catch').length}, most ${most('catch')}`,
      'the aim: once each',
      true,
      true,
    ),
    row('connection nodes not connected at the end', `${notConnected.length}`, '0', notConnected.length === 0 && r.back),
    row('PLCs with 2 connections after the full redeploy', `${doubled.length}`, '0', doubled.length === 0),
    row('connections at the simulators at the end', `${connections}`, `${o.plcs}`, connections === o.plcs),
    row(
      'polls achieved / due, healthy PLCs',
      `${(achieved * 100).toFixed(1)} %, load ${r.load.highest.toFixed(1)}`,
      '≥ 95 %',
      o.countsOnly || achieved >= 0.95,
      o.countsOnly,
    ),
    row(
      'event-loop delay p99 (Node-RED)',
      `${results.loopP99Ms.toFixed(1)} ms, load ${r.load.highest.toFixed(1)}`,
      '< 50 ms',
      o.countsOnly || results.loopP99Ms < 50,
      o.countsOnly,
    ),
  ];
  for (const x of rows) {
    if (x.skipped) x.within = x.check.startsWith('fault episodes') ? undefined : x.ok;
    if (!x.ok && !x.skipped && !failed.some((f) => f.startsWith(x.check))) failed.push(`${x.check}: ${x.measured}`);
  }
  const figures = [
    `Node-RED ${r.version}; deploy ${r.deployMs[0].toFixed(0)} ms, full redeploy half-way ${r.deployMs[1].toFixed(0)} ms`,
    `seed ${o.seed}; ${healthy.length} of ${fleet.length} PLCs without faults; ${episodes.length} fault episodes`,
    `episodes neither Status nor Catch saw, by fault: ${
      Object.entries(unseen)
        .map(([f, n]) => `${f} ${n}`)
        .join(', ') || 'none'
    }`,
    `writes: ${t.writes}, ${t.acked} acknowledged, ${t.rejected} rejected, of those ${t.inDoubt} applied by the PLC (answer lost: in doubt); ${t.cut} in flight when the redeploy closed their node (applied at most once)`,
    `Catch messages: ${record.errors.length}; Status messages: ${record.statuses.length}`,
    ...record.wrong.slice(0, 3).map((w) => `wrong value: ${w}`),
    ...(() => {
      const worst = episodes.reduce((m, e) => (e.catch > (m ? m.catch : 0) ? e : m), undefined);
      return worst ? [`the episode Catch heard most of (PLC ${worst.plc}, ${worst.fault}):`, ...worst.caught.map((c) => `  ${c}`)] : [];
    })(),
    `load average (1 min) on ${os.availableParallelism()} cores: ${r.load.start.toFixed(1)} at the start, ${r.load.highest.toFixed(1)} at the highest, ${r.load.end.toFixed(1)} at the end`,
  ];
  return { o, rows, failed, histories: [], figures, episodes };
}

module.exports = { runNodeRed };
