/**
 * Our S7CommPlus client against an independent peer: the server emulator of
 * the s7commplus Python package (MIT; s7commplus.server.S7CommPlusServer),
 * over TLS (a certificate from lib/s7plus/transport/cert.ts, pinned by its
 * fingerprint) and in plain V1 with tls=false. The handshake, the trust
 * decision before any S7CommPlus data, never a fallback between TLS and plain
 * text, the DeleteObject on close, and no socket left after any of it.
 *
 * The peer runs from a small launcher of this file until the shared peer
 * harness (test/support/s7commplus-peer.ts) is there.
 */
import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import * as fs from 'node:fs';
import * as net from 'node:net';
import * as os from 'node:os';
import * as path from 'node:path';
import { createClient } from '../lib/connect';
import { PlcError } from '../lib/errors';
import type { S7PlusClient } from '../lib/s7plus/client';
import { generateCertificate, type GeneratedCertificate } from '../lib/s7plus/transport/cert';
import { skipBecause } from './support/skip';
import { settle, until } from './support/wait';

const ROOT = path.resolve(__dirname, '../..');
const PYTHON = path.join(ROOT, 'test/interop/.venv-s7commplus', process.platform === 'win32' ? 'Scripts/python.exe' : 'bin/python');

/** Starts the emulator with DB1 registered; prints "READY <port>", and a line per client that leaves; stops when stdin closes. */
const LAUNCHER = `
import sys, socket, logging
from s7commplus.server import S7CommPlusServer
class Gone(logging.Handler):
    def emit(self, record):
        if record.getMessage().startswith('Client disconnected'): print('GONE', flush=True)
log = logging.getLogger('s7commplus.server'); log.setLevel(logging.INFO); log.addHandler(Gone())
version, cert, key = int(sys.argv[1]), sys.argv[2], sys.argv[3]
server = S7CommPlusServer(protocol_version=version)
server.register_db(1, {"temperature": ("Real", 0), "count": ("DInt", 4)}, size=64)
probe = socket.socket(); probe.bind(('127.0.0.1', 0)); port = probe.getsockname()[1]; probe.close()
tls = cert != '-'
server.start('127.0.0.1', port, use_tls=tls, tls_cert=cert if tls else None, tls_key=key if tls else None)
print('READY', port, flush=True)
sys.stdin.read()
server.stop()
`;

interface Peer {
  port: number;
  /** Clients that left (the emulator's "Client disconnected"). */
  gone: number;
  stop(): Promise<void>;
}

function startPeer(version: number, cert?: { certFile: string; keyFile: string }): Promise<Peer> {
  const child: ChildProcess = spawn(PYTHON, ['-c', LAUNCHER, String(version), cert?.certFile ?? '-', cert?.keyFile ?? '-'], {
    stdio: ['pipe', 'pipe', 'pipe'],
  });
  let stderr = '';
  child.stderr!.on('data', (d: Buffer) => (stderr += d.toString()));
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`the s7commplus emulator did not start: ${stderr}`)), 20_000);
    const peer: Peer = {
      port: 0,
      gone: 0,
      stop: () =>
        new Promise<void>((done) => {
          if (child.exitCode !== null) return done();
          child.once('exit', () => done());
          child.stdin!.end();
        }),
    };
    let out = '';
    child.stdout!.on('data', (d: Buffer) => {
      out += d.toString();
      const lines = out.split('\n');
      out = lines.pop()!;
      for (const line of lines) {
        const ready = /^READY (\d+)/.exec(line);
        if (ready) {
          clearTimeout(timer);
          peer.port = Number(ready[1]);
          resolve(peer);
        }
        if (line.startsWith('GONE')) peer.gone++;
      }
    });
    child.once('exit', (code) => reject(new Error(`the s7commplus emulator exited (${code}): ${stderr}`)));
  });
}

/** Our sockets to `port` still open. */
function socketsTo(port: number): number {
  const handles = (process as unknown as { _getActiveHandles(): unknown[] })._getActiveHandles();
  return handles.filter((h) => h instanceof net.Socket && !h.destroyed && h.remotePort === port).length;
}

async function connectError(client: S7PlusClient): Promise<PlcError> {
  try {
    await client.connect();
  } catch (err) {
    expect(err).to.be.instanceOf(PlcError);
    return err as PlcError;
  }
  throw new Error('connect() succeeded');
}

