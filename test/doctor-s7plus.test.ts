/**
 * The connection doctor on s7plus:// URLs (issue #25) against our simulator
 * of an S7-1500 and an S7-1200 (S7CommPlus over TLS on the PUT/GET port):
 * the walk tcp → cotp → InitSSL → TLS → session → password → identity →
 * browse → each name, a failure at each step in words with the later steps
 * not run, the URL that pins an unpinned certificate, and no connection left
 * on the simulator after any walk. The identity is the profile's, the same
 * PUT/GET's SZL gives.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as net from 'node:net';
import * as os from 'node:os';
import * as path from 'node:path';
import { diagnose, type DoctorReport, type DoctorStep } from '../lib/doctor';
import { createClient } from '../lib/connect';
import type { S7Client } from '../lib/s7/client';
import { S7Server, type S7Profile } from '../lib/s7/server';
import { S7PlusService } from '../lib/s7plus/server';
import { generateCertificate, type GeneratedCertificate } from '../lib/s7plus/transport/cert';
import { compileSymbols } from '../lib/symbols';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import type { S7PlusClient } from '../lib/s7plus/client';
import { requireS7CommPlus, startS7CommPlusServer, stopS7CommPlusPeers, type S7CommPlusPeerServer } from './support/s7commplus-peer';
import { until } from './support/wait';

const HANDSHAKE = ['tcp', 'cotp', 'InitSSL', 'TLS', 'session', 'password', 'identity', 'browse'];

const names = (r: DoctorReport) => r.steps.map((s) => s.step);
const by = (r: DoctorReport) => Object.fromEntries(r.steps.map((s) => [s.step, s])) as Record<string, DoctorStep>;

describe('doctor on s7plus:// (our simulator)', function () {
  this.timeout(30000);
  let cert: GeneratedCertificate;
  const servers: S7Server[] = [];

  async function simulator(
    profile: S7Profile = 's7-1500',
    served: GeneratedCertificate = cert,
  ): Promise<{ server: S7Server; url: string; fingerprint: string }> {
    const service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: served.cert, key: served.key } });
    const server = new S7Server({ port: 0, profile, s7plus: service });
    await server.listen();
    servers.push(server);
    return {
      server,
      url: `s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=5000`,
      fingerprint: service.fingerprint!,
    };
  }

  /** Every connection the walk opened is gone from the simulator. */
  const noConnections = (server: S7Server) => until(() => server.connectionCount === 0, 5000, 'the simulator to have no connection');

  before(async () => (cert = await generateCertificate({ commonName: 'plcwire doctor test' })));
  after(async () => {
    for (const s of servers) await s.close();
  });

  it('on s7:// an optimized block says to use s7plus:// with the URL to try: a name the sources mark optimized, an absolute address in it; that URL leads to the pin and the value', async () => {
    const { server, fingerprint } = await simulator();
    const s7url = `s7://127.0.0.1:${server.port}?slot=1&timeout=5000`;
    const symbols = compileSymbols(SOURCES, { db: DB_NUMBERS });
    const plusUrl = `s7plus://127.0.0.1:${server.port}`;
    const byName = await diagnose(s7url, ['"Recipe".Step'], { symbols });
    const named = byName.steps.at(-1)!;
    expect(named).to.include({ step: 'symbol "Recipe".Step', ok: false });
    expect(named.hint).to.contain(`plcwire doctor ${plusUrl} "<name>"`);
    const byAddress = await diagnose(s7url, ['DB2,INT0']);
    const address = byAddress.steps.at(-1)!;
    expect(address).to.include({ step: 'address DB2,INT0', ok: false });
    expect(address.detail).to.contain('probably an optimized DB');
    expect(address.hint).to.contain(`plcwire doctor ${plusUrl} `);
    // The URL of the hint: the TLS step shows the certificate and the URL that pins it, which reads the member.
    const first = await diagnose(plusUrl);
    const pin = /pin it: (s7plus:\/\/\S+)$/.exec(by(first).TLS!.hint!)![1]!;
    expect(pin).to.equal(`${plusUrl}?fingerprint=${fingerprint}`);
    const read = await diagnose(pin, ['"Recipe".Step']);
    expect(by(read)['symbol "Recipe".Step']!.detail).to.equal('"Recipe".Step = 3 (INT)');
    await noConnections(server);
  });

  it("the url step is the registry's: a URL that does not parse gets its scheme's hint, a protocol without a doctor the schemes that have one; each told to onStep, nothing connected", async () => {
    const told: DoctorStep[] = [];
    const plus = await diagnose('s7plus://127.0.0.1?password=x', [], { onStep: (s) => told.push(s) });
    expect(plus.ok).to.equal(false);
    expect(plus.steps.map((s) => s.step)).to.deep.equal(['url']);
    expect(plus.steps[0]!.hint).to.contain('s7plus://<host>');
    expect(plus.steps[0]!.detail).to.not.contain('=x');
    const s7 = await diagnose('s7://127.0.0.1?slot=99');
    expect(s7.steps[0]!.hint).to.contain('s7://<host>');
    const other = await diagnose('freeport+tcp://127.0.0.1:1');
    expect(other.steps[0]!.detail).to.equal('the doctor checks s7:// or s7plus:// connections; this URL is freeport');
    expect(told).to.deep.equal(plus.steps);
  });

  it('walks every step of a pinned connection and reads a name of the optimized DB, one of the standard DB and an address, each with its value and type', async () => {
    const { server, url, fingerprint } = await simulator();
    const seen: DoctorStep[] = [];
    const r = await diagnose(url, ['"Recipe".Step', '"Tank".Motor.Speed', 'DB1.DBW4:INT'], { onStep: (s) => seen.push(s) });
    expect(r.ok, JSON.stringify(r.steps, null, 1)).to.equal(true);
    expect(names(r)).to.deep.equal([...HANDSHAKE, 'symbol "Recipe".Step', 'symbol "Tank".Motor.Speed', 'address DB1.DBW4:INT']);
    expect(seen).to.deep.equal(r.steps);
    const s = by(r);
    expect(s.cotp!.detail).to.contain('"SIMATIC-ROOT-HMI"');
    expect(s.TLS!.detail).to.match(/^TLSv1\.[23]; the PLC's certificate matches the URL's fingerprint: SHA-256 /);
    expect(s.TLS!.detail).to.contain(fingerprint).and.contain('CN=plcwire doctor test');
    expect(s.session!.detail).to.match(/^S7CommPlus V2 with integrity ids, session id 0x[0-9a-f]+$/);
    expect(s.identity!.detail).to.equal('6ES7 516-3AN02-0AB0 firmware V3.1; in RUN');
    expect(s.browse!.detail).to.match(/^2 data blocks \(1 optimized, 1 standard\), \d+ entries$/);
    expect(s['symbol "Recipe".Step']!.detail).to.equal('"Recipe".Step = 3 (INT)');
    expect(s['symbol "Tank".Motor.Speed']!.detail).to.equal('"Tank".Motor.Speed = 1500 (DINT)');
    expect(s['address DB1.DBW4:INT']!.detail).to.equal('DB1.DBW4:INT = 7 (INT)');
    await noConnections(server);
  });

  it('tells the identity PUT/GET tells for the profile: an S7-1200 with its order code and firmware, and in STOP with a hint', async () => {
    const { server, url } = await simulator('s7-1200');
    const s7 = createClient(`s7://127.0.0.1:${server.port}?slot=1`) as S7Client;
    await s7.connect();
    const info = await s7.info();
    await s7.close();
    server.stop();
    const r = await diagnose(url);
    const identity = by(r).identity!;
    expect(identity.detail).to.equal(`${info.orderCode!} firmware ${info.firmware!.replace(/\.\d+$/, '')}; in STOP`);
    expect(identity.detail).to.equal('6ES7 214-1AG40-0XB0 firmware V4.7; in STOP');
    expect(identity.hint).to.contain('STOP');
    expect(r.ok).to.equal(true);
    await noConnections(server);
  });

  it('an unpinned certificate fails the TLS step with the certificate shown and the URL that pins it; that URL then passes', async () => {
    const { server, url, fingerprint } = await simulator();
    const unpinned = url.replace(/fingerprint=[0-9A-F]+&/, '');
    const r = await diagnose(unpinned, ['"Recipe".Step']);
    expect(r.ok).to.equal(false);
    expect(names(r)).to.deep.equal(['tcp', 'cotp', 'InitSSL', 'TLS']);
    const tls = by(r).TLS!;
    expect(tls.ok).to.equal(false);
    expect(tls.detail)
      .to.contain(`SHA-256 ${fingerprint}`)
      .and.contain('CN=plcwire doctor test')
      .and.match(/valid \d{4}-/);
    const tryUrl = /pin it: (s7plus:\/\/\S+)$/.exec(tls.hint!)![1]!;
    expect(tryUrl).to.contain(`fingerprint=${fingerprint}`);
    await noConnections(server);
    const again = await diagnose(tryUrl, ['"Recipe".Step']);
    expect(again.ok, JSON.stringify(again.steps)).to.equal(true);
    await noConnections(server);
  });

  it('ca=: a certificate the CA signed passes the TLS step saying so; another CA, a wrong pin and an expired certificate fail it with what to do', async () => {
    const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'doctor-s7plus-ca-'));
    try {
      const ca = await generateCertificate({ commonName: 'TIA project CA', ca: true });
      const other = await generateCertificate({ commonName: 'another CA', ca: true });
      const caFile = path.join(dir, 'ca.pem');
      const otherFile = path.join(dir, 'other.pem');
      fs.writeFileSync(caFile, ca.cert);
      fs.writeFileSync(otherFile, other.cert);
      const leaf = await generateCertificate({ commonName: 'PLC_2', issuer: ca, hosts: ['127.0.0.1'] });
      const { server, url, fingerprint } = await simulator('s7-1500', leaf);
      const base = url.replace(/fingerprint=[0-9A-F]+&/, '');
      const signed = await diagnose(`${base}&ca=${encodeURIComponent(caFile)}`);
      expect(signed.ok, JSON.stringify(signed.steps)).to.equal(true);
      expect(by(signed).TLS!.detail).to.contain('is signed by the CA of ca=').and.contain('CN=PLC_2');
      const foreign = await diagnose(`${base}&ca=${encodeURIComponent(otherFile)}`);
      expect(names(foreign).at(-1)).to.equal('TLS');
      expect(by(foreign).TLS!.detail).to.contain('(not-signed-by-ca)');
      expect(by(foreign).TLS!.hint).to.contain('ca=FILE').and.contain(`fingerprint=${fingerprint}`);
      const wrongPin = await diagnose(url.replace(/fingerprint=[0-9A-F]+/, `fingerprint=${'AB'.repeat(32)}`));
      expect(by(wrongPin).TLS!.detail).to.contain('(wrong-pin)').and.contain(`SHA-256 ${fingerprint}`);
      expect(by(wrongPin).TLS!.hint).to.contain(`fingerprint=${fingerprint}`);
      await noConnections(server);

      const old = await generateCertificate({ notBefore: new Date('2020-01-01'), notAfter: new Date('2021-01-01') });
      const expired = await simulator('s7-1500', old);
      const r = await diagnose(expired.url);
      expect(by(r).TLS!.detail).to.contain('(expired)');
      expect(by(r).TLS!.hint).to.contain('Renew');
      await noConnections(expired.server);
    } finally {
      fs.rmSync(dir, { recursive: true, force: true });
    }
  });

  it('insecure=true passes the TLS step with a hint that gives the URL pinning the certificate it took unchecked', async () => {
    const { server, url, fingerprint } = await simulator();
    const r = await diagnose(url.replace(/fingerprint=[0-9A-F]+/, 'insecure=true'));
    const tls = by(r).TLS!;
    expect(tls.ok).to.equal(true);
    expect(tls.detail).to.contain('was accepted unchecked (insecure=true)');
    expect(tls.hint).to.contain(`fingerprint=${fingerprint}`).and.not.contain('insecure=true&');
    await noConnections(server);
  });

  it('an unknown name fails its step with the closest names; the names after it are not read', async () => {
    const { server, url } = await simulator();
    const r = await diagnose(url, ['"Recipe".Stepp', '"Tank".Count']);
    expect(names(r)).to.deep.equal([...HANDSHAKE, 'symbol "Recipe".Stepp']);
    const step = by(r)['symbol "Recipe".Stepp']!;
    expect(step.ok).to.equal(false);
    expect(step.detail).to.contain('"Recipe".Step');
    expect(step.hint).to.contain('plcwire browse');
    await noConnections(server);
  });

  it('tls=false against a CPU with secure communication fails at the session, saying to drop tls=false', async () => {
    const { server, url } = await simulator();
    const r = await diagnose(url.replace(/fingerprint=[0-9A-F]+/, 'tls=false'));
    expect(r.ok).to.equal(false);
    const last = r.steps.at(-1)!;
    expect(names(r)).to.deep.equal(['tcp', 'cotp', 'InitSSL', 'TLS', 'session']);
    expect(by(r).TLS!.detail).to.contain('tls=false');
    expect(last.ok).to.equal(false);
    expect(last.hint).to.contain('drop tls=false');
    await noConnections(server);
  });

  it('a CPU without S7CommPlus (an S7-300) takes the connection request but closes at InitSSL: the step says to use s7://', async () => {
    const server = new S7Server({ port: 0, profile: 's7-300' });
    await server.listen();
    servers.push(server);
    const r = await diagnose(`s7plus://127.0.0.1:${server.port}?insecure=true&timeout=3000`);
    expect(names(r)).to.deep.equal(['tcp', 'cotp', 'InitSSL']);
    expect(by(r).cotp!.detail).to.contain('SIMATIC-ROOT-HMI');
    expect(by(r).InitSSL!.ok).to.equal(false);
    expect(by(r).InitSSL!.detail).to.contain('closed the connection at InitSSL');
    expect(by(r).InitSSL!.hint).to.contain('use s7://');
    await noConnections(server);
  });

  it('a closed port fails the tcp step (ECONNREFUSED); a port that accepts and stays silent fails the cotp step within the deadline', async () => {
    const probe = net.createServer();
    await new Promise<void>((resolve) => probe.listen(0, '127.0.0.1', resolve));
    const port = (probe.address() as net.AddressInfo).port;
    await new Promise<void>((resolve) => probe.close(() => resolve()));
    const refused = await diagnose(`s7plus://127.0.0.1:${port}?insecure=true&timeout=3000`);
    expect(names(refused)).to.deep.equal(['tcp']);
    expect(by(refused).tcp!.detail).to.contain('ECONNREFUSED');

    const sockets = new Set<net.Socket>();
    // Reads (and drops) what comes, so that it sees the client close its end.
    const silent = net.createServer((s) => (sockets.add(s), s.resume(), s.on('close', () => sockets.delete(s))));
    await new Promise<void>((resolve) => silent.listen(0, '127.0.0.1', resolve));
    try {
      const r = await diagnose(`s7plus://127.0.0.1:${(silent.address() as net.AddressInfo).port}?insecure=true&timeout=800`, [], {
        timeout: 5000,
      });
      expect(r.ok).to.equal(false);
      expect(names(r)).to.deep.equal(['tcp', 'cotp']);
      expect(by(r).tcp!.ok).to.equal(true);
      expect(by(r).cotp!.detail).to.contain('nothing answered the connection request');
      expect(by(r).cotp!.hint).to.contain('not an S7 PLC');
      await until(() => sockets.size === 0, 5000, 'the silent server to have no connection');
    } finally {
      silent.close();
    }
  });

  it("a password is the client's: never in a step, a hint or the JSON of the report", async () => {
    const { server, url } = await simulator();
    const secret = 'Sw0rdfish-not-in-reports';
    const r = await diagnose(url, ['"Recipe".Step'], { password: secret });
    expect(JSON.stringify(r)).to.not.contain(secret);
    expect(names(r)).to.include('password');
    await noConnections(server);
  });

  it('a CPU protected with a password: the right one passes the password step with the access it gives, a wrong one fails there and the later steps are not run', async () => {
    const secret = 'Sw0rdfish-protected-cpu';
    const service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key }, password: secret });
    const server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await server.listen();
    servers.push(server);
    const url = `s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=5000`;
    const good = await diagnose(url, ['"Recipe".Step'], { password: secret });
    expect(names(good)).to.deep.equal([...HANDSHAKE, 'symbol "Recipe".Step']);
    expect(by(good).password).to.include({ ok: true });
    expect(by(good).password!.detail).to.equal('the PLC took the password (new legitimation): the session has full access');
    const bad = await diagnose(url, ['"Recipe".Step'], { password: 'not-the-password' });
    expect(names(bad)).to.deep.equal(['tcp', 'cotp', 'InitSSL', 'TLS', 'session', 'password']);
    expect(by(bad).password).to.include({ ok: false });
    expect(by(bad).password!.detail).to.contain('refused the password');
    expect(JSON.stringify([good, bad]))
      .to.not.contain(secret)
      .and.to.not.contain('not-the-password');
    await noConnections(server);
  });

  it('rejects with ABORTED when the caller aborts, and leaves no connection', async () => {
    const { server, url } = await simulator();
    const stop = new AbortController();
    const walk = diagnose(url, ['"Recipe".Step'], { signal: stop.signal, onStep: (s) => s.step === 'cotp' && stop.abort() });
    let code: string | undefined;
    try {
      await walk;
    } catch (err) {
      code = (err as { code?: string }).code;
    }
    expect(code).to.equal('ABORTED');
    await noConnections(server);
  });
});

