'use strict';
// Many raw S7 connections in one process, each repeating one Read Var request:
// { port, connections, durationMs, items, bytes } → { requestsPerSecond, errors }
const { openLoad, readRequest } = require('./lib/raw-s7');

process.once('message', async (job) => {
  try {
    const request = readRequest(Array.from({ length: job.items }, (_, i) => ({ offset: i * 16, bytes: job.bytes })));
    const loads = await Promise.all(Array.from({ length: job.connections }, () => openLoad(job.port, request)));
    const t0 = process.hrtime.bigint();
    loads.forEach((l) => l.start());
    await new Promise((resolve) => setTimeout(resolve, job.durationMs));
    loads.forEach((l) => l.stop());
    const seconds = Number(process.hrtime.bigint() - t0) / 1e9;
    const answers = loads.reduce((a, l) => a + l.answers, 0);
    const errors = loads.reduce((a, l) => a + l.errors, 0);
    loads.forEach((l) => l.close());
    process.send({ ok: true, requestsPerSecond: answers / seconds, errors }, () => process.exit(0));
  } catch (err) {
    process.send({ ok: false, error: String(err && err.message) }, () => process.exit(0));
  }
});
