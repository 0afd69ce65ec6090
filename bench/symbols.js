#!/usr/bin/env node
'use strict';
// Reading by name against reading by address (docs/symbols.md, "Reading and
// writing by name"): a prepared poll of 100 symbols beside the same 100
// absolute addresses, and a struct of 50 members read as one object beside
// its 50 members by name; the simulator built from the same generated
// source, in this process. Rounds interleave the cases so drift in the
// machine's load touches each alike; CPU time per poll is printed beside
// polls/s, since on a loaded machine it moves less.
//   node bench/symbols.js [ms per case, default 3000] [rounds, default 3]
const { compileSymbols, connect, S7Server } = require('../dist/lib/index.js');

const [ms = '3000', rounds = '3'] = process.argv.slice(2);
const TYPES = ['Int', 'Real', 'Bool', 'DInt', 'Bool', 'Word', 'Real'];

/** DB1 "Bench": 100 scattered members, then a Struct of 50 (TIA source text, standard access). */
function source() {
  const lines = ['DATA_BLOCK "Bench"', "{ S7_Optimized_Access := 'FALSE' }", 'VERSION : 0.1', '   STRUCT'];
  for (let i = 0; i < 100; i++) lines.push(`      M${i} : ${TYPES[i % TYPES.length]};`);
  lines.push('      S : Struct');
  for (let i = 0; i < 50; i++) lines.push(`         F${i} : ${TYPES[(i * 3) % TYPES.length]};`);
  lines.push('      END_STRUCT;', '   END_STRUCT;', 'BEGIN', 'END_DATA_BLOCK', '');
  return lines.join('\r\n');
}

async function rate(read, duration = Number(ms)) {
  for (let i = 0; i < 200; i++) await read();
  let n = 0;
  const cpu0 = process.cpuUsage();
  const t0 = process.hrtime.bigint();
  const until = Date.now() + duration;
  while (Date.now() < until) {
    await read();
    n++;
  }
  const cpu = process.cpuUsage(cpu0);
  // CPU per poll counts client and simulator (one process) and is less moved by other processes than polls/s.
  return { perSecond: n / (Number(process.hrtime.bigint() - t0) / 1e9), cpuUs: (cpu.user + cpu.system) / n };
}

async function main() {
  const symbols = compileSymbols([{ name: 'Bench.db', content: source() }], { db: { Bench: 1 } });
  const server = new S7Server({ port: 0, profile: 's7-300', symbols });
  await server.listen();
  const plc = await connect(`s7://127.0.0.1:${server.port}?rack=0&slot=2`, { symbols });
  try {
    const names = Array.from({ length: 100 }, (_, i) => `"Bench".M${i}`);
    const addresses = names.map((n) => symbols.lookup(n).address);
    const members = Array.from({ length: 50 }, (_, i) => `"Bench".S.F${i}`);
    const cases = {
      '100 addresses': plc.prepare(addresses),
      '100 symbols': plc.prepare(names),
      'struct of 50 as one object': plc.prepare(['"Bench".S']),
      'its 50 members by name': plc.prepare(members),
    };
    // The same values either way, before anything is timed.
    const byName = await cases['100 symbols'].read();
    const byAddress = await cases['100 addresses'].read();
    if (names.some((n, i) => JSON.stringify(byName[n]) !== JSON.stringify(byAddress[addresses[i]])))
      throw new Error('names and addresses differ');
    // What each poll sends: jobs and items of one poll.
    const shape = {};
    for (const [label, poll] of Object.entries(cases)) {
      const seen = [];
      const on = (r) => r.kind === 'read' && seen.push(r.items);
      server.on('request', on);
      await poll.read();
      server.off('request', on);
      const items = seen.reduce((a, b) => a + b, 0);
      shape[label] = `${seen.length} job${seen.length > 1 ? 's' : ''}, ${items} item${items > 1 ? 's' : ''}`;
    }
    const results = Object.fromEntries(Object.keys(cases).map((k) => [k, []]));
    // A round not counted: the first case timed would otherwise carry the JIT's warm-up.
    for (const poll of Object.values(cases)) await rate(() => poll.read(), Number(ms) / 2);
    for (let r = 0; r < Number(rounds); r++) {
      for (const [label, poll] of Object.entries(cases)) results[label].push(await rate(() => poll.read()));
    }
    for (const [label, rs] of Object.entries(results)) {
      const k = rs.map((x) => (x.perSecond / 1000).toFixed(1).padStart(5)).join(' ');
      const cpu = rs.map((x) => x.cpuUs.toFixed(0).padStart(4)).join(' ');
      console.log(`${label.padEnd(28)} ${shape[label].padEnd(16)} ${k} k polls/s   ${cpu} µs CPU/poll`);
    }
  } finally {
    await plc.close();
    await server.close();
  }
}

main().catch((err) => {
  console.error(err);
  process.exitCode = 1;
});
