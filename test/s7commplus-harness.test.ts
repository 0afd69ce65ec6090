/**
 * The s7commplus peer harness (test/support/s7commplus-peer.ts and the Python
 * runners in test/interop/s7commplus/) proven on the peer alone: its client
 * against its server emulator, plain V1 and V2 over TLS, for what the
 * S7CommPlus tests of our client and simulator lean on: connect (TLS pinned
 * by fingerprint or by the certificate as CA; TLS 1.3, and 1.2 where the
 * server refuses 1.3; certificates made by lib/s7plus/transport/cert.ts
 * accepted by this independent TLS stack), list the DBs, read and write
 * by address (each write reported by the server), the CPU state, and the
 * harness's own failures (a bad configuration, a refused pin, no server, a
 * notification that never comes), with no process left afterwards.
 *
 * Skips, saying why, where s7commplus is not installed
 * (`node test/support/install-peers.js s7commplus`; npm test does).
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as net from 'node:net';
import * as os from 'node:os';
import * as path from 'node:path';
import { generateCertificate } from '../lib/s7plus/transport/cert';
import {
  liveS7CommPlusPeers,
  openS7CommPlusClient,
  requireS7CommPlus,
  runS7CommPlusClient,
  S7CommPlusPeerServer,
  s7CommPlusClientOk,
  startS7CommPlusServer,
  stopS7CommPlusPeers,
  type PeerDb,
} from './support/s7commplus-peer';

const DB1 = Buffer.from('42f6e979' + '0457' + '01' + '00' + '0102030405060708', 'hex'); // Real 123.456, Int 1111, Bool true
const DBS: PeerDb[] = [
  { number: 1, size: 16, variables: { temperature: ['Real', 0], count: ['Int', 4], running: ['Bool', 6] }, data: DB1 },
  { number: 7, size: 4 },
];

/** A port that was listening a moment ago and is closed now. */
async function closedPort(): Promise<number> {
  const s = net.createServer().listen(0, '127.0.0.1');
  await new Promise((r) => s.once('listening', r));
  const { port } = s.address() as net.AddressInfo;
  await new Promise((r) => s.close(r));
  return port;
}

