'use strict';
// The benchmark's worker processes, started and driven over IPC by the
// sections of bench/run.js: one server (server-worker.js) and one client at a
// time (client-worker.js), each in a process of its own.
const { fork } = require('node:child_process');
const path = require('node:path');

const BENCH = path.resolve(__dirname, '..');

/** Sends `msg` to `child` and resolves with its one answer (rejects on `{ ok: false }`). */
function ask(child, msg) {
  return new Promise((resolve, reject) => {
    child.once('message', (m) => (m.ok === false ? reject(new Error(m.error)) : resolve(m)));
    child.send(msg);
  });
}

/** Starts a server worker of `kind`; resolves with its port (and what else it answers) and `fill`/`stop`. */
async function startServer(kind, extra = {}) {
  const child = fork(path.join(BENCH, 'server-worker.js'), [], { serialization: 'advanced', stdio: 'inherit' });
  let started;
  try {
    started = await ask(child, { op: 'start', kind, ...extra });
  } catch (err) {
    child.kill();
    throw err;
  }
  const { ok: _ok, ...answer } = started;
  return {
    ...answer,
    fill: (db1) => ask(child, { op: 'fill', db1 }),
    stop: () =>
      new Promise((resolve) => {
        child.once('exit', resolve);
        child.send({ op: 'stop' });
      }),
  };
}

/** Runs one client job in a fresh process; a proxy counts its PDUs and bytes when asked. */
async function runClient(job, proxy) {
  const child = fork(path.join(BENCH, 'client-worker.js'), [], {
    serialization: 'advanced',
    execArgv: ['--expose-gc'],
    stdio: 'inherit',
  });
  let counted;
  return new Promise((resolve) => {
    const timer = setTimeout(() => {
      child.kill();
      resolve({ error: 'timed out' });
    }, 60_000);
    child.on('message', (m) => {
      if (m.counting) {
        proxy.reset();
        child.send({ go: true });
      } else if (m.counted) {
        counted = {
          pdusPerPoll: proxy.jobs / job.countPolls,
          bytesPerPoll: (proxy.bytesToServer + proxy.bytesToClient) / job.countPolls,
          maxItems: proxy.maxItemsPerJob,
          plusPerPoll: perPoll(proxy.plus, job.countPolls),
        };
        child.send({ go: true });
      } else {
        clearTimeout(timer);
        if (!m.ok) return resolve({ error: m.error });
        resolve({ ...m.result, ...counted });
      }
    });
    child.on('exit', (code) => {
      clearTimeout(timer);
      resolve({ error: `exited with ${code}` });
    });
    child.send(job);
  });
}

/** The proxy's S7CommPlus counters divided by `polls`. */
function perPoll(counters, polls) {
  return Object.fromEntries(Object.entries(counters).map(([k, v]) => [k, v / polls]));
}

module.exports = { ask, startServer, runClient, perPoll };
