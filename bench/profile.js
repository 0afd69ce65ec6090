#!/usr/bin/env node
'use strict';
// Profiling driver: our client in this process, the simulator in a child, so
// `node --cpu-prof bench/profile.js [table] [ms] [client]` profiles the client alone.
//   node --cpu-prof --cpu-prof-dir=/tmp/prof bench/profile.js "100 scattered" 3000
// S7CommPlus (bench/s7plus.js's tags, the simulator serving them over TLS):
//   node --cpu-prof --cpu-prof-dir=/tmp/prof bench/profile.js names 3000 ours-s7plus plus
//   (names: the optimized DB's 100 names; standard: the standard DB's 100 addresses; client ours or ours-s7plus)
const { fork } = require('node:child_process');
const path = require('node:path');
const { table, image } = require('./lib/tables');
const { CLIENTS, LOADERS } = require('./lib/clients');
const { optimizedNames, standardAddresses } = require('./lib/s7plus-program');
const { plcwire } = require('./lib/peers');

const [name = '100 scattered', ms = '2000', client = 'ours', kind = 'ours'] = process.argv.slice(2);

function ask(child, msg) {
  return new Promise((resolve, reject) => {
    child.once('message', (m) => (m.ok === false ? reject(new Error(m.error)) : resolve(m)));
    child.send(msg);
  });
}

async function main() {
  const server = fork(path.join(__dirname, 'server-worker.js'), [], { serialization: 'advanced' });
  const { port, fingerprint } = await ask(server, { op: 'start', kind });
  let tags;
  if (kind === 'plus') {
    const plus = name === 'names' ? optimizedNames() : standardAddresses(plcwire().compileSymbols);
    tags = plus.map((t) => ({ address: t.name }));
  } else {
    tags = table(name);
    await ask(server, { op: 'fill', db1: image(tags) });
  }
  LOADERS[client]();
  const c = await CLIENTS[client]({
    port,
    fingerprint,
    maxItems: 50,
    pdu: kind === 'snap7' ? 240 : 960,
    addresses: tags.map((t) => t.address),
  });
  for (let i = 0; i < 200; i++) await c.read();
  const cpu0 = process.cpuUsage();
  const t0 = process.hrtime.bigint();
  const until = Date.now() + Number(ms);
  let polls = 0;
  while (Date.now() < until) {
    await c.read();
    polls++;
  }
  const elapsed = Number(process.hrtime.bigint() - t0) / 1e6;
  const cpu = process.cpuUsage(cpu0);
  console.log(
    `${client} ${name}: ${((polls * 1000) / elapsed).toFixed(0)} polls/s, ${((cpu.user + cpu.system) / polls).toFixed(1)} µs CPU/poll, ` +
      `${((cpu.user + cpu.system) / polls / tags.length).toFixed(3)} µs/tag (user ${(cpu.user / polls).toFixed(1)}, sys ${(cpu.system / polls).toFixed(1)})`,
  );
  await c.close();
  await ask(server, { op: 'stop' }).catch(() => undefined);
  server.kill();
}
main().catch((e) => {
  console.error(e);
  process.exit(1);
});
