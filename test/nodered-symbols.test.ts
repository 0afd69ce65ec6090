/**
 * Tags by name in Node-RED: a connection node with the PLC's own DB and UDT
 * sources in the flow, in the real runtime of the test helper, against the
 * in-process S7 simulator over a real socket. Reads and writes by name, a
 * struct read as an object, a data block whose length differs from its
 * source, sources that do not compile, two connection nodes for one PLC, and
 * the admin endpoints the dialogs use. Status texts are checked against the
 * real catalogs (the helper's RED._ is the identity).
 */
import { expect } from 'chai';
import * as path from 'node:path';
import { LOCALES, loadCatalogs, rawCatalog, withCatalog, type Catalogs } from './nodes/catalogs';
import { ALL_NODES, helper, nodes, Recorder, ROOT, until } from './nodes/support';

const lib = require(path.join(ROOT, 'dist/lib/index.js'));
const status = require(path.join(ROOT, 'nodes/shared/status.js'));

const MOTOR_UDT = `TYPE "Motor"
VERSION : 0.1
   STRUCT
      Speed : Real;   // rpm
      Run : Bool;
   END_STRUCT;

END_TYPE
`;

/** DB "Tank" in standard access: Level REAL at 0, Count INT at 4, Motor ("Motor": Speed REAL at 6, Run at 10.0); 12 bytes. */
const TANK_DB = `DATA_BLOCK "Tank"
{ S7_Optimized_Access := 'FALSE' }
VERSION : 0.1
NON_RETAIN
   STRUCT
      Level : Real;
      Count : Int;
      Motor : "Motor";
   END_STRUCT;


BEGIN

END_DATA_BLOCK
`;
const TANK_LENGTH = 12;

/** The same DB with a typo in line 7 (an unknown type). */
const BROKEN_DB = TANK_DB.replace('Count : Int;', 'Count : Integr;');

const SOURCES = [
  { name: 'Motor.udt', content: MOTOR_UDT },
  // Stored as base64, as the dialog stores an .xlsx: the runtime decodes it before compiling.
  { name: 'Tank.db', content: Buffer.from(TANK_DB).toString('base64'), encoding: 'base64' },
];
const DB_NUMBERS = [{ block: 'Tank', db: 1 }];

const TAB = { id: 'tab', type: 'tab', label: 'symbols' };
const at = { z: 'tab', x: 100, y: 100 };

function conn(url: string, extra: Record<string, unknown> = {}, id = 'conn') {
  return {
    id,
    type: 'plcwire-connection',
    name: 'tank plc',
    url,
    symbolSources: SOURCES,
    dbNumbers: DB_NUMBERS,
    strictSymbols: false,
    ...extra,
  };
}

function readNode(tags: object[], extra: Record<string, unknown> = {}) {
  return {
    id: 'read',
    type: 'plcwire-read',
    ...at,
    connection: 'conn',
    interval: 0,
    output: 'object',
    deadband: 0,
    tags,
    wires: [['out']],
    ...extra,
  };
}

const helperNode = (id: string) => ({ id, type: 'helper', ...at });
const catcher = () => ({ id: 'catcher', type: 'catch', ...at, scope: null, uncaught: false, wires: [['caught']] });
const watcher = () => ({ id: 'watcher', type: 'status', ...at, scope: null, wires: [['statuses']] });

interface Plc {
  server: any;
  memory: any;
  url: string;
  db(): Buffer;
}

/**
 * The simulated CPU: an S7-300 (slot 2), whose block functions tell DB
 * lengths (an S7-1500 over PUT/GET cannot, and the client's layout check
 * then reports layoutUnknown).
 */
async function startPlc(dbLength = TANK_LENGTH): Promise<Plc> {
  const memory = new lib.PlcMemory({ dataBlocks: { 1: dbLength, 2: 16 } });
  const server = new lib.S7Server({ port: 0, memory, profile: 's7-300' });
  const port: number = await server.listen();
  return { server, memory, url: `s7://127.0.0.1:${port}?rack=0&slot=2&timeout=1000`, db: () => memory.area('DB', 1) as Buffer };
}

