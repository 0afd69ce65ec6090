#!/usr/bin/env node
'use strict';
// `npm run bench:nodered`: the Node-RED layer's own cost. The same PLCs (each
// its own simulator, in a server process) polled by
//   - the libraries alone (ours, @st-one-io/nodes7; bench/fleet-client-worker.js),
//   - a real Node-RED with our read nodes in object, per-tag and changes mode,
//   - the same Node-RED with node-red-contrib-s7's `s7 in` (all, all-split, diff),
// each in its own process; one INT tag per PLC changes every 100 ms, so
// 'changes' modes have a few changes to send. Then one runtime with 100
// connection and 100 read nodes: deploy time, and the connections the
// simulators see after full redeploys. See bench/README.md ("Node-RED").
//
//   node bench/nodered.js [--quick] [--rows 50x100] [--modes 'lib ours,ours object'] [--duration ms] [--rounds n] [--deploy 100] [--prof dir]
// --prof DIR: a V8 CPU profile of each Node-RED runtime's timed window (the profiler's own cost then counts too),
// summarized by `node bench/lib/cpuprofile.js DIR/nodered-ours-object.cpuprofile [--match nodes/read.js]`.
const { fork } = require('node:child_process');
const os = require('node:os');
const path = require('node:path');
const { startFleet, runFleetClient, closedStats, ask } = require('./lib/fleet');
const { oursFlow, contribFlow } = require('./lib/nodered-flows');
const { fmt, printTable, option } = require('./lib/print');

const args = process.argv.slice(2);
const QUICK = args.includes('--quick');
const DURATION_MS = Number(option(args, 'duration', QUICK ? 2000 : 8000));
const WARM_MS = QUICK ? 1500 : 3000;
const INTERVAL_MS = Number(option(args, 'interval', 100));
const CHANGE_EVERY_MS = 100;
const PDU = 960;
const PROF_DIR = option(args, 'prof');
const ROWS = option(args, 'rows', '50x100')
  .split(',')
  .map((r) => {
    const [plcs, tags] = r.split('x').map(Number);
    return { plcs, tags };
  });
const DEPLOY_PLCS = Number(option(args, 'deploy', QUICK ? 20 : 100));
const REDEPLOYS = 3;
const ROUNDS = Number(option(args, 'rounds', QUICK ? 1 : 2));

const MODES = {
  'lib ours': { library: 'ours' },
  'lib st-one': { library: 'st-one' },
  'ours object': { flow: (o) => oursFlow({ ...o, output: 'object' }), library: 'ours' },
  'ours per-tag': { flow: (o) => oursFlow({ ...o, output: 'per-tag' }), library: 'ours' },
  'ours changes': { flow: (o) => oursFlow({ ...o, output: 'changes' }), library: 'ours' },
  'contrib all': { flow: (o) => contribFlow({ ...o, mode: 'all' }), library: 'st-one' },
  'contrib all-split': { flow: (o) => contribFlow({ ...o, mode: 'all-split' }), library: 'st-one' },
  'contrib all diff': { flow: (o) => contribFlow({ ...o, mode: 'all', diff: true }), library: 'st-one' },
  'contrib split diff': { flow: (o) => contribFlow({ ...o, mode: 'all-split', diff: true }), library: 'st-one' },
};
const modeNames = option(args, 'modes', Object.keys(MODES).join(',')).split(',');

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

async function startRuntime(name) {
  const child = fork(path.join(__dirname, 'nodered-worker.js'), [], { serialization: 'advanced', stdio: 'inherit' });
  const started = await ask(child, { op: 'start', name });
  return {
    version: started.version,
    ask: (msg) => ask(child, msg),
    stop: () =>
      new Promise((resolve) => {
        if (child.exitCode !== null) return resolve();
        child.once('exit', resolve);
        child.send({ op: 'stop' });
      }),
  };
}

