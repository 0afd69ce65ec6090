/**
 * The read node's mode "when the PLC reports a change" (issue #25), in the
 * real Node-RED runtime against the S7-1500 simulator over S7CommPlus: every
 * tag first, then each change written by another client as the polled
 * mode's change messages; subscribed again after the link was reset; a
 * redeploy leaves no connection. (s7:// to an S7-1500, which refuses cyclic
 * data, is in read-push-s7.test.ts.)
 */
import { expect } from 'chai';
import { createClient } from '../../lib/connect';
import type { S7PlusClient } from '../../lib/s7plus/client';
import { S7Server } from '../../lib/s7/server';
import { S7PlusService } from '../../lib/s7plus/server';
import { generateCertificate } from '../../lib/s7plus/transport/cert';
import { DB_NUMBERS, SOURCES } from '../fixtures/s7plus';
import { ALL_NODES, helper, Recorder, until } from './support';

const at = { z: 'tab', x: 100, y: 100 };

function flow(url: string, mode = 'push') {
  return [
    { id: 'tab', type: 'tab', label: 'plcwire' },
    { id: 'c1', type: 'plcwire-connection', name: 'press', url },
    {
      id: 'r1',
      type: 'plcwire-read',
      ...at,
      connection: 'c1',
      mode,
      cycle: 20,
      interval: 60000,
      output: 'object',
      tags: [
        { name: 'step', address: '"Recipe".Step' },
        { name: 'inlet', address: '"Recipe".Inlet' },
        { name: 'count', address: 'DB1.DBW4:INT' },
        { name: 'target', address: '"Recipe".Target' },
      ],
      wires: [['out']],
    },
    { id: 'out', type: 'helper', ...at },
    { id: 'catcher', type: 'catch', ...at, scope: ['r1'], uncaught: false, wires: [['caught']] },
    { id: 'caught', type: 'helper', ...at },
    { id: 'watcher', type: 'status', ...at, scope: ['r1'], wires: [['statuses']] },
    { id: 'statuses', type: 'helper', ...at },
  ];
}

describe('nodes: the read node when the PLC reports a change (s7plus://)', function () {
  this.timeout(30000);
  let server: S7Server;
  let service: S7PlusService;
  let url: string;
  let writer: S7PlusClient;

  before(async () => {
    const cert = await generateCertificate();
    service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await server.listen();
    url = `s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=3000`;
  });
  after(async () => {
    await server?.close();
  });
  beforeEach(async () => {
    await helper.startServer();
    writer = createClient(url) as S7PlusClient;
    await writer.connect();
  });
  afterEach(async () => {
    await writer?.close();
    await helper.unload();
    await helper.stopServer();
  });

  it('sends every tag first, then each change another client writes, as change messages; no poll runs', async () => {
    await writer.write({ '"Recipe".Step': 4, '"Tank".Count': 7 });
    await helper.load(ALL_NODES, flow(url));
    const out = new Recorder(helper.getNode('out'));
    const first = await out.next((m) => m.topic === 'step', 10000, 'the first value of step');
    expect(first).to.include({ topic: 'step', address: '"Recipe".Step', payload: 4, quality: 'good' });
    await until(
      () => ['inlet', 'count'].every((t) => out.messages.some((m) => m.topic === t)),
      5000,
      'the first values of inlet and count',
    );
    expect(out.messages.find((m) => m.topic === 'count')).to.include({ payload: 7, quality: 'good', address: 'DB1.DBW4:INT' });
    const started = Date.now();
    await writer.write({ '"Recipe".Step': 5, '"Recipe".Inlet': { Open: true, Position: 3 } });
    const step = await out.next((m) => m.topic === 'step', 5000, 'the change of step');
    expect(step.payload).to.equal(5);
    expect(Date.now() - started).to.be.below(1000);
    const inlet = await out.next((m) => m.topic === 'inlet', 5000, 'the change of inlet');
    expect(inlet.payload).to.deep.equal({ Open: true, Position: 3 });
    // Only what changed: count sent no second message.
    expect(out.messages.filter((m) => m.topic === 'count')).to.have.length(1);
  });

  it('a REAL the PLC reports has the digits TIA shows, as a polled message has (one rule on every path)', async () => {
    await writer.write({ '"Recipe".Target': 40.4 });
    await helper.load(ALL_NODES, flow(url));
    const out = new Recorder(helper.getNode('out'));
    const first = await out.next((m) => m.topic === 'target', 10000, 'the first value of target');
    expect(first.payload).to.equal(40.4);
    await writer.write({ '"Recipe".Target': 75.9 });
    const change = await out.next((m) => m.topic === 'target', 5000, 'the change of target');
    expect(change.payload).to.equal(75.9);
  });

  it('a flow without a sample time (from before the push mode, or the example switched to push) subscribes and reports changes', async () => {
    const bare = flow(url).map((n) => (n.id === 'r1' ? { ...n, cycle: undefined } : n));
    await writer.write({ '"Recipe".Step': 2 });
    await helper.load(ALL_NODES, bare);
    const out = new Recorder(helper.getNode('out'));
    expect((await out.next((m) => m.topic === 'step', 10000, 'the first value of step')).payload).to.equal(2);
    await writer.write({ '"Recipe".Step': 3 });
    expect((await out.next((m) => m.topic === 'step', 5000, 'the change of step')).payload).to.equal(3);
  });

  it('is subscribed again after the link was reset, and a redeploy leaves no connection', async () => {
    await writer.write({ '"Recipe".Step': 1 });
    await helper.load(ALL_NODES, flow(url));
    const out = new Recorder(helper.getNode('out'));
    const statuses = new Recorder(helper.getNode('statuses'));
    await out.next((m) => m.topic === 'step' && m.payload === 1, 10000, 'the first value');
    const conn = helper.getNode('c1');
    server.dropConnections();
    await statuses.next((m) => m.status.text !== 'plcwire.status.connected', 5000, 'a status of the lost link');
    await until(() => conn.linkStatus.state === 'connected', 10000, 'reconnected');
    await until(() => writer.state === 'connected', 10000, 'the writer reconnected');
    // Wait until the subscription is back, then change the value: its message must come.
    for (let v = 2; ; v++) {
      await writer.write({ '"Recipe".Step': v }).catch(() => undefined);
      const m = await out.next((x) => x.topic === 'step' && x.payload === v, 1000, 'the change after the reconnect').catch(() => undefined);
      if (m) break;
      if (v > 20) throw new Error('no change message after the reconnect');
    }
    await helper.unload();
    await writer.close();
    await until(() => server.connectionCount === 0, 5000, `no connection left (have ${server.connectionCount})`);
  });
});
