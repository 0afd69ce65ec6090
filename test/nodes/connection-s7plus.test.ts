/**
 * The connection node on s7plus:// (issue #25): the password as a Node-RED
 * credential (handed to the client, in no flow export, in no error), and the
 * dialog's endpoints "Get certificate" (plcwire/s7plus/certificate) and
 * "Browse PLC" (plcwire/s7plus/browse), against the S7-1500 simulator
 * serving S7CommPlus over TLS on its PUT/GET port.
 */
import { expect } from 'chai';
import { S7Server } from '../../lib/s7/server';
import { S7PlusService } from '../../lib/s7plus/server';
import { generateCertificate } from '../../lib/s7plus/transport/cert';
import { DB_NUMBERS, SOURCES } from '../fixtures/s7plus';
import { loadCatalogs, withCatalog, type Catalogs, type Locale } from './catalogs';
import { ALL_NODES, helper, nodes, Recorder, until } from './support';

const SECRET = 'n0de-red-Secret!';

describe('nodes: the connection on s7plus:// (S7CommPlus)', function () {
  this.timeout(30000);
  let server: S7Server;
  let service: S7PlusService;
  let url: string;

  before(async () => {
    const cert = await generateCertificate();
    service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await server.listen();
    url = `s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=3000`;
  });
  after(async () => {
    await server?.close();
  });
  beforeEach(async () => {
    await helper.startServer();
  });
  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
  });

  describe('Get certificate', () => {
    it('takes the PLC certificate without trusting it (an unpinned URL) and closes before any session', async () => {
      await helper.load(ALL_NODES, []);
      const bare = `s7plus://127.0.0.1:${server.port}`;
      const res = await helper.request().post('/plcwire/s7plus/certificate').send({ url: bare }).expect(200);
      expect(res.body.ok, JSON.stringify(res.body)).to.equal(true);
      expect(res.body.fingerprint).to.equal(service.fingerprint!);
      // The bytes as TIA Portal shows them, for the dialog to join by colons (it holds no fingerprint rule).
      expect(res.body.bytes.join('')).to.equal(service.fingerprint!);
      expect(res.body.bytes)
        .to.have.length(32)
        .and.satisfy((bytes: string[]) => bytes.every((b) => /^[0-9A-F]{2}$/.test(b)));
      expect(res.body.subject).to.include('CN=plcwire simulator');
      expect(new Date(res.body.validTo).getTime()).to.be.greaterThan(Date.now());
      expect(new Date(res.body.validFrom).getTime()).to.be.lessThan(Date.now() + 60_000);
      await until(() => server.connectionCount === 0, 3000, `no connection left (have ${server.connectionCount})`);
    });

    it('a URL that is not s7plus://, a tls=false one and a PLC that is not there answer why, typed', async () => {
      await helper.load(ALL_NODES, []);
      const s7 = await helper
        .request()
        .post('/plcwire/s7plus/certificate')
        .send({ url: `s7://127.0.0.1:${server.port}` })
        .expect(200);
      expect(s7.body).to.include({ ok: false, code: 'INVALID_URL' });
      expect(s7.body.message).to.include('need an s7plus:// URL');
      const plain = await helper
        .request()
        .post('/plcwire/s7plus/certificate')
        .send({ url: `s7plus://127.0.0.1:${server.port}?tls=false` })
        .expect(200);
      expect(plain.body).to.include({ ok: false, code: 'INVALID_URL' });
      const off = await helper.request().post('/plcwire/s7plus/certificate').send({ url: 's7plus://127.0.0.1:1?timeout=1000' }).expect(200);
      expect(off.body.ok).to.equal(false);
      expect(off.body.code).to.be.a('string');
    });
  });

  describe('the password credential', () => {
    const flow = () => [
      { id: 'c1', type: 'plcwire-connection', name: 'press', url },
      { id: 'r1', type: 'plcwire-read', connection: 'c1', tags: [{ name: 'count', address: 'DB1.DBW4:INT' }], interval: 0 },
    ];

    it('is loaded as the node credential, and is in no flow export nor in the link status', async () => {
      await helper.load(ALL_NODES, flow(), { c1: { password: SECRET } });
      const conn = helper.getNode('c1');
      expect(conn.credentials.password).to.equal(SECRET);
      expect(conn.client, 'the pooled client').to.not.equal(undefined);
      expect(JSON.stringify(conn.linkStatus)).not.to.include(SECRET);
      // The flows as the runtime holds them for an export (the credentials are kept apart, encrypted in their own file).
      const exported = JSON.stringify(helper._redNodes.getFlows());
      expect(exported).to.include('"plcwire-connection"');
      expect(exported).not.to.include(SECRET);
      // The node type declares it a password credential: the editor never sends it back, an export never holds it.
      expect(helper._redNodes.getCredentialDefinition('plcwire-connection')).to.deep.equal({ password: { type: 'password' } });
    });

    it('without one the same connection reads', async () => {
      await helper.load(ALL_NODES, flow());
      const conn = helper.getNode('c1');
      await until(() => conn.linkStatus.state === 'connected', 10000, 'connected');
    });
  });

  describe('Browse PLC', () => {
    it('refuses a URL that is not s7plus://', async () => {
      await helper.load(ALL_NODES, []);
      const res = await helper.request().post('/plcwire/s7plus/browse').send({ url: 's7://127.0.0.1' }).expect(200);
      expect(res.body).to.include({ ok: false, code: 'INVALID_URL' });
    });

    it('answers the table in the shape of the sources compile (blocks, entries, types, errors)', async () => {
      await helper.load(ALL_NODES, []);
      const res = await helper.request().post('/plcwire/s7plus/browse').send({ url }).expect(200);
      expect(res.body.ok, JSON.stringify(res.body)).to.equal(true);
      expect(res.body).to.have.keys(['ok', 'blocks', 'entries', 'types', 'errors']);
      const step = res.body.entries.find((e: { name: string }) => e.name === '"Recipe".Step');
      expect(step).to.include({ type: 'INT', address: null });
      await until(() => server.connectionCount === 0, 3000, 'no connection left');
    });
  });

  describe('POST /plcwire/validate on s7plus:// (issue #31: BYTE for every name, typos included)', () => {
    const validate = (body: object) => helper.request().post('/plcwire/validate').send(body).expect(200);

    it('without sources and without a deployed connection: the PLC browsed, its type; a typo invalid with the closest names', async () => {
      await helper.load(ALL_NODES, []);
      const res = await validate({ url, addresses: ['"Recipe".Step', '"Recipe".Stepp', '"Recipe".Inlet', 'DB1.DBW4:INT'] });
      expect(res.body.url).to.deep.equal({ ok: true });
      expect(res.body.results['"Recipe".Step']).to.include({ ok: true, type: 'INT', kind: 'elementary' });
      expect(res.body.results['"Recipe".Inlet']).to.include({ ok: true, kind: 'struct' });
      const typo = res.body.results['"Recipe".Stepp'];
      expect(typo).to.include({ ok: false, code: 'INVALID_ADDRESS' });
      expect(typo.message).to.include('unknown symbol "Recipe".Stepp').and.include('"Recipe".Step');
      // An absolute address keeps the parser's answer.
      expect(res.body.results['DB1.DBW4:INT']).to.include({ ok: true, type: 'INT' });
      await until(() => server.connectionCount === 0, 3000, 'the browse made for the question closed its connection');
    });

    it("with the connection deployed: its client's table, no connection of the question's own", async () => {
      await helper.load(ALL_NODES, [
        { id: 'c1', type: 'plcwire-connection', name: 'press', url },
        { id: 'r1', type: 'plcwire-read', connection: 'c1', tags: [{ name: 'step', address: '"Recipe".Step' }], interval: 0 },
      ]);
      const conn = helper.getNode('c1');
      await until(() => conn.linkStatus.state === 'connected', 10000, 'connected');
      const before = server.connectionCount;
      const res = await validate({ url, addresses: ['"Recipe".Nope'] });
      expect(res.body.results['"Recipe".Nope']).to.include({ ok: false, code: 'INVALID_ADDRESS' });
      expect(res.body.results['"Recipe".Nope'].message).to.include('unknown symbol "Recipe".Nope');
      expect(server.connectionCount).to.equal(before);
    });

    it('a PLC that cannot be browsed: the name is not checked, and the answer says why instead of a type', async () => {
      await helper.load(ALL_NODES, []);
      const res = await validate({ url: 's7plus://127.0.0.1:1?timeout=1000', addresses: ['"Recipe".Step'] });
      const answer = res.body.results['"Recipe".Step'];
      expect(answer).to.include({ ok: true, type: '?' });
      expect(answer.unchecked).to.include('the PLC could not be browsed');
    });
  });

  describe('read and write nodes by name (no sources: the PLC browsed)', () => {
    it('a write node writes a member of the optimized block and a struct by name; a read node reads them back', async () => {
      const at = { z: 'tab', x: 100, y: 100 };
      await helper.load(ALL_NODES, [
        { id: 'tab', type: 'tab', label: 'plcwire' },
        { id: 'c1', type: 'plcwire-connection', name: 'press', url },
        { id: 'w1', type: 'plcwire-write', ...at, connection: 'c1', tags: [], wires: [['wout']] },
        { id: 'wout', type: 'helper', ...at },
        {
          id: 'r1',
          type: 'plcwire-read',
          ...at,
          connection: 'c1',
          interval: 0,
          output: 'object',
          tags: [
            { name: 'step', address: '"Recipe".Step' },
            { name: 'inlet', address: '"Recipe".Inlet' },
          ],
          wires: [['rout']],
        },
        { id: 'rout', type: 'helper', ...at },
      ]);
      const conn = helper.getNode('c1');
      await until(() => conn.linkStatus.state === 'connected', 10000, 'connected');
      const written = new Recorder(helper.getNode('wout'));
      helper.getNode('w1').receive({ payload: { '"Recipe".Step': 12, '"Recipe".Inlet': { Open: true, Position: 7 } } });
      const ack = await written.next(() => true, 10000, 'the write acknowledged');
      expect(
        Object.values(ack.results).every((r: any) => r.ok),
        JSON.stringify(ack.results),
      ).to.equal(true);
      const read = new Recorder(helper.getNode('rout'));
      helper.getNode('r1').receive({});
      const msg = await read.next(() => true, 10000, 'the read');
      expect(msg.payload).to.deep.equal({ step: 12, inlet: { Open: true, Position: 7 } });
    });
  });

  describe('a link that retries because waiting will not help says why (issue #31: "retry in 30 s")', () => {
    let catalogs: Catalogs;
    before(async () => {
      catalogs = await loadCatalogs();
    });
    const at = { z: 'tab', x: 100, y: 100 };
    /** The read node's modules with RED._ of the real catalog of `locale`. */
    const translated = (locale: Locale) =>
      ALL_NODES.map((m) => (m === nodes.read ? withCatalog(nodes.read, catalogs.translator(locale, 'plcwire-read')) : m));
    const flowTo = (target: string) => [
      { id: 'tab', type: 'tab', label: 'plcwire' },
      { id: 'c1', type: 'plcwire-connection', name: 'press', url: target },
      { id: 'r1', type: 'plcwire-read', ...at, connection: 'c1', tags: [{ name: 'step', address: '"Recipe".Step' }], interval: 0 },
      { id: 'catcher', type: 'catch', ...at, scope: null, uncaught: false, wires: [['caught']] },
      { id: 'caught', type: 'helper', ...at },
    ];
    /** Every status text the node has shown (the helper spies on the nodes' status()). */
    const shownBy = (node: any): string[] =>
      node.status
        .getCalls()
        .filter((c: { thisValue: unknown }) => c.thisValue === node)
        .map((c: { args: [{ text: string }] }) => c.args[0].text);
    const expected: Record<Locale, string> = { 'en-US': 'not trusted: pin it', de: 'Zertifikat pinnen', 'zh-CN': '证书不受信任：请固定' };

    for (const locale of ['en-US', 'de', 'zh-CN'] as const) {
      it(`${locale}: an unpinned certificate: the status says to pin it, Catch has the whole message with the fingerprint=`, async () => {
        const unpinned = `s7plus://127.0.0.1:${server.port}?timeout=3000`;
        await helper.load(translated(locale), flowTo(unpinned));
        const caught = new Recorder(helper.getNode('caught'));
        const read = helper.getNode('r1');
        const reported = await caught.next((m) => m.error.source.type === 'plcwire-connection', 10000, "the connection's error on Catch");
        await until(() => shownBy(read).includes(expected[locale]), 10000, `the status "${expected[locale]}"`);
        const shown = shownBy(read);
        expect(
          shown.some((t) => /retry|neu in|重连/.test(t)),
          shown.join(' | '),
        ).to.equal(false);
        expect(reported.payload).to.include({ code: 'CERTIFICATE_UNTRUSTED', url: unpinned });
        // The whole text, fingerprint to pin included, within what a Debug node shows uncut (debugMaxLength 1000).
        expect(reported.payload.message).to.include(`fingerprint=${service.fingerprint!}`);
        expect(reported.payload.message.length).to.be.lessThan(1000);
      });
    }

    it('a refused password: the status says so, in place of "retry in 30 s"', async () => {
      const cert = await generateCertificate();
      const plus = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key }, password: SECRET });
      const locked = new S7Server({ port: 0, profile: 's7-1500', s7plus: plus });
      await locked.listen();
      try {
        const target = `s7plus://127.0.0.1:${locked.port}?fingerprint=${plus.fingerprint!}&timeout=3000`;
        await helper.load(translated('en-US'), flowTo(target), { c1: { password: `${SECRET}-stale` } });
        const read = helper.getNode('r1');
        await until(
          () => shownBy(read).includes('password refused'),
          10000,
          `the status "password refused" (shown: ${shownBy(read).join(' | ')})`,
        );
        expect(
          shownBy(read).some((t) => t.startsWith('retry in')),
          shownBy(read).join(' | '),
        ).to.equal(false);
      } finally {
        await helper.unload();
        await locked.close();
      }
    });
  });

  describe('a PLC protected with a password (legitimation)', () => {
    let locked: S7Server;
    let lockedUrl: string;
    before(async () => {
      const cert = await generateCertificate();
      const plus = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key }, password: SECRET });
      locked = new S7Server({ port: 0, profile: 's7-1500', s7plus: plus });
      await locked.listen();
      lockedUrl = `s7plus://127.0.0.1:${locked.port}?fingerprint=${plus.fingerprint!}&timeout=3000`;
    });
    after(async () => {
      await locked?.close();
    });

    const at = { z: 'tab', x: 100, y: 100 };
    const flow = () => [
      { id: 'tab', type: 'tab', label: 'plcwire' },
      { id: 'c1', type: 'plcwire-connection', name: 'press', url: lockedUrl },
      { id: 'w1', type: 'plcwire-write', ...at, connection: 'c1', tags: [{ name: 'step', address: '"Recipe".Step' }], wires: [['wout']] },
      { id: 'wout', type: 'helper', ...at },
      { id: 'catcher', type: 'catch', ...at, scope: ['w1'], uncaught: false, wires: [['caught']] },
      { id: 'caught', type: 'helper', ...at },
    ];

    it('a write node through a connection whose password credential is set writes (the session legitimated)', async () => {
      await helper.load(ALL_NODES, flow(), { c1: { password: SECRET } });
      const conn = helper.getNode('c1');
      await until(() => conn.linkStatus.state === 'connected', 10000, 'connected');
      const written = new Recorder(helper.getNode('wout'));
      helper.getNode('w1').receive({ payload: { step: 41 } });
      const ack = await written.next(() => true, 10000, 'the write acknowledged');
      expect(ack.results, JSON.stringify(ack.results)).to.deep.equal({ step: { ok: true, address: '"Recipe".Step' } });
      expect(JSON.stringify(conn.linkStatus)).not.to.include(SECRET);
      expect(JSON.stringify(helper._redNodes.getFlows())).not.to.include(SECRET);
    });

    it('without it, the write fails on Catch with the read-only message and the ways to give the password', async () => {
      await helper.load(ALL_NODES, flow());
      const conn = helper.getNode('c1');
      await until(() => conn.linkStatus.state === 'connected', 10000, 'connected');
      const caught = new Recorder(helper.getNode('caught'));
      helper.getNode('w1').receive({ payload: { step: 42 } });
      const failed = await caught.next(() => true, 10000, 'the write refused on Catch');
      expect(failed.error.message).to.include('gives this connection read access only without its password');
      expect(failed.error.message).to.include("the connection node's password in Node-RED");
      expect(failed.results.step).to.include({ ok: false, code: 'ACCESS_DENIED' });
    });

    it('a wrong password credential: the link waits the longest delay with ACCESS_DENIED, and the error reaches Catch without the password', async () => {
      const wrong = `${SECRET}-stale`;
      // One Catch for the whole tab (the test helper registers a core node's type once): the connection's link errors go there.
      const flowWithCatch = flow().map((n) => (n.id === 'catcher' ? { ...n, scope: null } : n));
      await helper.load(ALL_NODES, flowWithCatch, { c1: { password: wrong } });
      const caught = new Recorder(helper.getNode('caught'));
      const conn = helper.getNode('c1');
      const reported = await caught.next((m) => m.error.source.type === 'plcwire-connection', 10000, "the connection's error on Catch");
      expect(reported.error.message).to.include('refused the password');
      await until(() => conn.linkStatus.state === 'reconnecting', 10000, 'reconnecting');
      const status = conn.linkStatus;
      expect(status.error.code).to.equal('ACCESS_DENIED');
      // The default backoff's longest delay, 30 s ± 20 %, where a transient fault waits half a second.
      expect(status.delay).to.be.at.least(24_000);
      const caughtText = JSON.stringify(caught.messages.map((m) => ({ ...m, error: { message: m.error.message } })));
      expect(caughtText + JSON.stringify(status) + String(status.error.message)).not.to.include(wrong);
    });

    it('Browse PLC with the password typed in the dialog legitimates; a wrong one answers ACCESS_DENIED without echoing it', async () => {
      await helper.load(ALL_NODES, []);
      const ok = await helper.request().post('/plcwire/s7plus/browse').send({ url: lockedUrl, password: SECRET }).expect(200);
      expect(ok.body.ok, JSON.stringify(ok.body)).to.equal(true);
      const wrong = `${SECRET}-typo`;
      const refused = await helper.request().post('/plcwire/s7plus/browse').send({ url: lockedUrl, password: wrong }).expect(200);
      expect(refused.body).to.include({ ok: false, code: 'ACCESS_DENIED' });
      expect(refused.body.message).to.include('refused the password');
      expect(JSON.stringify(refused.body)).not.to.include(wrong);
      await until(() => locked.connectionCount === 0, 3000, 'no connection left');
    });
  });
});