/** Every PLC served at least one more read than in `before`, or throws after `ms`. */
async function everyPlcPolled(fleet, before, ms) {
  const until = Date.now() + ms;
  for (;;) {
    const s = await fleet.stats();
    const quiet = s.readsPerPlc.filter((r, i) => r <= before.readsPerPlc[i]).length;
    if (quiet === 0) return s;
    if (Date.now() > until) throw new Error(`${quiet} PLCs were not polled within ${ms} ms`);
    await sleep(20);
  }
}

let nodeRedVersion = '';

/** One Node-RED mode on `fleet`: { polls, seconds, messages, cpuUs, … } over the timed window. */
async function runNodeRed(name, fleet, row, round) {
  const rt = await startRuntime(name);
  nodeRedVersion = rt.version;
  try {
    const s0 = await fleet.stats();
    await rt.ask({ op: 'deploy', nodes: MODES[name].flow({ ports: fleet.ports, tags: row.tags, intervalMs: INTERVAL_MS }), type: 'full' });
    await everyPlcPolled(fleet, s0, 20000);
    await sleep(WARM_MS);
    const [a, f0] = await Promise.all([rt.ask({ op: 'mark' }), fleet.stats()]);
    const t0 = performance.now();
    if (PROF_DIR) await rt.ask({ op: 'profile' });
    await sleep(DURATION_MS);
    const [b, f1] = await Promise.all([rt.ask({ op: 'mark' }), fleet.stats()]);
    if (PROF_DIR) await rt.ask({ op: 'profile', file: path.join(PROF_DIR, `nodered-${name.replace(/\W+/g, '-')}-${round}.cpuprofile`) });
    const seconds = (performance.now() - t0) / 1000;
    return {
      seconds,
      reads: f1.reads - f0.reads,
      messages: b.messages - a.messages,
      cpuUs: b.cpuUs - a.cpuUs,
      userUs: b.userUs - a.userUs,
      systemUs: b.systemUs - a.systemUs,
      rssMiB: b.rss / 2 ** 20,
      loopP99Ms: b.loopP99Ms,
    };
  } finally {
    await rt.stop();
  }
}

async function polling(row, names = modeNames) {
  const fleet = await startFleet(row.plcs, row.tags);
  const results = {};
  const pdusPerPoll = {};
  // Each mode keeps its best round (the lowest CPU per poll), as bench/run.js keeps each client's best round.
  const keep = (name, r) => {
    const prev = results[name];
    if (!prev || prev.error || r.cpuUs / r.polls < prev.cpuUs / prev.polls) results[name] = r;
  };
  try {
    // The libraries alone first: they check every PLC's values, which the change ticker then moves.
    const libs = names.filter((m) => !MODES[m].flow);
    const flows = names.filter((m) => MODES[m].flow);
    for (let round = 0; round < ROUNDS; round++) {
      for (const name of round % 2 ? [...libs].reverse() : libs) {
        const lib = MODES[name].library;
        const s0 = await fleet.stats();
        const execArgv = PROF_DIR ? ['--cpu-prof', '--cpu-prof-dir', PROF_DIR, '--cpu-prof-name', `lib-${lib}-${round}.cpuprofile`] : [];
        const r = await runFleetClient(
          { client: lib, ports: fleet.ports, tags: row.tags, pdu: PDU, intervalMs: INTERVAL_MS, warmMs: WARM_MS, durationMs: DURATION_MS },
          execArgv,
        );
        const s1 = await closedStats(fleet);
        if (r.error) results[name] ??= { error: r.error };
        else {
          pdusPerPoll[lib] = (s1.reads - s0.reads) / r.allStarted;
          keep(name, {
            seconds: r.seconds,
            polls: r.done,
            messages: undefined,
            cpuUs: r.cpuUsPerPoll * r.done,
            userUs: r.userUsPerPoll * r.done,
            systemUs: r.systemUsPerPoll * r.done,
            rssMiB: r.rssMiB,
            loopP99Ms: r.loopP99Ms,
          });
        }
      }
    }
    await fleet.change(CHANGE_EVERY_MS);
    for (let round = 0; round < ROUNDS; round++) {
      for (const name of round % 2 ? [...flows].reverse() : flows) {
        try {
          const r = await runNodeRed(name, fleet, row, round);
          const perPoll = pdusPerPoll[MODES[name].library] || Math.ceil(row.tags / 100);
          keep(name, { ...r, polls: r.reads / perPoll });
          const s = await closedStats(fleet);
          const open = s.connections.reduce((x, y) => x + y, 0);
          if (open) console.log(`(${name}: ${open} connections still open at the simulators after Node-RED stopped)`);
        } catch (err) {
          results[name] ??= { error: String(err.message).split('\n')[0] };
        }
      }
    }
  } finally {
    await fleet.stop();
  }
  return results;
}

