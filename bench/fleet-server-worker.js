'use strict';
// Many S7 simulators in one process (each its own port and memory), so their
// CPU never counts as the client's. Driven over IPC by bench/lib/fleet.js:
//   { op: 'start', plcs: [{ db1, changing }] } → { ports }
//   { op: 'stats' } → { connections: [..], readsPerPlc: [..], reads, writes, cpuUs }
//   { op: 'change', everyMs } → {}     { op: 'drop' } → {}     { op: 'stop' } → exits
const { plcwire } = require('./lib/peers');

const servers = [];
let reads = 0;
let writes = 0;
let ticker;

async function start(msg) {
  const { S7Server, PlcMemory } = plcwire();
  const ports = [];
  for (const plc of msg.plcs) {
    const memory = new PlcMemory({ dataBlocks: { 1: plc.db1.length } });
    Buffer.from(plc.db1).copy(memory.area('DB', 1));
    const server = new S7Server({ port: 0, memory, profile: 's7-1500' });
    const entry = { server, db: memory.area('DB', 1), changing: plc.changing, next: 0, reads: 0 };
    server.on('request', (r) => {
      if (r.kind === 'read') {
        reads++;
        entry.reads++;
      } else writes++;
    });
    ports.push(await server.listen());
    servers.push(entry);
  }
  return { ports };
}

function change(everyMs) {
  clearInterval(ticker);
  if (!everyMs) return;
  ticker = setInterval(() => {
    for (const s of servers) {
      if (s.changing.length === 0) continue;
      const offset = s.changing[s.next++ % s.changing.length];
      s.db.writeInt16BE(((s.db.readInt16BE(offset) + 32768 + 1) % 65536) - 32768, offset);
    }
  }, everyMs);
}

process.on('message', async (msg) => {
  try {
    if (msg.op === 'start') process.send({ ok: true, ...(await start(msg)) });
    else if (msg.op === 'stats') {
      const cpu = process.cpuUsage();
      process.send({
        ok: true,
        connections: servers.map((s) => s.server.connectionCount),
        readsPerPlc: servers.map((s) => s.reads),
        reads,
        writes,
        cpuUs: cpu.user + cpu.system,
      });
    } else if (msg.op === 'change') {
      change(msg.everyMs);
      process.send({ ok: true });
    } else if (msg.op === 'drop') {
      for (const s of servers) s.server.faults.dropConnections();
      process.send({ ok: true });
    } else if (msg.op === 'stop') {
      clearInterval(ticker);
      await Promise.all(servers.map((s) => s.server.close()));
      process.exit(0);
    }
  } catch (err) {
    process.send({ ok: false, error: String((err && err.stack) || err) });
  }
});
process.on('disconnect', () => process.exit(0));
