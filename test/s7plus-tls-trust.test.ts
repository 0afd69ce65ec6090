/**
 * lib/s7plus/transport/trust.ts, handshake.ts and server-tls.ts: what our
 * client offers in its ClientHello, whom it trusts (pin, CA file, insecure)
 * and how it refuses everything else before any S7CommPlus byte; hostile and
 * silent peers; the simulator's certificate files. After every test the
 * server counts 0 open connections.
 */
import { expect } from 'chai';
import * as crypto from 'node:crypto';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import * as tls from 'node:tls';
import { generateCertificate, type GeneratedCertificate } from '../lib/s7plus/transport/cert';
import { startTls, tlsFailure, type SecureChannel } from '../lib/s7plus/transport/handshake';
import { acceptTls, loadServerCertificate } from '../lib/s7plus/transport/server-tls';
import { CertificateError, parseFingerprint, type TlsTrust } from '../lib/s7plus/transport/trust';
import { FrameReader } from '../lib/link/framer';
import { checkTpkt } from '../lib/iso/tpkt';
import { tunnelPair } from './support/s7plus-tls';
import { until, waitFor } from './support/wait';

type Pair = Awaited<ReturnType<typeof tunnelPair>>;

/** Every pair a test opened, closed after it even when an assertion failed half-way. */
const opened: Pair[] = [];
async function pairFor(...args: Parameters<typeof tunnelPair>): Promise<Pair> {
  const pair = await tunnelPair(...args);
  opened.push(pair);
  return pair;
}

/** A pair whose server side runs Node TLS with `cert` (and extra server options); the client side is left to startTls. */
async function servedPair(cert: GeneratedCertificate, serverOptions: tls.TlsOptions = {}) {
  const pair = await pairFor();
  const serverTls = new tls.TLSSocket(pair.serverTunnel!, { isServer: true, cert: cert.cert, key: cert.key, ...serverOptions });
  const received: Buffer[] = [];
  serverTls.on('data', (d: Buffer) => received.push(d));
  serverTls.on('error', () => {});
  return { ...pair, serverTls, received };
}

/**
 * Waits until the server counts 0 open connections by the code under test
 * alone (every test ends its connection: a refusal, a timeout, or the test's
 * end() or destroy() of the TLS socket), then closes the test's server.
 * `clientSide`: the client's code ran and must have closed its socket too.
 */
async function closed(pair: Pair, clientSide = true): Promise<void> {
  const deadline = Date.now() + 5000;
  let open = await pair.srv.open();
  while (open > 0 && Date.now() < deadline) {
    await new Promise((r) => setImmediate(r));
    open = await pair.srv.open();
  }
  expect(open, 'connections left open at the server').to.equal(0);
  if (clientSide) expect(pair.client.destroyed, 'the client socket is closed').to.equal(true);
  await pair.close();
}

const connect = (pair: Pair, trust: TlsTrust, timeout = 10000, signal?: AbortSignal): Promise<SecureChannel> =>
  startTls(pair.clientTunnel, { trust, host: '127.0.0.1', timeout, ...(signal ? { signal } : {}) });

const withColons = (hex: string) => hex.toLowerCase().match(/../g)!.join(':');

