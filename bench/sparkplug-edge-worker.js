'use strict';
// One Sparkplug B edge node (lib/sparkplug/edge-node.ts) polling many PLCs in
// a process of its own, so its CPU is measured alone. Driven over IPC by
// bench/sparkplug.js:
//   { op: 'start', broker, ports, tags, intervalMs, buffer } → {}
//   { op: 'stats' } → { cpuUs, rssMb, published: { births, ddata, metrics, historical }, dropped, buffered, state }
//   { op: 'stop' } → NDEATH, exits
const path = require('node:path');
const { DIST } = require('./lib/peers');
const { plcTable } = require('./lib/fleet');

const { createClient } = require(path.join(DIST, 'lib/connect.js'));
const { SparkplugEdgeNode } = require(path.join(DIST, 'lib/sparkplug/edge-node.js'));

let node;
const clients = [];
const published = { births: 0, ddata: 0, metrics: 0, historical: 0 };

async function start(msg) {
  const devices = [];
  for (let i = 0; i < msg.ports.length; i++) {
    const client = createClient(`s7://127.0.0.1:${msg.ports[i]}?rack=0&slot=1`);
    client.on('error', () => undefined);
    await client.connect();
    client.start();
    clients.push(client);
    const tags = Object.fromEntries(plcTable(msg.tags, i).map((t) => [t.address, t.address]));
    devices.push({ name: `PLC${i}`, client, tags });
  }
  node = new SparkplugEdgeNode({
    brokers: [msg.broker],
    group: 'Bench',
    node: 'Edge1',
    devices,
    interval: msg.intervalMs,
    buffer: { count: msg.buffer, bytes: 500_000_000 },
    primaryHost: 'BenchHost',
    reconnectDelay: 500,
  });
  node.on('error', () => undefined);
  node.on('publish', (m) => {
    if (m.type === 'DBIRTH' || m.type === 'NBIRTH') published.births++;
    if (m.type !== 'DDATA') return;
    published.ddata++;
    for (const metric of m.payload.metrics) {
      published.metrics++;
      if (metric.isHistorical) published.historical++;
    }
  });
  node.start();
}

process.on('message', async (msg) => {
  try {
    if (msg.op === 'start') {
      await start(msg);
      process.send({ ok: true });
    } else if (msg.op === 'stats') {
      const cpu = process.cpuUsage();
      const s = node.stats;
      process.send({
        ok: true,
        cpuUs: cpu.user + cpu.system,
        rssMb: process.memoryUsage().rss / 1e6,
        published: { ...published },
        dropped: s.dropped,
        buffered: s.buffered,
        state: s.state,
      });
    } else if (msg.op === 'stop') {
      await node.stop();
      await Promise.all(clients.map((c) => c.close()));
      process.exit(0);
    }
  } catch (err) {
    process.send({ ok: false, error: String((err && err.stack) || err) });
  }
});
process.on('disconnect', () => process.exit(0));
