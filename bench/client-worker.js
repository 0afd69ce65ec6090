'use strict';
// One client in its own process, so process.cpuUsage() and RSS are that
// client's alone. Driven over IPC by bench/run.js with
//   { client, table, pdu, port, proxyPort?, durationMs?, countPolls?, latencyPolls? }
// and answers one result object.
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
  const tags = table(job.table);
  const addresses = tags.map((t) => t.address);
  const result = { client: job.client, table: job.table, tags: tags.length };

  if (job.durationMs) {
    const mem0 = await settle();
    const c = await open({ port: job.port, pdu: job.pdu, addresses });
    const wrong = firstMismatch(tags, await c.read());
    if (wrong) throw new Error(`wrong value from ${job.client}: ${wrong}`);
    let last;
    for (let i = 1; i < MEMORY_POLLS; i++) last = await c.read();
    // What stays reachable while connected: the client, its plan and its last result.
    const mem1 = await settle();
    if (!last) throw new Error('no result');
    const warmUntil = Date.now() + Math.min(300, job.durationMs / 4);
    while (Date.now() < warmUntil) await c.read();
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
    await c.close();
    Object.assign(result, {
      polls,
      pollsPerSecond: (polls * 1000) / elapsedMs,
      cpuMsPer1000Tags: ((cpu.user + cpu.system) / 1000 / (polls * tags.length)) * 1000,
      rssBytesPerTag: Math.max(0, mem1.rss - mem0.rss) / tags.length,
      heapBytesPerTag: Math.max(0, mem1.heap - mem0.heap) / tags.length,
    });
  }

  if (job.countPolls) {
    const c = await open({ port: job.proxyPort, pdu: job.pdu, addresses });
    process.send({ counting: true });
    await new Promise((resolve) => process.once('message', resolve)); // the proxy was reset
    for (let i = 0; i < job.countPolls; i++) {
      const wrong = firstMismatch(tags, await c.read());
      if (wrong) throw new Error(`wrong value from ${job.client} through the proxy: ${wrong}`);
    }
    await c.close();
  }

  if (job.latencyPolls) {
    const c = await open({ port: job.port, pdu: job.pdu, addresses });
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
