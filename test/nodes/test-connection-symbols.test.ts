/**
 * Test connection with tag names (issue #23): the dialog sends its symbol
 * sources and DB numbers with the URL; the endpoint compiles them as the
 * connection node does at start and the doctor resolves each name as a read
 * does. The S7 simulator holds the demo plant's DB built from demo/Plant.db.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { loadCatalogs, withCatalog, type Translate } from './catalogs';
import { helper, nodes, ROOT, until } from './support';

const lib = require('../../lib/index');

const PLANT_DB = fs.readFileSync(path.join(ROOT, 'demo/Plant.db'), 'utf8');
/** As the dialog holds them: sources as text, DB numbers as rows. */
const SOURCES = [{ name: 'Plant.db', content: PLANT_DB }];
const DB_NUMBERS = [{ block: 'Plant', db: 1 }];

describe('nodes: Test connection with tag names (the dialog sends its symbol sources)', function () {
  this.timeout(20000);
  let server: any;
  let url: string;
  let t: Translate;

  beforeEach(async () => {
    const table = lib.compileSymbols([{ name: 'Plant.db', content: PLANT_DB }], { db: { Plant: 1 } });
    server = new lib.S7Server({ port: 0, profile: 's7-300', symbols: table });
    url = `s7://127.0.0.1:${await server.listen()}?rack=0&slot=2&timeout=2000`;
    const catalogs = await loadCatalogs();
    t = catalogs.translator('en-US', 'plcwire-connection');
    await helper.startServer();
    await helper.load([withCatalog(nodes.connection, t)], []);
  });

  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
    await server.close();
  });

  const doctor = (body: object) => helper.request().post('/plcwire/doctor').send(body).expect(200);

  it('reads a name by its address through the sources as the dialog holds them (it used to fail as "not an S7 address")', async () => {
    const res = await doctor({ url, addresses: ['"Plant".Level', 'DB1,INT4'], symbolSources: SOURCES, dbNumbers: DB_NUMBERS });
    expect(res.body.ok, JSON.stringify(res.body.steps)).to.equal(true);
    expect(res.body.steps.slice(-2)).to.deep.equal([
      {
        step: 'symbol "Plant".Level',
        ok: true,
        detail: '"Plant".Level is DB1.DBD0:REAL; DB1 exists, 20 bytes (block info); "Plant".Level = 20',
      },
      { step: 'address DB1,INT4', ok: true, detail: 'DB1 exists, 20 bytes (block info); DB1,INT4 = 0' },
    ]);
    await until(() => server.connectionCount === 0, 2000, 'no connection left');
  });

  it('an unknown name is its own failed step with the closest names', async () => {
    const res = await doctor({ url, addresses: ['"Plant".Levle'], symbolSources: SOURCES, dbNumbers: DB_NUMBERS });
    expect(res.body.ok).to.equal(false);
    const last = res.body.steps.at(-1);
    expect(last.step).to.equal('symbol "Plant".Levle');
    expect(last.detail).to.equal('unknown symbol "Plant".Levle; did you mean "Plant".Level?');
  });

  it('without sources a name says to give them', async () => {
    const res = await doctor({ url, addresses: ['"Plant".Level'] });
    const last = res.body.steps.at(-1);
    expect([last.step, last.ok]).to.deep.equal(['symbol "Plant".Level', false]);
    expect(last.hint).to.contain("the connection node's Symbol sources");
  });

  it('sources that do not compile: the addresses are still checked, and a symbols step names the file and line', async () => {
    const broken = [{ name: 'Plant.db', content: PLANT_DB.replace('MotorSpeed : Int;', 'MotorSpeed : Intt;') }];
    const res = await doctor({ url, addresses: ['"Plant".Level', 'DB1,INT4'], symbolSources: broken, dbNumbers: DB_NUMBERS });
    expect(res.body.ok).to.equal(false);
    const steps = res.body.steps.map((s: any) => [s.step, s.ok]);
    expect(steps.slice(-2)).to.deep.equal([
      ['address DB1,INT4', true],
      ['symbols', false],
    ]);
    const last = res.body.steps.at(-1);
    const problem = 'Plant.db:14:20: unknown type Intt for member MotorSpeed (did you mean INT?)';
    expect(last.detail).to.equal(
      t('plcwire-connection.doctor.sources', { problem }) + t('plcwire-connection.doctor.namesNotChecked', { names: '"Plant".Level' }),
    );
    expect(last.detail).to.equal(`the symbol sources do not compile: ${problem}; names not checked: "Plant".Level`);
    expect(last.hint).to.equal(t('plcwire-connection.doctor.sourcesHint')).and.contain('Symbol sources');
    await until(() => server.connectionCount === 0, 2000, 'no connection left');
  });
});
