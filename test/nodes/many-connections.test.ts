/**
 * One Node-RED runtime with 100 connection nodes and 100 read nodes, each on
 * its own simulated PLC: every PLC serves exactly one connection after the
 * deploy and after full redeploys, and none after the flows are unloaded.
 * (How fast it deploys is measured in bench/nodered.js, not here.)
 */
import { expect } from 'chai';
import { S7Server } from '../../lib/s7/server';
import { PlcMemory } from '../../lib/sim/memory';
import { ALL_NODES, helper, until } from './support';

const PLCS = 100;

describe('nodes: 100 connections in one runtime', function () {
  this.timeout(30000);
  const servers: S7Server[] = [];
  const ports: number[] = [];
  const seen = new Set<string>();

  before(async () => {
    for (let i = 0; i < PLCS; i++) {
      const memory = new PlcMemory();
      memory.area('DB', 1)!.writeInt16BE(i, 0);
      const server = new S7Server({ port: 0, memory, profile: 's7-1500' });
      ports.push(await server.listen());
      servers.push(server);
    }
  });

  after(async () => {
    await Promise.all(servers.map((s) => s.close()));
  });

  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
  });

  function flow(n: number): object[] {
    const at = { x: 100, y: 100 };
    const nodes: object[] = [
      { id: 'tab', type: 'tab', label: 'many' },
      { id: 'out', type: 'helper', z: 'tab', ...at },
    ];
    ports.forEach((port, i) => {
      nodes.push({ id: `conn${i}`, type: 'plcwire-connection', name: `plc${i}`, url: `s7://127.0.0.1:${port}?rack=0&slot=1&timeout=2000` });
      nodes.push({
        id: `read${i}`,
        type: 'plcwire-read',
        z: 'tab',
        name: `plc${i} ${n}`,
        connection: `conn${i}`,
        interval: 200,
        output: 'object',
        deadband: 0,
        tags: [{ name: 'id', address: 'DB1.DBW0:INT' }],
        wires: [['out']],
        ...at,
      });
    });
    return nodes;
  }

  /** Waits until every read node sent a value (each its own PLC's), then until every PLC has exactly one connection. */
  async function everyPlcOnce(n: number, what: string): Promise<void> {
    seen.clear();
    helper.getNode('out').on('input', (msg: any) => seen.add(`${msg.topic}=${msg.payload.id}`));
    await until(() => seen.size >= PLCS, 15000, `${what}: every read node polled (${seen.size} of ${PLCS})`);
    for (let i = 0; i < PLCS; i++) expect(seen.has(`plc${i} ${n}=${i}`), `plc${i} ${n} read its own PLC`).to.equal(true);
    await until(
      () => servers.every((s) => s.connectionCount === 1),
      5000,
      `${what}: one connection per PLC (${servers.map((s) => s.connectionCount).join(',')})`,
    );
  }

  it('keeps exactly one connection per PLC through the deploy and full redeploys, and none after unloading', async () => {
    await helper.startServer();
    await helper.load(ALL_NODES, flow(0));
    await everyPlcOnce(0, 'deploy');
    for (const n of [1, 2]) {
      await helper.setFlows(flow(n), 'full');
      await everyPlcOnce(n, `full redeploy ${n}`);
    }
    expect(servers.reduce((a, s) => a + s.connectionCount, 0)).to.equal(PLCS);
    await helper.unload();
    await until(() => servers.every((s) => s.connectionCount === 0), 5000, 'no connection left after unloading');
  });
});