describe('s7plus transport: TLS trust and handshake', function () {
  this.timeout(30000);
  let plc: GeneratedCertificate;
  let dir: string;
  before(async () => {
    plc = await generateCertificate({ commonName: 'PLC_1' });
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-trust-'));
  });
  after(() => fs.rmSync(dir, { recursive: true, force: true }));
  afterEach(async () => {
    for (const pair of opened.splice(0)) await pair.close();
  });

  describe('fingerprint= values', () => {
    it('accepts 64 hex digits with colons, spaces and either case', () => {
      const hex = 'AB'.repeat(32);
      expect(parseFingerprint(hex.toLowerCase())).to.equal(hex);
      expect(parseFingerprint(withColons(hex))).to.equal(hex);
      expect(parseFingerprint(` ${withColons(hex).toUpperCase()} `)).to.equal(hex);
    });

    it('refuses other shapes with INVALID_URL saying what a fingerprint is', () => {
      const cases: Array<[string, RegExp]> = [
        ['AB'.repeat(31), /has 62 hex digits/],
        ['AB'.repeat(20), /has 40 hex digits \(a SHA-1 fingerprint\?\)/],
        [`${'AB'.repeat(31)}AG`, /"G" is not a hex digit/],
        ['', /has 0 hex digits/],
      ];
      for (const [value, why] of cases) {
        const err = (() => {
          try {
            parseFingerprint(value);
          } catch (e) {
            return e as Error & { code?: string };
          }
          throw new Error(`accepted ${value}`);
        })();
        expect(err.code, value).to.equal('INVALID_URL');
        expect(err.message).to.match(why).and.include('fingerprint=').and.include('64 hex digits');
      }
    });
  });

  it('offers TLS 1.3 and 1.2, the S7 suites, X25519 and P-256 only, no tickets, no encrypt-then-MAC, no extended master secret', async () => {
    const pair = await pairFor(0x0a, true);
    const hello = waitFor<Buffer>(pair.server, 'data');
    pair.server.resume();
    const refused = connect(pair, { insecure: true }, 5000).catch((e) => e);
    const frame = await hello;
    const ch = parseClientHello(frame.subarray(7));
    expect(ch.versions).to.include.members([0x0304, 0x0303]);
    expect(ch.versions).to.not.include(0x0302);
    expect(ch.groups).to.deep.equal([0x001d, 0x0017]); // x25519, secp256r1
    expect(ch.extensions).to.not.include(35, 'session_ticket');
    expect(ch.extensions).to.not.include(22, 'encrypt_then_mac');
    expect(ch.extensions).to.not.include(23, 'extended_master_secret');
    // ECDHE-RSA-AES128/256-GCM, AES128/256-GCM, AES128/256-SHA256 (RFC 5288, RFC 5246), and the TLS 1.3 suites.
    expect(ch.suites).to.include.members([0xc02f, 0xc030, 0x009c, 0x009d, 0x003c, 0x003d, 0x1301, 0x1302]);
    // Six TLS 1.2 suites and nothing else (0x00FF is the renegotiation-info signal of RFC 5746, not a suite).
    expect(ch.suites.filter((s) => (s < 0x1300 || s > 0x13ff) && s !== 0x00ff)).to.have.length(6);
    pair.server.destroy();
    expect((await refused).code).to.equal('CONNECT_FAILED');
    await closed(pair);
  });

  it('refuses a certificate nothing vouches for, showing its fingerprint, subject, validity and the fingerprint= that pins it', async () => {
    const pair = await servedPair(plc);
    const err = await connect(pair, {}).catch((e) => e);
    expect(err).to.be.instanceOf(CertificateError);
    expect(err.code).to.equal('CERTIFICATE_UNTRUSTED');
    expect(err.problem).to.equal('not-trusted');
    expect(err.pin).to.equal(`fingerprint=${plc.fingerprint}`);
    const x = new crypto.X509Certificate(plc.cert);
    expect(err.message)
      .to.include(`add fingerprint=${plc.fingerprint} to the URL`)
      .and.include('CN=PLC_1')
      .and.include('self-signed')
      .and.include(`valid from ${new Date(x.validFrom).toISOString().slice(0, 19)}Z to ${new Date(x.validTo).toISOString().slice(0, 19)}Z`);
    expect(pair.received, 'nothing reached the server inside TLS').to.have.length(0);
    await closed(pair);
  });

  it('refuses a wrong pin in its own words, naming the pinned and the shown fingerprints', async () => {
    const pair = await servedPair(plc);
    const other = 'CD'.repeat(32);
    const err = await connect(pair, { fingerprint: withColons(other) }).catch((e) => e);
    expect(err.code).to.equal('CERTIFICATE_UNTRUSTED');
    expect(err.problem).to.equal('wrong-pin');
    expect(err.message)
      .to.include(`fingerprint= says ${other}`)
      .and.include(`SHA-256 ${plc.fingerprint}`)
      .and.include('is not the pinned one');
    expect(err.message).to.include(`pin the new one with fingerprint=${plc.fingerprint}`);
    expect(pair.received).to.have.length(0);
    await closed(pair);
  });

  for (const version of ['TLSv1.2', 'TLSv1.3'] as const) {
    it(`accepts the right pin written with colons in lower case (${version} server), and data flows`, async () => {
      const pair = await servedPair(plc, { maxVersion: version });
      const channel = await connect(pair, { fingerprint: withColons(plc.fingerprint) });
      expect(channel.protocol).to.equal(version);
      expect(channel.certificate.fingerprint).to.equal(plc.fingerprint);
      expect(channel.warning).to.equal(undefined);
      channel.socket.write('hello');
      await until(() => Buffer.concat(pair.received).toString() === 'hello', 5000, 'data at the server');
      channel.socket.end();
      await waitFor(channel.socket, 'close', 5000);
      await closed(pair);
    });
  }

  describe('ca= file', () => {
    let ca: GeneratedCertificate;
    let leaf: GeneratedCertificate;
    let caFile: string;
    before(async () => {
      ca = await generateCertificate({ commonName: 'TIA project CA', ca: true });
      leaf = await generateCertificate({ commonName: 'PLC_2', issuer: ca, hosts: ['127.0.0.1'] });
      caFile = path.join(dir, 'ca.pem');
      fs.writeFileSync(caFile, ca.cert);
    });

    it('trusts a certificate the CA signed for this address', async () => {
      const pair = await servedPair(leaf);
      const channel = await connect(pair, { ca: caFile });
      expect(channel.certificate.subject).to.include('CN=PLC_2');
      expect(channel.certificate.issuer).to.include('CN=TIA project CA');
      channel.socket.destroy();
      await closed(pair);
    });

    it('refuses a certificate the CA did not sign, and one it signed for another name', async () => {
      const pair = await servedPair(plc);
      const err = await connect(pair, { ca: caFile }).catch((e) => e);
      expect(err.code).to.equal('CERTIFICATE_UNTRUSTED');
      expect(err.problem).to.equal('not-signed-by-ca');
      expect(err.message).to.include(`not signed by the CA in ca=${caFile}`).and.include(`pin it with fingerprint=${plc.fingerprint}`);
      await closed(pair);
      const elsewhere = await generateCertificate({ commonName: 'PLC_3', issuer: ca, hosts: ['10.1.2.3'] });
      const pair2 = await servedPair(elsewhere);
      const err2 = await connect(pair2, { ca: caFile }).catch((e) => e);
      expect(err2.problem).to.equal('wrong-name');
      expect(err2.message).to.include('IP Address:10.1.2.3').and.include('not 127.0.0.1');
      expect(pair2.received).to.have.length(0);
      await closed(pair2);
    });

    it('names a ca= file it cannot use, before connecting', async () => {
      const pair = await pairFor();
      const missing = path.join(dir, 'nope.pem');
      const err = await connect(pair, { ca: missing }).catch((e) => e);
      expect(err.code).to.equal('INVALID_URL');
      expect(err.message).to.include(`ca=${missing}`).and.include('ENOENT');
      await closed(pair);
      const notPem = path.join(dir, 'not.pem');
      fs.writeFileSync(notPem, 'hello');
      const pair2 = await pairFor();
      const err2 = await connect(pair2, { ca: notPem }).catch((e) => e);
      expect(err2.message).to.include(`ca=${notPem}: the file holds no PEM certificate`);
      await closed(pair2);
    });
  });

  it('refuses an expired certificate, and one not yet valid, even when pinned', async () => {
    const expired = await generateCertificate({ notBefore: new Date('2015-01-01T00:00:00Z'), notAfter: new Date('2020-01-01T00:00:00Z') });
    const pair = await servedPair(expired);
    const err = await connect(pair, { fingerprint: expired.fingerprint }).catch((e) => e);
    expect(err.code).to.equal('CERTIFICATE_UNTRUSTED');
    expect(err.problem).to.equal('expired');
    expect(err.message).to.include('expired on 2020-01-01T00:00:00Z').and.include("this computer's clock says");
    expect(pair.received).to.have.length(0);
    await closed(pair);
    const future = await generateCertificate({ notBefore: new Date('2090-01-01T00:00:00Z'), notAfter: new Date('2095-01-01T00:00:00Z') });
    const pair2 = await servedPair(future);
    const err2 = await connect(pair2, { fingerprint: future.fingerprint }).catch((e) => e);
    expect(err2.problem).to.equal('not-yet-valid');
    expect(err2.message).to.include('is not valid before 2090-01-01T00:00:00Z');
    await closed(pair2);
  });

  it('with insecure=true accepts anything and warns on every connect, naming the certificate', async () => {
    const expired = await generateCertificate({ notBefore: new Date('2015-01-01Z'), notAfter: new Date('2016-01-01Z') });
    for (let i = 0; i < 2; i++) {
      const pair = await servedPair(expired);
      const channel = await connect(pair, { insecure: true });
      expect(channel.warning, `connect ${i + 1}`)
        .to.be.a('string')
        .and.include('insecure=true')
        .and.include(`SHA-256 ${expired.fingerprint}`)
        .and.include(`use fingerprint=${expired.fingerprint}`);
      channel.socket.destroy();
      await closed(pair);
    }
    // A pin given beside insecure=true is still honoured.
    const pair = await servedPair(expired);
    const err = await connect(pair, { insecure: true, fingerprint: 'CD'.repeat(32) }).catch((e) => e);
    expect(err.problem).to.equal('wrong-pin');
    await closed(pair);
  });

  it('fails with CONNECT_FAILED and the alert when the PLC accepts none of the suites offered', async () => {
    const pair = await servedPair(plc, { maxVersion: 'TLSv1.2', ciphers: 'ECDHE-RSA-CHACHA20-POLY1305' });
    const err = await connect(pair, { fingerprint: plc.fingerprint }).catch((e) => e);
    expect(err.code).to.equal('CONNECT_FAILED');
    expect(err.message).to.include('alert from the PLC').and.include('handshake failure').and.include('none of the TLS versions or suites');
    await closed(pair);
  });

  it('times out with a TIMEOUT error on a peer that stops in the middle of the handshake; only TLS records were sent', async () => {
    const pair = await pairFor(0x0a, true);
    const seen: Buffer[] = [];
    pair.server.on('data', (d: Buffer) => seen.push(d)); // reads the ClientHello, never answers
    pair.server.resume();
    const started = process.hrtime.bigint();
    const err = await connect(pair, { fingerprint: plc.fingerprint }, 400).catch((e) => e);
    const elapsed = Number(process.hrtime.bigint() - started) / 1e6;
    expect(err.code).to.equal('TIMEOUT');
    expect(err.message).to.include('did not complete within 400 ms');
    expect(elapsed).to.be.at.least(390);
    await until(() => pair.server.destroyed || pair.server.readableEnded, 5000, 'the server sees the client go');
    // What the server got is DT frames of TLS handshake records (0x16), never S7CommPlus in clear (0x72).
    const frames = new FrameReader(checkTpkt).push(Buffer.concat(seen));
    expect(frames.length).to.be.at.least(1);
    const payload = Buffer.concat(frames.map((f) => f.subarray(7)));
    expect(payload[0]).to.equal(0x16);
    expect(payload.readUInt16BE(3) + 5, 'one ClientHello record and nothing after it').to.equal(payload.length);
    await closed(pair);
  });

  it('gives up with ABORTED when the signal fires during the handshake', async () => {
    const pair = await pairFor(0x0a, true);
    pair.server.on('data', () => {});
    pair.server.resume();
    const controller = new AbortController();
    const pending = connect(pair, { insecure: true }, 10000, controller.signal).catch((e) => e);
    await waitFor(pair.server, 'data');
    controller.abort();
    expect((await pending).code).to.equal('ABORTED');
    await closed(pair);
  });

  it('fails with PROTOCOL_ERROR on garbage inside the tunnel instead of a ServerHello', async () => {
    const pair = await pairFor(0x0a, true);
    pair.server.once('data', () => pair.server.write(dtFrame(Buffer.from('HTTP/1.1 400 Bad Request\r\n\r\n'))));
    pair.server.resume();
    const err = await connect(pair, { insecure: true }).catch((e) => e);
    expect(err.code).to.equal('PROTOCOL_ERROR');
    expect(err.message).to.include('not valid TLS');
    await closed(pair);
  });

  it('reports garbage inside TLS mid-session as PROTOCOL_ERROR, and an alert from the PLC as CONNECTION_LOST', async () => {
    // Garbage: the server writes bytes that are no TLS record into the tunnel, below its TLS.
    const pair = await servedPair(plc);
    const channel = await connect(pair, { fingerprint: plc.fingerprint });
    const failed = waitFor<Error>(channel.socket, 'error');
    pair.serverTunnel!.write(Buffer.from('garbage, not a TLS record'));
    expect(tlsFailure(await failed, '127.0.0.1', 'session').code).to.equal('PROTOCOL_ERROR');
    channel.socket.destroy();
    await closed(pair);
    // Alert: our side sends a forged record below TLS; the server's TLS answers with a fatal alert.
    const pair2 = await servedPair(plc);
    const channel2 = await connect(pair2, { fingerprint: plc.fingerprint });
    const failed2 = waitFor<Error>(channel2.socket, 'error');
    pair2.clientTunnel.write(Buffer.concat([Buffer.from([0x17, 0x03, 0x03, 0x00, 0x20]), crypto.randomBytes(32)]));
    const mapped = tlsFailure(await failed2, '127.0.0.1', 'session');
    expect(mapped.code).to.equal('CONNECTION_LOST');
    expect(mapped.message).to.include('the TLS session with 127.0.0.1 ended with an alert from the PLC');
    channel2.socket.destroy();
    await closed(pair2);
  });

  describe('server side (the simulator)', () => {
    it('serves a generated certificate, and our pinned client connects to it', async () => {
      const served = await loadServerCertificate();
      expect(served.source).to.equal('generated at start');
      const pair = await pairFor();
      const [server, channel] = await Promise.all([
        acceptTls(pair.serverTunnel!, served, { timeout: 10000, peer: 'client' }),
        connect(pair, { fingerprint: served.fingerprint }),
      ]);
      server.write('from the PLC');
      expect(((await waitFor(channel.socket, 'data')) as Buffer).toString()).to.equal('from the PLC');
      channel.socket.end();
      await waitFor(server, 'close', 5000);
      await closed(pair);
    });

    it('times out a client that never sends its ClientHello', async () => {
      const served = await loadServerCertificate({ certFile: writePem('c.pem', plc.cert), keyFile: writePem('k.pem', plc.key) });
      const pair = await pairFor();
      const err = await acceptTls(pair.serverTunnel!, served, { timeout: 300, peer: 'client 1' }).catch((e) => e);
      expect(err.code).to.equal('TIMEOUT');
      expect(err.message).to.include('client 1');
      await closed(pair, false);
    });

    it('reads --tls-cert/--tls-key files, and refuses bad ones naming the file, never the key', async () => {
      const certFile = writePem('cert.pem', plc.cert);
      const keyFile = writePem('key.pem', plc.key);
      const served = await loadServerCertificate({ certFile, keyFile });
      expect(served.fingerprint).to.equal(plc.fingerprint);
      expect(served.source).to.equal(certFile);
      const other = await generateCertificate({ keyType: 'ec' });
      const otherKey = writePem('other-key.pem', other.key);
      const cases: Array<[Parameters<typeof loadServerCertificate>[0], RegExp]> = [
        [{ certFile }, /give both files \(only --tls-cert was given\)/],
        [{ certFile, keyFile: otherKey }, /other-key\.pem is not the private key of the certificate in .*cert\.pem/],
        [{ certFile: keyFile, keyFile }, /key\.pem holds no PEM certificate/],
        [{ certFile, keyFile: certFile }, /cert\.pem holds no PEM private key/],
        [{ certFile: path.join(dir, 'missing.pem'), keyFile }, /cannot read .*missing\.pem \(ENOENT\)/],
      ];
      for (const [files, message] of cases) {
        const err = await loadServerCertificate(files).catch((e) => e);
        expect(err.code, message.source).to.equal('INVALID_VALUE');
        expect(err.message).to.match(message);
        expect(err.message).to.not.include('PRIVATE KEY');
      }
    });
  });

  function writePem(name: string, text: string): string {
    const file = path.join(dir, name);
    fs.writeFileSync(file, text);
    return file;
  }
});

