'use strict';
// One client in its own process, so process.cpuUsage() and RSS are that
// client's alone. Driven over IPC by bench/run.js with
//   { client, table, pdu, port, proxyPort?, durationMs?, countPolls?, latencyPolls? }
// and answers one result object. The S7CommPlus section gives its own tags
// instead of a table ({ tags: [{ address, value }], connect: { fingerprint, maxItems },
// memoryPolls: 0, warmPolls }); a client that counts its requests (ours over s7plus://)
// reports them per poll.
const { CLIENTS, LOADERS } = require('./lib/clients');
const { table, firstMismatch } = require('./lib/tables');

const gc = global.gc || (() => undefined);
/** Polls before memory is measured: the same number for every client, so a faster client's extra garbage does not count as memory. */
const MEMORY_POLLS = 500;
/** Polls before the latency model's polls are timed. */
const LATENCY_WARM_POLLS = 20;

/**
 * Memory after full GCs 30 ms apart, the least seen: freed ArrayBuffers leave
 * `external` only after the sweeper has run, and code the optimizing compiler
 * finishes in the background lands on the heap a little later.
 */
async function settle() {
  let heap = Infinity;
  let rss = Infinity;
  for (let i = 0; i < 6; i++) {
    gc();
    await new Promise((resolve) => setTimeout(resolve, 30));
    gc();
    const m = process.memoryUsage();
    heap = Math.min(heap, m.heapUsed + m.external);
    rss = Math.min(rss, m.rss);
  }
  return { rss, heap };
}

async function run(job) {
  const open = CLIENTS[job.client];
  LOADERS[job.client]();
  const tags = job.tags ?? table(job.table);
  const addresses = tags.map((t) => t.address);
  const result = { client: job.client, table: job.table, tags: tags.length };
  const memoryPolls = job.memoryPolls ?? MEMORY_POLLS;
  const connect = (port) => open({ port, pdu: job.pdu, addresses, ...job.connect });

  if (job.durationMs) {
    const mem0 = memoryPolls ? await settle() : undefined;
    const c = await connect(job.port);
    const wrong = firstMismatch(tags, await c.read());
    if (wrong) throw new Error(`wrong value from ${job.client}: ${wrong}`);
    let last;
    for (let i = 1; i < memoryPolls; i++) last = await c.read();
    // What stays reachable while connected: the client, its plan and its last result.
    const mem1 = memoryPolls ? await settle() : undefined;
    if (memoryPolls && !last) throw new Error('no result');
    // Polls to warm up when no memory polls came first (the S7CommPlus section): compiled code, not the first polls' compiling, is timed.
    for (let i = 0; i < (job.warmPolls ?? 0); i++) await c.read();
    const warmUntil = Date.now() + Math.min(300, job.durationMs / 4);
    while (Date.now() < warmUntil) await c.read();
    const requests0 = c.requests?.();
    const cpu0 = process.cpuUsage();
    const t0 = process.hrtime.bigint();
    const until = Date.now() + job.durationMs;
    let polls = 0;
    while (Date.now() < until) {
      await c.read();
      polls++;
    }
    const elapsedMs = Number(process.hrtime.bigint() - t0) / 1e6;
    const cpu = process.cpuUsage(cpu0);
    if (c.requests) result.requestsPerPoll = (c.requests() - requests0) / polls;
    // The items per request the client settled on (ours over s7plus://: the PLC's SystemLimits, or the URL's maxItems).
    if (c.itemLimit) result.itemLimit = c.itemLimit();
    await c.close();
    Object.assign(result, {
      polls,
      pollsPerSecond: (polls * 1000) / elapsedMs,
      cpuMsPerPoll: (cpu.user + cpu.system) / 1000 / polls,
      cpuMsPer1000Tags: ((cpu.user + cpu.system) / 1000 / (polls * tags.length)) * 1000,
    });
    if (memoryPolls) {
      result.rssBytesPerTag = Math.max(0, mem1.rss - mem0.rss) / tags.length;
      result.heapBytesPerTag = Math.max(0, mem1.heap - mem0.heap) / tags.length;
    }
  }

  if (job.countPolls) {
    const c = await connect(job.proxyPort);
    // The first read of names browses the PLC: not a poll, so not counted.
    await c.read();
    process.send({ counting: true });
    await new Promise((resolve) => process.once('message', resolve)); // the proxy was reset
    for (let i = 0; i < job.countPolls; i++) {
      const wrong = firstMismatch(tags, await c.read());
      if (wrong) throw new Error(`wrong value from ${job.client} through the proxy: ${wrong}`);
    }
    // The proxy's counts are taken now: the close's own request (S7CommPlus: DeleteObject) is not a poll's.
    process.send({ counted: true });
    await new Promise((resolve) => process.once('message', resolve));
    await c.close();
  }

  if (job.latencyPolls) {
    const c = await connect(job.port);
    // Warm: the steady poll is measured, not the first ones' compiling. A
    // 1000-tag poll takes ~15 polls to settle (1-2 ms slower before, measured
    // poll by poll), so 20, the same for every client.
    for (let i = 0; i < LATENCY_WARM_POLLS; i++) await c.read();
    // The median poll: on a shared VM one poll in a few is late by milliseconds (scheduling), which says nothing of the client.
    const times = [];
    for (let i = 0; i < job.latencyPolls; i++) {
      const t0 = process.hrtime.bigint();
      await c.read();
      times.push(Number(process.hrtime.bigint() - t0) / 1e6);
    }
    times.sort((a, b) => a - b);
    result.pollMs = times[times.length >> 1];
    await c.close();
  }
  return result;
}

process.once('message', (job) => {
  run(job).then(
    (result) => {
      process.send({ ok: true, result }, () => process.exit(0));
    },
    (err) => {
      process.send({ ok: false, error: String((err && err.message) || err) }, () => process.exit(0));
    },
  );
});