function pollingRows(row, results, names = modeNames) {
  const label = `${row.plcs} × ${row.tags}`;
  const rows = [];
  for (const name of names) {
    const r = results[name];
    if (!r) continue;
    if (r.error) {
      rows.push([label, name, `error: ${r.error}`.slice(0, 80)]);
      continue;
    }
    rows.push([
      label,
      name,
      fmt(r.polls / r.seconds),
      fmt((row.plcs * 1000) / INTERVAL_MS),
      r.messages === undefined ? '' : fmt(r.messages / r.seconds),
      `${fmt(r.cpuUs / 1e4 / r.seconds, 1)} %`,
      `${fmt(r.cpuUs / r.polls, 0)} (${fmt(r.userUs / r.polls, 0)}+${fmt(r.systemUs / r.polls, 0)})`,
      fmt(r.cpuUs / r.polls / row.tags, 3),
      fmt(r.rssMiB, 0),
      fmt(r.loopP99Ms, 1),
    ]);
  }
  const per = (name) => (results[name] && !results[name].error ? results[name].cpuUs / results[name].polls : undefined);
  const ratio = (a, b, what) => {
    if (per(a) === undefined || per(b) === undefined) return;
    rows.push([label, `${a} / ${b}`, '', '', '', '', `${fmt(per(a) / per(b), 2)}×`, '', '', what]);
  };
  ratio('ours object', 'lib ours', 'the layer over the library');
  ratio('contrib all', 'lib st-one', 'the layer over the library');
  ratio('ours object', 'contrib all', 'ours vs the incumbent');
  ratio('ours per-tag', 'contrib all-split', 'ours vs the incumbent');
  ratio('ours changes', 'contrib split diff', 'ours vs the incumbent');
  ratio('ours changes', 'ours object', 'changes vs object');
  // The layer alone: what the runtime with its nodes costs per poll on top of the same library alone.
  const layer = (mode, lib) => (per(mode) !== undefined && per(lib) !== undefined ? per(mode) - per(lib) : undefined);
  for (const [mode, lib] of [
    ['ours object', 'lib ours'],
    ['ours per-tag', 'lib ours'],
    ['ours changes', 'lib ours'],
    ['contrib all', 'lib st-one'],
    ['contrib all-split', 'lib st-one'],
    ['contrib split diff', 'lib st-one'],
  ]) {
    if (layer(mode, lib) !== undefined)
      rows.push([label, `${mode} − ${lib}`, '', '', '', '', `${fmt(layer(mode, lib), 0)} µs`, '', '', 'the Node-RED layer per poll']);
  }
  return rows;
}

