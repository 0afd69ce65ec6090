/**
 * Two connection nodes for one PLC share one link, so they must agree on the
 * settings that link enforces (readOnly, allow, control, symbol sources).
 * When they do not, the second is refused with its own code,
 * SETTINGS_CONFLICT, and words that say the URL is valid, which connection
 * holds the link and which settings differ; its users show "settings
 * conflict" (not "bad connection") while the first connection's users run.
 */
import { expect } from 'chai';
import { loadCatalogs, withCatalog } from './catalogs';
import { ALL_NODES, helper, nodes, Recorder, until } from './support';
import { s7Sim } from './sims';
import type { Sim } from './support';

const TAB = { id: 'tab', type: 'tab', label: 'settings conflict' };
const at = { z: 'tab', x: 100, y: 100 };

function flow(first: object, second: object): object[] {
  const read = (id: string, connection: string) => ({
    id,
    type: 'plcwire-read',
    ...at,
    connection,
    interval: 100,
    output: 'object',
    tags: [{ name: 'a', address: 'DB1.DBW0:INT' }],
    wires: [[`${id}.out`]],
  });
  return [
    TAB,
    { id: 'demo', type: 'plcwire-connection', name: 'S7-1200 sim', ...first },
    { id: 'mine', type: 'plcwire-connection', name: 'my example', ...second },
    read('r1', 'demo'),
    read('r2', 'mine'),
    { id: 'r1.out', type: 'helper', ...at },
    { id: 'r2.out', type: 'helper', ...at },
    { id: 'catcher', type: 'catch', ...at, scope: ['r1', 'r2'], uncaught: false, wires: [['caught']] },
    { id: 'caught', type: 'helper', ...at },
    { id: 'watcher', type: 'status', ...at, scope: null, wires: [['statuses']] },
    { id: 'statuses', type: 'helper', ...at },
  ];
}

describe('nodes: two connection nodes for one PLC with other settings', function () {
  this.timeout(15000);
  let sim: Sim;

  beforeEach(async () => {
    sim = await s7Sim();
    await helper.startServer();
  });
  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
    await sim.close();
  });

  it('refuses the second with SETTINGS_CONFLICT, naming the connection that holds the link and the setting that differs; the first runs', async () => {
    const catalogs = await loadCatalogs();
    await helper.load(
      [nodes.connection, withCatalog(nodes.read, catalogs.translator('en-US', 'plcwire-read'))],
      flow({ url: `${sim.url}&control=true` }, { url: sim.url }),
    );
    const statuses = new Recorder(helper.getNode('statuses'));
    const caught = await new Recorder(helper.getNode('caught')).next((m) => m.error.source.id === 'r2', 4000, "r2's refusal");
    expect(caught.error.code).to.equal('SETTINGS_CONFLICT');
    expect(caught.payload).to.deep.include({ state: 'invalid', code: 'SETTINGS_CONFLICT' });
    const message: string = caught.error.message;
    expect(message).to.include('is a valid URL');
    expect(message).to.include('connection "S7-1200 sim"');
    expect(message).to.include('control is true there, not set here');
    expect(message).not.to.match(/readOnly is|allow is/);
    // The user sees the conflict, in the catalog's words, not "bad connection".
    await statuses.next((m) => m.status.source.id === 'r2' && m.status.text === 'settings conflict', 4000, 'r2 shows "settings conflict"');
    // The connection that holds the link is not disturbed.
    const value = await new Recorder(helper.getNode('r1.out')).next(undefined, 4000, "r1's first value");
    expect(value.payload).to.have.property('a');
    expect(helper.getNode('r2').linkState).to.equal('invalid');
  });

  it('names every setting that differs (readOnly, allow)', async () => {
    await helper.load(ALL_NODES, flow({ url: `${sim.url}&readOnly=true` }, { url: `${sim.url}&allow=DB1` }));
    const caught = await new Recorder(helper.getNode('caught')).next((m) => m.error.source.id === 'r2', 4000, "r2's refusal");
    expect(caught.error.code).to.equal('SETTINGS_CONFLICT');
    expect(caught.error.message).to.include('readOnly is true there, not set here');
    expect(caught.error.message).to.include('allow is not set there, DB1 here');
    expect(caught.error.message).not.to.include('control is');
  });

  it('refuses other symbol sources with the same code, and saying so', async () => {
    const source = { name: 'Tank.db', content: 'DATA_BLOCK "Tank"\nSTRUCT\n  Level : Real;\nEND_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n' };
    await helper.load(ALL_NODES, flow({ url: sim.url, symbolSources: [source], dbNumbers: [{ block: 'Tank', db: 1 }] }, { url: sim.url }));
    const caught = await new Recorder(helper.getNode('caught')).next((m) => m.error.source.id === 'r2', 4000, "r2's refusal");
    expect(caught.error.code).to.equal('SETTINGS_CONFLICT');
    expect(caught.error.message).to.include('is a valid URL');
    expect(caught.error.message).to.include('no symbol sources (it has some)');
  });

  it('lets two connection nodes with the same settings share one client', async () => {
    await helper.load(ALL_NODES, flow({ url: `${sim.url}&control=true` }, { url: `${sim.url}&control=true` }));
    await until(
      () => helper.getNode('r1').linkState === 'connected' && helper.getNode('r2').linkState === 'connected',
      4000,
      'both connected',
    );
    expect(helper.getNode('demo').client).to.equal(helper.getNode('mine').client);
  });
});
