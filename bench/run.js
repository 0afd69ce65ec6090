#!/usr/bin/env node
'use strict';
// `npm run bench`: our S7 client beside nodes7 and @st-one-io/nodes7 on the
// same servers (our simulator, snap7's server), then the latency model, the
// planner's lower bound, the simulator's own requests per second, S7CommPlus,
// and the Node-RED layer (the library alone beside our read node, bench/nodered.js).
// Each server and each client runs in its own process; see bench/README.md.
//
//   node bench/run.js [--quick] [--clients ours,nodes7,st-one] [--tables 10,100] [--duration ms] [--latency ms]
const { fork } = require('node:child_process');
const path = require('node:path');
const { ask, startServer, runClient } = require('./lib/workers');
const { CountingProxy } = require('./lib/proxy');
const { TABLES, table, image } = require('./lib/tables');
const { CLIENT_NAMES } = require('./lib/clients');
const { plcwire, DIST } = require('./lib/peers');
const { s7plusSection } = require('./s7plus');
const { layerSection } = require('./nodered');
const { sparkplugSection } = require('./sparkplug');

const args = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = args.indexOf(`--${name}`);
  return i >= 0 ? args[i + 1] : dflt;
};
const QUICK = args.includes('--quick');
const DURATION_MS = Number(opt('duration', QUICK ? 300 : 700));
const ROUNDS = QUICK ? 1 : 3;
const COUNT_POLLS = 3;
const LATENCY_MS = Number(opt('latency', 20));
const LATENCY_POLLS = QUICK ? 3 : 9;
const LOAD_MS = QUICK ? 300 : 1000;
const clients = opt('clients', CLIENT_NAMES.join(',')).split(',');
const tableNames = TABLES.map((t) => t.name).filter((n) => {
  const only = opt('tables');
  return !only || only.split(',').some((x) => n.startsWith(`${x} `));
});
const SECTIONS = ['comparison', 'latency', 'load', 's7plus', 'nodered', 'sparkplug'];
const sections = opt('sections', SECTIONS.join(',')).split(',');
for (const s of sections) if (!SECTIONS.includes(s)) throw new Error(`--sections: no section "${s}" (${SECTIONS.join(', ')})`);
const SERVERS = [
  // snap7's server serves at most 20 items a job, and the anchors fill a job up to the PDU: every client
  // asks for PDU 240 there (at most 19 items a job). Ours sends at most 20 (its default maxItems) anywhere.
  { kind: 'ours', label: 'plcwire simulator', pdu: 960 },
  { kind: 'snap7', label: 'snap7 server', pdu: 240 },
];

/** The first of `files` under DIST that exists (a build from before lib/s7/plan/ has the bound in lib/s7/planner.js). */
function requireFirst(files) {
  for (const file of files.slice(0, -1)) {
    try {
      return require(path.join(DIST, file));
    } catch (err) {
      if (!err || err.code !== 'MODULE_NOT_FOUND') throw err;
    }
  }
  return require(path.join(DIST, files[files.length - 1]));
}

/** The planner's lower bound at the PDU size and the item limit our client uses by default (a build without one: 255). */
function lowerBound(tags, pdu) {
  try {
    const lib = plcwire();
    const { lowerBoundPdus } = requireFirst(['lib/s7/plan/bound.js', 'lib/s7/planner.js']);
    return lowerBoundPdus(
      tags.map((t) => lib.parseAddress(t.address)),
      pdu,
      { maxItems: lib.DEFAULTS.maxItems },
    );
  } catch {
    return undefined;
  }
}

// --- printing ---------------------------------------------------------------
const fmt = (v, digits = 0) => (v === undefined || Number.isNaN(v) ? '–' : v >= 1e5 ? v.toExponential(2) : v.toFixed(digits));
function printTable(title, header, rows) {
  const widths = header.map((h, i) => Math.max(h.length, ...rows.map((r) => String(r[i]).length)));
  const line = (cells) => cells.map((c, i) => (i < 2 ? String(c).padEnd(widths[i]) : String(c).padStart(widths[i]))).join('  ');
  console.log(`\n${title}`);
  console.log(line(header));
  console.log(widths.map((w) => '-'.repeat(w)).join('  '));
  for (const r of rows) console.log(line(r));
}

