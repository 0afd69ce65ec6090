'use strict';
// The client side of `npm run chaos -- --nodered`: one real Node-RED (the
// version in the root node_modules) in its own process with, per PLC, a
// plcwire-connection, a plcwire-read polling its tags and a plcwire-write
// for its write slots; one Catch and one Status node (all nodes of the tab)
// and every read and write node wired to a chaos-record node
// (nodered-record/), which keeps what arrives with its time. Writes go in
// through the write nodes' input, one in flight per slot, each value unique.
// Driven over IPC by nodered.js:
//   { op: 'start' } → { version }
//   { op: 'deploy', flow, expect } → { deployMs }     (a full deploy; expect: per PLC the statics [name, type, value])
//   { op: 'drive', plcs, t0, durationMs, writeEveryMs } → {}   (writes until t0 + durationMs)
//   { op: 'states' } → { states: [per PLC: the connection's link state] }
//   { op: 'results' } → { record, writes: [per PLC: { seq, slots: [slot of write n - 1], outcomes }], loopP99Ms }
//                        (outcomes: 0 pending, 1 acknowledged, 2 rejected, 3 both, 4 in flight when a redeploy closed its node)
//   { op: 'stop' } → exits
const fs = require('node:fs');
const http = require('node:http');
const os = require('node:os');
const path = require('node:path');
const { monitorEventLoopDelay } = require('node:perf_hooks');
const { ROOT } = require('../lib/peers');
const { SLOTS } = require('./plan');

const LOOP_RESOLUTION_MS = 10;
const record = (global.__plcwireChaosRecord ??= { errors: [], statuses: [], acked: [], reads: [], wrong: [], expect: [] });
const loop = monitorEventLoopDelay({ resolution: LOOP_RESOLUTION_MS });
let RED;
let userDir;
const writes = [];
const timers = new Set();

async function start() {
  userDir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-chaos-nr-'));
  RED = require(require.resolve('node-red', { paths: [ROOT] }));
  RED.init(http.createServer(), {
    userDir,
    flowFile: 'flows.json',
    credentialSecret: false,
    disableEditor: true,
    httpAdminRoot: '/admin',
    httpNodeRoot: false,
    uiPort: 0,
    nodesDir: [ROOT, path.join(__dirname, 'nodered-record')],
    // The runtime's own log stays quiet: what the flows report is what Catch and Status see.
    logging: { chaos: { level: 'off', metrics: false, audit: false, handler: () => () => undefined } },
    editorTheme: { tours: false },
    telemetry: { enabled: false },
    externalModules: { autoInstall: false },
  });
  await RED.start();
  const missing = ['plcwire-read', 'plcwire-write', 'plcwire-connection', 'chaos-record'].filter((t) => !RED.nodes.getType(t));
  if (missing.length) throw new Error(`node types not registered: ${missing.join(', ')}`);
  return { version: RED.version() };
}

/** Outcome of a write in flight when a full redeploy closed its node: the flow can no longer hear how it ended. */
const CUT = 4;

/** Writes still in flight (sent into nodes a redeploy closes, also while it runs) count as cut; their slots are free. */
function cutInFlight() {
  for (const w of writes) {
    if (!w) continue;
    w.outcomes.forEach((o, n) => o === 0 && (w.outcomes[n] = CUT));
    w.busy.fill(false);
  }
}

async function deploy(flow, expect) {
  if (expect) record.expect = expect;
  cutInFlight();
  const t0 = performance.now();
  await RED.runtime.flows.setFlows({ flows: { flows: flow }, deploymentType: 'full' });
  cutInFlight();
  return { deployMs: performance.now() - t0 };
}

