/**
 * plcwire-control in real flows of the test helper against the S7 simulator
 * (an S7-300 profile: it serves every system service, block functions
 * included) over real sockets: each action, the refusals of a connection
 * without control=true, only-new diagnostics, and other protocols.
 */
import { expect } from 'chai';
import { loadCatalogs, withCatalog } from './catalogs';
import { fetchWriteSim } from './sims';
import { ALL_NODES, helper, nodes, Recorder, until } from './support';
import { DiagnosticsCursor, actionOf } from '../../lib/flows/control';

const lib = require('../../lib/index');

const ISO = /^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z$/;

describe('nodes: plcwire-control', function () {
  this.timeout(20000);
  let server: any;
  let port: number;
  let requests: { kind: string }[];
  /** Our nodes, the control node with the real en-US catalog (its own error texts are the catalog's). */
  let modules: unknown[];

  before(async () => {
    const catalogs = await loadCatalogs();
    modules = ALL_NODES.map((m) => (m === nodes.control ? withCatalog(nodes.control, catalogs.translator('en-US', 'plcwire-control')) : m));
  });

  beforeEach(async () => {
    server = new lib.S7Server({ port: 0, memory: new lib.PlcMemory(), profile: 's7-300' });
    port = await server.listen();
    requests = [];
    server.on('request', (r: { kind: string }) => requests.push(r));
    await helper.startServer();
  });

  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
    await server.close();
  });

  const url = (extra = '') => `s7://127.0.0.1:${port}?rack=0&slot=2&timeout=1000${extra}`;

  /** A flow with the control node `ctl` → `out`, a Catch for it → `caught`; resolves once the node is connected. */
  async function load(
    connectionUrl: string,
    control: Record<string, unknown> = {},
  ): Promise<{ out: Recorder; caught: Recorder; node: any }> {
    const at = { z: 'tab', x: 100, y: 100 };
    await helper.load(modules, [
      { id: 'tab', type: 'tab', label: 'control' },
      { id: 'conn', type: 'plcwire-connection', name: 'plc', url: connectionUrl },
      {
        id: 'ctl',
        type: 'plcwire-control',
        ...at,
        name: '',
        connection: 'conn',
        action: 'info',
        newOnly: false,
        wires: [['out']],
        ...control,
      },
      { id: 'out', type: 'helper', ...at },
      { id: 'catcher', type: 'catch', ...at, scope: ['ctl'], uncaught: false, wires: [['caught']] },
      { id: 'caught', type: 'helper', ...at },
    ]);
    const node = helper.getNode('ctl');
    const out = new Recorder(helper.getNode('out'));
    const caught = new Recorder(helper.getNode('caught'));
    if (!connectionUrl.startsWith('fetchwrite')) await until(() => node.linkState === 'connected', 4000, 'control node connected');
    return { out, caught, node };
  }

  it('info: the CPU identity, its mode and clock (as an ISO string), with msg.topic = info', async () => {
    const { out, node } = await load(url());
    node.receive({ payload: 'go', keep: 7 });
    const msg = await out.next();
    expect(msg.topic).to.equal('info');
    expect(msg.keep).to.equal(7);
    expect(msg.payload).to.include({
      orderCode: server.cpu.identity.orderCode,
      firmware: server.cpu.identity.firmware,
      state: 'RUN',
      pduSize: 240,
    });
    expect(msg.payload.clock).to.match(ISO);
    expect(Math.abs(Date.parse(msg.payload.clock) - server.cpu.now().getTime())).to.be.lessThan(2000);
    expect(msg.payload.protection).to.include({ level: 1 });
  });

  it('state follows stop and start (msg.topic overrides the configured action) on a connection with control=true', async () => {
    const { out, node } = await load(url('&control=true'), { action: 'state' });
    node.receive({});
    expect((await out.next()).payload).to.include({ state: 'run', mode: 'RUN' });
    node.receive({ topic: 'stop' });
    const stopped = await out.next();
    expect([stopped.topic, stopped.payload]).to.deep.equal(['stop', { state: 'stop' }]);
    expect(server.state).to.equal('STOP');
    node.receive({ topic: 'not an action' });
    const state = await out.next();
    expect([state.topic, state.payload.state, state.payload.eventId]).to.deep.equal(['state', 'stop', 0x4304]);
    expect(state.payload.time).to.match(ISO);
    node.receive({ action: 'start' });
    const started = await out.next();
    expect([started.topic, started.payload]).to.deep.equal(['start', { state: 'run' }]);
    expect(server.state).to.equal('RUN');
  });

  for (const action of ['stop', 'start', 'clock-sync']) {
    it(`${action} on a connection without control=true goes to Catch as WRITE_NOT_ALLOWED and sends nothing to the PLC`, async () => {
      const offset = 3_600_000;
      server.clockOffset = offset;
      if (action === 'start') server.stop();
      const mode = server.state;
      const { out, caught, node } = await load(url(), { action });
      requests.length = 0;
      node.receive({ payload: 1 });
      const msg = await caught.next();
      expect(msg.error.code).to.equal('WRITE_NOT_ALLOWED');
      expect(msg.error.message).to.include('control=true');
      expect(msg.error.source.id).to.equal('ctl');
      expect(msg.topic).to.equal(action);
      expect(requests, 'requests the PLC saw').to.deep.equal([]);
      expect(server.state).to.equal(mode);
      expect(server.clockOffset).to.equal(offset);
      expect(out.messages).to.deep.equal([]);
    });
  }

  it('diagnostics: the buffer newest first; with newOnly, after a stop only the entry it logged, then none', async () => {
    const { out, node } = await load(url(), { action: 'diagnostics', newOnly: true });
    node.receive({});
    const all = (await out.next()).payload;
    expect(all.length).to.equal(server.diagnostics.length).and.to.be.greaterThan(0);
    expect(all[0]).to.include({ eventId: server.diagnostics[0].eventId, description: server.diagnostics[0].description });
    for (const e of all) expect(Object.keys(e)).to.include.members(['time', 'eventId', 'description', 'priority', 'ob']);
    expect(all[0].time).to.match(ISO);

    server.stop();
    node.receive({});
    const fresh = await out.next();
    expect(fresh.topic).to.equal('diagnostics');
    expect(fresh.payload.map((e: any) => e.eventId)).to.deep.equal([0x4304]);
    expect(fresh.payload[0].description).to.match(/STOP/);

    node.receive({});
    expect((await out.next()).payload).to.deep.equal([]);
    server.start();
    node.receive({});
    expect((await out.next()).payload.map((e: any) => e.eventId)).to.deep.equal([0x4302, 0x4301, 0x1381]);
  });

  it('diagnostics without newOnly: every entry on every call', async () => {
    const { out, node } = await load(url(), { action: 'diagnostics' });
    node.receive({});
    const first = (await out.next()).payload;
    node.receive({});
    expect((await out.next()).payload).to.deep.equal(first);
  });

  it('clock reads the PLC clock; clock-sync sets it to the host clock', async () => {
    server.clockOffset = -3 * 86_400_000;
    const { out, node } = await load(url('&control=true'), { action: 'clock' });
    node.receive({});
    const read = await out.next();
    expect(read.topic).to.equal('clock');
    expect(read.payload).to.match(ISO);
    expect(Math.abs(Date.parse(read.payload) - (Date.now() - 3 * 86_400_000))).to.be.lessThan(2000);
    const before = Date.now();
    node.receive({ topic: 'clock-sync' });
    const synced = await out.next();
    expect(synced.topic).to.equal('clock-sync');
    expect(synced.payload.set).to.match(ISO);
    expect(Date.parse(synced.payload.set)).to.be.within(before, Date.now());
    expect(Math.abs(server.clockOffset)).to.be.lessThan(1000);
  });

  it('blocks: the block counts of the CPU per type', async () => {
    const { out, node } = await load(url(), { action: 'blocks' });
    node.receive({});
    const msg = await out.next();
    expect(msg.topic).to.equal('blocks');
    expect(msg.payload.OB).to.equal(server.cpu.blockNumbers('OB').length);
    expect(msg.payload.DB).to.equal(server.cpu.blockNumbers('DB').length).and.to.be.greaterThan(0);
  });

  it('an unknown msg.action goes to Catch as INVALID_VALUE and runs nothing', async () => {
    const { out, caught, node } = await load(url('&control=true'), { action: 'state' });
    requests.length = 0;
    node.receive({ action: 'reboot' });
    const msg = await caught.next();
    expect(msg.error.code).to.equal('INVALID_VALUE');
    expect(msg.error.message).to.include('reboot');
    expect(requests).to.deep.equal([]);
    expect(out.messages).to.deep.equal([]);
  });

  it('a FETCH/WRITE connection fails with NOT_SUPPORTED on Catch', async () => {
    const sim = await fetchWriteSim();
    try {
      const { out, caught, node } = await load(sim.url, { action: 'state' });
      node.receive({});
      const msg = await caught.next();
      expect(msg.error.code).to.equal('NOT_SUPPORTED');
      expect(msg.error.message).to.match(/s7:\/\//);
      expect(msg.error.message).to.include('fetchwrite');
      expect(out.messages).to.deep.equal([]);
    } finally {
      await helper.unload();
      await sim.close();
    }
  });

  it('a connection with control=true never shares its client with one without it', async () => {
    const at = { z: 'tab', x: 100, y: 100 };
    await helper.load(modules, [
      { id: 'tab', type: 'tab', label: 'control' },
      { id: 'plain', type: 'plcwire-connection', url: url() },
      { id: 'ctrl', type: 'plcwire-connection', url: url('&control=true') },
      { id: 'a', type: 'plcwire-control', ...at, connection: 'plain', action: 'state', wires: [[]] },
      { id: 'b', type: 'plcwire-control', ...at, connection: 'ctrl', action: 'stop', wires: [[]] },
      { id: 'catcher', type: 'catch', ...at, scope: ['b'], uncaught: false, wires: [['caught']] },
      { id: 'caught', type: 'helper', ...at },
    ]);
    const caught = new Recorder(helper.getNode('caught'));
    const msg = await caught.next();
    expect(msg.error.code).to.equal('SETTINGS_CONFLICT');
    expect(msg.error.message).to.include('control');
    helper.getNode('b').receive({});
    expect((await caught.next()).error.code).to.equal('SETTINGS_CONFLICT');
    expect(server.state).to.equal('RUN');
  });
});