async function comparison() {
  const rows = [];
  const memory = [];
  for (const s of SERVERS) {
    let server;
    try {
      server = await startServer(s.kind);
    } catch (err) {
      console.log(`(${s.label}: not available — ${err.message.split('\n')[0]})`);
      continue;
    }
    const proxy = new CountingProxy(server.port);
    const proxyPort = await proxy.listen();
    for (const name of tableNames) {
      const tags = table(name);
      await server.fill(image(tags));
      // Rounds in alternating client order; each client keeps its best round, so a
      // burst of load from elsewhere on the machine does not decide the ratio.
      const results = clients.map(() => undefined);
      for (let round = 0; round < ROUNDS; round++) {
        const order = clients.map((c, i) => i);
        if (round % 2) order.reverse();
        for (const i of order) {
          const r = await runClient(
            {
              client: clients[i],
              table: name,
              pdu: s.pdu,
              port: server.port,
              proxyPort,
              durationMs: DURATION_MS,
              countPolls: round === 0 ? COUNT_POLLS : 0,
            },
            proxy,
          );
          const prev = results[i];
          if (!prev) results[i] = r;
          else if (!r.error && (prev.error || r.pollsPerSecond > prev.pollsPerSecond)) {
            results[i] = { ...r, pdusPerPoll: prev.pdusPerPoll, bytesPerPoll: prev.bytesPerPoll, maxItems: prev.maxItems };
          }
        }
      }
      const anchors = results.filter((r) => r.client !== 'ours' && !r.error);
      const best = (key, higher) =>
        anchors.length ? anchors.map((r) => r[key]).reduce((a, b) => (higher ? Math.max(a, b) : Math.min(a, b))) : undefined;
      const ours = results.find((r) => r.client === 'ours');
      const bound = lowerBound(tags, s.pdu);
      for (const r of results) {
        if (!r.error)
          memory.push({ server: s.label, table: name, client: r.client, tags: tags.length, heap: r.heapBytesPerTag * tags.length });
        if (r.error) {
          rows.push([s.label, name, r.client ?? '', `error: ${r.error}`.slice(0, 60), '', '', '', '', '', '', '']);
          continue;
        }
        rows.push([
          s.label,
          name,
          r.client,
          fmt(r.pollsPerSecond),
          fmt(r.pdusPerPoll, 1),
          r.client === 'ours' ? fmt(bound) : '',
          fmt(r.maxItems),
          fmt(r.bytesPerPoll),
          fmt(r.cpuMsPer1000Tags, 2),
          fmt(r.rssBytesPerTag),
          fmt(r.heapBytesPerTag),
        ]);
      }
      if (ours && !ours.error && anchors.length) {
        rows.push([
          s.label,
          name,
          'ours/best anchor',
          `${fmt(ours.pollsPerSecond / best('pollsPerSecond', true), 2)}×`,
          `${fmt(ours.pdusPerPoll / best('pdusPerPoll', false), 2)}×`,
          '',
          '',
          `${fmt(ours.bytesPerPoll / best('bytesPerPoll', false), 2)}×`,
          `${fmt(ours.cpuMsPer1000Tags / best('cpuMsPer1000Tags', false), 2)}×`,
          `${fmt(ours.rssBytesPerTag / best('rssBytesPerTag', false), 2)}×`,
          `${fmt(ours.heapBytesPerTag / best('heapBytesPerTag', false), 2)}×`,
        ]);
      }
    }
    await proxy.close();
    await server.stop();
  }
  printTable(
    `Polls against the same server (loopback; best of ${ROUNDS} rounds of ${DURATION_MS} ms per client; PDUs and bytes counted by a proxy over ${COUNT_POLLS} polls)`,
    [
      'server',
      'table',
      'client',
      'polls/s',
      'PDUs/poll',
      'lower bound',
      'max items',
      'bytes/poll',
      'CPU ms/1000 tags',
      'RSS B/tag',
      'heap B/tag',
    ],
    rows.map((r) => [`${r[0]}`, `${r[1]} ${r[2]}`, ...r.slice(3)]),
  );
  printMarginalMemory(memory);
}

/**
 * Heap per added tag: what a client keeps for the tags themselves, without
 * its fixed cost (code, connection, buffers), which dominates "per tag" on
 * small tables: (heap with table T − heap with the 10-tag table) / (tags of
 * T − 10), both after the same 500 polls, per server and client. Only for
 * the 1000-tag tables: the heap varies by ±100 kB between runs, which is
 * ±1 kB per tag on 100 tags. (RSS varies by megabytes: not shown.)
 */
