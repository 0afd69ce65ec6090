#!/usr/bin/env node
'use strict';
// Profiling driver for the simulator: the simulator in this process, our
// client polling it from a child, so `node --cpu-prof` profiles the server alone.
//   node --cpu-prof --cpu-prof-dir=/tmp/sprof bench/profile-server.js "1000 scattered" 3000
const { fork } = require('node:child_process');
const { table, image, DB1_SIZE } = require('./lib/tables');

const asClient = process.argv[2] === '--client';
const args = process.argv.slice(asClient ? 4 : 2);
const [name = '1000 scattered', ms = '3000'] = args;

async function client(port) {
  const { CLIENTS, LOADERS } = require('./lib/clients');
  LOADERS.ours();
  const c = await CLIENTS.ours({ port, pdu: 960, addresses: table(name).map((t) => t.address) });
  for (let i = 0; i < 200; i++) await c.read();
  process.send({ ready: true });
  const t0 = Date.now();
  let polls = 0;
  while (Date.now() - t0 < Number(ms)) {
    await c.read();
    polls++;
  }
  await c.close();
  process.send({ polls, elapsed: Date.now() - t0 }, () => process.exit(0));
}

async function server() {
  const { plcwire } = require('./lib/peers');
  const { S7Server, PlcMemory } = plcwire();
  const s = new S7Server({ port: 0, memory: new PlcMemory({ dataBlocks: { 1: DB1_SIZE } }) });
  const port = await s.listen();
  Buffer.from(image(table(name))).copy(s.memory.area('DB', 1));
  const child = fork(__filename, ['--client', String(port), name, ms]);
  let cpu0;
  child.on('message', async (m) => {
    if (m.ready) {
      cpu0 = process.cpuUsage();
      return;
    }
    const cpu = process.cpuUsage(cpu0);
    console.log(
      `simulator, ${name}: ${((m.polls * 1000) / m.elapsed).toFixed(0)} polls/s, ${((cpu.user + cpu.system) / m.polls).toFixed(1)} µs CPU/poll ` +
        `(user ${(cpu.user / m.polls).toFixed(1)}, sys ${(cpu.system / m.polls).toFixed(1)})`,
    );
    await s.close();
  });
}

if (asClient) {
  client(Number(process.argv[3])).catch((e) => {
    console.error(e);
    process.exit(1);
  });
} else {
  server().catch((e) => {
    console.error(e);
    process.exit(1);
  });
}
