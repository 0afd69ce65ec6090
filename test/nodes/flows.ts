/**
 * The node suite every protocol runs: real flows in the test helper against
 * a simulator over real sockets. Messages and link states are awaited with
 * deadlines; nothing sleeps and hopes.
 */
import { expect } from 'chai';
import { ALL_NODES, helper, OurTimers, Recorder, until, type Sim, type SimFactory } from './support';

const TAB = { id: 'tab', type: 'tab', label: 'plcwire' };

function conn(url: string, id = 'conn') {
  return { id, type: 'plcwire-connection', name: 'plc', url };
}

function readNode(extra: Record<string, unknown>) {
  return {
    id: 'read',
    type: 'plcwire-read',
    z: 'tab',
    name: 'poll',
    connection: 'conn',
    interval: 100,
    output: 'object',
    deadband: 0,
    tags: [],
    wires: [['out']],
    ...extra,
  };
}

const out = (id = 'out') => ({ id, type: 'helper', z: 'tab' });
const catcher = (scope: string[] | null = null) => ({
  id: 'catcher',
  type: 'catch',
  z: 'tab',
  scope,
  uncaught: false,
  wires: [['caught']],
});
const watcher = (scope: string[] | null = null) => ({ id: 'watcher', type: 'status', z: 'tab', scope, wires: [['statuses']] });

/** Flow nodes need a position: the runtime takes a node without x/y for a config node. */
function placed(flow: object[]): object[] {
  return flow.map((n: any) => (n.z ? { x: 100, y: 100, ...n } : n));
}

async function load(flow: object[]): Promise<void> {
  await helper.load(ALL_NODES, placed([TAB, ...flow]));
}

const recorder = (id: string) => new Recorder(helper.getNode(id));