/** The library's own message for sources that do not compile. */
function compileError(sources: object[]): string {
  try {
    lib.compileSymbols(sources, { db: { Tank: 1 } });
  } catch (err) {
    return (err as Error).message;
  }
  throw new Error('the sources compiled');
}

/** The catalog text of `key` for `type` in `locale`, its placeholders filled in. */
function catalogText(locale: (typeof LOCALES)[number], type: string, key: string, params: Record<string, unknown>): string {
  const template = String(key.split('.').reduce((o: any, k) => o?.[k], rawCatalog(locale, type)));
  return template.replace(/__(\w+)__/g, (_m, name: string) => String(params[name]));
}

describe('nodes: tags by name (symbol sources in the connection node)', function () {
  this.timeout(20000);
  let plc: Plc;
  let catalogs: Catalogs;

  before(async () => {
    catalogs = await loadCatalogs();
  });

  beforeEach(async () => {
    plc = await startPlc();
    await helper.startServer();
  });

  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
    await plc.server.close();
  });

  it('reads by name: a REAL and a whole UDT instance, which arrives in msg.payload as an object', async () => {
    plc.db().writeFloatBE(12.5, 0);
    plc.db().writeFloatBE(1450, 6);
    plc.db()[10] = 0x01;
    await helper.load(ALL_NODES, [
      TAB,
      conn(plc.url),
      readNode([
        { name: 'level', address: '"Tank".Level' },
        { name: 'motor', address: 'Tank.Motor' },
        { name: 'raw', address: 'DB1.DBW4:INT' },
      ]),
      helperNode('out'),
    ]);
    plc.db().writeInt16BE(-3, 4);
    await until(() => helper.getNode('read').linkState === 'connected', 4000, 'read node connected');
    const out = new Recorder(helper.getNode('out'));
    helper.getNode('read').receive({});
    const msg = await out.next();
    expect(msg.payload).to.deep.equal({ level: 12.5, motor: { Speed: 1450, Run: true }, raw: -3 });
    expect(msg.quality).to.deep.equal({ level: 'good', motor: 'good', raw: 'good' });
    expect(msg.addresses).to.deep.equal({ level: '"Tank".Level', motor: 'Tank.Motor', raw: 'DB1.DBW4:INT' });
  });

  it('a REAL member of a struct read by name has the digits TIA shows, as a REAL read alone has', async () => {
    plc.db().writeFloatBE(40.4, 0);
    plc.db().writeFloatBE(40.4, 6);
    await helper.load(ALL_NODES, [
      TAB,
      conn(plc.url),
      readNode([
        { name: 'level', address: '"Tank".Level' },
        { name: 'motor', address: 'Tank.Motor' },
      ]),
      helperNode('out'),
    ]);
    await until(() => helper.getNode('read').linkState === 'connected', 4000, 'read node connected');
    const out = new Recorder(helper.getNode('out'));
    helper.getNode('read').receive({});
    const msg = await out.next();
    expect(msg.payload).to.deep.equal({ level: 40.4, motor: { Speed: 40.4, Run: false } });
  });

  it('writes by name, from the tag table and as a key of msg.payload, then sends msg.results', async () => {
    await helper.load(ALL_NODES, [
      TAB,
      conn(plc.url),
      { id: 'write', type: 'plcwire-write', ...at, connection: 'conn', tags: [{ name: 'count', address: 'Tank.Count' }], wires: [['out']] },
      helperNode('out'),
    ]);
    await until(() => helper.getNode('write').linkState === 'connected', 4000, 'write node connected');
    const out = new Recorder(helper.getNode('out'));
    helper.getNode('write').receive({ payload: { count: 7, '"Tank".Motor.Run': true, '"Tank".Motor.Speed': 2.5 } });
    const msg = await out.next();
    expect(msg.results.count).to.include({ ok: true });
    expect(msg.results['"Tank".Motor.Run']).to.include({ ok: true });
    expect(plc.db().readInt16BE(4)).to.equal(7);
    expect(plc.db().readFloatBE(6)).to.equal(2.5);
    expect(plc.db()[10]! & 1).to.equal(1);
  });

  it('an unknown name fails alone, with INVALID_ADDRESS and the closest names of the sources', async () => {
    await helper.load(ALL_NODES, [
      TAB,
      conn(plc.url),
      readNode([
        { name: 'level', address: 'Tank.Level' },
        { name: 'typo', address: 'Tank.Levl' },
      ]),
      helperNode('out'),
      catcher(),
      helperNode('caught'),
    ]);
    await until(() => helper.getNode('read').linkState === 'connected', 4000, 'read node connected');
    const out = new Recorder(helper.getNode('out'));
    helper.getNode('read').receive({});
    const msg = await out.next();
    expect(msg.quality).to.deep.equal({ level: 'good', typo: 'bad' });
    expect(msg.errors.typo.code).to.equal('INVALID_ADDRESS');
    expect(msg.errors.typo.message).to.include('Level');
  });

  for (const locale of LOCALES) {
    it(`${locale}: a data block resized on the PLC shows the DB and both lengths on the users' status until it fits again`, async () => {
      const modules = [
        withCatalog(nodes.connection, catalogs.translator(locale, 'plcwire-connection')),
        withCatalog(nodes.read, catalogs.translator(locale, 'plcwire-read')),
        nodes.status,
      ];
      await helper.load(modules, [
        TAB,
        conn(plc.url),
        readNode([{ name: 'level', address: 'Tank.Level' }]),
        helperNode('out'),
        watcher(),
        helperNode('statuses'),
      ]);
      const statuses = new Recorder(helper.getNode('statuses'));
      const connected = catalogText(locale, 'plcwire-read', 'plcwire.status.connected', {});
      const shows = (text: string) => (m: any) => m.status.source.id === 'read' && m.status.text === text;
      await statuses.next(shows(connected), 4000, `"${connected}" on the read node`);

      // The PLC gets another DB1 (a download nobody compiled the sources for); the client checks again on its next connection.
      plc.memory.createDataBlock(1, TANK_LENGTH + 4);
      plc.server.dropConnections();
      const text = catalogText(locale, 'plcwire-read', 'plcwire.status.layoutMismatch', {
        db: 1,
        declared: TANK_LENGTH,
        actual: TANK_LENGTH + 4,
      });
      expect(text)
        .to.include('DB1')
        .and.to.include(String(TANK_LENGTH))
        .and.to.include(String(TANK_LENGTH + 4));
      const seen = await statuses.next(shows(text), 6000, `"${text}" on the read node`);
      expect(seen.status).to.include({ fill: 'red', shape: 'ring' });
      // The log names the block and both lengths in words.
      const warnings = helper
        .log()
        .getCalls()
        .map((c: any) => c.args[0])
        .filter((e: any) => e && e.level === 30 && e.id === 'conn')
        .map((w: any) => w.msg);
      expect(warnings).to.deep.equal([
        catalogText(locale, 'plcwire-connection', 'plcwire-connection.errors.layoutMismatch', {
          block: 'Tank',
          db: 1,
          declared: TANK_LENGTH,
          actual: TANK_LENGTH + 4,
        }),
      ]);

      // Downloaded back to the sources' length: a check on the same connection (no reconnect to clear
      // anything) finds it fine, and the status says connected again.
      plc.memory.createDataBlock(1, TANK_LENGTH);
      statuses.skip();
      await helper.getNode('conn').client.checkLayout();
      await statuses.next(shows(connected), 6000, `"${connected}" again`);
    });
  }

  it('a data block the PLC does not have shows as missing', async () => {
    const modules = [
      withCatalog(nodes.connection, catalogs.translator('en-US', 'plcwire-connection')),
      withCatalog(nodes.read, catalogs.translator('en-US', 'plcwire-read')),
      nodes.status,
    ];
    plc.memory.deleteDataBlock(1);
    await helper.load(modules, [
      TAB,
      conn(plc.url),
      readNode([{ name: 'level', address: 'Tank.Level' }]),
      helperNode('out'),
      watcher(),
      helperNode('statuses'),
    ]);
    const text = catalogText('en-US', 'plcwire-read', 'plcwire.status.layoutMissing', { db: 1 });
    await new Recorder(helper.getNode('statuses')).next((m) => m.status.source.id === 'read' && m.status.text === text, 6000, `"${text}"`);
  });

  it('with strict layout, a read of the mismatching DB is refused with LAYOUT_MISMATCH', async () => {
    await plc.server.close();
    plc = await startPlc(TANK_LENGTH + 4);
    await helper.load(ALL_NODES, [
      TAB,
      conn(plc.url, { strictSymbols: true }),
      readNode([{ name: 'level', address: 'Tank.Level' }]),
      helperNode('out'),
    ]);
    await until(() => helper.getNode('read').linkState === 'connected', 4000, 'read node connected');
    const out = new Recorder(helper.getNode('out'));
    helper.getNode('read').receive({});
    const msg = await out.next();
    expect(msg.quality).to.deep.equal({ level: 'bad' });
    expect(msg.errors.level.code).to.equal('LAYOUT_MISMATCH');
  });

  const brokenConn = () =>
    conn(plc.url, {
      symbolSources: [
        { name: 'Motor.udt', content: MOTOR_UDT },
        { name: 'Tank.db', content: BROKEN_DB },
      ],
    });

  for (const locale of LOCALES) {
    it(`${locale}: sources that do not compile are logged with file and line, shown as "source error", and absolute addresses still work`, async () => {
      const modules = [
        withCatalog(nodes.connection, catalogs.translator(locale, 'plcwire-connection')),
        withCatalog(nodes.read, catalogs.translator(locale, 'plcwire-read')),
        nodes.status,
      ];
      plc.db().writeInt16BE(42, 4);
      await helper.load(modules, [
        TAB,
        brokenConn(),
        readNode([{ name: 'count', address: 'DB1.DBW4:INT' }]),
        helperNode('out'),
        watcher(),
        helperNode('statuses'),
      ]);
      const text = catalogText(locale, 'plcwire-read', 'plcwire.status.sourceError', {});
      const statuses = new Recorder(helper.getNode('statuses'));
      const seen = await statuses.next((m) => m.status.source.id === 'read' && m.status.text === text, 4000, `"${text}" on the read node`);
      expect(seen.status).to.include({ fill: 'yellow', shape: 'dot' });
      // Reported when the flows started: by now the log has it, in the catalog's words, naming file and line.
      const logged = helper
        .log()
        .getCalls()
        .map((c: any) => c.args[0])
        .filter((e: any) => e && e.level === 20 && e.id === 'conn');
      expect(logged.length).to.equal(1);
      const problem = compileError([
        { name: 'Motor.udt', content: MOTOR_UDT },
        { name: 'Tank.db', content: BROKEN_DB },
      ]);
      expect(problem).to.match(/^Tank\.db:7:\d+: .*Integr/);
      expect(String(logged[0].msg)).to.equal(
        `PlcError: ${catalogText(locale, 'plcwire-connection', 'plcwire-connection.errors.sources', { name: 'tank plc', problem })}`,
      );
      const out = new Recorder(helper.getNode('out'));
      helper.getNode('read').receive({});
      expect((await out.next()).payload).to.deep.equal({ count: 42 });
    });
  }

  it("sources that do not compile reach the users' Catch nodes with INVALID_SOURCE and the problems with file and line", async () => {
    const modules = [withCatalog(nodes.connection, catalogs.translator('en-US', 'plcwire-connection')), nodes.read, nodes.catch];
    await helper.load(modules, [
      TAB,
      brokenConn(),
      readNode([{ name: 'count', address: 'DB1.DBW4:INT' }]),
      helperNode('out'),
      catcher(),
      helperNode('caught'),
    ]);
    const caught = await new Recorder(helper.getNode('caught')).next(() => true, 4000, 'the compile error on Catch');
    expect(caught.error.code).to.equal('INVALID_SOURCE');
    expect(caught.error.message).to.match(/Tank\.db:7:\d+/);
    expect(caught.error.source.id).to.equal('conn');
    expect(caught.payload.problems).to.have.length(1);
    expect(caught.payload.problems[0]).to.include({ code: 'INVALID_SOURCE', file: 'Tank.db', line: 7 });
  });

  it('two connection nodes for one PLC share a client with the same sources, and the second is refused with other ones', async () => {
    const same = (id: string, readId: string, connection: string) => ({
      ...readNode([{ name: 'l', address: 'Tank.Level' }]),
      id,
      connection: connection,
      wires: [[readId]],
    });
    await helper.load(ALL_NODES, [
      TAB,
      conn(plc.url, {}, 'conn'),
      conn(plc.url, {}, 'twin'),
      conn(plc.url, { symbolSources: [{ name: 'Motor.udt', content: MOTOR_UDT }] }, 'other'),
      same('r1', 'o1', 'conn'),
      same('r2', 'o2', 'twin'),
      same('r3', 'o3', 'other'),
      helperNode('o1'),
      helperNode('o2'),
      helperNode('o3'),
      catcher(),
      helperNode('caught'),
    ]);
    const caught = await new Recorder(helper.getNode('caught')).next((m) => m.error.source.id === 'r3', 4000, "r3's refusal");
    expect(caught.error.code).to.equal('SETTINGS_CONFLICT');
    expect(caught.error.message).to.include('other symbol sources');
    await until(
      () => helper.getNode('r1').linkState === 'connected' && helper.getNode('r2').linkState === 'connected',
      4000,
      'r1, r2 connected',
    );
    expect(helper.getNode('conn').client).to.equal(helper.getNode('twin').client);
    expect(helper.getNode('other').client).to.equal(undefined);
    expect(plc.server.connectionCount).to.equal(1);
  });

  it('keeps the sources in the flow as text: a DB of 2,000 members costs its own size and not much more', async () => {
    const lines = Array.from({ length: 2000 }, (_v, i) => `      Value_${String(i).padStart(4, '0')} : Real;   // sensor ${i}`);
    const big = `DATA_BLOCK "Big"\n{ S7_Optimized_Access := 'FALSE' }\nVERSION : 0.1\n   STRUCT\n${lines.join('\n')}\n   END_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n`;
    const config = conn(plc.url, { symbolSources: [{ name: 'Big.db', content: big }], dbNumbers: [{ block: 'Big', db: 2 }] });
    await helper.load(ALL_NODES, [TAB, config]);
    const res = await helper
      .request()
      .post('/plcwire/symbols')
      .send({ symbolSources: config.symbolSources, dbNumbers: config.dbNumbers })
      .expect(200);
    expect(res.body.errors).to.deep.equal([]);
    expect(res.body.blocks).to.deep.equal([{ name: 'Big', db: 2, length: 8000, file: 'Big.db' }]);
    const stored = JSON.stringify(config);
    expect(stored.length).to.be.lessThan(Buffer.byteLength(big) * 1.05 + 1024);
  });
});

