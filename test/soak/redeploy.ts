/**
 * `npm run soak:redeploy`: 100 Node-RED redeploys (full, nodes and flows
 * deploys in turn) of a flow with read, write and heartbeat nodes against the
 * S7 simulator, in the test helper. Afterwards the simulator must see exactly
 * one connection, the read node must poll at its own pace (one poller), and
 * no "Close timed out" may be logged. Prints the figures; exit code 1 on failure.
 *
 *   npm run soak:redeploy -- [redeploys]
 */
import { S7Server, type S7RequestEvent } from '../../lib/s7/server';
import { PlcMemory } from '../../lib/sim/memory';
import { ALL_NODES, helper, Recorder, until } from '../nodes/support';

const REDEPLOYS = Number(process.argv[2] ?? 100);
const INTERVAL = 100;
const TYPES = ['full', 'nodes', 'flows'] as const;

function flow(url: string, n: number): object[] {
  const at = { x: 100, y: 100 };
  return [
    { id: 'tab', type: 'tab', label: 'soak' },
    { id: 'conn', type: 'plcwire-connection', name: 'plc', url },
    // The name changes every time so a 'nodes' deploy restarts the read node.
    {
      id: 'read',
      type: 'plcwire-read',
      z: 'tab',
      name: `poll ${n}`,
      connection: 'conn',
      interval: INTERVAL,
      output: 'object',
      deadband: 0,
      tags: [{ name: 'a', address: 'DB1.DBW0:INT' }],
      wires: [['out']],
      ...at,
    },
    { id: 'write', type: 'plcwire-write', z: 'tab', name: `w ${n % 2}`, connection: 'conn', tags: [], wires: [[]], ...at },
    {
      id: 'hb',
      type: 'plcwire-heartbeat',
      z: 'tab',
      name: 'hb',
      connection: 'conn',
      writeAddress: 'DB1.DBW10:INT',
      writeMode: 'counter',
      interval: 200,
      watchAddress: '',
      timeout: 1000,
      wires: [[]],
      ...at,
    },
    { id: 'out', type: 'helper', z: 'tab', ...at },
  ];
}

async function main(): Promise<void> {
  const memory = new PlcMemory();
  const server = new S7Server({ port: 0, memory, profile: 's7-1500' });
  const port = await server.listen();
  const url = `s7://127.0.0.1:${port}?timeout=1000`;
  let reads = 0;
  server.on('request', (r: S7RequestEvent) => void (r.kind === 'read' && reads++));
  let connections = 0;
  server.on('connection', () => connections++);

  const logged: string[] = [];
  const started = Date.now();
  await helper.startServer();
  await helper.load(ALL_NODES, flow(url, 0));
  // The helper spies on the runtime log from load() on; every entry is kept.
  const spy = helper.log();
  let out = new Recorder(helper.getNode('out'));
  await out.next(() => true, 5000, 'a first poll');
  const slowest = { ms: 0, n: 0 };
  for (let n = 1; n <= REDEPLOYS; n++) {
    const type = TYPES[n % TYPES.length]!;
    const t0 = Date.now();
    await helper.setFlows(flow(url, n), type);
    out = new Recorder(helper.getNode('out'));
    memory.area('DB', 1)!.writeInt16BE(n, 0);
    await out.next((m) => m.payload.a === n, 5000, `a poll after redeploy ${n} (${type})`);
    const ms = Date.now() - t0;
    if (ms > slowest.ms) Object.assign(slowest, { ms, n });
  }
  const redeployMs = Date.now() - started;

  // In the helper RED._ is the identity: a close timeout is logged as the key "nodes.flows.stopping-error".
  // Let closes settle, then measure: one connection, and polls at the configured pace.
  await until(() => server.connectionCount === 1, 3000, 'one connection').catch(() => undefined);
  const connected = server.connectionCount;
  out.skip();
  const readsBefore = reads;
  const windowMs = 2000;
  await new Promise((r) => setTimeout(r, windowMs));
  const polls = out.messages.length - (out as unknown as { cursor: number }).cursor;
  const readsPerInterval = ((reads - readsBefore) / windowMs) * INTERVAL;
  const pollsPerInterval = (polls / windowMs) * INTERVAL;

  for (const call of spy.getCalls()) {
    const entry = call.args[0];
    logged.push(typeof entry?.msg === 'string' ? entry.msg : JSON.stringify(entry?.msg ?? entry));
  }
  const closeTimeouts = logged.filter((m) => /close timed out|stopping-error/i.test(m));
  const closeStarted = Date.now();
  await helper.unload();
  const closeMs = Date.now() - closeStarted;
  await helper.stopServer();
  await until(() => server.connectionCount === 0, 3000, 'no connection after unload').catch(() => undefined);
  const afterUnload = server.connectionCount;
  await server.close();

  // The read node polls once per interval; the heartbeat (no watch address) only writes.
  const failures: string[] = [];
  if (connected !== 1) failures.push(`${connected} connections at the simulator after the redeploys (want 1)`);
  if (pollsPerInterval > 1.2) failures.push(`${pollsPerInterval.toFixed(2)} poll messages per interval (a second poller?)`);
  if (pollsPerInterval < 0.5) failures.push(`${pollsPerInterval.toFixed(2)} poll messages per interval (polling stalled?)`);
  if (readsPerInterval > 1.2) failures.push(`${readsPerInterval.toFixed(2)} read jobs per interval at the simulator (a second poller?)`);
  if (closeTimeouts.length > 0) failures.push(`"Close timed out" logged ${closeTimeouts.length} times`);
  if (afterUnload !== 0) failures.push(`${afterUnload} connections left after the flows stopped`);
  if (closeMs > 2000) failures.push(`closing took ${closeMs} ms`);

  console.log(
    `redeploys:               ${REDEPLOYS} (${TYPES.join('/')} in turn) in ${(redeployMs / 1000).toFixed(1)} s, slowest ${slowest.ms} ms (#${slowest.n})`,
  );
  console.log(`connections opened:      ${connections} over the run`);
  console.log(`connections afterwards:  ${connected} (want 1); after unload ${afterUnload} (want 0), unload took ${closeMs} ms`);
  console.log(
    `pollers:                 ${pollsPerInterval.toFixed(2)} poll messages and ${readsPerInterval.toFixed(2)} read jobs per ${INTERVAL} ms interval (want ≈1)`,
  );
  console.log(`"Close timed out":       ${closeTimeouts.length}`);
  console.log(`log entries:             ${logged.length}`);
  if (failures.length > 0) {
    console.error(`FAILED:\n  ${failures.join('\n  ')}`);
    process.exitCode = 1;
  } else {
    console.log('OK');
  }
}

main().then(
  () => setTimeout(() => process.exit(), 100).unref(),
  (err) => {
    console.error(err);
    process.exit(1);
  },
);
