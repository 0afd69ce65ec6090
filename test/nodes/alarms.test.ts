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
});