describe('nodes: the symbol endpoints of the editor', function () {
  this.timeout(10000);
  beforeEach(() => helper.startServer());
  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
  });

  it('POST /plcwire/symbols answers the blocks with number and length, and every entry with its address and type', async () => {
    await helper.load(ALL_NODES, []);
    const res = await helper.request().post('/plcwire/symbols').send({ symbolSources: SOURCES, dbNumbers: DB_NUMBERS }).expect(200);
    expect(res.body.errors).to.deep.equal([]);
    expect(res.body.blocks).to.deep.equal([{ name: 'Tank', db: 1, length: TANK_LENGTH, file: 'Tank.db' }]);
    const byName = Object.fromEntries(res.body.entries.map((e: any) => [e.name, e]));
    expect(byName['"Tank".Level']).to.deep.include({ address: 'DB1.DBD0:REAL', type: 'REAL', kind: 'elementary' });
    expect(byName['"Tank".Motor.Run']).to.deep.include({ address: 'DB1.DBX10.0', kind: 'elementary' });
    expect(byName['"Tank".Motor']).to.deep.include({ kind: 'struct', children: ['"Tank".Motor.Speed', '"Tank".Motor.Run'] });
    expect(res.body.types).to.deep.equal(['Motor']);
  });

  it('POST /plcwire/symbols answers compile errors with file, line and column', async () => {
    await helper.load(ALL_NODES, []);
    const res = await helper
      .request()
      .post('/plcwire/symbols')
      .send({
        symbolSources: [
          { name: 'Motor.udt', content: MOTOR_UDT },
          { name: 'Tank.db', content: BROKEN_DB },
        ],
        dbNumbers: DB_NUMBERS,
      })
      .expect(200);
    expect(res.body.blocks).to.deep.equal([]);
    expect(res.body.errors.length).to.be.greaterThan(0);
    expect(res.body.errors[0]).to.include({ code: 'INVALID_SOURCE', file: 'Tank.db', line: 7 });
    expect(res.body.errors[0].column).to.be.a('number');
    expect(res.body.errors[0].message).to.match(/^Tank\.db:7:\d+: .*Integr/);
  });

  it('POST /plcwire/validate resolves names with the sources: address, type and kind; an unknown name gets the closest ones', async () => {
    await helper.load(ALL_NODES, []);
    const res = await helper
      .request()
      .post('/plcwire/validate')
      .send({
        url: 's7://10.0.0.1',
        addresses: ['"Tank".Level', 'Tank.Motor', 'Tank.Levl', 'DB1.DBW0:INT'],
        symbolSources: SOURCES,
        dbNumbers: DB_NUMBERS,
      })
      .expect(200);
    expect(res.body.symbols).to.deep.equal({ ok: true });
    expect(res.body.results['"Tank".Level']).to.deep.include({
      ok: true,
      symbol: '"Tank".Level',
      address: 'DB1.DBD0:REAL',
      kind: 'elementary',
    });
    expect(res.body.results['Tank.Motor']).to.deep.include({ ok: true, symbol: '"Tank".Motor', kind: 'struct' });
    expect(res.body.results['Tank.Levl']).to.include({ ok: false, code: 'INVALID_ADDRESS' });
    expect(res.body.results['Tank.Levl'].message).to.include('"Tank".Level');
    expect(res.body.results['DB1.DBW0:INT']).to.deep.equal({ ok: true, type: 'INT', count: 1 });
    // Without the sources the same name is no address.
    const plain = await helper
      .request()
      .post('/plcwire/validate')
      .send({ url: 's7://10.0.0.1', addresses: ['"Tank".Level'] })
      .expect(200);
    expect(plain.body.results['"Tank".Level'].ok).to.equal(false);
  });
});

describe('nodes: the status texts of tags by name', () => {
  it('stay under 20 characters in every locale, with the DB number and both lengths at their largest', async () => {
    const catalogs = await loadCatalogs();
    for (const locale of LOCALES) {
      const t = catalogs.translator(locale, 'plcwire-read');
      // S7-1500: DB numbers up to 60999, a standard-access DB up to 65534 bytes.
      const layout = status.linkStatus(t, { state: 'connected', notice: { kind: 'layout', db: 60999, declared: 65534, actual: 65534 } });
      const sources = status.linkStatus(t, { state: 'connected', notice: { kind: 'sources' } });
      for (const s of [layout, sources]) {
        expect(s.text, locale).not.to.match(/__|plcwire\./);
        expect([...s.text].length, `${locale}: "${s.text}"`).to.be.lessThan(20);
      }
      expect(layout.text).to.include('60999').and.to.include('65534');
    }
  });
});