function dtFrame(payload: Buffer): Buffer {
  const f = Buffer.alloc(7 + payload.length);
  f[0] = 3;
  f.writeUInt16BE(f.length, 2);
  f[4] = 2;
  f[5] = 0xf0;
  f[6] = 0x80;
  payload.copy(f, 7);
  return f;
}

/** The parts of a TLS ClientHello record (RFC 8446 §4.1.2) these tests look at. */
function parseClientHello(record: Buffer) {
  expect(record[0], 'a handshake record').to.equal(0x16);
  expect(record[5], 'a ClientHello').to.equal(0x01);
  let p = 5 + 4 + 2 + 32;
  p += 1 + record[p]!; // session id
  const suitesLength = record.readUInt16BE(p);
  const suites: number[] = [];
  for (let i = 0; i < suitesLength; i += 2) suites.push(record.readUInt16BE(p + 2 + i));
  p += 2 + suitesLength;
  p += 1 + record[p]!; // compression methods
  const end = p + 2 + record.readUInt16BE(p);
  p += 2;
  const extensions: number[] = [];
  let groups: number[] = [];
  let versions: number[] = [];
  while (p < end) {
    const type = record.readUInt16BE(p);
    const length = record.readUInt16BE(p + 2);
    const body = record.subarray(p + 4, p + 4 + length);
    extensions.push(type);
    if (type === 10) groups = Array.from({ length: body.readUInt16BE(0) / 2 }, (_, i) => body.readUInt16BE(2 + 2 * i));
    if (type === 43) versions = Array.from({ length: body[0]! / 2 }, (_, i) => body.readUInt16BE(1 + 2 * i));
    p += 4 + length;
  }
  return { suites, extensions, groups, versions };
}
