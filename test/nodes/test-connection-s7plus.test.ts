/**
 * Test connection (POST plcwire/doctor) of an s7plus:// connection (issue
 * #25): the S7CommPlus walk on the runtime against the S7-1500 simulator,
 * with the password typed in the dialog or the deployed node's credential
 * (by id), which no answer carries; no connection left.
 */
import { expect } from 'chai';
import { S7Server } from '../../lib/s7/server';
import { S7PlusService } from '../../lib/s7plus/server';
import { generateCertificate } from '../../lib/s7plus/transport/cert';
import { DB_NUMBERS, SOURCES } from '../fixtures/s7plus';
import { ALL_NODES, helper, until } from './support';

const SECRET = 'd0ctor-Secret!';

describe('nodes: Test connection on s7plus:// (the S7CommPlus doctor)', function () {
  this.timeout(30000);
  let server: S7Server;
  let url: string;

  before(async () => {
    const cert = await generateCertificate();
    const service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await server.listen();
    url = `s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=3000`;
  });
  after(async () => {
    await server?.close();
  });
  beforeEach(() => helper.startServer());
  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
  });

  const doctor = async (body: object) => (await helper.request().post('/plcwire/doctor').send(body).expect(200)).body;
  const password = (r: { steps: { step: string; ok: boolean; detail: string }[] }) => r.steps.find((s) => s.step === 'password');

  it('walks TLS, session, identity and browse, and reads the names given, without a password', async () => {
    await helper.load(ALL_NODES, []);
    const r = await doctor({ url, addresses: ['"Recipe".Step', 'DB1.DBW4:INT'] });
    expect(r.ok, JSON.stringify(r.steps)).to.equal(true);
    expect(r.steps.map((s: { step: string }) => s.step)).to.deep.equal([
      'tcp',
      'cotp',
      'InitSSL',
      'TLS',
      'session',
      'password',
      'identity',
      'browse',
      'symbol "Recipe".Step',
      'address DB1.DBW4:INT',
    ]);
    expect(password(r)!.detail).to.match(/^none given/);
    await until(() => server.connectionCount === 0, 3000, 'no connection left');
  });

  it("takes the password typed in the dialog, else the deployed node's credential (by id); no answer carries it", async () => {
    await helper.load(ALL_NODES, [{ id: 'c1', type: 'plcwire-connection', name: 'press', url }], { c1: { password: SECRET } });
    const typed = await doctor({ url, password: `${SECRET}-typed` });
    const stored = await doctor({ url, id: 'c1' });
    // The placeholder the editor sends for a stored credential is not a password: the credential is used.
    const placeholder = await doctor({ url, id: 'c1', password: '__PWRD__' });
    for (const r of [typed, stored, placeholder]) {
      expect(JSON.stringify(r)).to.not.contain(SECRET);
      expect(password(r)!.detail, JSON.stringify(r.steps)).to.not.match(/^none given/);
    }
    // An s7:// URL never takes the credential: its doctor has no password step.
    const s7 = await doctor({ url: `s7://127.0.0.1:${server.port}?slot=1&timeout=3000`, id: 'c1' });
    expect(JSON.stringify(s7)).to.not.contain(SECRET);
    expect(password(s7)).to.equal(undefined);
    await until(() => server.connectionCount === 0, 3000, 'no connection left');
  });
});
