#!/usr/bin/env node
'use strict';
// `npm run bench -- --sections sparkplug` (or node bench/sparkplug.js): 100
// simulated PLCs × 100 tags polled every 100 ms by one Sparkplug B edge node
// (its own process) into a real mosquitto, a primary host (this process)
// subscribed to spBv1.0/Bench/#. Every 10 ms one INT tag of each PLC changes
// (100 changes a second a PLC, 10 000 in all). Measured: the edge node's CPU
// per tag change published, the latency from the edge node's read (the
// metric's timestamp) to the host, p50/p99, and a broker outage of 30 s:
// the values changed meanwhile arrive after the new births as historical
// metrics, and what the store-and-forward bound dropped is counted.
//
//   node bench/sparkplug.js [--quick] [--plcs 100] [--tags 100] [--interval 100] [--change 10] [--outage 30000] [--buffer 1000000]
const { fork, spawn } = require('node:child_process');
const fs = require('node:fs');
const os = require('node:os');
const path = require('node:path');
const net = require('node:net');
const { DIST } = require('./lib/peers');
const { startFleet, ask, percentile } = require('./lib/fleet');
const { fmt, printTable, option } = require('./lib/print');

const mqtt = require('mqtt');

async function freePort() {
  const s = net.createServer().listen(0, '127.0.0.1');
  await new Promise((r) => s.once('listening', r));
  const port = s.address().port;
  await new Promise((r) => s.close(r));
  return port;
}

/** mosquitto (Debian's /usr/sbin/mosquitto, or MOSQUITTO) on `port`; resolves once it listens. */
async function startMosquitto(port, dir) {
  const bin = process.env.MOSQUITTO ?? (fs.existsSync('/usr/sbin/mosquitto') ? '/usr/sbin/mosquitto' : 'mosquitto');
  const conf = path.join(dir, 'mosquitto.conf');
  fs.writeFileSync(
    conf,
    `listener ${port} 127.0.0.1\nallow_anonymous true\npersistence false\nmax_queued_messages 0\nmax_inflight_messages 0\n`,
  );
  const child = spawn(bin, ['-c', conf], { stdio: 'ignore' });
  const deadline = Date.now() + 10_000;
  for (;;) {
    if (child.exitCode !== null) throw new Error(`mosquitto exited (${child.exitCode}): is it installed (Debian package mosquitto)?`);
    const up = await new Promise((resolve) => {
      const s = net.connect(port, '127.0.0.1');
      s.once('connect', () => (s.destroy(), resolve(true)));
      s.once('error', () => (s.destroy(), resolve(false)));
    });
    if (up) return child;
    if (Date.now() > deadline) throw new Error(`mosquitto did not listen on ${port}`);
    await new Promise((r) => setTimeout(r, 50));
  }
}

function stopProcess(child) {
  return new Promise((resolve) => {
    if (child.exitCode !== null || child.signalCode !== null) return resolve();
    child.once('exit', resolve);
    child.kill('SIGTERM');
  });
}

/** The primary host: STATE online after every (re)connect, every DDATA/DBIRTH decoded and counted. */
function startHost(url, decodePayload) {
  const seen = { births: 0, metrics: 0, historical: 0, latencies: [] };
  const client = mqtt.connect(url, { clientId: 'bench-host', reconnectPeriod: 100, clean: true });
  client.on('error', () => undefined);
  client.on('connect', () => {
    client.subscribe('spBv1.0/Bench/#', { qos: 1 }, () => {
      client.publish('spBv1.0/STATE/BenchHost', JSON.stringify({ online: true, timestamp: Date.now() }), { qos: 1, retain: true });
    });
  });
  client.on('message', (topic, bytes) => {
    const type = topic.split('/')[2];
    if (type === 'DBIRTH') seen.births++;
    if (type !== 'DDATA') return;
    const now = Date.now();
    const p = decodePayload(bytes);
    for (const m of p.metrics) {
      seen.metrics++;
      if (m.isHistorical) seen.historical++;
      else if (seen.timing && m.timestamp !== undefined) seen.latencies.push(now - Number(m.timestamp));
    }
  });
  return { seen, close: () => client.endAsync(true) };
}

async function until(what, condition, ms) {
  const deadline = Date.now() + ms;
  while (!(await condition())) {
    if (Date.now() > deadline) throw new Error(`${what}: not within ${ms} ms`);
    await new Promise((r) => setTimeout(r, 100));
  }
}

