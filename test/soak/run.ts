/**
 * `npm run soak`: long runs outside the test suite. 100,000 polls and 1,000
 * reconnects against the in-process simulators; prints heap growth and
 * handle counts, and fails when handles grow or a poll returns a wrong value.
 *
 *   npm run soak -- [polls] [reconnects]
 */
import { createClient } from '../../lib/connect';
import { startPlant } from '../../lib/plant/plant';
import type { ClientEvents, PlcClient } from '../../lib/types';

const POLLS = Number(process.argv[2] ?? 100_000);
const RECONNECTS = Number(process.argv[3] ?? 1_000);

function handles(): number {
  return (process as unknown as { _getActiveHandles(): unknown[] })._getActiveHandles().length;
}

function heapMiB(): number {
  global.gc?.();
  return process.memoryUsage().heapUsed / 2 ** 20;
}

function once(client: PlcClient, event: keyof ClientEvents, ms: number): Promise<void> {
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`no ${event} within ${ms} ms`)), ms);
    client.once(event, () => {
      clearTimeout(timer);
      resolve();
    });
  });
}

async function main(): Promise<void> {
  const plant = await startPlant({ ports: { s7: 0, fetch: 0, write: 0, freeport: 0 }, periodMs: 1000 });
  plant.process.stop();
  // The plant's DB1 is its 20-byte source and DB2 its optimized "Tank" (refused over PUT/GET); the polls get a DB of
  // their own, as if downloaded beside them.
  plant.memory.createDataBlock(3, 1024);
  const db3 = plant.memory.area('DB', 3)!;
  const rows: string[] = [];
  let failed = false;
  for (const [name, url, tags] of [
    ['S7', plant.urls.s7, Array.from({ length: 20 }, (_, i) => `DB3,INT${100 + i * 2}`)],
    ['FETCH/WRITE', plant.urls.fetchwrite, Array.from({ length: 20 }, (_, i) => `DB3,INT${100 + i * 2}`)],
    ['freeport (tcp)', plant.urls.freeport, ['ST5,DWORD0']],
  ] as const) {
    const polls = name.startsWith('freeport') ? Math.min(POLLS, 5_000) : POLLS;
    const client = createClient(url, { backoff: { initialDelay: 1, maxDelay: 5, jitter: 0 } });
    await client.connect();
    const handles0 = handles();
    const heap0 = heapMiB();
    const started = Date.now();
    for (let i = 0; i < polls; i++) {
      db3.writeInt16BE(i & 0x7fff, 100);
      const v = await client.read(tags);
      if (name !== 'freeport (tcp)' && v[tags[0]!] !== (i & 0x7fff)) {
        failed = true;
        console.error(`${name}: poll ${i} read ${String(v[tags[0]!])}`);
        break;
      }
    }
    const pollMs = Date.now() - started;
    const heap1 = heapMiB();
    const reconnects = name.startsWith('freeport') ? Math.min(RECONNECTS, 200) : RECONNECTS;
    for (let i = 0; i < reconnects; i++) {
      const lost = once(client, 'connected', 5000);
      if (name === 'S7') plant.s7.dropConnections();
      else if (name === 'FETCH/WRITE') plant.fetchwrite.dropConnections();
      else plant.freeport.dropConnections();
      await lost;
    }
    await client.read(tags);
    const heap2 = heapMiB();
    const handles1 = handles();
    await client.close();
    if (handles1 > handles0) failed = true;
    rows.push(
      `${name.padEnd(16)}${String(polls).padEnd(9)}${(polls / (pollMs / 1000)).toFixed(0).padEnd(10)}${String(reconnects).padEnd(12)}` +
        `${heap0.toFixed(1)} → ${heap1.toFixed(1)} → ${heap2.toFixed(1)} MiB`.padEnd(28) +
        `${handles0} → ${handles1}`,
    );
  }
  await plant.close();
  console.log(
    `${'protocol'.padEnd(16)}${'polls'.padEnd(9)}${'polls/s'.padEnd(10)}${'reconnects'.padEnd(12)}${'heap start → polls → reconnects'.padEnd(28)}handles`,
  );
  for (const r of rows) console.log(r);
  process.exitCode = failed ? 1 : 0;
}

main().catch((err) => {
  console.error(err);
  process.exitCode = 1;
});