describe('s7commplus peer harness: its client against its own server', function () {
  this.timeout(120_000);
  let python = '';
  const servers: S7CommPlusPeerServer[] = [];

  before(function () {
    python = requireS7CommPlus(this);
  });
  after(async () => {
    await Promise.all(servers.splice(0).map((s) => s.stop()));
    await stopS7CommPlusPeers();
  });

  for (const mode of ['plain V1', 'V2 over TLS'] as const) {
    describe(mode, () => {
      const tls = mode === 'V2 over TLS';
      let server: S7CommPlusPeerServer;
      before(async function () {
        if (!python) return;
        server = await startS7CommPlusServer(python, { dbs: DBS, ...(tls ? { tls: 'self-signed' as const } : {}) });
        servers.push(server);
      });
      const connect = () => ({ op: 'connect' as const, port: server.port, tls, ...(tls ? { fingerprint: server.fingerprint! } : {}) });

      it('starts on a free port it reports, with the certificate fingerprint under TLS', () => {
        expect(server.port).to.be.within(1, 65535);
        if (tls) {
          expect(server.fingerprint).to.match(/^[0-9a-f]{64}$/);
          expect(fs.readFileSync(server.certPath!, 'utf8')).to.include('BEGIN CERTIFICATE');
        } else {
          expect(server.fingerprint).to.equal(null);
        }
      });

      it(`connects with protocol version ${tls ? 2 : 1}${tls ? ', the pinned certificate presented' : ' in plain text'}, and lists the DBs`, async () => {
        const [session, dbs] = await s7CommPlusClientOk(python, [connect(), { op: 'list_datablocks' }, { op: 'disconnect' }]);
        expect(session).to.deep.include({ protocolVersion: tls ? 2 : 1, tls, fingerprint: tls ? server.fingerprint : null });
        expect((dbs as { name: string; number: number }[]).map((d) => [d.name, d.number])).to.deep.equal([
          ['DB1', 1],
          ['DB7', 7],
        ]);
      });

      it('reads by address what the server holds', async () => {
        const [, whole, middle] = await s7CommPlusClientOk(python, [
          connect(),
          { op: 'db_read', db: 1, offset: 0, size: 16 },
          { op: 'db_read', db: 1, offset: 4, size: 3 },
        ]);
        expect(whole).to.equal(DB1.toString('hex'));
        expect(middle).to.equal('045701');
      });

      it('writes by address: the server reports the write, its memory has the bytes, and a read returns them', async () => {
        const before = server.writes.length;
        const [, , readBack] = await s7CommPlusClientOk(python, [
          connect(),
          { op: 'db_write', db: 7, offset: 1, data: 'a1b2' },
          { op: 'db_read', db: 7, offset: 0, size: 4 },
        ]);
        const w = await server.waitForWrite((x) => x.db === 7);
        expect(server.writes.length).to.equal(before + 1);
        expect(w).to.deep.include({ db: 7, offset: 1, size: 2, ok: true });
        expect(w.data.toString('hex')).to.equal('a1b2');
        expect((await server.read(7, 0, 4)).toString('hex')).to.equal('00a1b200');
        expect(readBack).to.equal('00a1b200');
      });

      it('reads a value the server changes in its memory, as a PLC program would', async () => {
        await server.write(1, 4, Buffer.from('fffe', 'hex'));
        const [, v] = await s7CommPlusClientOk(python, [connect(), { op: 'db_read', db: 1, offset: 4, size: 2 }]);
        expect(v).to.equal('fffe');
        await server.write(1, 4, DB1.subarray(4, 6));
      });

      it('reports a write outside the DB as refused, and the client gets an error', async () => {
        const r = await runS7CommPlusClient(python, [connect(), { op: 'db_write', db: 7, offset: 3, data: '0102' }]);
        expect(r.ok).to.equal(false);
        if (!r.ok) expect(r.failed).to.equal(1);
        const w = await server.waitForWrite((x) => x.db === 7 && x.offset === 3);
        expect(w.ok).to.equal(false);
        expect((await server.read(7, 0, 4)).toString('hex')).to.equal('00a1b200');
      });

      it('reports each connection, its requests and its DeleteObject, and the close of its socket', async () => {
        const before = server.events.length;
        await s7CommPlusClientOk(python, [connect(), { op: 'db_read', db: 1, offset: 0, size: 2 }, { op: 'disconnect' }]);
        await server.waitForNoClients();
        const events = server.events.slice(before);
        const kinds = events.map((e) => e.event);
        expect(kinds[0]).to.equal('connected');
        expect(kinds.at(-1)).to.equal('disconnected');
        const functions = events.flatMap((e) => (e.event === 'request' ? [e.function] : []));
        // InitSSL 0x05B3, CreateObject 0x04CA, the session setup write and the read (SetMultiVariables 0x0542,
        // GetMultiVariables 0x054C), DeleteObject 0x04D4; the client may read the protection level in between.
        expect(functions[0]).to.equal(0x05b3);
        expect(functions[1]).to.equal(0x04ca);
        expect(functions).to.include.members([0x0542, 0x054c]);
        expect(functions.at(-1)).to.equal(0x04d4);
        expect(kinds.filter((k) => k === 'deleteObject')).to.have.length(1);
        const sizes = events.flatMap((e) => (e.event === 'request' ? [e.bytes] : []));
        expect(Math.min(...sizes)).to.be.greaterThan(14);
        expect(server.openClients()).to.deep.equal([]);
      });

      it('reports the CPU state the server is set to', async () => {
        const states: unknown[] = [];
        for (const state of ['STOP', 'RUN'] as const) {
          await server.setCpuState(state);
          const [, s] = await s7CommPlusClientOk(python, [connect(), { op: 'get_cpu_state' }]);
          states.push(s);
        }
        expect(states).to.deep.equal(['STOP', 'RUN']);
      });

      it('keeps one session open across operations in interactive mode', async () => {
        const client = openS7CommPlusClient(python);
        try {
          const session = (await client.ok(connect())) as { sessionId: number };
          await client.ok({ op: 'db_write', db: 7, offset: 0, data: '55' });
          expect(await client.ok({ op: 'db_read', db: 7, offset: 0, size: 1 })).to.equal('55');
          const refused = await client.op({ op: 'db_read', db: 99, offset: 0, size: 1 });
          expect(refused.ok).to.equal(false);
          // Still the same session after a refused operation.
          expect(await client.ok({ op: 'db_read', db: 7, offset: 0, size: 1 })).to.equal('55');
          expect(session.sessionId).to.be.a('number');
        } finally {
          await client.close();
        }
      });

      it('has no subscriptions: the emulator offers no subscription container, and a notification wait times out', async () => {
        const client = openS7CommPlusClient(python);
        try {
          await client.ok(connect());
          const sub = await client.op({ op: 'subscribe', items: ['8A0E0001.A'] });
          expect(sub.ok).to.equal(false);
          if (!sub.ok) expect(sub.error.message).to.include('subscription container');
          const n = await client.op({ op: 'notification', timeoutMs: 300 });
          expect(n).to.deep.equal({ ok: false, error: { type: 'Timeout', message: 'no notification within 300 ms' } });
        } finally {
          await client.close();
        }
      });
    });
  }

  describe('TLS trust', () => {
    let server: S7CommPlusPeerServer;
    before(async function () {
      if (!python) return;
      server = await startS7CommPlusServer(python, { dbs: DBS, tls: 'self-signed' });
      servers.push(server);
    });

    it('accepts the certificate given as CA (ca=)', async () => {
      const [session] = await s7CommPlusClientOk(python, [{ op: 'connect', port: server.port, tls: true, ca: server.certPath! }]);
      expect(session).to.deep.include({ tls: true, fingerprint: server.fingerprint });
    });

    it('refuses another certificate pinned, before any data', async () => {
      const other = server.fingerprint!.replace(/^./, (c) => (c === '0' ? '1' : '0'));
      const r = await runS7CommPlusClient(python, [
        { op: 'connect', port: server.port, tls: true, fingerprint: other },
        { op: 'db_write', db: 7, offset: 0, data: '99' },
      ]);
      expect(r.ok).to.equal(false);
      if (!r.ok) {
        expect(r.failed).to.equal(0);
        expect(r.error.message.toLowerCase()).to.include('fingerprint');
      }
      expect(server.writes).to.deep.equal([]);
      expect((await server.read(7, 0, 1)).toString('hex')).to.equal('00');
    });

    it('negotiates TLS 1.3 by default, and TLS 1.2 with a server that refuses 1.3', async () => {
      const capped = await startS7CommPlusServer(python, { dbs: DBS, tls: 'self-signed', tlsMaxVersion: '1.2' });
      servers.push(capped);
      const [v13] = await s7CommPlusClientOk(python, [{ op: 'connect', port: server.port, tls: true, fingerprint: server.fingerprint! }]);
      const [v12, data] = await s7CommPlusClientOk(python, [
        { op: 'connect', port: capped.port, tls: true, fingerprint: capped.fingerprint! },
        { op: 'db_read', db: 1, offset: 0, size: 4 },
      ]);
      expect(v13).to.deep.include({ tlsVersion: 'TLSv1.3' });
      expect(v12).to.deep.include({ tlsVersion: 'TLSv1.2', protocolVersion: 2 });
      expect(data).to.equal('42f6e979');
    });

    it('serves a certificate and key given by path', async () => {
      const byPath = await startS7CommPlusServer(python, {
        dbs: DBS,
        tls: { cert: server.certPath!, key: path.join(path.dirname(server.certPath!), 'key.pem') },
      });
      servers.push(byPath);
      expect(byPath.fingerprint).to.equal(server.fingerprint);
      const [session, data] = await s7CommPlusClientOk(python, [
        { op: 'connect', port: byPath.port, tls: true, fingerprint: server.fingerprint! },
        { op: 'db_read', db: 1, offset: 0, size: 4 },
      ]);
      expect(session).to.deep.include({ protocolVersion: 2, tls: true });
      expect(data).to.equal('42f6e979');
    });
  });

  describe('certificates made by lib/s7plus/transport/cert.ts, checked by an independent TLS stack', () => {
    let dir = '';
    before(function () {
      if (!python) return;
      dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-s7cp-cert-'));
    });
    after(() => {
      if (dir) fs.rmSync(dir, { recursive: true, force: true });
    });
    const write = (name: string, text: string) => {
      fs.writeFileSync(path.join(dir, name), text);
      return path.join(dir, name);
    };

    for (const version of ['1.3', '1.2'] as const) {
      it(`a self-signed one, served by the emulator and pinned by its fingerprint, over TLS ${version}`, async () => {
        const cert = await generateCertificate();
        const server = await startS7CommPlusServer(python, {
          dbs: DBS,
          tls: { cert: write(`self-${version}.pem`, cert.cert), key: write(`self-${version}-key.pem`, cert.key) },
          tlsMaxVersion: version,
        });
        servers.push(server);
        expect(server.fingerprint).to.equal(cert.fingerprint.toLowerCase());
        const [session, data] = await s7CommPlusClientOk(python, [
          { op: 'connect', port: server.port, tls: true, fingerprint: cert.fingerprint },
          { op: 'db_read', db: 1, offset: 0, size: 4 },
        ]);
        expect(session).to.deep.include({ tls: true, tlsVersion: `TLSv${version}`, fingerprint: cert.fingerprint.toLowerCase() });
        expect(data).to.equal('42f6e979');
      });
    }

    it('one signed by a CA of ours, accepted by the client given that CA (ca=), refused by a client given another CA', async () => {
      const ca = await generateCertificate({ ca: true, commonName: 'plcwire test CA' });
      const otherCa = await generateCertificate({ ca: true, commonName: 'another CA' });
      const leaf = await generateCertificate({ issuer: ca, commonName: 'PLC_1' });
      const server = await startS7CommPlusServer(python, {
        dbs: DBS,
        tls: { cert: write('leaf.pem', leaf.cert), key: write('leaf-key.pem', leaf.key) },
      });
      servers.push(server);
      const [session] = await s7CommPlusClientOk(python, [{ op: 'connect', port: server.port, tls: true, ca: write('ca.pem', ca.cert) }]);
      expect(session).to.deep.include({ tls: true, fingerprint: leaf.fingerprint.toLowerCase() });
      const refused = await runS7CommPlusClient(python, [
        { op: 'connect', port: server.port, tls: true, ca: write('other.pem', otherCa.cert) },
      ]);
      expect(refused.ok).to.equal(false);
      if (!refused.ok) expect(refused.error.message).to.match(/certificate verify failed|unable to get local issuer/i);
    });
  });

  describe('failures of the harness itself', () => {
    it('rejects a server configuration the emulator refuses, with its reason, and leaves no process', async () => {
      const before = liveS7CommPlusPeers();
      let err: Error | undefined;
      await startS7CommPlusServer(python, { dbs: [{ number: 2, variables: { x: ['Real32', 0] } }] }).catch((e: Error) => (err = e));
      expect(err?.message).to.include("Unknown type name: 'Real32'");
      expect(liveS7CommPlusPeers()).to.equal(before);
    });

    it('reports a client that cannot connect as a JSON error, exit non-zero', async () => {
      const r = await runS7CommPlusClient(python, [{ op: 'connect', port: await closedPort() }, { op: 'list_datablocks' }]);
      expect(r.ok).to.equal(false);
      if (!r.ok) {
        expect(r.failed).to.equal(0);
        expect(r.results).to.deep.equal([]);
        expect(r.error.type).to.be.a('string').and.not.equal('');
      }
    });

    it('rejects a server command that fails, naming it', async () => {
      const server = await startS7CommPlusServer(python, { dbs: DBS });
      servers.push(server);
      let err: Error | undefined;
      await server.read(99, 0, 1).catch((e: Error) => (err = e));
      expect(err?.message).to.include('DB99 is not registered');
      await server.stop();
      servers.splice(servers.indexOf(server), 1);
      let after: Error | undefined;
      await server.setCpuState('STOP').catch((e: Error) => (after = e));
      expect(after?.message).to.include('has exited');
    });

    it('leaves no peer process running once the suites stop them', async () => {
      await Promise.all(servers.splice(0).map((s) => s.stop()));
      expect(liveS7CommPlusPeers()).to.equal(0);
    });
  });
});