async function sparkplugSection(args = process.argv.slice(2)) {
  const quick = args.includes('--quick');
  const PLCS = Number(option(args, 'plcs', 100));
  const TAGS = Number(option(args, 'tags', 100));
  const INTERVAL = Number(option(args, 'interval', 100));
  const CHANGE = Number(option(args, 'change', 10));
  const OUTAGE = Number(option(args, 'outage', quick ? 5000 : 30_000));
  const BUFFER = Number(option(args, 'buffer', 1_000_000));
  const WINDOW = quick ? 3000 : 10_000;
  const { decodePayload } = require(path.join(DIST, 'lib/sparkplug/payload.js'));
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-bench-spb-'));
  const port = await freePort();
  const url = `mqtt://127.0.0.1:${port}`;
  let broker = await startMosquitto(port, dir);
  const fleet = await startFleet(PLCS, TAGS);
  const host = startHost(url, decodePayload);
  const edge = fork(path.join(__dirname, 'sparkplug-edge-worker.js'), [], { serialization: 'advanced', stdio: 'inherit' });
  const rows = [];
  try {
    await ask(edge, { op: 'start', broker: url, ports: fleet.ports, tags: TAGS, intervalMs: INTERVAL, buffer: BUFFER });
    await until('every DBIRTH at the host', () => host.seen.births >= PLCS, 60_000);
    await fleet.change(CHANGE);
    await new Promise((r) => setTimeout(r, 2000)); // warm-up
    const a = await ask(edge, { op: 'stats' });
    const received0 = host.seen.metrics;
    host.seen.timing = true;
    const t0 = Date.now();
    await new Promise((r) => setTimeout(r, WINDOW));
    host.seen.timing = false;
    const b = await ask(edge, { op: 'stats' });
    const seconds = (Date.now() - t0) / 1000;
    const published = b.published.metrics - a.published.metrics;
    const lat = host.seen.latencies.sort((x, y) => x - y);
    const cpuPct = ((b.cpuUs - a.cpuUs) / 1e6 / seconds) * 100;
    rows.push([
      `${PLCS} PLCs × ${TAGS} tags, poll ${INTERVAL} ms`,
      fmt(PLCS * (1000 / CHANGE)),
      fmt(published / seconds),
      fmt((host.seen.metrics - received0) / seconds),
      `${cpuPct.toFixed(0)} %`,
      `${((b.cpuUs - a.cpuUs) / published).toFixed(1)} µs`,
      `${percentile(lat, 50)} / ${percentile(lat, 99)} ms`,
      `${b.rssMb.toFixed(0)} MB`,
    ]);
    printTable(
      'Sparkplug B: one edge node into mosquitto (bench/sparkplug.js)',
      [
        'load',
        'changes/s asked',
        'metrics/s published',
        'metrics/s at host',
        'edge CPU',
        'CPU per change',
        'read→host p50/p99',
        'edge RSS',
      ],
      rows,
    );

    // The outage: the broker away for OUTAGE ms while the PLCs keep changing.
    const before = await ask(edge, { op: 'stats' });
    const hostHistorical0 = host.seen.historical;
    const birthsBefore = host.seen.births;
    await stopProcess(broker);
    await new Promise((r) => setTimeout(r, OUTAGE));
    const during = await ask(edge, { op: 'stats' });
    broker = await startMosquitto(port, dir);
    await until('the births after the outage', () => host.seen.births >= birthsBefore + PLCS, 60_000);
    await until(
      'the buffered values at the host',
      async () => host.seen.historical - hostHistorical0 >= during.buffered || (await ask(edge, { op: 'stats' })).buffered === 0,
      120_000,
    );
    await new Promise((r) => setTimeout(r, 1000));
    const after = await ask(edge, { op: 'stats' });
    const historical = host.seen.historical - hostHistorical0;
    printTable(
      `Broker outage of ${OUTAGE / 1000} s (store-and-forward bound ${fmt(BUFFER)} values)`,
      [
        "kept after the outage's first " + OUTAGE / 1000 + ' s',
        'dropped at the bound',
        'sent as historical',
        'historical at the host',
        'lost beyond the bound',
      ],
      [
        [
          fmt(during.buffered),
          fmt(after.dropped - before.dropped),
          fmt(after.published.historical - before.published.historical),
          fmt(historical),
          fmt(after.published.historical - before.published.historical - historical),
        ],
      ],
    );
  } finally {
    await stopProcess(edge);
    await host.close();
    await fleet.stop();
    await stopProcess(broker);
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

module.exports = { sparkplugSection };

if (require.main === module) {
  sparkplugSection().then(
    () => process.exit(0),
    (err) => {
      console.error(err);
      process.exit(1);
    },
  );
}
