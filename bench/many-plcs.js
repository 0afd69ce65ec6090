#!/usr/bin/env node
'use strict';
// `npm run bench:scale`: many PLCs from one process. 10, 50, 100 and 200
// simulated PLCs with 100 scattered tags each and 20 PLCs with 1000, every PLC
// polled every 100 ms; our client beside @st-one-io/nodes7 and nodes7, each
// library in its own process, the simulators in another. Per row: polls done
// vs due, polls skipped (due while the PLC's previous poll still ran) and
// failed, client CPU % and µs per tag-poll, RSS, event-loop delay p99.
// See bench/README.md ("Many PLCs from one process").
//
//   node bench/many-plcs.js [--quick] [--rows 10x100,20x1000] [--clients ours,st-one,nodes7] [--duration ms] [--interval ms] [--rounds n] [--prof dir]
const os = require('node:os');
const { CLIENT_NAMES } = require('./lib/clients');
const { startFleet, runFleetClient, closedStats } = require('./lib/fleet');
const { fmt, printTable, option } = require('./lib/print');

const args = process.argv.slice(2);
const QUICK = args.includes('--quick');
const DURATION_MS = Number(option(args, 'duration', QUICK ? 1500 : 6000));
const WARM_MS = QUICK ? 800 : 2000;
const INTERVAL_MS = Number(option(args, 'interval', 100));
const ROWS = option(args, 'rows', '10x100,50x100,100x100,200x100,20x1000')
  .split(',')
  .map((r) => {
    const [plcs, tags] = r.split('x').map(Number);
    return { plcs, tags };
  });
// 'raw': the floor, prebuilt requests and no parsing (bench/lib/raw-poll.js); not an anchor.
const CLIENTS = option(args, 'clients', [...['ours', 'st-one', 'nodes7'].filter((c) => CLIENT_NAMES.includes(c)), 'raw'].join(',')).split(
  ',',
);
const PDU = 960;
const ROUNDS = Number(option(args, 'rounds', QUICK ? 1 : 2));
// --prof DIR: every client process writes a V8 CPU profile there (summarize with bench/lib/cpuprofile.js).
const PROF_DIR = option(args, 'prof');

/**
 * The better of two rounds of one client: one that kept up (under 1 % of its
 * polls skipped or failed) over one that did not — a burst of load from
 * elsewhere on the machine stalls a round — then the lower CPU per poll.
 */
function better(a, b) {
  if (!a || a.error) return b;
  if (b.error) return a;
  const missed = (r) => (r.skipped + r.failed) / r.due > 0.01;
  if (missed(a) !== missed(b)) return missed(a) ? b : a;
  return b.cpuUsPerPoll < a.cpuUsPerPoll ? b : a;
}