describe('s7plus client against the s7commplus emulator', function () {
  this.timeout(60_000);
  let cert: GeneratedCertificate;
  let files: { certFile: string; keyFile: string };
  let dir: string;

  before(async function () {
    if (!fs.existsSync(PYTHON))
      skipBecause(this, 'no s7commplus venv (test/interop/.venv-s7commplus): run `node test/support/install-peers.js`');
    cert = await generateCertificate({ commonName: 'plcwire test PLC' });
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 's7plus-client-'));
    files = { certFile: path.join(dir, 'cert.pem'), keyFile: path.join(dir, 'key.pem') };
    fs.writeFileSync(files.certFile, cert.cert);
    fs.writeFileSync(files.keyFile, cert.key);
  });

  after(() => {
    if (dir) fs.rmSync(dir, { recursive: true, force: true });
  });

  describe('over TLS', () => {
    let peer: Peer;
    before(async () => (peer = await startPeer(1, files)));
    after(() => peer?.stop());

    it('connects with the certificate pinned (colons and case ignored), sets the session up with IntegrityIds at 0, and closes with a DeleteObject', async () => {
      const pin = cert.fingerprint.replace(/(..)(?!$)/g, '$1:').toLowerCase();
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?fingerprint=${pin}&timeout=5000`);
      await client.connect();
      expect(client.state).to.equal('connected');
      expect(client.certificate?.fingerprint).to.equal(cert.fingerprint.toLowerCase());
      expect(client.certificate?.subject).to.contain('plcwire test PLC');
      const session = (client as unknown as { session: { integrityIds: unknown; version: number } }).session;
      expect(session.integrityIds).to.deep.equal({ read: 0, write: 0 });
      expect(session.version).to.equal(2);
      // CreateObject and the session setup.
      expect(client.stats.requestsSent).to.equal(2);
      const gone = peer.gone;
      await client.close();
      // The DeleteObject went out and was answered before the link closed.
      expect(client.stats.requestsSent).to.equal(3);
      await until(() => peer.gone === gone + 1, 10_000, 'the emulator saw the client leave');
      await settle();
      expect(socketsTo(peer.port)).to.equal(0);
    });

    it('reads and writes a standard DB by address, with the IntegrityIds counting a read and a write, and tells the CPU state and the DBs', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?fingerprint=${cert.fingerprint}&timeout=5000`);
      await client.connect();
      await client.write({ 'DB1.DBD0:REAL': 21.5, 'DB1.DBD4:DINT': -7, 'DB1.DBW10': 300, 'DB1.DBB12': 0x5a });
      expect(await client.read(['DB1.DBD0:REAL', 'DB1.DBD4:DINT', 'DB1.DBW10', 'DB1.DBB12'])).to.deep.equal({
        'DB1.DBD0:REAL': 21.5,
        'DB1.DBD4:DINT': -7,
        'DB1.DBW10': 300,
        'DB1.DBB12': 0x5a,
      });
      const session = (client as unknown as { session: { integrityIds: unknown } }).session;
      expect(session.integrityIds).to.deep.equal({ read: 1, write: 1 });
      expect(await client.cpuState()).to.equal('RUN');
      expect((await client.dataBlocks()).map((b) => b.number)).to.deep.equal([1]);
      expect(session.integrityIds).to.deep.equal({ read: 3, write: 1 });
      await client.close();
    });

    it('gives each tag its own failure: a DB the PLC lacks, an offset past the end, an area S7CommPlus does not reach, a bit write', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?fingerprint=${cert.fingerprint}&timeout=5000`);
      await client.connect();
      const read = await client.readDetailed(['DB1.DBW10', 'DB2.DBW0', 'DB1.DBB100', 'C1']);
      expect(read['DB1.DBW10']!.ok).to.equal(true);
      const code = (a: string) => (read[a]!.ok ? 'ok' : read[a]!.error.code);
      expect([code('DB2.DBW0'), code('DB1.DBB100'), code('C1')]).to.deep.equal([
        'OBJECT_DOES_NOT_EXIST',
        'OBJECT_DOES_NOT_EXIST',
        'NOT_SUPPORTED',
      ]);
      const written = await client.writeDetailed({ 'DB1.DBX8.0': true, 'DB1.DBW10': 301 });
      expect(written['DB1.DBX8.0']!.ok).to.equal(false);
      expect(written['DB1.DBW10']!.ok).to.equal(true);
      expect(await client.read(['DB1.DBW10'])).to.deep.equal({ 'DB1.DBW10': 301 });
      await client.close();
    });

    it('refuses a certificate the pin does not match before any S7CommPlus request, showing the pin that would match', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?fingerprint=${'0'.repeat(64)}&timeout=5000`);
      const err = await connectError(client);
      expect(err.code).to.equal('CONNECT_FAILED');
      expect(err.message).to.contain('is not the one fingerprint= pins');
      expect(err.message).to.contain(`fingerprint=${cert.fingerprint.toLowerCase()}`);
      expect(err.message).to.contain('plcwire test PLC');
      expect(client.stats.requestsSent).to.equal(0);
      await client.close();
      await settle();
      expect(socketsTo(peer.port)).to.equal(0);
    });

    it('refuses a certificate nothing in the URL trusts, and says how to pin it', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?timeout=5000`);
      const err = await connectError(client);
      expect(err.message).to.contain('nothing in the URL trusts');
      expect(err.message).to.match(/valid .* to /);
      expect(client.stats.requestsSent).to.equal(0);
      await client.close();
      await settle();
      expect(socketsTo(peer.port)).to.equal(0);
    });

    it('insecure=true connects and warns with the certificate it accepted unchecked', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?insecure=true&timeout=5000`);
      const warnings: string[] = [];
      client.on('insecure', (e: { message: string }) => warnings.push(e.message));
      await client.connect();
      expect(warnings).to.have.length(1);
      expect(warnings[0]).to.contain(`fingerprint=${cert.fingerprint.toLowerCase()}`);
      await client.close();
    });

    it('tls=false against a PLC that starts TLS fails: never a fallback to plain text', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?tls=false&timeout=3000`);
      const err = await connectError(client);
      expect(['CONNECT_FAILED', 'TIMEOUT']).to.include(err.code);
      await client.close();
      await settle();
      expect(socketsTo(peer.port)).to.equal(0);
    });
  });

  describe('in plain V1 (tls=false)', () => {
    let peer: Peer;
    before(async () => (peer = await startPeer(1)));
    after(() => peer?.stop());

    it('connects without IntegrityIds and closes with a DeleteObject', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?tls=false&timeout=5000`);
      await client.connect();
      const session = (client as unknown as { session: { integrityIds: unknown; version: number } }).session;
      expect(session.integrityIds).to.equal(undefined);
      expect(session.version).to.equal(1);
      expect(client.certificate).to.equal(undefined);
      await client.close();
      expect(client.stats.requestsSent).to.equal(3);
      await settle();
      expect(socketsTo(peer.port)).to.equal(0);
    });

    it('reads and writes by address and tells the CPU state in plain text too', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?tls=false&timeout=5000`);
      await client.connect();
      await client.write({ 'DB1.DBD4:DINT': 123456, 'DB1.DBW10': 7 });
      expect(await client.read(['DB1.DBD4:DINT', 'DB1.DBW10'])).to.deep.equal({ 'DB1.DBD4:DINT': 123456, 'DB1.DBW10': 7 });
      expect(await client.cpuState()).to.equal('RUN');
      await client.close();
    });

    it('a TLS URL against a PLC without TLS fails: never a fallback to plain text', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?insecure=true&timeout=3000`);
      const err = await connectError(client);
      expect(['CONNECT_FAILED', 'TIMEOUT']).to.include(err.code);
      expect(client.stats.requestsSent).to.equal(0);
      await client.close();
      await settle();
      expect(socketsTo(peer.port)).to.equal(0);
    });
  });

  describe('a PLC that speaks V2 asked for plain text', () => {
    let peer: Peer;
    before(async () => (peer = await startPeer(2)));
    after(() => peer?.stop());

    it('is refused with what the PLC wants and what to do', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?tls=false&timeout=5000`);
      const err = await connectError(client);
      expect(err.code).to.equal('CONNECT_FAILED');
      expect(err.message).to.contain('speaks S7CommPlus V2 and wants it over TLS');
      expect(err.message).to.contain('drop tls=false');
      await client.close();
      await settle();
      expect(socketsTo(peer.port)).to.equal(0);
    });
  });
});