export function describeProtocol(title: string, factory: SimFactory): void {
  describe(`nodes over ${title}`, function () {
    this.timeout(20000);
    let sim: Sim;

    beforeEach(async () => {
      sim = await factory();
      for (let i = 0; i < 6; i++) sim.set(i, 0);
      await helper.startServer();
    });

    afterEach(async () => {
      await helper.unload();
      await helper.stopServer();
      await sim.close();
    });

    describe('plcwire-read', () => {
      it('polls in object mode: one message with every tag, quality good', async () => {
        sim.set(0, 11);
        sim.set(1, -22);
        await load([
          conn(sim.url),
          readNode({
            tags: [
              { name: 'speed', address: sim.addr(0) },
              { name: 'level', address: sim.addr(1) },
            ],
          }),
          out(),
        ]);
        const msg = await recorder('out').next((m) => m.payload.speed === 11);
        expect(msg.payload).to.deep.equal({ speed: 11, level: -22 });
        expect(msg.quality).to.deep.equal({ speed: 'good', level: 'good' });
        expect(msg.addresses).to.deep.equal({ speed: sim.addr(0), level: sim.addr(1) });
        expect(msg).not.to.have.property('errors');
        sim.set(0, 12);
        const later = await recorder('out').next((m) => m.payload.speed === 12);
        expect(later.payload.level).to.equal(-22);
      });

      it('polls its table with one address array, so the client keeps its parsed tags and plan for it', async () => {
        await load([
          conn(sim.url),
          readNode({
            tags: [
              { name: 'a', address: sim.addr(0) },
              { name: 'b', address: sim.addr(1) },
              { name: 'a2', address: sim.addr(0) },
            ],
          }),
          out(),
        ]);
        const rec = recorder('out');
        await rec.next(() => true);
        const client = helper.getNode('conn').client;
        const seen = new Set<unknown>();
        // read() when every tag succeeds, readDetailed() for the per-tag outcomes: both get the one array.
        const methods = { read: client.read, readDetailed: client.readDetailed };
        for (const [method, original] of Object.entries(methods)) {
          client[method] = function (addresses: string[], ...rest: unknown[]) {
            seen.add(addresses);
            expect(addresses).to.deep.equal([sim.addr(0), sim.addr(1)]);
            return original.call(this, addresses, ...rest);
          };
        }
        for (let i = 0; i < 3; i++) await rec.next(() => true);
        Object.assign(client, methods);
        expect(seen.size).to.equal(1);
      });

      it('polls in per-tag mode: one message per tag, topic = name', async () => {
        sim.set(0, 5);
        sim.set(1, 6);
        await load([
          conn(sim.url),
          readNode({
            output: 'per-tag',
            tags: [
              { name: 'a', address: sim.addr(0) },
              { name: 'b', address: sim.addr(1) },
            ],
          }),
          out(),
        ]);
        const rec = recorder('out');
        const a = await rec.next((m) => m.topic === 'a');
        const b = await rec.next((m) => m.topic === 'b');
        expect([a.payload, a.quality, a.address]).to.deep.equal([5, 'good', sim.addr(0)]);
        expect([b.payload, b.quality]).to.deep.equal([6, 'good']);
      });

      it('in changes mode sends only tags that moved beyond the deadband', async () => {
        sim.set(0, 100);
        sim.set(1, 200);
        await load([
          conn(sim.url),
          readNode({
            output: 'changes',
            deadband: 5,
            tags: [
              { name: 'a', address: sim.addr(0) },
              { name: 'b', address: sim.addr(1) },
            ],
          }),
          out(),
        ]);
        const rec = recorder('out');
        await rec.next((m) => m.topic === 'a' && m.payload === 100);
        await rec.next((m) => m.topic === 'b' && m.payload === 200);
        // In one step, so any poll sees both: a moves within the deadband, b beyond it.
        sim.set(0, 103);
        sim.set(1, 300);
        const next = await rec.next();
        expect([next.topic, next.payload]).to.deep.equal(['b', 300]);
        sim.set(0, 110);
        const moved = await rec.next();
        expect([moved.topic, moved.payload]).to.deep.equal(['a', 110]);
        expect(rec.messages.filter((m) => m.topic === 'a').map((m) => m.payload)).to.deep.equal([100, 110]);
      });

      it('reads on input, and reads msg.tags on demand, keeping the message', async () => {
        sim.set(2, 77);
        sim.set(3, 88);
        await load([
          conn(sim.url),
          readNode({ interval: 0, tags: [{ name: 'x', address: sim.addr(2) }] }),
          out(),
          watcher(['read']),
          out('statuses'),
        ]);
        await recorder('statuses').next((m) => m.status.text === 'plcwire.status.connected', 4000, 'connected status');
        const rec = recorder('out');
        helper.getNode('read').receive({ _msgid: 'm1', correlation: 42 });
        const first = await rec.next();
        expect(first.payload).to.deep.equal({ x: 77 });
        expect(first.correlation).to.equal(42);
        helper.getNode('read').receive({ tags: { y: sim.addr(3) } });
        const demand = await rec.next();
        expect(demand.payload).to.deep.equal({ y: 88 });
        helper.getNode('read').receive({ tags: [sim.addr(2), sim.addr(3)] });
        const both = await rec.next();
        expect(both.payload).to.deep.equal({ [sim.addr(2)]: 77, [sim.addr(3)]: 88 });
      });

      it('reports a bad tag on msg.errors and to Catch without stopping the others', async () => {
        sim.set(0, 9);
        await load([
          conn(sim.url),
          readNode({
            tags: [
              { name: 'good', address: sim.addr(0) },
              { name: 'typo', address: 'XYZ%' },
              { name: 'gone', address: sim.missing },
            ],
          }),
          out(),
          catcher(['read']),
          out('caught'),
        ]);
        const msg = await recorder('out').next();
        expect(msg.payload).to.deep.equal({ good: 9 });
        expect(msg.quality).to.deep.equal({ good: 'good', typo: 'bad', gone: 'bad' });
        expect(msg.errors.typo.code).to.equal('INVALID_ADDRESS');
        expect(msg.errors.typo.address).to.equal('XYZ%');
        expect(msg.errors.gone.code).to.be.a('string').and.not.equal('INVALID_ADDRESS');
        const caught = await recorder('caught').next();
        expect(caught.error.message).to.include('typo');
        expect(caught.error.source.id).to.equal('read');
        // Reported once, not on every poll: the next polls come without a second Catch message.
        await recorder('out').next(() => true);
        await recorder('out').next(() => true);
        expect(recorder('caught').messages.length).to.be.at.most(1);
      });

      it('sends an input-triggered read with a bad tag to done(err) (Catch) and still outputs the good ones', async () => {
        sim.set(0, 3);
        await load([
          conn(sim.url),
          readNode({
            interval: 0,
            tags: [
              { name: 'ok', address: sim.addr(0) },
              { name: 'bad', address: 'NOPE' },
            ],
          }),
          out(),
          catcher(['read']),
          out('caught'),
        ]);
        await until(() => helper.getNode('read').linkState === 'connected', 4000, 'connected');
        helper.getNode('read').receive({ payload: 'go' });
        const msg = await recorder('out').next();
        expect(msg.payload).to.deep.equal({ ok: 3 });
        const caught = await recorder('caught').next();
        expect(caught.error.message).to.match(/"bad" \(NOPE\)/);
        expect(caught.error.code).to.equal('INVALID_ADDRESS');
      });
    });

    describe('plcwire-write', () => {
      const writer = (extra: Record<string, unknown> = {}) => ({
        id: 'write',
        type: 'plcwire-write',
        z: 'tab',
        name: 'w',
        connection: 'conn',
        tags: [{ name: 'setpoint', address: sim.addr(4) }],
        wires: [['out']],
        ...extra,
      });

      async function connected(): Promise<void> {
        await until(() => helper.getNode('write').linkState === 'connected', 4000, 'write node connected');
      }

      it('writes { name: value } and { address: value }, then sends msg.results once acknowledged', async () => {
        await load([conn(sim.url), writer(), out()]);
        await connected();
        helper.getNode('write').receive({ payload: { setpoint: 1234, [sim.addr(5)]: -5 } });
        const msg = await recorder('out').next();
        expect(msg.results).to.deep.equal({
          setpoint: { ok: true, address: sim.addr(4) },
          [sim.addr(5)]: { ok: true, address: sim.addr(5) },
        });
        expect(sim.get(4)).to.equal(1234);
        expect(sim.get(5)).to.equal(-5);
      });

      it('writes msg.topic = name with a scalar payload', async () => {
        await load([conn(sim.url), writer(), out()]);
        await connected();
        helper.getNode('write').receive({ topic: 'setpoint', payload: 321 });
        const msg = await recorder('out').next();
        expect(msg.results.setpoint.ok).to.equal(true);
        expect(sim.get(4)).to.equal(321);
      });

      it('sends bad values and addresses to Catch, naming the tag, and writes nothing for them', async () => {
        await load([conn(sim.url), writer(), out(), catcher(['write']), out('caught')]);
        await connected();
        sim.set(4, 7);
        helper.getNode('write').receive({ payload: { setpoint: 'not a number' } });
        const caught = await recorder('caught').next();
        expect(caught.error.message).to.include('"setpoint"');
        expect(caught.error.code).to.equal('INVALID_VALUE');
        expect(sim.get(4)).to.equal(7);
        helper.getNode('write').receive({ payload: { 'NO SUCH': 1 } });
        const second = await recorder('caught').next();
        expect(second.error.message).to.include('NO SUCH');
        helper.getNode('write').receive({ payload: 5 });
        const third = await recorder('caught').next();
        expect(third.error.code).to.equal('INVALID_VALUE');
        expect(recorder('out').messages).to.deep.equal([]);
      });
    });

    describe('plcwire-heartbeat', () => {
      it('reports alive, lost when the PLC stops, restored when it comes back', async () => {
        await load([
          conn(sim.url),
          // The PLC's life sign is our own counter read back: it keeps changing exactly while the link works.
          {
            id: 'hb',
            type: 'plcwire-heartbeat',
            z: 'tab',
            name: 'hb',
            connection: 'conn',
            writeAddress: sim.addr(5),
            writeMode: 'counter',
            interval: 100,
            watchAddress: sim.addr(5),
            timeout: 600,
            wires: [['out']],
          },
          out(),
        ]);
        const rec = recorder('out');
        const alive = await rec.next((m) => m.payload.event === 'alive', 5000, 'alive');
        expect(alive.payload.state).to.equal('alive');
        await until(() => sim.get(5) >= 3, 4000, 'counter written');
        await sim.stop();
        const lost = await rec.next((m) => m.payload.event === 'lost', 5000, 'lost');
        expect(lost.payload.losses).to.equal(1);
        expect(lost.payload.age).to.be.greaterThan(600);
        await sim.restart();
        const restored = await rec.next((m) => m.payload.event === 'restored', 8000, 'restored');
        expect(restored.payload.changes).to.be.greaterThan(alive.payload.changes);
        expect(restored.payload.age).to.be.lessThan(600);
      });

      it('toggles a life sign and shows it on its status', async () => {
        await load([
          conn(sim.url),
          {
            id: 'hb',
            type: 'plcwire-heartbeat',
            z: 'tab',
            name: 'hb',
            connection: 'conn',
            writeAddress: sim.addr(3),
            writeMode: 'toggle',
            interval: 100,
            watchAddress: '',
            timeout: 1000,
            wires: [['out']],
          },
          watcher(['hb']),
          out('statuses'),
        ]);
        const seen = new Set<number>();
        await until(() => (seen.add(sim.get(3)), seen.has(0) && seen.has(1)), 4000, 'toggled 0 → 1 → 0');
        await recorder('statuses').next((m) => m.status.text === 'plcwire.status.sent', 4000, 'sent status');
      });
    });

    describe('connection', () => {
      it('Status nodes see connecting then connected; Catch sees connection errors from a PLC that is off', async () => {
        await sim.stop();
        await load([
          conn(sim.url),
          readNode({ tags: [{ name: 'a', address: sim.addr(0) }] }),
          out(),
          catcher(['read']),
          out('caught'),
          watcher(['read']),
          out('statuses'),
        ]);
        const caught = await recorder('caught').next(() => true, 4000, 'connection error');
        expect(caught.error.source.type).to.equal('plcwire-connection');
        expect(caught.error.code).to.be.oneOf(['CONNECT_FAILED', 'TIMEOUT', 'CONNECTION_LOST']);
        const statuses = recorder('statuses');
        await statuses.next((m) => m.status.text === 'plcwire.status.retryIn' && m.status.fill === 'red', 4000, 'retry status');
        await sim.restart();
        await statuses.next((m) => m.status.text === 'plcwire.status.connected' && m.status.fill === 'green', 8000, 'connected status');
        await recorder('out').next(() => true, 4000, 'a poll after the PLC came back');
      });

      it('shares one connection between nodes and config nodes of the same endpoint', async () => {
        await load([
          conn(sim.url, 'conn'),
          conn(sim.url.replace('timeout=1000', 'timeout=2000'), 'conn2'),
          readNode({ tags: [{ name: 'a', address: sim.addr(0) }] }),
          { id: 'write', type: 'plcwire-write', z: 'tab', connection: 'conn2', tags: [], wires: [[]] },
          {
            id: 'hb',
            type: 'plcwire-heartbeat',
            z: 'tab',
            connection: 'conn2',
            writeAddress: sim.addr(5),
            writeMode: 'counter',
            interval: 100,
            watchAddress: '',
            timeout: 1000,
            wires: [[]],
          },
          out(),
        ]);
        await recorder('out').next();
        await until(() => sim.get(5) > 1, 4000, 'heartbeat wrote');
        expect(sim.connectionCount()).to.equal(1);
      });

      it('leaves exactly one connection after partial and full redeploys, ×10', async () => {
        const flow = (n: number) => [
          TAB,
          conn(sim.url),
          readNode({ name: `poll ${n}`, tags: [{ name: 'a', address: sim.addr(0) }] }),
          { id: 'write', type: 'plcwire-write', z: 'tab', name: `w ${n % 2}`, connection: 'conn', tags: [], wires: [[]] },
          out(),
        ];
        await load(flow(0).slice(1));
        await recorder('out').next();
        for (let n = 1; n <= 10; n++) {
          await helper.setFlows(placed(flow(n)), n % 3 === 0 ? 'full' : n % 3 === 1 ? 'nodes' : 'flows');
          const rec = recorder('out');
          await rec.next(() => true, 4000, `a poll after redeploy ${n}`);
          await until(() => sim.connectionCount() === 1, 3000, `one connection after redeploy ${n} (have ${sim.connectionCount()})`);
        }
        // And exactly one poller: polls arrive at the configured pace, not twice as fast.
        const rec = recorder('out');
        rec.skip();
        const t0 = Date.now();
        for (let i = 0; i < 5; i++) await rec.next();
        expect(Date.now() - t0).to.be.at.least(5 * 100 - 60);
        expect(sim.connectionCount()).to.equal(1);
      });

      it('closes within 2 s, mid-poll and while reconnecting, leaving no timers and no connection', async () => {
        const ours = new OurTimers().start();
        try {
          await load([
            conn(sim.url),
            readNode({ interval: 10, tags: [{ name: 'a', address: sim.addr(0) }] }),
            {
              id: 'hb',
              type: 'plcwire-heartbeat',
              z: 'tab',
              connection: 'conn',
              writeAddress: sim.addr(5),
              writeMode: 'counter',
              interval: 100,
              watchAddress: sim.addr(5),
              timeout: 500,
              wires: [[]],
            },
            out(),
          ]);
          await recorder('out').next();
          expect(ours.count, 'timers while running').to.be.greaterThan(0);
          const t0 = Date.now();
          await helper.unload();
          expect(Date.now() - t0).to.be.lessThan(2000);
          await until(() => sim.connectionCount() === 0, 2000, 'the PLC saw the connection close');
          await until(() => ours.count === 0, 2000, `no timers left: ${ours.describe()}`);

          await sim.stop();
          await load([conn(sim.url), readNode({ tags: [{ name: 'a', address: sim.addr(0) }] }), watcher(['read']), out('statuses')]);
          await recorder('statuses').next((m) => m.status.text === 'plcwire.status.retryIn', 4000, 'reconnecting');
          const t1 = Date.now();
          await helper.unload();
          expect(Date.now() - t1).to.be.lessThan(2000);
          await until(() => ours.count === 0, 2000, `no timers left while reconnecting: ${ours.describe()}`);
          await sim.restart();
        } finally {
          ours.stop();
        }
      });
    });
  });
}