async function main() {
  const t0 = Date.now();
  console.log(
    `plcwire many-PLC benchmark — Node ${process.version}, ${os.cpus()[0].model}, ${os.cpus().length} CPUs, load ${os.loadavg()[0].toFixed(1)}`,
  );
  const rows = [];
  const ours = [];
  for (const row of ROWS) {
    const fleet = await startFleet(row.plcs, row.tags);
    const results = CLIENTS.map(() => undefined);
    for (let round = 0; round < ROUNDS; round++) {
      const order = CLIENTS.map((c, i) => i);
      if (round % 2) order.reverse();
      for (const i of order) {
        const client = CLIENTS[i];
        const job = {
          client,
          ports: fleet.ports,
          tags: row.tags,
          pdu: PDU,
          intervalMs: INTERVAL_MS,
          warmMs: WARM_MS,
          durationMs: DURATION_MS,
        };
        const r = await runFleetClient(
          job,
          PROF_DIR
            ? ['--cpu-prof', '--cpu-prof-dir', PROF_DIR, '--cpu-prof-name', `${client}-${row.plcs}x${row.tags}-${round}.cpuprofile`]
            : [],
        );
        // Every connection closed: the client closed each one before its process exited.
        const s1 = await closedStats(fleet);
        if (s1.connections.some((c) => c !== 0)) r.leftOpen = s1.connections.reduce((a, b) => a + b, 0);
        results[i] = better(results[i], r);
      }
    }
    await fleet.stop();
    const label = `${row.plcs} × ${row.tags}`;
    for (const r of results) {
      if (r.error) {
        rows.push([label, r.client, `error: ${r.error}`.slice(0, 70)]);
        continue;
      }
      if (r.client === 'ours') ours.push({ row, r });
      rows.push([
        label,
        r.client,
        fmt(r.done / r.seconds),
        fmt(r.due / r.seconds),
        `${fmt((100 * r.done) / r.due, 1)} %`,
        fmt(r.skipped),
        fmt(r.failed),
        `${fmt(r.cpuPercent, 1)} %`,
        fmt(r.cpuUsPerTagPoll, 3),
        `${fmt(r.cpuUsPerPoll, 0)} (${fmt(r.userUsPerPoll, 0)}+${fmt(r.systemUsPerPoll, 0)})`,
        fmt(r.rssMiB, 0),
        fmt(r.loopP99Ms, 1),
        fmt(r.pollP99Ms, 1),
      ]);
      if (r.firstError) console.log(`(${label} ${r.client}: first failure: ${r.firstError})`);
      if (r.leftOpen) console.log(`(${label} ${r.client}: ${r.leftOpen} connections still open at the simulators after close)`);
    }
    const o = results.find((r) => r.client === 'ours' && !r.error);
    const anchors = results.filter((r) => r.client !== 'ours' && r.client !== 'raw' && !r.error && r.done > 0);
    const floor = results.find((r) => r.client === 'raw' && !r.error && r.done > 0);
    if (o && anchors.length) {
      const best = anchors.reduce((a, b) => (a.cpuUsPerTagPoll <= b.cpuUsPerTagPoll ? a : b));
      rows.push([
        label,
        `ours/${best.client}`,
        '',
        '',
        '',
        '',
        '',
        `${fmt(o.cpuPercent / best.cpuPercent, 2)}×`,
        `${fmt(o.cpuUsPerTagPoll / best.cpuUsPerTagPoll, 2)}×`,
        `${fmt(o.cpuUsPerPoll / best.cpuUsPerPoll, 2)}×`,
        `${fmt(o.rssMiB / best.rssMiB, 2)}×`,
        '',
        '',
      ]);
      if (floor) {
        // What each library spends per poll on top of the floor (the socket and timer path every client pays).
        const above = (r) => r.cpuUsPerPoll - floor.cpuUsPerPoll;
        rows.push([
          label,
          `ours/${best.client} above raw`,
          '',
          '',
          '',
          '',
          '',
          '',
          `${fmt(above(o) / above(best), 2)}×`,
          `${fmt(above(o), 0)} / ${fmt(above(best), 0)}`,
          '',
          '',
          '',
        ]);
      }
    }
  }
  printTable(
    `Many PLCs from one process: every PLC polled every ${INTERVAL_MS} ms for ${DURATION_MS} ms (after ${WARM_MS} ms warm-up), better of ${ROUNDS} rounds; simulators (S7-1500, PDU ${PDU}) in another process`,
    [
      'PLCs × tags',
      'client',
      'polls/s',
      'due/s',
      'done',
      'skipped',
      'failed',
      'CPU',
      'µs/tag-poll',
      'µs/poll (user+sys)',
      'RSS MiB',
      'loop p99 ms',
      'poll p99 ms',
    ],
    rows,
  );
  const flat = ours.filter((x) => x.row.tags === 100);
  if (flat.length > 1) {
    const per = flat.map((x) => x.r.cpuUsPerTagPoll);
    console.log(
      `\nours, 100 tags: µs per tag-poll ${flat.map((x) => `${x.row.plcs} PLCs ${fmt(x.r.cpuUsPerTagPoll, 3)}`).join(', ')}; highest/lowest ${fmt(Math.max(...per) / Math.min(...per), 2)}×`,
    );
  }
  console.log(`\n(${((Date.now() - t0) / 1000).toFixed(0)} s)`);
}

main().catch((err) => {
  console.error(err);
  process.exit(1);
});
