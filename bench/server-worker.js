'use strict';
// One S7 server in its own process, so its CPU never competes with the
// client under test. Driven over IPC by bench/run.js:
//   { op: 'start', kind: 'ours'|'snap7', profile?, latencyMs? } → { port }
//   { op: 'start', kind: 'plus' } → { port, fingerprint }: our simulator of an S7-1500 serving
//     S7CommPlus over TLS too (a certificate generated here), the S7CommPlus benchmark's program
//     (bench/lib/s7plus-program.js) in its memory
//   { op: 'fill', db1 } → {}        { op: 'stop' } → exits
const net = require('node:net');
const path = require('node:path');
const { peer, plcwire, DIST } = require('./lib/peers');
const { program } = require('./lib/s7plus-program');
const { DB1_SIZE } = require('./lib/tables');

let server;
let kind;

function freePort() {
  return new Promise((resolve) => {
    const s = net.createServer().listen(0, '127.0.0.1', () => {
      const { port } = s.address();
      s.close(() => resolve(port));
    });
  });
}

async function start(msg) {
  kind = msg.kind;
  if (kind === 'snap7') {
    const snap7 = peer('node-snap7');
    server = new snap7.S7Server();
    server.RegisterArea(server.srvAreaDB, 1, Buffer.alloc(DB1_SIZE));
    const port = await freePort();
    if (!server.SetParam(server.LocalPort, port)) throw new Error('snap7: cannot set LocalPort');
    if (!server.StartTo('127.0.0.1')) throw new Error(`snap7 server did not start on ${port}`);
    return { port };
  }
  const { S7Server, PlcMemory, S7PlusService } = plcwire();
  if (kind === 'plus') {
    const { generateCertificate } = require(path.join(DIST, 'lib/s7plus/transport/cert.js'));
    const cert = await generateCertificate({ commonName: 'plcwire benchmark' });
    const service = new S7PlusService({ ...program(), tls: { cert: cert.cert, key: cert.key } });
    // An S7-1500 unless the job names another profile (an S7-1200 reports SystemLimits of 50 tags per request).
    server = new S7Server({ port: 0, profile: msg.profile ?? 's7-1500', s7plus: service });
    return { port: await server.listen(), fingerprint: service.fingerprint };
  }
  const memory = new PlcMemory({ dataBlocks: { 1: DB1_SIZE } });
  const options = { port: 0, memory };
  if (msg.profile) options.profile = msg.profile;
  server = new S7Server(options);
  if (msg.latencyMs) setLatency(server, msg.latencyMs);
  const port = await server.listen();
  return { port };
}

function setLatency(s, ms) {
  // The simulator's latency fault: each request waits L ms, up to AmQ at once.
  if (typeof s.setFault === 'function') s.setFault({ latencyMs: ms });
  else if (s.faults) s.faults.latencyMs = ms;
  else throw new Error('S7Server has no latency fault');
}

function fill(db1) {
  const data = Buffer.from(db1);
  if (kind === 'snap7') server.SetArea(server.srvAreaDB, 1, data);
  else data.copy(server.memory.area('DB', 1));
}

process.on('message', async (msg) => {
  try {
    if (msg.op === 'start') process.send({ ok: true, ...(await start(msg)) });
    else if (msg.op === 'fill') {
      fill(msg.db1);
      process.send({ ok: true });
    } else if (msg.op === 'stop') {
      if (kind === 'snap7') server.Stop();
      else if (server) await server.close();
      process.exit(0);
    }
  } catch (err) {
    process.send({ ok: false, error: String((err && err.stack) || err) });
  }
});
process.on('disconnect', () => process.exit(0));
