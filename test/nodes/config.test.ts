/**
 * Configuration errors in a running flow: a connection whose URL the
 * library's parser refuses reaches the Catch node of every node that uses it,
 * once per start of that node, with code INVALID_URL.
 */
import { expect } from 'chai';
import { loadCatalogs, withCatalog } from './catalogs';
import { ALL_NODES, helper, nodes, Recorder } from './support';

const TAB = { id: 'tab', type: 'tab', label: 'config errors' };
const at = { z: 'tab', x: 100, y: 100 };
const USERS = ['read', 'write', 'hb'];

function flow(url: string, readName = 'poll'): object[] {
  return [
    TAB,
    { id: 'conn', type: 'plcwire-connection', name: 'press 3', url },
    {
      id: 'read',
      type: 'plcwire-read',
      ...at,
      name: readName,
      connection: 'conn',
      interval: 100,
      output: 'object',
      tags: [{ name: 'a', address: 'DB1.DBW0:INT' }],
      wires: [[]],
    },
    { id: 'write', type: 'plcwire-write', ...at, connection: 'conn', tags: [], wires: [[]] },
    {
      id: 'hb',
      type: 'plcwire-heartbeat',
      ...at,
      connection: 'conn',
      writeAddress: 'DB1.DBW2:INT',
      writeMode: 'counter',
      interval: 100,
      watchAddress: '',
      timeout: 1000,
      wires: [[]],
    },
    // One Catch scoped to the three users (the test helper loads a core node's module once per node of its type).
    { id: 'catcher', type: 'catch', ...at, scope: USERS, uncaught: false, wires: [['caught']] },
    { id: 'caught', type: 'helper', ...at },
    { id: 'watcher', type: 'status', ...at, scope: null, wires: [['statuses']] },
    { id: 'statuses', type: 'helper', ...at },
  ];
}

describe('nodes: a connection with an invalid URL', function () {
  this.timeout(10000);
  beforeEach(() => helper.startServer());
  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
  });

  it("reaches the Catch node of every node that uses it, with INVALID_URL and the parser's words", async () => {
    await helper.load(ALL_NODES, flow('s7://127.0.0.1?rack=0&slott=1'));
    const statuses = new Recorder(helper.getNode('statuses'));
    const catches = new Recorder(helper.getNode('caught'));
    for (const id of USERS) {
      const caught = await catches.next((m) => m.error.source.id === id, 3000, `${id}'s error on Catch`);
      expect(caught.error.code, id).to.equal('INVALID_URL');
      expect(caught.error.message, id).to.include('unknown parameter "slott"');
      expect(caught.error.message, id).to.include('press 3');
      expect(caught.error.source.id, id).to.equal(id);
      expect(caught.payload).to.deep.include({ state: 'invalid', code: 'INVALID_URL' });
    }
    for (const id of USERS) {
      await statuses.next(
        (m) => m.status.source.id === id && m.status.text === 'plcwire.status.badConfig',
        3000,
        `${id} shows bad connection`,
      );
    }
  });

  it('is reported again to a node that is redeployed, and not to the others', async () => {
    await helper.load(ALL_NODES, flow('s7://127.0.0.1?slott=1'));
    const catches = new Recorder(helper.getNode('caught'));
    for (const id of USERS) await catches.next((m) => m.error.source.id === id, 3000, `${id}'s first report`);
    await helper.setFlows(flow('s7://127.0.0.1?slott=1', 'poll 2'), 'nodes');
    const again = await catches.next(() => true, 3000, 'report after the redeploy');
    expect([again.error.source.id, again.error.code]).to.deep.equal(['read', 'INVALID_URL']);
    // Every report is made when the flows have started: by now each node has made all of its.
    expect(catches.messages.map((m) => m.error.source.id).sort()).to.deep.equal(['hb', 'read', 'read', 'write']);
  });

  it('credentials in the URL never reach the Catch message', async () => {
    await helper.load(ALL_NODES, flow('s7://user:hunter2@127.0.0.1?slott=1'));
    const caught = await new Recorder(helper.getNode('caught')).next(() => true, 3000, 'error on Catch');
    expect(JSON.stringify(caught)).not.to.include('hunter2');
  });
});

describe('nodes: a tag table with a name used twice', function () {
  this.timeout(10000);
  beforeEach(() => helper.startServer());
  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
  });

  it('is a warning naming it, from the read and the write node (in object output only one value could arrive)', async () => {
    const catalogs = await loadCatalogs();
    const tags = [
      { name: 'speed', address: 'MW2' },
      { name: 'level', address: 'MW4' },
      { name: 'speed', address: 'MW6' },
    ];
    await helper.load(
      [
        nodes.connection,
        withCatalog(nodes.read, catalogs.translator('en-US', 'plcwire-read')),
        withCatalog(nodes.write, catalogs.translator('en-US', 'plcwire-write')),
      ],
      [
        TAB,
        { id: 'conn', type: 'plcwire-connection', url: 's7://127.0.0.1?slott=1' },
        { id: 'read', type: 'plcwire-read', ...at, connection: 'conn', interval: 0, output: 'object', tags, wires: [[]] },
        { id: 'write', type: 'plcwire-write', ...at, connection: 'conn', tags, wires: [[]] },
      ],
    );
    // The helper's log spy is made by load() and records what the nodes logged while being created.
    const warnings = helper
      .log()
      .getCalls()
      .map((c: any) => c.args[0])
      .filter((e: any) => e && e.level === 30 && e.id);
    expect(warnings.map((w: any) => [w.id, w.msg])).to.deep.equal([
      ['read', 'tag name "speed" is given to rows 1, 3: give each row its own name'],
      ['write', 'tag name "speed" is given to rows 1, 3: give each row its own name'],
    ]);
  });
});