function printMarginalMemory(memory) {
  const rows = [];
  const servers = [...new Set(memory.map((m) => m.server))];
  for (const server of servers) {
    for (const name of tableNames) {
      if (table(name).length < 1000) continue;
      const per = {};
      for (const client of clients) {
        const base = memory.find((m) => m.server === server && m.client === client && m.table === '10 scattered');
        const at = memory.find((m) => m.server === server && m.client === client && m.table === name);
        if (!base || !at) continue;
        per[client] = { heap: (at.heap - base.heap) / (at.tags - base.tags) };
        rows.push([server, `${name} ${client}`, fmt(per[client].heap)]);
      }
      const anchors = Object.keys(per).filter((c) => c !== 'ours');
      if (per.ours && anchors.length) {
        const best = (key) => Math.min(...anchors.map((c) => per[c][key]));
        rows.push([server, `${name} ours/best anchor`, `${fmt(per.ours.heap / best('heap'), 2)}×`]);
      }
    }
  }
  if (rows.length === 0) return;
  printTable(
    'Heap per added tag: (heap with the table − heap with the 10-tag table) / added tags, both after 500 polls',
    ['server', 'table client', 'heap B/added tag'],
    rows,
  );
}

async function latencyModel() {
  const rows = [];
  for (const p of [
    { profile: 's7-1200', pdu: 240, amq: 3 },
    { profile: 's7-1500', pdu: 960, amq: 8 },
  ]) {
    let server;
    try {
      server = await startServer('ours', { profile: p.profile, latencyMs: LATENCY_MS });
    } catch (err) {
      console.log(`(latency model: simulator not available — ${err.message.split('\n')[0]})`);
      return;
    }
    const proxy = new CountingProxy(server.port);
    const proxyPort = await proxy.listen();
    for (const name of tableNames) {
      const tags = table(name);
      await server.fill(image(tags));
      for (const client of clients) {
        const r = await runClient(
          { client, table: name, pdu: p.pdu, port: server.port, proxyPort, countPolls: 1, latencyPolls: LATENCY_POLLS },
          proxy,
        );
        if (r.error) {
          rows.push([`PDU ${p.pdu} / AmQ ${p.amq}`, `${name} ${client}`, `error: ${r.error}`.slice(0, 60), '', '', '']);
          continue;
        }
        const floor = Math.ceil(r.pdusPerPoll / p.amq) * LATENCY_MS;
        rows.push([
          `PDU ${p.pdu} / AmQ ${p.amq}`,
          `${name} ${client}`,
          fmt(r.pdusPerPoll),
          fmt(r.pollMs, 1),
          fmt(floor),
          `${fmt((r.pollMs / floor - 1) * 100, 0)} %`,
        ]);
      }
    }
    await proxy.close();
    await server.stop();
  }
  printTable(
    `Latency model: the simulator delays each request ${LATENCY_MS} ms and serves up to AmQ at once; poll ms = median of ${LATENCY_POLLS} polls; floor = ceil(PDUs / AmQ) × ${LATENCY_MS} ms`,
    ['model', 'table client', 'PDUs/poll', 'poll ms', 'floor ms', 'over floor'],
    rows,
  );
}

async function serverLoad() {
  const rows = [];
  const request = { items: 10, bytes: 4 };
  for (const kind of ['ours', 'snap7']) {
    let server;
    try {
      server = await startServer(kind);
    } catch (err) {
      rows.push([kind === 'ours' ? 'plcwire simulator' : 'snap7 server', `not available: ${err.message.split('\n')[0]}`]);
      continue;
    }
    const row = [kind === 'ours' ? 'plcwire simulator' : 'snap7 server'];
    for (const connections of [1, 4, 16]) {
      const child = fork(path.join(__dirname, 'load-worker.js'), [], { serialization: 'advanced', stdio: 'inherit' });
      const r = await ask(child, { port: server.port, connections, durationMs: LOAD_MS, ...request });
      row.push(r.errors ? `${fmt(r.requestsPerSecond)} (${r.errors} errors)` : fmt(r.requestsPerSecond));
    }
    rows.push(row);
    await server.stop();
  }
  printTable(
    'Server: Read Var requests per second (10 items of 4 bytes in DB1, one request in flight per connection)',
    ['server', '', '1 client', '4 clients', '16 clients'],
    rows.map((r) => [r[0], '', ...r.slice(1)]),
  );
}

async function main() {
  const t0 = Date.now();
  console.log(
    `plcwire benchmark — Node ${process.version}, ${require('node:os').cpus()[0].model}, ${require('node:os').cpus().length} CPUs`,
  );
  if (sections.includes('comparison')) await comparison();
  if (sections.includes('latency')) await latencyModel();
  if (sections.includes('load')) await serverLoad();
  if (sections.includes('s7plus'))
    await s7plusSection({ durationMs: DURATION_MS, rounds: ROUNDS, countPolls: COUNT_POLLS, warmPolls: QUICK ? 100 : 500 });
  if (sections.includes('nodered')) await layerSection();
  if (sections.includes('sparkplug')) await sparkplugSection(QUICK ? ['--quick'] : []);
  console.log(`\n(${((Date.now() - t0) / 1000).toFixed(0)} s)`);
}

main().catch((err) => {
  console.error(err);
  process.exit(1);
});