/** Writes into PLC i's write node every `writeEveryMs`, slot after slot, one in flight per slot, value i × 1,000,000 + n. */
function drive({ plcs, t0, durationMs, writeEveryMs }) {
  const end = t0 + durationMs;
  // Polls are counted from t0 to the end, as they are due.
  record.from = t0;
  record.to = end;
  loop.enable();
  for (let i = 0; i < plcs; i++) {
    const w = { seq: 0, slots: [], outcomes: [], busy: new Array(SLOTS).fill(false), next: 0 };
    writes[i] = w;
    let due = t0 + (i * writeEveryMs) / plcs + 7;
    const tick = () => {
      timers.delete(timer);
      if (Date.now() >= end) return;
      writeOnce(i, w);
      due += writeEveryMs;
      timer = setTimeout(tick, Math.max(0, due - Date.now()));
      timers.add(timer);
    };
    let timer = setTimeout(tick, Math.max(0, due - Date.now()));
    timers.add(timer);
  }
  return {};
}

function writeOnce(i, w) {
  const k = w.next;
  w.next = (k + 1) % SLOTS;
  if (w.busy[k]) return;
  const node = RED.nodes.getNode(`write${i}`);
  // Between a full redeploy's stop and start there is no write node: nothing to write into.
  if (!node) return;
  w.busy[k] = true;
  const n = ++w.seq;
  w.slots.push(k);
  w.outcomes.push(0);
  node.receive({ topic: `plc${i}`, payload: { [`slot${k}`]: i * 1_000_000 + n } });
}

/** An acknowledged write (the write node sent it on) or a rejected one (Catch): its slot is free again. */
function settle(plc, payload, outcome) {
  const w = writes[plc];
  if (!w || !payload) return;
  for (const [name, value] of Object.entries(payload)) {
    const n = value - plc * 1_000_000;
    const k = Number(name.replace('slot', ''));
    if (!(n >= 1 && n <= w.seq) || w.slots[n - 1] !== k) continue;
    // A write counted as cut by a redeploy whose node answered after all keeps that answer.
    if (w.outcomes[n - 1] === 0 || w.outcomes[n - 1] === CUT) w.outcomes[n - 1] = outcome;
    else w.outcomes[n - 1] = 3; // settled twice
    w.busy[k] = false;
  }
}

// The record node pushes; the outcomes are settled as they arrive.
const push = { acked: record.acked.push.bind(record.acked), errors: record.errors.push.bind(record.errors) };
record.acked.push = (e) => {
  settle(e.plc, e.payload, 1);
  return push.acked({ t: e.t, plc: e.plc });
};
record.errors.push = (e) => {
  if (e.type === 'plcwire-write') settle(e.plc, e.payload, 2);
  return push.errors({ t: e.t, plc: e.plc, type: e.type, code: e.code, message: String(e.message).slice(0, 200) });
};

function states(plcs) {
  const out = [];
  for (let i = 0; i < plcs; i++) {
    const conn = RED.nodes.getNode(`conn${i}`);
    out.push(conn && conn.linkStatus ? conn.linkStatus.state : 'none');
  }
  return { states: out };
}

function results() {
  for (const t of timers) clearTimeout(t);
  timers.clear();
  loop.disable();
  return {
    record: { errors: [...record.errors], statuses: record.statuses, reads: record.reads, wrong: record.wrong, acked: record.acked.length },
    writes: writes.map((w) => ({ seq: w.seq, slots: w.slots, outcomes: w.outcomes })),
    loopP99Ms: loop.count ? Math.max(0, loop.percentile(99) / 1e6 - LOOP_RESOLUTION_MS) : 0,
  };
}

process.on('message', async (msg) => {
  try {
    if (msg.op === 'start') process.send({ ok: true, ...(await start()) });
    else if (msg.op === 'deploy') process.send({ ok: true, ...(await deploy(msg.flow, msg.expect)) });
    else if (msg.op === 'drive') process.send({ ok: true, ...drive(msg) });
    else if (msg.op === 'states') process.send({ ok: true, ...states(msg.plcs) });
    else if (msg.op === 'results') process.send({ ok: true, ...results() });
    else if (msg.op === 'stop') {
      await RED.stop().catch(() => undefined);
      fs.rmSync(userDir, { recursive: true, force: true });
      process.exit(0);
    }
  } catch (err) {
    process.send({ ok: false, error: String((err && err.stack) || err) });
  }
});
process.on('disconnect', () => process.exit(0));
