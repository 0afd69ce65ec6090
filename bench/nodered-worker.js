'use strict';
// One Node-RED runtime (the version in the root node_modules) in its own
// process, so its CPU is the Node-RED layer's plus the S7 library's under it.
// It loads our nodes, node-red-contrib-s7 (from test/interop) and the
// bench-count node (bench/lib/nodered-count); the editor and admin API are
// off. Driven over IPC by bench/nodered.js:
//   { op: 'start', name? } → { version }     (name labels its log lines)
//   { op: 'deploy', nodes, type } → { deployMs }       (a flow array, 'full' | 'nodes' | 'flows')
//   { op: 'wait-topics', topics, ms } → { ms }          (until bench-count saw each topic once)
//   { op: 'mark' } → { cpuUs, userUs, systemUs, messages, rss, loopP99Ms }
//   { op: 'profile', file? } → {}   (starts a V8 CPU profile; with `file`, stops it and writes it there)
//   { op: 'stop' } → exits
const fs = require('node:fs');
const http = require('node:http');
const os = require('node:os');
const path = require('node:path');
const inspector = require('node:inspector');
const { monitorEventLoopDelay } = require('node:perf_hooks');
const { ROOT } = require('./lib/peers');

const LOOP_RESOLUTION_MS = 10;
let RED;
let userDir;
let name = 'node-red';
let logging = false;
const counter = (global.__plcwireBenchCount ??= { messages: 0, track: false, topics: new Set() });
const loop = monitorEventLoopDelay({ resolution: LOOP_RESOLUTION_MS });

async function start(label) {
  if (label) name = label;
  userDir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-nr-bench-'));
  const contrib = path.dirname(require.resolve('node-red-contrib-s7/package.json', { paths: [path.join(ROOT, 'test/interop')] }));
  RED = require(require.resolve('node-red', { paths: [ROOT] }));
  RED.init(http.createServer(), {
    userDir,
    flowFile: 'flows.json',
    credentialSecret: false,
    disableEditor: true,
    httpAdminRoot: '/admin',
    httpNodeRoot: false,
    uiPort: 0,
    // Our package and node-red-contrib-s7 as a palette install would load them, and the counter.
    nodesDir: [ROOT, contrib, path.join(__dirname, 'lib/nodered-count')],
    // Warnings and errors while flows run; none from start-up (projects, credentials) or from stopping (contrib-s7 logs every disconnect).
    logging: {
      bench: {
        level: 'warn',
        metrics: false,
        audit: false,
        handler: () => (m) => {
          if (logging)
            console.log(
              `[${name}] ${m.type ? `[${m.type}${m.name ? `:${m.name}` : ''}] ` : ''}${m.msg && m.msg.stack ? m.msg.stack : m.msg}`,
            );
        },
      },
    },
    editorTheme: { tours: false },
    telemetry: { enabled: false },
    externalModules: { autoInstall: false },
  });
  await RED.start();
  const missing = ['plcwire-read', 'plcwire-connection', 's7 in', 's7 endpoint', 'bench-count'].filter((t) => !RED.nodes.getType(t));
  if (missing.length) throw new Error(`node types not registered: ${missing.join(', ')}`);
  return { version: RED.version() };
}

async function deploy(nodes, type) {
  logging = true;
  const t0 = performance.now();
  await RED.runtime.flows.setFlows({ flows: { flows: nodes }, deploymentType: type || 'full' });
  return { deployMs: performance.now() - t0 };
}

async function waitTopics(topics, ms) {
  const t0 = performance.now();
  counter.topics.clear();
  counter.track = true;
  try {
    while (!topics.every((t) => counter.topics.has(t))) {
      if (performance.now() - t0 > ms) {
        throw new Error(`only ${topics.filter((t) => counter.topics.has(t)).length} of ${topics.length} read nodes sent within ${ms} ms`);
      }
      await new Promise((resolve) => setTimeout(resolve, 5));
    }
  } finally {
    counter.track = false;
  }
  return { ms: performance.now() - t0 };
}

function mark() {
  const cpu = process.cpuUsage();
  const r = {
    cpuUs: cpu.user + cpu.system,
    userUs: cpu.user,
    systemUs: cpu.system,
    messages: counter.messages,
    rss: process.memoryUsage().rss,
    loopP99Ms: loop.count ? Math.max(0, loop.percentile(99) / 1e6 - LOOP_RESOLUTION_MS) : undefined,
  };
  loop.reset();
  loop.enable();
  return r;
}

let session;
/** The timed window alone in a profile (node --cpu-prof would hold Node-RED's start-up too). */
async function profile(file) {
  const post = (method, params) =>
    new Promise((resolve, reject) => session.post(method, params, (err, r) => (err ? reject(err) : resolve(r))));
  if (!file) {
    session = new inspector.Session();
    session.connect();
    await post('Profiler.enable');
    await post('Profiler.setSamplingInterval', { interval: 200 });
    await post('Profiler.start');
    return {};
  }
  const { profile: p } = await post('Profiler.stop');
  fs.writeFileSync(file, JSON.stringify(p));
  session.disconnect();
  return {};
}

process.on('message', async (msg) => {
  try {
    if (msg.op === 'start') process.send({ ok: true, ...(await start(msg.name)) });
    else if (msg.op === 'deploy') process.send({ ok: true, ...(await deploy(msg.nodes, msg.type)) });
    else if (msg.op === 'wait-topics') process.send({ ok: true, ...(await waitTopics(msg.topics, msg.ms)) });
    else if (msg.op === 'mark') process.send({ ok: true, ...mark() });
    else if (msg.op === 'profile') process.send({ ok: true, ...(await profile(msg.file)) });
    else if (msg.op === 'stop') {
      logging = false;
      await RED.stop().catch(() => undefined);
      fs.rmSync(userDir, { recursive: true, force: true });
      process.exit(0);
    }
  } catch (err) {
    process.send({ ok: false, error: String((err && err.stack) || err) });
  }
});
process.on('disconnect', () => process.exit(0));
