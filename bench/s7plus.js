'use strict';
// The S7CommPlus section of `npm run bench` (issue #25): 100 tags by name in
// an optimized DB on our simulator (an S7-1500 serving S7CommPlus over TLS
// with a certificate it generated, pinned by its fingerprint), polled by our
// client and by the s7commplus Python client (PyPI 0.3.0, MIT, in
// test/interop/.venv-s7commplus); then our s7plus:// against our s7:// on
// the same 100 tags of a standard DB. Each client in a process of its own,
// the server in another; every client's first poll is checked against the
// members' start values. See bench/README.md ("S7CommPlus").
const { spawn, spawnSync } = require('node:child_process');
const fs = require('node:fs');
const path = require('node:path');
const { startServer, runClient, perPoll } = require('./lib/workers');
const { CountingProxy } = require('./lib/proxy');
const { optimizedNames, standardAddresses, firstWrong } = require('./lib/s7plus-program');
const { plcwire, ROOT } = require('./lib/peers');
const { fmt, printTable } = require('./lib/print');

const VENV_PYTHON = path.join(ROOT, 'test/interop/.venv-s7commplus', process.platform === 'win32' ? 'Scripts/python.exe' : 'bin/python');
const POLL_SCRIPT = path.join(__dirname, 's7commplus-poll.py');
/**
 * Items per request of the s7commplus client (client.py, max_items_per_request = 50, and max_request_bytes = 900).
 * Ours reads the PLC's SystemLimits once per session (issue #32): our simulator's S7-1500 reports 100, its S7-1200 50.
 */
const PYTHON_ITEM_LIMIT = 50;
/** The issue's targets (#32): polls/s against the Python client's, CPU per poll against our own transport's floor. */
const TARGETS = { pollsVsPython: 10, cpuVsFloor: 2 };

/**
 * A Python that imports the s7commplus version the interop tests use (the venv's, else python3's), or why
 * there is none. PLCWIRE_BENCH_PYTHON names the only one to try (another venv; or none, to see the table without it).
 */
function findPython() {
  const { S7COMMPLUS_VERSION } = require(path.join(ROOT, 'test/support/install-peers.js'));
  const probe = 'import importlib.metadata as m, s7commplus; print(m.version("s7commplus"))';
  const tried = [];
  const candidates = process.env.PLCWIRE_BENCH_PYTHON
    ? [process.env.PLCWIRE_BENCH_PYTHON]
    : [...(fs.existsSync(VENV_PYTHON) ? [VENV_PYTHON] : []), 'python3'];
  for (const python of candidates) {
    const r = spawnSync(python, ['-c', probe], { encoding: 'utf8', timeout: 30_000 });
    const version = r.status === 0 ? r.stdout.trim() : undefined;
    if (version === S7COMMPLUS_VERSION) return { python };
    tried.push(
      r.error
        ? `${path.basename(python)}: ${r.error.code}`
        : `${path.basename(python)}: ${version ? `s7commplus ${version}` : 'no s7commplus'}`,
    );
  }
  return {
    reason: `s7commplus ${S7COMMPLUS_VERSION} is not installed (${tried.join('; ')}); \`node test/support/install-peers.js s7commplus\` installs it`,
  };
}

/**
 * The Python client in its own process (bench/s7commplus-poll.py): its first
 * poll checked, polls/s and CPU ms per poll of its process, and what the
 * proxy counted over `countPolls` polls on a second connection.
 */
function runPython(python, job, proxy, tags) {
  return new Promise((resolve) => {
    const child = spawn(python, [POLL_SCRIPT], { stdio: ['pipe', 'pipe', 'pipe'] });
    let stderr = '';
    let out = '';
    let result = { client: 'python' };
    const timer = setTimeout(() => child.kill('SIGKILL'), 60_000);
    child.stderr.on('data', (d) => (stderr = (stderr + d).slice(-2000)));
    child.stdout.on('data', (d) => {
      out += d;
      for (let nl = out.indexOf('\n'); nl >= 0; nl = out.indexOf('\n')) {
        const line = out.slice(0, nl);
        out = out.slice(nl + 1);
        const m = JSON.parse(line);
        if (m.event === 'first') {
          const wrong = firstWrong(tags, m.values, 'python');
          if (wrong) result.error = `wrong value from the s7commplus client: ${wrong}`;
        } else if (m.event === 'timed') {
          Object.assign(result, { pollsPerSecond: (m.polls * 1000) / m.elapsedMs, cpuMsPerPoll: m.cpuMs / m.polls });
        } else if (m.event === 'counting') {
          proxy.reset();
          child.stdin.write('go\n');
        } else if (m.event === 'counted') {
          result.plusPerPoll = perPoll(proxy.plus, m.polls);
        } else if (m.event === 'error') {
          result.error ??= `${m.type}: ${m.message}`;
        }
      }
    });
    child.on('error', (err) => (result = { client: 'python', error: err.message }));
    child.on('close', (code) => {
      clearTimeout(timer);
      if (code !== 0 && !result.error) result.error = `exited with ${code}: ${stderr.trim().split('\n').pop()}`;
      resolve(result);
    });
    child.stdin.write(JSON.stringify(job) + '\n');
  });
}

