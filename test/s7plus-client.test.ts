/**
 * Our S7CommPlus client against an independent peer: the server emulator of
 * the s7commplus Python package (MIT; s7commplus.server.S7CommPlusServer, run
 * by test/support/s7commplus-peer.ts), over TLS (a certificate from
 * lib/s7plus/transport/cert.ts, pinned by its fingerprint) and in plain V1
 * with tls=false. The handshake, the trust decision before any S7CommPlus
 * data, never a fallback between TLS and plain text, reads and writes by
 * address checked in the emulator's memory, the CPU state and the data
 * blocks, the DeleteObject on close, and no connection left after any of it.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as net from 'node:net';
import * as os from 'node:os';
import * as path from 'node:path';
import { createClient } from '../lib/connect';
import { PlcError } from '../lib/errors';
import { compileSymbols } from '../lib/symbols';
import type { S7PlusClient } from '../lib/s7plus/client';
import { generateCertificate, type GeneratedCertificate } from '../lib/s7plus/transport/cert';
import {
  requireS7CommPlus,
  startS7CommPlusServer,
  stopS7CommPlusPeers,
  type PeerDb,
  type S7CommPlusPeerServer,
} from './support/s7commplus-peer';
import { settle, waitFor } from './support/wait';

const DB1: PeerDb = { number: 1, size: 64, variables: { temperature: ['Real', 0], count: ['DInt', 4] } };

/** Our sockets to `port` still open. */
function socketsTo(port: number): number {
  const handles = (process as unknown as { _getActiveHandles(): unknown[] })._getActiveHandles();
  return handles.filter((h) => h instanceof net.Socket && !h.destroyed && h.remotePort === port).length;
}

/** No connection left on either side: none of our sockets, none the emulator still holds. */
async function noConnections(peer: S7CommPlusPeerServer): Promise<void> {
  await peer.waitForNoClients(10_000);
  await settle();
  expect(socketsTo(peer.port)).to.equal(0);
}

