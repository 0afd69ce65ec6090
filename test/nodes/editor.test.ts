/**
 * The editor's admin endpoints (address validation and URL parsing with the
 * library's own parser, guarded by Node-RED permissions) and the examples,
 * which must load as flows.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { ALL_NODES, helper, ROOT } from './support';

describe('nodes: editor endpoints', function () {
  this.timeout(10000);
  beforeEach(() => helper.startServer());
  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
  });

  it('validates addresses with the parser of the connection URL protocol', async () => {
    await helper.load(ALL_NODES, []);
    const res = await helper
      .request()
      .post('/plcwire/validate')
      .send({ url: 's7://10.0.0.1?rack=0&slot=1', addresses: ['DB1.DBW0:INT', 'DB1,REAL4', 'MW2:INT[3]', 'DBX'] })
      .expect(200);
    expect(res.body.results['DB1.DBW0:INT']).to.deep.equal({ ok: true, type: 'INT', count: 1 });
    expect(res.body.results['DB1,REAL4']).to.deep.equal({ ok: true, type: 'REAL', count: 1 });
    expect(res.body.results['MW2:INT[3]']).to.deep.equal({ ok: true, type: 'INT', count: 3 });
    expect(res.body.results.DBX.ok).to.equal(false);
    expect(res.body.results.DBX.code).to.equal('INVALID_ADDRESS');
    expect(res.body.results.DBX.message).to.include('DBX');
  });

  it('validates without a URL with the S7 parser, and reports a bad URL', async () => {
    await helper.load(ALL_NODES, []);
    const plain = await helper
      .request()
      .post('/plcwire/validate')
      .send({ addresses: ['M0.1'] })
      .expect(200);
    expect(plain.body.results['M0.1']).to.deep.equal({ ok: true, type: 'BOOL', count: 1 });
    const bad = await helper
      .request()
      .post('/plcwire/validate')
      .send({ url: 's7://host?rakc=0', addresses: ['M0.1'] })
      .expect(200);
    expect(bad.body.url.ok).to.equal(false);
    expect(bad.body.url.message).to.include('rakc');
  });

  it('parses a URL into the fields of the dialog and formats fields back', async () => {
    await helper.load(ALL_NODES, []);
    const parsed = await helper
      .request()
      .post('/plcwire/url')
      .send({ url: 'fetchwrite://10.0.0.2?fetchPort=2000&writePort=2001' })
      .expect(200);
    expect(parsed.body.ok).to.equal(true);
    expect(parsed.body.endpoint).to.include({ protocol: 'fetchwrite', host: '10.0.0.2', fetchPort: 2000, writePort: 2001 });
    const formatted = await helper
      .request()
      .post('/plcwire/url')
      .send({ endpoint: { ...parsed.body.endpoint, writePort: 2000 } })
      .expect(200);
    expect(formatted.body.url).to.equal('fetchwrite://10.0.0.2?port=2000');
    const wrong = await helper.request().post('/plcwire/url').send({ url: 'modbus://x' }).expect(200);
    expect(wrong.body).to.include({ ok: false, code: 'INVALID_URL' });
  });

  it('imports CSV with the parser of the connection URL: the type column, names used twice', async () => {
    await helper.load(ALL_NODES, []);
    const s7 = await helper
      .request()
      .post('/plcwire/csv')
      .send({ url: 's7://10.0.0.1?rack=0&slot=1', text: 'name,address,type\nspeed,DB1.DBW6,INT\nlevel,DB1.DBD8,REAL\nspeed,MW2,\n' })
      .expect(200);
    expect(s7.body.tags).to.deep.equal([
      { name: 'speed', address: 'DB1.DBW6:INT' },
      { name: 'level', address: 'DB1.DBD8:REAL' },
      { name: 'speed', address: 'MW2' },
    ]);
    expect(s7.body.problems.map((p: any) => [p.line, p.code])).to.deep.equal([[4, 'DUPLICATE_NAME']]);
    const freeport = await helper
      .request()
      .post('/plcwire/csv')
      .send({ url: 'freeport+tcp://10.0.0.1:4001', text: 'a;ST5,INT2;INT\nb;ST5,BYTE1;INT\n' })
      .expect(200);
    expect(freeport.body.tags).to.deep.equal([
      { name: 'a', address: 'ST5,INT2' },
      { name: 'b', address: 'ST5,BYTE1' },
    ]);
    expect(freeport.body.problems.map((p: any) => [p.line, p.code])).to.deep.equal([[2, 'TYPE_MISMATCH']]);
    const bad = await helper.request().post('/plcwire/csv').send({ url: 's7://host?rakc=0', text: 'MW2' }).expect(200);
    expect(bad.body.url).to.include({ ok: false, code: 'INVALID_URL' });
    expect(bad.body.tags).to.deep.equal([{ name: '', address: 'MW2' }]);
  });

  it('exports a tag table as CSV that the import reads back to the same rows, awkward names included', async () => {
    await helper.load(ALL_NODES, []);
    const tags = [
      { name: 'speed', address: 'DB1.DBW6:INT' },
      { name: 'level "top", max', address: 'DB1.DBD8:REAL' },
      { name: 'semi;colon', address: 'MW2' },
      { name: '"Tank".Level', address: '"Tank".Level' },
    ];
    const exported = await helper.request().post('/plcwire/csv/export').send({ tags }).expect(200);
    const lib = require(path.join(ROOT, 'dist/lib/index.js'));
    expect(exported.body.csv).to.equal(lib.tagsToCsv(tags));
    expect(exported.body.csv.split('\r\n')[2]).to.equal('"level ""top"", max",DB1.DBD8:REAL');
    const back = await helper.request().post('/plcwire/csv').send({ text: exported.body.csv }).expect(200);
    expect(back.body.tags).to.deep.equal(tags);
    expect(back.body.problems).to.deep.equal([]);
    // Anything but a list of rows exports the header alone; rows that are no objects export as empty cells.
    const odd = await helper.request().post('/plcwire/csv/export').send({ tags: 'speed' }).expect(200);
    expect(odd.body.csv).to.equal('name,address\r\n');
    const holes = await helper
      .request()
      .post('/plcwire/csv/export')
      .send({ tags: [null, { name: 5 }] })
      .expect(200);
    expect(holes.body.csv).to.equal('name,address\r\n,\r\n5,\r\n');
  });

  it('answers the names a tag table gives more than one row (the editor keeps no copy of the rule)', async () => {
    await helper.load(ALL_NODES, []);
    const tags = [
      { name: 'speed', address: 'DB1.DBW0:INT' },
      { name: ' speed ', address: 'DB1.DBW6:INT' },
      { name: '', address: 'MW2' },
      { name: 'MW2', address: 'MW4' },
      { name: 'level', address: 'DB1.DBD8:REAL' },
    ];
    const res = await helper.request().post('/plcwire/duplicates').send({ tags }).expect(200);
    // A name is trimmed; a row without one is known by its address.
    expect(res.body).to.deep.equal({
      duplicates: [
        { name: 'speed', rows: [0, 1] },
        { name: 'MW2', rows: [2, 3] },
      ],
    });
    const odd = await helper.request().post('/plcwire/duplicates').send({ tags: 'speed' }).expect(200);
    expect(odd.body).to.deep.equal({ duplicates: [] });
    const editor = fs.readFileSync(path.join(ROOT, 'resources/plcwire-editor.js'), 'utf8');
    expect(editor).to.include("url: 'plcwire/duplicates'");
    expect(editor).not.to.match(/count\[n\]/);
  });

  it('serves the CPU presets of the library, TSAPs and items per job included', async () => {
    await helper.load(ALL_NODES, []);
    const lib = require(path.join(ROOT, 'dist/lib/index.js'));
    const res = await helper.request().get('/plcwire/presets').expect(200);
    expect(res.body).to.deep.equal(JSON.parse(JSON.stringify(lib.S7_CPU_PRESETS)));
    expect(res.body['s7-1200']).to.deep.equal({ rack: 0, slot: 1, maxItems: 255 });
    expect(res.body['s7-200']).to.deep.equal({ localTsap: 0x1000, remoteTsap: 0x1001 });
  });

  it('asks for the plcwire.read permission', () => {
    const source = fs.readFileSync(path.join(ROOT, 'nodes/connection.js'), 'utf8');
    const routes = source.match(/RED\.httpAdmin\.(get|post)\([^)]*\)/g) ?? [];
    expect(routes.length).to.equal(9);
    for (const r of routes) expect(r).to.include('canRead');
    expect(source).to.include("RED.auth.needsPermission('plcwire.read')");
  });
});

describe('nodes: examples', function () {
  this.timeout(10000);
  const dir = path.join(ROOT, 'examples');
  const files = fs.readdirSync(dir).filter((f) => f.endsWith('.json'));

  beforeEach(() => helper.startServer());
  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
  });

  it('has a flow per protocol and an error-handling flow, each starting with a Comment that says how to start the simulator', () => {
    expect(files.length).to.be.at.least(4);
    const urls = new Set<string>();
    for (const f of files) {
      const flow = JSON.parse(fs.readFileSync(path.join(dir, f), 'utf8'));
      expect(flow[0].type, f).to.equal('comment');
      // A flow by name reads the demo plant, whose simulator is built from the source its connection carries.
      expect(flow[0].name, f).to.match(/npx plcwire (serve (s7|fetchwrite|freeport)|demo)/);
      for (const n of flow) if (n.type === 'plcwire-connection') urls.add(n.url.split(':')[0]);
    }
    expect([...urls].sort()).to.deep.equal(['fetchwrite', 'freeport+tcp', 's7', 's7plus']);
  });

  for (const f of files) {
    it(`loads "${f}" and every address in it parses`, async () => {
      const flow = JSON.parse(fs.readFileSync(path.join(dir, f), 'utf8'));
      const tab = { id: 'ex.tab', type: 'tab', label: f };
      const wired = flow
        .filter(
          (n: any) =>
            ['plcwire-connection', 'plcwire-read', 'plcwire-write', 'plcwire-heartbeat', 'plcwire-control', 'comment'].includes(n.type) ||
            n.type === 'catch' ||
            n.type === 'status',
        )
        .map((n: any) => (n.type === 'plcwire-connection' ? n : { ...n, z: 'ex.tab', wires: (n.wires ?? []).map(() => []) }));
      await helper.load(
        ALL_NODES.concat(
          require(
            path.join(
              path.dirname(
                require.resolve('@node-red/nodes/package.json', {
                  paths: [path.dirname(require.resolve(process.env.PLCWIRE_NODE_RED || 'node-red'))],
                }),
              ),
              'core/common/90-comment.js',
            ),
          ),
        ),
        [tab, ...wired],
      );
      for (const n of wired.filter((x: any) => x.type.startsWith('plcwire-'))) expect(helper.getNode(n.id), n.id).to.be.ok;
      // Each connection with the addresses of the nodes that use it (an example may reach several PLCs).
      for (const conn of flow.filter((n: any) => n.type === 'plcwire-connection')) {
        const addresses = flow
          .filter((n: any) => n.connection === conn.id)
          .flatMap((n: any) => [...(n.tags ?? []).map((t: any) => t.address), n.writeAddress, n.watchAddress])
          .filter(Boolean);
        const sources = { symbolSources: conn.symbolSources, dbNumbers: conn.dbNumbers };
        const res = await helper
          .request()
          .post('/plcwire/validate')
          .send({ url: conn.url, addresses, ...sources })
          .expect(200);
        expect(res.body.url.ok, res.body.url.message).to.equal(true);
        if (conn.symbolSources) expect(res.body.symbols, JSON.stringify(res.body.symbols)).to.deep.equal({ ok: true });
        for (const a of addresses) expect(res.body.results[a].ok, `${conn.id} ${a}: ${res.body.results[a].message}`).to.equal(true);
      }
    });
  }
});
