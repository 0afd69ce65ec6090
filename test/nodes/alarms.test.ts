/**
 * plcwire-alarms in real flows of the test helper, with the node's real
 * en-US catalog: a connection whose protocol has no alarms is one Catch
 * message (NOT_SUPPORTED) however often it is asked, and the node's status
 * says it failed; a message it cannot read goes to Catch as INVALID_VALUE.
 */
import { expect } from 'chai';
import { loadCatalogs, withCatalog } from './catalogs';
import { fetchWriteSim } from './sims';
import { ALL_NODES, helper, nodes, Recorder, until, type Sim } from './support';
import type { AlarmDefinition } from '../../lib/alarms/model';
import { DB_NUMBERS, SOURCES } from '../fixtures/s7plus';
import { startPlusSimulator, type PlusSimulator } from '../support/s7plus-sim';

describe('nodes: plcwire-alarms', function () {
  this.timeout(20000);
  let sim: Sim;
  let modules: unknown[];

  before(async () => {
    const catalogs = await loadCatalogs();
    modules = ALL_NODES.map((m) => (m === nodes.alarms ? withCatalog(nodes.alarms, catalogs.translator('en-US', 'plcwire-alarms')) : m));
  });

  beforeEach(async () => {
    sim = await fetchWriteSim();
    await helper.startServer();
  });

  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
    await sim.close();
  });

  /** A flow with the alarms node `al` → `out`, a Catch for it → `caught`. */
  async function load(url: string): Promise<{ out: Recorder; caught: Recorder; node: any }> {
    const at = { z: 'tab', x: 100, y: 100 };
    await helper.load(modules, [
      { id: 'tab', type: 'tab', label: 'alarms' },
      { id: 'conn', type: 'plcwire-connection', name: 'plc', url },
      { id: 'al', type: 'plcwire-alarms', ...at, name: '', connection: 'conn', mode: false, diagnostics: false, wires: [['out']] },
      { id: 'out', type: 'helper', ...at },
      { id: 'catcher', type: 'catch', ...at, scope: ['al'], uncaught: false, wires: [['caught']] },
      { id: 'caught', type: 'helper', ...at },
    ]);
    return { out: new Recorder(helper.getNode('out')), caught: new Recorder(helper.getNode('caught')), node: helper.getNode('al') };
  }

  it('a connection without alarms is one NOT_SUPPORTED Catch message at start, in the catalog’s words, and the status says so', async () => {
    const { caught, node } = await load(sim.url);
    const statuses: any[] = [];
    node.on('call:status', (call: any) => statuses.push(call.args[0]));
    const msg = await caught.next(undefined, 8000, 'the refusal on Catch');
    expect(msg.error.code).to.equal('NOT_SUPPORTED');
    expect(msg.error.message).to.contain('fetchwrite:// has no alarms; they are served over ');
    expect(msg.error.source.id).to.equal('al');
    expect(msg.payload).to.deep.include({ code: 'NOT_SUPPORTED' });
    // An acknowledgement asked of it fails at the node (the message's own error), not a second start report.
    node.receive({ ack: 1001 });
    const ack = await caught.next(undefined, 4000, 'the refused acknowledgement');
    expect(ack.error.code).to.equal('NOT_SUPPORTED');
    expect(ack.ack).to.equal(1001);
    await until(() => statuses.some((s) => s.text === 'alarms failed'), 4000, 'status "alarms failed"');
    expect(caught.messages).to.have.length(2);
  });

  it('a message that asks for nothing it knows goes to Catch as INVALID_VALUE, naming what it takes', async () => {
    const { caught, out, node } = await load(sim.url);
    await caught.next(undefined, 8000, 'the start refusal');
    node.receive({ payload: 'hello' });
    const msg = await caught.next();
    expect(msg.error.code).to.equal('INVALID_VALUE');
    expect(msg.error.message).to.contain('msg.ack = <alarm id>').and.to.contain('msg.topic = "list"');
    expect(out.messages).to.deep.equal([]);
  });

  describe('on an S7-1500 (our simulator, Program_Alarm over S7CommPlus)', () => {
    const TANK_HIGH: AlarmDefinition = {
      id: 7,
      kind: 'Program_Alarm',
      texts: { 'en-US': 'Tank level high: @1%5.1f@ m' },
      needsAck: true,
      priority: 5,
      trigger: '"Tank".Alarm',
      values: ['"Tank".Level'],
    };
    let plus: PlusSimulator;
    const trigger = (on: boolean) => plus.server.memory.writeBit('DB', 1, 6, 1, on); // "Tank".Alarm is DB1.DBX6.1

    before(async () => {
      plus = await startPlusSimulator({ sources: SOURCES, db: DB_NUMBERS, alarms: [TANK_HIGH] });
    });
    afterEach(() => trigger(false));
    after(() => plus?.server.close());

    it('sends each event with its alarm as plain data, counts in the status, the active list on topic "list"', async () => {
      const { out, caught, node } = await load(plus.url);
      const statuses: { fill: string; text: string }[] = [];
      node.on('call:status', (call: any) => statuses.push(call.args[0]));
      await until(() => statuses.some((s) => s.text === 'no active alarms'), 15000, 'subscribed: "no active alarms"');
      trigger(true);
      const coming = await out.next((m) => m.topic === 'alarm/7/coming', 10000, 'the coming event');
      expect(coming.payload).to.deep.include({ type: 'alarm', change: 'coming' });
      expect(coming.payload.alarm).to.deep.include({ id: 7, kind: 'Program_Alarm', needsAck: true, acknowledged: false, priority: 5 });
      expect(coming.payload.alarm.texts['en-US'].text).to.equal('Tank level high:  12.5 m');
      expect(coming.payload.at).to.be.a('string');
      await until(() => statuses.some((s) => s.text === '1/1 unacked' && s.fill === 'red'), 5000, 'status "1/1 unacked"');
      node.receive({ topic: 'list' });
      const list = await out.next((m) => m.topic === 'list', 10000, 'the active list');
      expect(list.payload.map((a: { id: number }) => a.id)).to.deep.equal([7]);
      trigger(false);
      await out.next((m) => m.topic === 'alarm/7/going', 10000, 'the going event');
      await until(() => statuses.at(-1)?.text === 'no active alarms', 5000, 'status back to "no active alarms"');
      expect(caught.messages).to.deep.equal([]);
    });

    it('msg.ack: the S7CommPlus client refuses it, the refusal reaches Catch with its code and the message', async () => {
      const { caught, node } = await load(plus.url);
      await until(() => node.linkState === 'connected', 15000, 'connected');
      node.receive({ ack: 7, keep: 1 });
      const msg = await caught.next(undefined, 10000, 'the refusal');
      expect(msg.error.code).to.equal('NOT_SUPPORTED');
      expect(msg.error.message).to.contain('acknowledge of alarm 7');
      expect(msg.keep).to.equal(1);
    });
  });
});
