'use strict';
// One client library polling many PLCs from one process, as a gateway does:
// every PLC is polled every `intervalMs`, the PLCs' schedules spread evenly
// over the interval, and a poll that comes due while the PLC's previous poll
// is still running is skipped and counted (never overlapped, never dropped
// silently). Driven over IPC by bench/many-plcs.js with
//   { client, ports, tags, pdu, intervalMs, warmMs, durationMs }
// and answers one result: polls due / started / done / skipped / failed in
// the timed window, the process's CPU, RSS and event-loop delay.
const { monitorEventLoopDelay } = require('node:perf_hooks');
const { CLIENTS, LOADERS } = require('./lib/clients');
const { firstMismatch } = require('./lib/tables');
const { plcTable, percentile } = require('./lib/fleet');
const { openRaw } = require('./lib/raw-poll');

const LOOP_RESOLUTION_MS = 10;

async function run(job) {
  const raw = job.client === 'raw';
  if (!raw) LOADERS[job.client]();
  const open = raw ? openRaw : CLIENTS[job.client];
  const plcs = [];
  // Connect and check every PLC's values first: a fast wrong answer fails the run.
  for (let i = 0; i < job.ports.length; i++) {
    const tags = plcTable(job.tags, i);
    const addresses = tags.map((t) => t.address);
    const c = await open({ port: job.ports[i], pdu: job.pdu, addresses, tags: job.tags });
    const wrong = raw ? undefined : firstMismatch(tags, await c.read());
    if (wrong) throw new Error(`wrong value from ${job.client} at PLC ${i}: ${wrong}`);
    plcs.push({ c, busy: false });
  }

  const counts = { due: 0, started: 0, done: 0, skipped: 0, failed: 0 };
  const pollMs = [];
  let timing = false;
  let stopped = false;
  let firstError;
  const t0 = performance.now() + 20;
  const n = plcs.length;
  plcs.forEach((p, i) => {
    let next = t0 + (i * job.intervalMs) / n;
    const tick = () => {
      if (stopped) return;
      counts.due++;
      if (p.busy) counts.skipped++;
      else {
        p.busy = true;
        counts.started++;
        const started = performance.now();
        p.c
          .read()
          .then(
            () => {
              counts.done++;
              if (timing) pollMs.push(performance.now() - started);
            },
            (err) => {
              counts.failed++;
              firstError ??= String((err && err.message) || err);
            },
          )
          .finally(() => (p.busy = false));
      }
      next += job.intervalMs;
      setTimeout(tick, Math.max(0, next - performance.now()));
    };
    setTimeout(tick, Math.max(0, next - performance.now()));
  });

  await new Promise((resolve) => setTimeout(resolve, job.warmMs));
  const before = { ...counts };
  // The histogram records the time between its timer's firings: its resolution plus the delay.
  const loop = monitorEventLoopDelay({ resolution: LOOP_RESOLUTION_MS });
  loop.enable();
  timing = true;
  const cpu0 = process.cpuUsage();
  const w0 = performance.now();
  await new Promise((resolve) => setTimeout(resolve, job.durationMs));
  const cpu = process.cpuUsage(cpu0);
  const elapsedMs = performance.now() - w0;
  loop.disable();
  timing = false;
  const window = Object.fromEntries(Object.keys(counts).map((k) => [k, counts[k] - before[k]]));
  const rss = process.memoryUsage().rss;
  stopped = true;
  // Let the polls in flight finish, then close.
  const deadline = Date.now() + 10000;
  while (plcs.some((p) => p.busy) && Date.now() < deadline) await new Promise((r) => setTimeout(r, 10));
  await Promise.all(plcs.map((p) => p.c.close().catch(() => undefined)));
  pollMs.sort((a, b) => a - b);
  const cpuUs = cpu.user + cpu.system;
  return {
    client: job.client,
    plcs: n,
    tags: job.tags,
    ...window,
    /** Every poll started since connecting, the value checks included. */
    allStarted: counts.started + n,
    seconds: elapsedMs / 1000,
    cpuPercent: (cpuUs / 1000 / elapsedMs) * 100,
    cpuUsPerTagPoll: cpuUs / (window.done * job.tags),
    cpuUsPerPoll: cpuUs / window.done,
    userUsPerPoll: cpu.user / window.done,
    systemUsPerPoll: cpu.system / window.done,
    rssMiB: rss / 2 ** 20,
    loopP99Ms: Math.max(0, loop.percentile(99) / 1e6 - LOOP_RESOLUTION_MS),
    pollP99Ms: percentile(pollMs, 99),
    firstError,
  };
}

process.once('message', (job) => {
  run(job).then(
    (result) => process.send({ ok: true, result }, () => process.exit(0)),
    (err) => process.send({ ok: false, error: String((err && err.message) || err) }, () => process.exit(0)),
  );
});