async function rejection(p: Promise<unknown>): Promise<PlcError> {
  try {
    await p;
  } catch (err) {
    expect(err).to.be.instanceOf(PlcError);
    return err as PlcError;
  }
  throw new Error('resolved');
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
  let python: string;
  let cert: GeneratedCertificate;
  let files: { cert: string; key: string };
  let dir: string;

  before(async function () {
    python = requireS7CommPlus(this);
    cert = await generateCertificate({ commonName: 'plcwire test PLC' });
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 's7plus-client-'));
    files = { cert: path.join(dir, 'cert.pem'), key: path.join(dir, 'key.pem') };
    fs.writeFileSync(files.cert, cert.cert);
    fs.writeFileSync(files.key, cert.key);
  });

  after(async () => {
    await stopS7CommPlusPeers();
    if (dir) fs.rmSync(dir, { recursive: true, force: true });
  });

  describe('over TLS', () => {
    let peer: S7CommPlusPeerServer;
    before(async () => (peer = await startS7CommPlusServer(python, { dbs: [DB1], tls: files, version: 1 })));
    after(() => peer?.stop());

    it('connects with the certificate pinned (colons and case ignored), sets the session up with IntegrityIds from 0, and closes with a DeleteObject', async () => {
      const pin = cert.fingerprint.replace(/(..)(?!$)/g, '$1:').toLowerCase();
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?fingerprint=${pin}&timeout=5000`);
      await client.connect();
      expect(client.state).to.equal('connected');
      expect(client.certificate?.fingerprint).to.equal(cert.fingerprint.toUpperCase());
      expect(client.certificate?.subject).to.contain('plcwire test PLC');
      const session = (client as unknown as { session: { integrityIds: unknown; version: number } }).session;
      // The IntegrityIds start at 0 after the setup; the protection level read (as s7commplus's client does) took read 0.
      expect(session.integrityIds).to.deep.equal({ read: 1, write: 0 });
      expect(session.version).to.equal(2);
      // CreateObject, the session setup, the protection level.
      expect(client.stats.requestsSent).to.equal(3);
      const deletes = peer.events.filter((e) => e.event === 'deleteObject').length;
      await client.close();
      // The DeleteObject went out and was answered before the link closed.
      expect(client.stats.requestsSent).to.equal(4);
      await peer.waitForEvent((e) => e.event === 'deleteObject' && peer.events.filter((x) => x.event === 'deleteObject').length > deletes);
      await noConnections(peer);
    });

    it('subscribe(): the emulator offers no subscription container, so it is refused in words (NOT_SUPPORTED) and no connection is left', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?fingerprint=${cert.fingerprint}&timeout=5000`) as S7PlusClient;
      await client.connect();
      const err = await rejection(client.subscribe(['DB1.DBW4']));
      expect(err.code).to.equal('NOT_SUPPORTED');
      expect(err.message).to.include('no subscription container');
      // The client's own session goes on.
      expect(await client.read(['DB1.DBD4:DINT'])).to.have.keys('DB1.DBD4:DINT');
      await client.close();
      await noConnections(peer);
    });

    it('reads and writes a standard DB by address, with the IntegrityIds counting a read and a write, and tells the CPU state and the DBs', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?fingerprint=${cert.fingerprint}&timeout=5000`);
      await client.connect();
      await client.write({ 'DB1.DBD0:REAL': 21.5, 'DB1.DBD4:DINT': -7, 'DB1.DBW10': 300, 'DB1.DBB12': 0x5a });
      // What the emulator holds, read from its memory, not over the network.
      expect((await peer.read(1, 0, 13)).toString('hex')).to.equal('41ac0000' + 'fffffff9' + '0000' + '012c' + '5a');
      await peer.write(1, 20, Buffer.from([0x12, 0x34]));
      expect(await client.read(['DB1.DBW20'])).to.deep.equal({ 'DB1.DBW20': 0x1234 });
      expect(await client.read(['DB1.DBD0:REAL', 'DB1.DBD4:DINT', 'DB1.DBW10', 'DB1.DBB12'])).to.deep.equal({
        'DB1.DBD0:REAL': 21.5,
        'DB1.DBD4:DINT': -7,
        'DB1.DBW10': 300,
        'DB1.DBB12': 0x5a,
      });
      const session = (client as unknown as { session: { integrityIds: unknown } }).session;
      // The reads: the protection level at connect, the PLC's SystemLimits (once per session, issue #32; the emulator reports none) and the two above.
      expect(session.integrityIds).to.deep.equal({ read: 4, write: 1 });
      expect(await client.cpuState()).to.equal('RUN');
      await peer.setCpuState('STOP');
      expect(await client.cpuState()).to.equal('STOP');
      await peer.setCpuState('RUN');
      expect((await client.dataBlocks()).map((b) => b.number)).to.deep.equal([1]);
      expect(session.integrityIds).to.deep.equal({ read: 7, write: 1 });
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

    it('reads and writes a standard DB by the names of its source (a compiled symbol table), at the offsets the source gives', async () => {
      const symbols = compileSymbols(
        [
          {
            name: 'Tank.db',
            content:
              'DATA_BLOCK "Tank"\n{ S7_Optimized_Access := \'FALSE\' }\nSTRUCT\n  Level : REAL;\n  Count : DINT;\n  Name : STRING[8];\nEND_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n',
          },
        ],
        { db: { Tank: 1 } },
      );
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?fingerprint=${cert.fingerprint}&timeout=5000`, { symbols });
      client.on('layoutUnknown', () => {});
      await client.connect();
      await client.write({ '"Tank".Level': 3.25, '"Tank".Count': 42, '"Tank".Name': 'pump' });
      expect(await client.read(['"Tank".Level', '"Tank".Count', '"Tank".Name'])).to.deep.equal({
        '"Tank".Level': 3.25,
        '"Tank".Count': 42,
        '"Tank".Name': 'pump',
      });
      const memory = await peer.read(1, 0, 14);
      expect(memory.readFloatBE(0)).to.equal(3.25);
      expect(memory.readInt32BE(4)).to.equal(42);
      expect(memory.subarray(8, 14).toString('latin1')).to.equal('\x08\x04pump');
      await client.close();
    });

    it('refuses a certificate the pin does not match before any S7CommPlus request, showing the pin that would match', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?fingerprint=${'0'.repeat(64)}&timeout=5000`);
      const err = await connectError(client);
      expect(err.code).to.equal('CERTIFICATE_UNTRUSTED');
      expect(err.message).to.contain('is not the pinned one');
      expect(err.message).to.contain(`fingerprint=${cert.fingerprint.toUpperCase()}`);
      expect(err.message).to.contain('plcwire test PLC');
      expect(client.stats.requestsSent).to.equal(0);
      await client.close();
      await noConnections(peer);
    });

    it('refuses a certificate nothing in the URL trusts, and says how to pin it', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?timeout=5000`);
      const err = await connectError(client);
      expect(err.code).to.equal('CERTIFICATE_UNTRUSTED');
      expect(err.message).to.contain('nothing in the URL pins it');
      expect(err.message).to.match(/fingerprint=[0-9A-F]{64}/);
      expect(client.stats.requestsSent).to.equal(0);
      await client.close();
      await noConnections(peer);
    });

    it('insecure=true connects and warns with the certificate it accepted unchecked', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?insecure=true&timeout=5000`);
      const warnings: string[] = [];
      client.on('insecure', (e: { message: string }) => warnings.push(e.message));
      await client.connect();
      expect(warnings).to.have.length(1);
      expect(warnings[0]).to.contain(`fingerprint=${cert.fingerprint.toUpperCase()}`);
      await client.close();
    });

    it('tls=false against a PLC that starts TLS fails, saying to drop tls=false: never a fallback to plain text', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?tls=false&timeout=3000`);
      const err = await connectError(client);
      expect(err.code).to.equal('CONNECT_FAILED');
      expect(err.message).to.contain('CreateObject failed');
      expect(err.message).to.contain('drop tls=false');
      await client.close();
      await noConnections(peer);
    });
  });

  describe('in plain V1 (tls=false)', () => {
    let peer: S7CommPlusPeerServer;
    before(async () => (peer = await startS7CommPlusServer(python, { dbs: [DB1], version: 1 })));
    after(() => peer?.stop());

    it('connects without IntegrityIds and closes with a DeleteObject', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?tls=false&timeout=5000`);
      await client.connect();
      const session = (client as unknown as { session: { integrityIds: unknown; version: number } }).session;
      expect(session.integrityIds).to.equal(undefined);
      expect(session.version).to.equal(1);
      expect(client.certificate).to.equal(undefined);
      await client.close();
      // CreateObject, the session setup, the protection level, the DeleteObject.
      expect(client.stats.requestsSent).to.equal(4);
      await noConnections(peer);
    });

    it('reads and writes by address and tells the CPU state in plain text too', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?tls=false&timeout=5000`);
      await client.connect();
      await client.write({ 'DB1.DBD4:DINT': 123456, 'DB1.DBW10': 7 });
      expect(await client.read(['DB1.DBD4:DINT', 'DB1.DBW10'])).to.deep.equal({ 'DB1.DBD4:DINT': 123456, 'DB1.DBW10': 7 });
      expect(await client.cpuState()).to.equal('RUN');
      await client.close();
    });

    it('puts a poll in the fewest requests the item limit allows: 20 tags in one, 21 in two, 12 in three with maxItems=5', async () => {
      const tags = (n: number) => Array.from({ length: n }, (_, i) => `DB1.DBB${i}`);
      for (const [query, count, requests] of [
        ['', 20, 1],
        ['', 21, 2],
        ['&maxItems=5', 12, 3],
      ] as const) {
        const client = createClient(`s7plus://127.0.0.1:${peer.port}?tls=false&timeout=5000${query}`);
        await client.connect();
        // The session's first read asks the PLC's SystemLimits too (issue #32): the emulator reports none, 20 stay.
        await client.read(['DB1.DBB0']);
        expect(client.maxItems).to.equal(query ? 5 : 20);
        const before = client.stats.requestsSent;
        const values = await client.read(tags(count));
        expect(Object.keys(values), query).to.have.length(count);
        expect(client.stats.requestsSent - before, `${count} tags${query}`).to.equal(requests);
        await client.close();
      }
    });

    it('a TLS URL against a PLC without TLS fails, naming tls=false: never a fallback to plain text', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?insecure=true&timeout=3000`);
      const err = await connectError(client);
      expect(err.code).to.equal('CONNECT_FAILED');
      expect(err.message).to.contain('TLS failed');
      expect(err.message).to.contain('tls=false reaches it');
      expect(client.stats.requestsSent).to.equal(0);
      await client.close();
      await noConnections(peer);
    });
  });

  describe('a PLC that resets the connection on a too large request', () => {
    let peer: S7CommPlusPeerServer;
    before(async () => (peer = await startS7CommPlusServer(python, { dbs: [DB1], version: 1, maxRequestBytes: 250 })));
    after(() => peer?.stop());

    it('teaches the client a lower item limit: the read after the reconnect goes in smaller requests and gets every value', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?tls=false&timeout=5000`, {
        backoff: { initialDelay: 10, maxDelay: 50 },
      });
      await peer.write(1, 0, Buffer.from(Array.from({ length: 20 }, (_, i) => i + 1)));
      const limits: { limit: number; was: number }[] = [];
      client.on('itemLimit', (e: { limit: number; was: number }) => limits.push(e));
      client.on('error', () => {});
      await client.connect();
      const tags = Array.from({ length: 20 }, (_, i) => `DB1.DBB${i}`);
      const err = await rejection(client.read(tags));
      expect(err.code).to.equal('CONNECTION_LOST');
      expect(limits).to.deep.equal([{ limit: 10, was: 20 }]);
      await waitFor(client, 'connected', 10_000);
      const values = await client.read(tags);
      expect(Object.values(values)).to.deep.equal(Array.from({ length: 20 }, (_, i) => i + 1));
      expect(client.maxItems).to.equal(10);
      await client.close();
      await noConnections(peer);
    });
  });

  describe('a PLC that speaks V2 asked for plain text', () => {
    let peer: S7CommPlusPeerServer;
    before(async () => (peer = await startS7CommPlusServer(python, { dbs: [DB1], version: 2 })));
    after(() => peer?.stop());

    it('is refused with what the PLC wants and what to do', async () => {
      const client = createClient(`s7plus://127.0.0.1:${peer.port}?tls=false&timeout=5000`);
      const err = await connectError(client);
      expect(err.code).to.equal('CONNECT_FAILED');
      expect(err.message).to.contain('speaks S7CommPlus V2 and wants it over TLS');
      expect(err.message).to.contain('drop tls=false');
      await client.close();
      await noConnections(peer);
    });
  });
});
