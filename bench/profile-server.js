#!/usr/bin/env node
'use strict';
// Profiling driver for the simulator: the simulator in this process, our
// client polling it from a child, so `node --cpu-prof` profiles the server alone.
//   node --cpu-prof --cpu-prof-dir=/tmp/sprof bench/profile-server.js "1000 scattered" 3000
// S7CommPlus: the simulator serving bench/s7plus.js's program over TLS, our client reading its 100 names
// (table "names") or the standard DB's 100 addresses (table "standard") over s7plus://:
//   node --cpu-prof --cpu-prof-dir=/tmp/sprof bench/profile-server.js names 3000
const { fork } = require('node:child_process');
const { table, image, DB1_SIZE } = require('./lib/tables');

const asClient = process.argv[2] === '--client';
const args = process.argv.slice(asClient ? 4 : 2);
const [name = '1000 scattered', ms = '3000'] = args;

const PLUS_TABLES = ['names', 'standard'];

function plusAddresses() {
  const { optimizedNames, standardAddresses } = require('./lib/s7plus-program');
  const { plcwire } = require('./lib/peers');
  return (name === 'names' ? optimizedNames() : standardAddresses(plcwire().compileSymbols)).map((t) => t.name);
}

async function client(port, fingerprint) {
  const { CLIENTS, LOADERS } = require('./lib/clients');
  LOADERS.ours();
  const c = PLUS_TABLES.includes(name)
    ? await CLIENTS['ours-s7plus']({ port, fingerprint, maxItems: 50, addresses: plusAddresses() })
    : await CLIENTS.ours({ port, pdu: 960, addresses: table(name).map((t) => t.address) });
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
  const path = require('node:path');
  const { plcwire, DIST } = require('./lib/peers');
  const { S7Server, PlcMemory, S7PlusService } = plcwire();
  let s;
  let fingerprint = '';
  if (PLUS_TABLES.includes(name)) {
    const { program } = require('./lib/s7plus-program');
    const { generateCertificate } = require(path.join(DIST, 'lib/s7plus/transport/cert.js'));
    const cert = await generateCertificate();
    const service = new S7PlusService({ ...program(), tls: { cert: cert.cert, key: cert.key } });
    fingerprint = service.fingerprint;
    s = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
  } else {
    s = new S7Server({ port: 0, memory: new PlcMemory({ dataBlocks: { 1: DB1_SIZE } }) });
  }
  const port = await s.listen();
  if (!PLUS_TABLES.includes(name)) Buffer.from(image(table(name))).copy(s.memory.area('DB', 1));
  const child = fork(__filename, ['--client', String(port), name, ms, fingerprint]);
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
  client(Number(process.argv[3]), process.argv[6]).catch((e) => {
    console.error(e);
    process.exit(1);
  });
} else {
  server().catch((e) => {
    console.error(e);
    process.exit(1);
  });
}
