/**
 * The read node's mode "when the PLC reports a change" on s7:// to an
 * S7-300 (issue #33): the CPU's cyclic data (userdata group 2) in the real
 * Node-RED runtime: every tag first, then each change another client writes,
 * with no poll; subscribed again after the link was reset.
 */
import { expect } from 'chai';
import { createClient } from '../../lib/connect';
import type { S7Client } from '../../lib/s7/client';
import { S7Server, type S7RequestEvent } from '../../lib/s7/server';
import { ALL_NODES, helper, Recorder } from './support';

const at = { z: 'tab', x: 100, y: 100 };

function flow(url: string) {
  return [
    { id: 'tab', type: 'tab', label: 'plcwire' },
    { id: 'c1', type: 'plcwire-connection', name: 'press', url },
    {
      id: 'r1',
      type: 'plcwire-read',
      ...at,
      connection: 'c1',
      mode: 'push',
      cycle: 100,
      interval: 60000,
      output: 'object',
      tags: [
        { name: 'count', address: 'DB1.DBW4:INT' },
        { name: 'level', address: 'DB1.DBD8:REAL' },
        { name: 'run', address: 'M0.1' },
      ],
      wires: [['out']],
    },
    { id: 'out', type: 'helper', ...at },
    { id: 'catcher', type: 'catch', ...at, scope: ['r1'], uncaught: false, wires: [['caught']] },
    { id: 'caught', type: 'helper', ...at },
  ];
}

describe('nodes: the read node when the PLC reports a change (s7:// to an S7-300, cyclic data)', function () {
  this.timeout(30000);
  let server: S7Server;
  let url: string;
  let writer: S7Client;

  beforeEach(async () => {
    server = new S7Server({ port: 0, profile: 's7-300', layout: { dataBlocks: { 1: 64 }, flags: 16 } });
    await server.listen();
    url = `s7://127.0.0.1:${server.port}?rack=0&slot=2&timeout=3000`;
    await helper.startServer();
    writer = createClient(url) as S7Client;
    await writer.connect();
  });
  afterEach(async () => {
    await writer?.close();
    await helper.unload();
    await helper.stopServer();
    await server?.close();
  });

  it('sends every tag first, then each change another client writes; the node polls nothing', async () => {
    await writer.write({ 'DB1.DBW4:INT': 7, 'DB1.DBD8:REAL': 1.5 });
    const reads: S7RequestEvent[] = [];
    server.on('request', (r: S7RequestEvent) => r.kind === 'read' && reads.push(r));
    await helper.load(ALL_NODES, flow(url));
    const out = new Recorder(helper.getNode('out'));
    const count = await out.next((m) => m.topic === 'count', 10000, 'the first value of count');
    expect(count).to.include({ payload: 7, quality: 'good', address: 'DB1.DBW4:INT' });
    await out.next((m) => m.topic === 'level' && m.payload === 1.5, 5000, 'the first value of level');
    await writer.write({ 'DB1.DBW4:INT': 8 });
    const next = await out.next((m) => m.topic === 'count', 5000, 'the change of count');
    expect(next.payload).to.equal(8);
    // Only the writer's own write ran as a job: the node read nothing by Read Var.
    expect(reads).to.have.length(0);
    expect(new Recorder(helper.getNode('caught')).messages).to.have.length(0);
  });

  it('is subscribed again after the link was reset', async () => {
    await helper.load(ALL_NODES, flow(url));
    const out = new Recorder(helper.getNode('out'));
    await out.next((m) => m.topic === 'count', 10000, 'the first value of count');
    server.dropConnections();
    server.memory.writeBit('M', 0, 0, 1, true);
    const run = await out.next((m) => m.topic === 'run' && m.payload === true, 15000, 'the change of run after the reset');
    expect(run.quality).to.equal('good');
  });

  it('on s7:// to an S7-1500 (no cyclic data) it says so to Catch and Status (NOT_SUPPORTED, naming s7plus://) and sends nothing', async () => {
    const s1500 = new S7Server({ port: 0, profile: 's7-1500', layout: { dataBlocks: { 1: 64 }, flags: 16 } });
    await s1500.listen();
    try {
      await helper.load(ALL_NODES, [
        ...flow(`s7://127.0.0.1:${s1500.port}?rack=0&slot=1&timeout=3000`),
        { id: 'watcher', type: 'status', ...at, scope: ['r1'], wires: [['statuses']] },
        { id: 'statuses', type: 'helper', ...at },
      ]);
      const caught = new Recorder(helper.getNode('caught'));
      const statuses = new Recorder(helper.getNode('statuses'));
      const err = await caught.next(() => true, 10000, 'the error');
      expect(err.error.message).to.include('does not offer cyclic data (0x8104)');
      expect(err.error.message).to.include('s7plus://');
      expect(err.error.source.id).to.equal('r1');
      await statuses.next((m) => m.status.text === 'plcwire-read.status.noPush', 5000, 'the status');
      expect(new Recorder(helper.getNode('out')).messages).to.have.length(0);
    } finally {
      await helper.unload();
      await s1500.close();
    }
  });
});