describe('doctor and info() on s7plus:// against the s7commplus emulator (an independent peer)', function () {
  this.timeout(60_000);
  let python: string;
  let peer: S7CommPlusPeerServer;
  let cert: GeneratedCertificate;
  let dir: string;

  before(async function () {
    python = requireS7CommPlus(this);
    cert = await generateCertificate({ commonName: 'plcwire emulator PLC' });
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'doctor-s7plus-'));
    const files = { cert: path.join(dir, 'cert.pem'), key: path.join(dir, 'key.pem') };
    fs.writeFileSync(files.cert, cert.cert);
    fs.writeFileSync(files.key, cert.key);
    peer = await startS7CommPlusServer(python, {
      dbs: [{ number: 1, size: 16, variables: { temperature: ['Real', 0] } }],
      tls: files,
      version: 1,
    });
    await peer.write(1, 0, Buffer.from([0x41, 0xac, 0, 0]));
  });
  after(async () => {
    await stopS7CommPlusPeers();
    if (dir) fs.rmSync(dir, { recursive: true, force: true });
  });

  it('info(): the state, protocol version and certificate; no order code or firmware from a session version without a device string', async () => {
    const client = createClient(`s7plus://127.0.0.1:${peer.port}?fingerprint=${cert.fingerprint}&timeout=5000`) as S7PlusClient;
    await client.connect();
    try {
      const info = await client.info();
      expect(info).to.deep.include({ orderCode: undefined, firmware: undefined, device: undefined, state: 'RUN', protocolVersion: 2 });
      expect(info.certificate!.fingerprint).to.equal(cert.fingerprint.toUpperCase());
    } finally {
      await client.close();
    }
  });

  it('the walk passes to the browse, which says the PLC gives no type information, and reads an address of its DB', async () => {
    const r = await diagnose(`s7plus://127.0.0.1:${peer.port}?fingerprint=${cert.fingerprint}&timeout=5000`, ['DB1.DBD0:REAL']);
    expect(r.ok, JSON.stringify(r.steps, null, 1)).to.equal(true);
    expect(names(r)).to.deep.equal([...HANDSHAKE, 'address DB1.DBD0:REAL']);
    expect(by(r).identity!.detail).to.equal('the CPU does not say what it is (no device string in its session); in RUN');
    expect(by(r).browse!.detail).to.equal('1 data block (0 optimized, 0 standard, 1 without type information), 0 entries');
    expect(by(r).browse!.hint).to.contain('no type information');
    expect(by(r)['address DB1.DBD0:REAL']!.detail).to.equal('DB1.DBD0:REAL = 21.5 (REAL)');
    await peer.waitForNoClients(10_000);
  });
});