/** One runtime, `n` connection and read nodes: deploy time, first poll of every node, connections after full redeploys. */
async function deployCheck(n) {
  const fleet = await startFleet(n, 100);
  const rt = await startRuntime(`deploy-${n}`);
  const rows = [];
  try {
    const flow = oursFlow({ ports: fleet.ports, tags: 100, intervalMs: INTERVAL_MS, output: 'object' });
    const topics = fleet.ports.map((_, i) => `plc${i}`);
    for (let k = 0; k <= REDEPLOYS; k++) {
      // A full deploy of the same flow stops every node and starts it again.
      const { deployMs } = await rt.ask({ op: 'deploy', nodes: flow, type: 'full' });
      const t0 = performance.now();
      await rt.ask({ op: 'wait-topics', topics, ms: 20000 });
      const firstMs = deployMs + performance.now() - t0;
      // Connections settle: a closed one's FIN reaches the simulator a moment later.
      let s = await fleet.stats();
      const until = Date.now() + 3000;
      while (s.connections.some((c) => c !== 1) && Date.now() < until) {
        await sleep(50);
        s = await fleet.stats();
      }
      await sleep(500);
      s = await fleet.stats();
      const total = s.connections.reduce((a, b) => a + b, 0);
      const off = s.connections.filter((c) => c !== 1).length;
      rows.push([
        k === 0 ? 'deploy' : `full redeploy ${k}`,
        `${n} + ${n}`,
        fmt(deployMs, 0),
        fmt(firstMs, 0),
        fmt(total),
        off ? `${off} PLCs without exactly 1` : 'exactly 1 each',
      ]);
    }
  } finally {
    await rt.stop();
    await fleet.stop();
  }
  return rows;
}

async function main() {
  const t0 = Date.now();
  const rows = [];
  for (const row of ROWS) rows.push(...pollingRows(row, await polling(row)));
  console.log(
    `plcwire Node-RED benchmark — Node ${process.version}, Node-RED ${nodeRedVersion}, ${os.cpus()[0].model}, ${os.cpus().length} CPUs, load ${os.loadavg()[0].toFixed(1)}`,
  );
  printTable(
    `Polls through Node-RED: every PLC every ${INTERVAL_MS} ms, ${DURATION_MS} ms timed after ${WARM_MS} ms, best of ${ROUNDS} rounds; one INT per PLC changes every ${CHANGE_EVERY_MS} ms; "lib" = the library alone in a process`,
    ['PLCs × tags', 'runtime / mode', 'polls/s', 'due/s', 'msgs/s', 'CPU', 'µs/poll (user+sys)', 'µs/tag-poll', 'RSS MiB', 'loop p99 ms'],
    rows,
  );
  if (DEPLOY_PLCS > 0) {
    printTable(
      `One Node-RED runtime with ${DEPLOY_PLCS} connection and ${DEPLOY_PLCS} read nodes (100 tags each, object mode), one simulator per connection`,
      ['deploy', 'nodes', 'setFlows ms', 'every node polled ms', 'connections', 'per PLC'],
      await deployCheck(DEPLOY_PLCS),
    );
  }
  console.log(`\n(${((Date.now() - t0) / 1000).toFixed(0)} s)`);
}

/**
 * `npm run bench`'s Node-RED section (bench/run.js): the library alone and a real Node-RED with our read node
 * (object output) on the same PLCs, from one run, side by side, with the layer's ratio, so a move of logic into
 * the per-poll path cannot hide a cost (issue #32). Both modes are alternated over the rounds.
 */
async function layerSection(row = { plcs: 50, tags: 100 }) {
  const names = ['lib ours', 'ours object'];
  const rows = pollingRows(row, await polling(row, names), names);
  printTable(
    `Node-RED layer: ${row.plcs} PLCs × ${row.tags} tags every ${INTERVAL_MS} ms, the library alone in a process beside a real Node-RED ${nodeRedVersion} with our read node (object output), ${DURATION_MS} ms timed after ${WARM_MS} ms, best of ${ROUNDS} rounds; load ${os.loadavg()[0].toFixed(1)} on ${os.cpus().length} CPUs`,
    ['PLCs × tags', 'runtime / mode', 'polls/s', 'due/s', 'msgs/s', 'CPU', 'µs/poll (user+sys)', 'µs/tag-poll', 'RSS MiB', 'loop p99 ms'],
    rows,
  );
}

module.exports = { layerSection };

if (require.main === module) {
  main().catch((err) => {
    console.error(err);
    process.exit(1);
  });
}
