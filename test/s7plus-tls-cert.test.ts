/**
 * lib/s7plus/transport/cert.ts: the certificate our S7CommPlus simulator makes
 * at start, read back by Node's own X.509 parser, used by a real TLS server
 * with a client that pins it, and loaded by Python's ssl (what the s7commplus
 * package's server and client use).
 */
import { expect } from 'chai';
import { spawnSync } from 'node:child_process';
import * as crypto from 'node:crypto';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import * as tls from 'node:tls';
import { fingerprint256, generateCertificate, type GeneratedCertificate } from '../lib/s7plus/transport/cert';
import { skipBecause } from './support/skip';

describe('s7plus transport: certificate generator', function () {
  this.timeout(30000);
  let rsa: GeneratedCertificate;

  before(async () => {
    rsa = await generateCertificate({ commonName: 'plcwire test PLC' });
  });

  it('makes an RSA 2048 certificate that Node parses, with our subject, SAN and validity', () => {
    const x = new crypto.X509Certificate(rsa.cert);
    expect(x.subject).to.include('CN=plcwire test PLC');
    expect(x.issuer).to.equal(x.subject);
    expect(x.subjectAltName).to.include('DNS:localhost');
    expect(x.subjectAltName).to.include('IP Address:127.0.0.1');
    expect(x.publicKey.asymmetricKeyType).to.equal('rsa');
    expect(x.publicKey.asymmetricKeyDetails?.modulusLength).to.equal(2048);
    expect(x.checkPrivateKey(crypto.createPrivateKey(rsa.key))).to.equal(true);
    expect(x.verify(x.publicKey), 'self-signed: its own key verifies it').to.equal(true);
    expect(x.ca).to.equal(false);
    expect(x.checkIP('127.0.0.1')).to.equal('127.0.0.1');
    expect(x.checkHost('localhost')).to.equal('localhost');
    const notBefore = Date.parse(x.validFrom);
    expect(notBefore).to.be.below(Date.now());
    expect(Date.parse(x.validTo) - notBefore).to.be.above(9 * 365 * 86400_000);
    expect(x.keyUsage ?? [], 'extended key usage').to.include('1.3.6.1.5.5.7.3.1');
  });

  it('fingerprint256 is the SHA-256 of the DER as 64 upper-case hex digits, as Node computes it', () => {
    const x = new crypto.X509Certificate(rsa.cert);
    expect(rsa.fingerprint).to.match(/^[0-9A-F]{64}$/);
    expect(rsa.fingerprint).to.equal(x.fingerprint256.replace(/:/g, ''));
    expect(fingerprint256(x.raw)).to.equal(rsa.fingerprint);
    expect(Buffer.compare(x.raw, rsa.der)).to.equal(0);
  });

  it('two certificates differ in key, serial and fingerprint', async () => {
    const other = await generateCertificate();
    const a = new crypto.X509Certificate(rsa.cert);
    const b = new crypto.X509Certificate(other.cert);
    expect(b.serialNumber).to.not.equal(a.serialNumber);
    expect(other.fingerprint).to.not.equal(rsa.fingerprint);
    expect(b.checkPrivateKey(crypto.createPrivateKey(rsa.key))).to.equal(false);
  });

  it('writes the validity it is given (UTCTime before 2050, GeneralizedTime after)', async () => {
    const past = await generateCertificate({ notBefore: new Date('2020-01-01T00:00:00Z'), notAfter: new Date('2021-01-01T00:00:00Z') });
    const x = new crypto.X509Certificate(past.cert);
    expect(new Date(x.validFrom).toISOString()).to.equal('2020-01-01T00:00:00.000Z');
    expect(new Date(x.validTo).toISOString()).to.equal('2021-01-01T00:00:00.000Z');
    const far = await generateCertificate({ keyType: 'ec', notAfter: new Date('2060-06-30T12:00:00Z') });
    expect(new Date(new crypto.X509Certificate(far.cert).validTo).toISOString()).to.equal('2060-06-30T12:00:00.000Z');
  });

  it('refuses a validity that ends before it starts, naming both dates', async () => {
    const err = await generateCertificate({ notBefore: new Date('2030-01-01Z'), notAfter: new Date('2029-01-01Z') }).catch((e) => e);
    expect(err.code).to.equal('INVALID_VALUE');
    expect(err.message).to.include('2029-01-01').and.include('2030-01-01');
  });

  it('makes an EC P-256 certificate on request', async () => {
    const ec = await generateCertificate({ keyType: 'ec', hosts: ['plc.example', '10.0.0.5', 'fe80::1'] });
    const x = new crypto.X509Certificate(ec.cert);
    expect(x.publicKey.asymmetricKeyType).to.equal('ec');
    expect(x.verify(x.publicKey)).to.equal(true);
    expect(x.checkPrivateKey(crypto.createPrivateKey(ec.key))).to.equal(true);
    expect(x.subjectAltName).to.include('DNS:plc.example').and.include('IP Address:10.0.0.5').and.include('IP Address:FE80:0:0:0:0:0:0:1');
  });

  it('signs a server certificate with a CA it made, and the chain verifies', async () => {
    const ca = await generateCertificate({ commonName: 'plcwire test CA', ca: true });
    const leaf = await generateCertificate({ commonName: 'PLC_1', issuer: ca });
    const caX = new crypto.X509Certificate(ca.cert);
    const leafX = new crypto.X509Certificate(leaf.cert);
    expect(caX.ca).to.equal(true);
    expect(leafX.issuer).to.equal(caX.subject);
    expect(leafX.verify(caX.publicKey)).to.equal(true);
    expect(leafX.checkIssued(caX)).to.equal(true);
    expect(leafX.checkPrivateKey(crypto.createPrivateKey(leaf.key))).to.equal(true);
  });

  it('serves TLS with it, and a client that pins its fingerprint completes the handshake over TLS 1.2 and 1.3', async () => {
    for (const version of ['TLSv1.2', 'TLSv1.3'] as const) {
      const server = tls.createServer({ cert: rsa.cert, key: rsa.key, minVersion: version, maxVersion: version }, (s) => s.end('hello'));
      await new Promise<void>((r) => server.listen(0, '127.0.0.1', r));
      const port = (server.address() as { port: number }).port;
      try {
        const seen = await new Promise<{ fingerprint: string; text: string; protocol: string | null }>((resolve, reject) => {
          const socket = tls.connect({
            host: '127.0.0.1',
            port,
            rejectUnauthorized: false,
            checkServerIdentity: () => undefined,
          });
          let text = '';
          socket.on('data', (d) => (text += d));
          socket.on('error', reject);
          socket.on('end', () => {
            const cert = socket.getPeerX509Certificate();
            resolve({ fingerprint: cert ? fingerprint256(cert.raw) : '', text, protocol: socket.getProtocol() });
          });
        });
        expect(seen.protocol).to.equal(version);
        expect(seen.fingerprint).to.equal(rsa.fingerprint);
        expect(seen.text).to.equal('hello');
      } finally {
        await new Promise((r) => server.close(r));
      }
    }
  });

  it('is trusted as a CA file by a verifying Node client (self-signed)', async () => {
    const server = tls.createServer({ cert: rsa.cert, key: rsa.key }, (s) => s.end('ok'));
    await new Promise<void>((r) => server.listen(0, '127.0.0.1', r));
    const port = (server.address() as { port: number }).port;
    try {
      const authorized = await new Promise<boolean>((resolve, reject) => {
        const socket = tls.connect({ host: '127.0.0.1', port, ca: rsa.cert, servername: 'localhost' }, () => {
          resolve(socket.authorized);
          socket.destroy();
        });
        socket.on('error', reject);
      });
      expect(authorized).to.equal(true);
    } finally {
      await new Promise((r) => server.close(r));
    }
  });

  it("loads in Python's ssl as a server certificate and as a trust anchor", function () {
    const python = ['python3', 'python'].find((p) => spawnSync(p, ['--version']).status === 0);
    if (!python) skipBecause(this, 'no python3 on PATH');
    const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-cert-'));
    try {
      fs.writeFileSync(path.join(dir, 'cert.pem'), rsa.cert);
      fs.writeFileSync(path.join(dir, 'key.pem'), rsa.key);
      const script = [
        'import ssl, sys, hashlib',
        'd = sys.argv[1]',
        's = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)',
        "s.load_cert_chain(d + '/cert.pem', d + '/key.pem')",
        'c = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)',
        "c.load_verify_locations(d + '/cert.pem')",
        "der = ssl.PEM_cert_to_DER_cert(open(d + '/cert.pem').read())",
        'print(hashlib.sha256(der).hexdigest())',
      ].join('\n');
      const run = spawnSync(python!, ['-c', script, dir], { encoding: 'utf8' });
      expect(run.stderr).to.equal('');
      expect(run.status).to.equal(0);
      expect(run.stdout.trim().toUpperCase()).to.equal(rsa.fingerprint);
    } finally {
      fs.rmSync(dir, { recursive: true, force: true });
    }
  });
});