describe("nodes: the control node's logic", () => {
  const entry = (ms: number, eventId: number) => ({
    time: new Date(ms),
    eventId,
    priority: 1,
    ob: 1,
    dataId: 0,
    info1: 0,
    info2: 0,
    info3: 0,
  });

  it('takes msg.action, else msg.topic when it names an action, else the configured action', () => {
    expect(actionOf({ action: 'stop', topic: 'start' }, 'info')).to.equal('stop');
    expect(actionOf({ topic: 'clock-sync' }, 'info')).to.equal('clock-sync');
    expect(actionOf({ topic: 'line 3' }, 'blocks')).to.equal('blocks');
    expect(actionOf({ action: '' }, 'state')).to.equal('state');
    expect(() => actionOf({ action: 'STOP' }, 'info'))
      .to.throw(/"STOP"/)
      .with.property('code', 'INVALID_VALUE');
  });

  it('reports every entry first, then those logged since, also entries of the same millisecond', () => {
    const cursor = new DiagnosticsCursor();
    const old = [entry(1000, 2), entry(1000, 1)];
    expect(cursor.take(old)).to.deep.equal(old);
    expect(cursor.take(old)).to.deep.equal([]);
    const later = [entry(1000, 4), entry(1000, 3), ...old];
    expect(cursor.take(later).map((e: any) => e.eventId)).to.deep.equal([4, 3]);
  });

  it('when the last reported entry has left the buffer, the entries later than it are new', () => {
    const cursor = new DiagnosticsCursor();
    cursor.take([entry(1000, 1)]);
    expect(cursor.take([entry(3000, 9), entry(2000, 8)]).map((e: any) => e.eventId)).to.deep.equal([9, 8]);
    // A memory reset: only older stamps left, nothing new.
    expect(cursor.take([entry(500, 7)])).to.deep.equal([]);
  });
});