/** Runs each of `jobs` (functions of the round) `rounds` times in alternating order; each keeps its fastest round (and the counts of its first). */
async function bestOf(rounds, jobs) {
  const best = jobs.map(() => undefined);
  for (let round = 0; round < rounds; round++) {
    const order = jobs.map((_, i) => i);
    if (round % 2) order.reverse();
    for (const i of order) {
      const r = await jobs[i](round);
      const prev = best[i];
      if (!prev || (!r.error && (prev.error || r.pollsPerSecond > prev.pollsPerSecond))) {
        best[i] = prev ? { ...r, plusPerPoll: prev.plusPerPoll, pdusPerPoll: prev.pdusPerPoll } : r;
      }
    }
  }
  return best;
}

const ratio = (a, b) => (a === undefined || b === undefined ? undefined : a / b);
const times = (v) => (v === undefined ? '–' : `${fmt(v, 2)}×`);
const verdict = (ok) => (ok === undefined ? 'not measured' : ok ? 'pass' : 'FAIL');

/**
 * Prints the section's tables. `warmPolls`: polls before the timed ones, the same for every client of ours
 * (the S7 tables' clients make 500 for their memory figures first; a fresh process needs a few hundred
 * polls before the optimizing compiler has the poll's code).
 */
async function s7plusSection({ durationMs, rounds, countPolls, warmPolls }) {
  let server;
  try {
    server = await startServer('plus');
  } catch (err) {
    console.log(`\n(S7CommPlus: the simulator is not available — ${err.message.split('\n')[0]})`);
    return;
  }
  const proxy = new CountingProxy(server.port);
  const proxyPort = await proxy.listen();
  const named = optimizedNames();
  const standard = standardAddresses(plcwire().compileSymbols);
  const found = findPython();
  const ourJob =
    (client, tags, extra = {}) =>
    (round) =>
      runClient(
        {
          client,
          tags: tags.map((t) => ({ address: t.name, value: t.value })),
          port: server.port,
          proxyPort,
          durationMs,
          countPolls: round === 0 ? countPolls : 0,
          memoryPolls: 0,
          warmPolls,
          ...extra,
        },
        proxy,
      );
  // No maxItems: the client reads the PLC's SystemLimits (the floor gets the limit ours settled on, below).
  const plus = { connect: { fingerprint: server.fingerprint } };
  const pythonJob = (round) =>
    runPython(
      found.python,
      {
        port: server.port,
        fingerprint: server.fingerprint,
        names: named.map((t) => t.python),
        warmMs: Math.min(300, durationMs / 4),
        durationMs,
        ...(round === 0 ? { proxyPort, countPolls } : {}),
      },
      proxy,
      named,
    );
  const [oursNamed, transport, python, s7, plusStd] = await bestOf(rounds, [
    ourJob('ours-s7plus', named, plus),
    // The floor: the transport alone, the same requests with nothing decoded (the proxy counts decoded polls only).
    ourJob('ours-s7plus-transport', named, { ...plus, countPolls: 0 }),
    found.python ? pythonJob : async () => ({ client: 'python', error: found.reason }),
    ourJob('ours', standard, { pdu: 960 }),
    ourJob('ours-s7plus', standard, plus),
  ]);
  await proxy.close();
  await server.stop();
  const s7_1200 = await profileCount('s7-1200', named, { durationMs: Math.min(durationMs, 300), countPolls, warmPolls: 0 });

  const row = (label, r, requests, tls = true) =>
    r.error
      ? [label, `not measured: ${r.error}`.slice(0, 100), '', '', '', '']
      : [
          label,
          fmt(r.pollsPerSecond),
          fmt(r.cpuMsPerPoll, 3),
          requests(r),
          tls ? fmt(r.plusPerPoll?.tlsRecords, 1) : '–',
          fmt(r.plusPerPoll ? r.plusPerPoll.bytesToServer + r.plusPerPoll.bytesToClient : undefined),
        ];
  const ownCount = (r) => fmt(r.requestsPerPoll, 1);
  const header = ['client', 'polls/s', 'CPU ms/poll', 'requests/poll', 'TLS records/poll', 'bytes/poll'];
  printTable(
    `S7CommPlus: 100 tags by name in an optimized DB, our simulator (S7-1500, TLS, pinned certificate; SystemLimits ${oursNamed.itemLimit ?? '?'} items/request to ours, ${PYTHON_ITEM_LIMIT} for s7commplus; frames of at most 1024 bytes); best of ${rounds} rounds of ${durationMs} ms; TLS records and bytes counted by a proxy over ${countPolls} polls`,
    header,
    [
      row('ours (s7plus://, by name)', oursNamed, ownCount),
      row('  its transport alone (floor)', transport, ownCount),
      row('s7commplus 0.3.0 (Python)', python, () => '–'),
      [
        'ours/s7commplus',
        times(ratio(oursNamed.pollsPerSecond, python.pollsPerSecond)),
        times(ratio(oursNamed.cpuMsPerPoll, python.cpuMsPerPoll)),
        '',
        '',
        '',
      ],
      [
        'ours/its floor',
        times(ratio(oursNamed.pollsPerSecond, transport.pollsPerSecond)),
        times(ratio(oursNamed.cpuMsPerPoll, transport.cpuMsPerPoll)),
        '',
        '',
        '',
      ],
    ],
    1,
  );
  printTable(
    'Our s7plus:// against our s7:// on the same 100 tags of a standard DB, by address, the same simulator (s7://: PDU 960, 20 items/job; requests = S7 jobs)',
    header,
    [
      row('ours s7:// (PUT/GET)', s7, (r) => fmt(r.pdusPerPoll, 1), false),
      row('ours s7plus:// (TLS)', plusStd, ownCount),
      [
        's7plus/s7',
        times(ratio(plusStd.pollsPerSecond, s7.pollsPerSecond)),
        times(ratio(plusStd.cpuMsPerPoll, s7.cpuMsPerPoll)),
        '',
        '',
        '',
      ],
    ],
    1,
  );
  // A poll by name is the reads SystemLimits allows and nothing else (issue #32): each name carries its SymbolCrc, so
  // the PLC itself refuses a LID a download gave to another member; no Explore of the program per poll.
  const vsPython = ratio(oursNamed.pollsPerSecond, python.pollsPerSecond);
  const cpuVsFloor = ratio(oursNamed.cpuMsPerPoll, transport.cpuMsPerPoll);
  const cpuVsS7 = ratio(plusStd.cpuMsPerPoll, s7.cpuMsPerPoll);
  const measured = (v) => v !== undefined && !Number.isNaN(v);
  const countRow = (label, r) => {
    const expected = r.itemLimit ? Math.ceil(named.length / r.itemLimit) : undefined;
    const seen = [r.requestsPerPoll, r.plusPerPoll?.tlsRecords];
    return [
      `requests per poll, ${label}: ${named.length} names at SystemLimits ${r.itemLimit ?? '?'} = ${expected ?? '?'}`,
      r.error ? `not measured: ${r.error}`.slice(0, 60) : `${fmt(seen[0], 1)} (ours) / ${fmt(seen[1], 1)} (proxy)`,
      verdict(seen.every(measured) && expected !== undefined ? seen.every((n) => n === expected) : undefined),
    ];
  };
  printTable(
    'S7CommPlus targets (issues #25, #32)',
    ['target', 'measured', 'result'],
    [
      [
        `polls/s at least ${TARGETS.pollsVsPython}× the s7commplus client's (by name)`,
        times(vsPython),
        verdict(measured(vsPython) ? vsPython >= TARGETS.pollsVsPython : undefined),
      ],
      [
        `CPU per poll by name at most ${TARGETS.cpuVsFloor}× its TLS-in-COTP transport floor (same requests, nothing decoded)`,
        times(cpuVsFloor),
        verdict(measured(cpuVsFloor) ? cpuVsFloor <= TARGETS.cpuVsFloor : undefined),
      ],
      countRow('S7-1200', s7_1200),
      // 100 item addresses with their SymbolCrcs are about 1.4 kB: past the 1024-byte frame, so 2 requests, not 1.
      [...countRow('S7-1500', oursNamed).slice(0, 2), 'the 1024-byte frame: 2'],
      [`(info) CPU per poll of s7plus:// over our PUT/GET path's, the same standard tags`, times(cpuVsS7), ''],
    ],
    1,
  );
}

/** Our client by name on a simulator of `profile` through a counting proxy: its SystemLimits and requests per poll. */
async function profileCount(profile, named, { durationMs, countPolls, warmPolls }) {
  let server;
  try {
    server = await startServer('plus', { profile });
  } catch (err) {
    return { client: 'ours-s7plus', error: err.message };
  }
  const proxy = new CountingProxy(server.port);
  const proxyPort = await proxy.listen();
  try {
    return await runClient(
      {
        client: 'ours-s7plus',
        tags: named.map((t) => ({ address: t.name, value: t.value })),
        port: server.port,
        proxyPort,
        durationMs,
        countPolls,
        memoryPolls: 0,
        warmPolls,
        connect: { fingerprint: server.fingerprint },
      },
      proxy,
    );
  } finally {
    await proxy.close();
    await server.stop();
  }
}

module.exports = { s7plusSection };
