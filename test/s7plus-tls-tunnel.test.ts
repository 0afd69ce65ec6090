/**
 * lib/s7plus/transport/tunnel.ts: bytes in COTP DT frames over a connected
 * ISO-on-TCP socket, with Node's TLS on top on both sides; and our client
 * tunnel against the s7commplus package's (MIT) server emulator, up to a
 * completed TLS handshake. Every test ends with 0 connections open at the
 * server it used.
 */
import { expect } from 'chai';
import * as crypto from 'node:crypto';
import * as fs from 'node:fs';
import * as net from 'node:net';
import * as os from 'node:os';
import * as path from 'node:path';
import * as tls from 'node:tls';
import { FrameReader } from '../lib/link/framer';
import { decodeCotp } from '../lib/s7/codec/cotp';
import { checkTpkt } from '../lib/s7/codec/tpkt';
import { fingerprint256, generateCertificate, type GeneratedCertificate } from '../lib/s7plus/transport/cert';
import { CotpTunnel } from '../lib/s7plus/transport/tunnel';
import { skipBecause } from './support/skip';
import { cotpAccept, cotpConnect, countingServer, s7commplusPython, startPythonServer } from './support/s7plus-tls';
import { activeHandles, settle, until, waitFor } from './support/wait';

const dt = (payload: Buffer, eot = true) => {
  const f = Buffer.alloc(7 + payload.length);
  f[0] = 3;
  f.writeUInt16BE(f.length, 2);
  f[4] = 2;
  f[5] = 0xf0;
  f[6] = eot ? 0x80 : 0;
  payload.copy(f, 7);
  return f;
};

/** A client socket and the server's accepted one, COTP-connected; the client's and (unless `rawServer`) the server's wrapped in a tunnel. */
async function tunnelPair(tpduCode = 0x0a, rawServer = false) {
  let accepted!: (s: net.Socket) => void;
  const serverSide = new Promise<net.Socket>((r) => (accepted = r));
  const srv = await countingServer((s) => accepted(s));
  const client = net.connect({ host: '127.0.0.1', port: srv.port });
  const server = await serverSide;
  const [serverHead, { head, tpduSize }] = await Promise.all([cotpAccept(server, tpduCode), cotpConnect(client)]);
  // Listeners the sockets have before the tunnels add theirs (Node's own), to check that none of ours is left.
  const baseline = { client: listeners(client), server: listeners(server) };
  const clientTunnel = new CotpTunnel(client, { tpduSize, head });
  const serverTunnel = rawServer ? undefined : new CotpTunnel(server, { tpduSize: 1 << tpduCode, head: serverHead });
  const close = async () => {
    clientTunnel.destroy();
    serverTunnel?.destroy();
    server.destroy();
    await until(() => client.destroyed && server.destroyed, 5000, 'both sockets closed');
    await new Promise((r) => srv.server.close(r));
  };
  return { client, server, clientTunnel, serverTunnel, srv, close, baseline };
}

const listeners = (s: net.Socket) => ['data', 'end', 'drain', 'error', 'close'].reduce((n, e) => n + s.listenerCount(e), 0);

/** The TPKT frames a raw socket receives, cut and decoded. */
function collectFrames(socket: net.Socket) {
  const reader = new FrameReader(checkTpkt);
  const frames: Buffer[] = [];
  socket.on('data', (d) => frames.push(...reader.push(d)));
  return frames;
}

describe('s7plus transport: COTP tunnel', function () {
  this.timeout(30000);
  let cert: GeneratedCertificate;
  before(async () => {
    cert = await generateCertificate();
  });

  it('cuts a write into DT frames of at most the TPDU size, EOT on the last only', async () => {
    const srv = await countingServer(() => {});
    const client = net.connect({ host: '127.0.0.1', port: srv.port });
    let peer!: net.Socket;
    srv.server.once('connection', (s) => (peer = s));
    await waitFor(client, 'connect');
    await until(() => !!peer, 3000, 'accepted');
    const frames = collectFrames(peer);
    const tunnel = new CotpTunnel(client, { tpduSize: 128 });
    const data = crypto.randomBytes(600);
    tunnel.write(data);
    tunnel.write(Buffer.from('xy'));
    await until(
      () => Buffer.concat(frames.map((f) => decodeCotp(f)).map((m) => (m.type === 'DT' ? m.payload : Buffer.alloc(0)))).length === 602,
    );
    // TPDU size 128 is the COTP TPDU, its 3-byte header included (ISO 8073): 125 payload bytes, 132 with TPKT.
    expect(frames.map((f) => f.length)).to.deep.equal([132, 132, 132, 132, 7 + 600 - 4 * 125, 9]);
    expect(frames.map((f) => f[6])).to.deep.equal([0, 0, 0, 0, 0x80, 0x80]);
    const payload = Buffer.concat(frames.map((f) => f.subarray(7)));
    expect(payload.equals(Buffer.concat([data, Buffer.from('xy')]))).to.equal(true);
    tunnel.destroy();
    await until(() => client.destroyed);
    peer.destroy();
    await new Promise((r) => srv.server.close(r));
    expect(await srv.open()).to.equal(0);
  });

  it('gives back the DT payloads as one stream, however TCP cuts them, after the bytes handed over with the CC', async () => {
    const srv = await countingServer(() => {});
    const client = net.connect({ host: '127.0.0.1', port: srv.port });
    let peer!: net.Socket;
    srv.server.once('connection', (s) => (peer = s));
    await until(() => !!peer, 3000, 'accepted');
    const stream = Buffer.concat([dt(Buffer.from('bc'), false), dt(Buffer.alloc(0)), dt(Buffer.from('def')), dt(Buffer.alloc(3000, 0x41))]);
    const tunnel = new CotpTunnel(client, { tpduSize: 1024, head: dt(Buffer.from('a')).subarray(0, 5) });
    let got = Buffer.alloc(0);
    tunnel.on('data', (d: Buffer) => (got = Buffer.concat([got, d])));
    // The head ends inside a frame: its rest comes first, then the stream byte by byte in a few bursts.
    peer.write(dt(Buffer.from('a')).subarray(5));
    for (let i = 0; i < stream.length; i += 97) peer.write(stream.subarray(i, i + 97));
    await until(() => got.length === 3006, 5000, 'all bytes');
    expect(got.subarray(0, 6).toString()).to.equal('abcdef');
    peer.end();
    await waitFor(tunnel, 'close');
    expect(client.destroyed).to.equal(true);
    await new Promise((r) => srv.server.close(r));
    expect(await srv.open()).to.equal(0);
  });

  for (const version of ['TLSv1.2', 'TLSv1.3'] as const) {
    it(`carries Node TLS (${version}) both ways between a client and a server tunnel, 1 MB each way intact`, async () => {
      const handlesBefore = activeHandles();
      const pair = await tunnelPair();
      const serverTls = new tls.TLSSocket(pair.serverTunnel!, {
        isServer: true,
        cert: cert.cert,
        key: cert.key,
        minVersion: version,
        maxVersion: version,
      });
      const clientTls = tls.connect({
        socket: pair.clientTunnel,
        rejectUnauthorized: false,
        checkServerIdentity: () => undefined,
        maxVersion: version,
      });
      await waitFor(clientTls, 'secureConnect', 10000);
      expect(clientTls.getProtocol()).to.equal(version);
      expect(fingerprint256(clientTls.getPeerX509Certificate()!.raw)).to.equal(cert.fingerprint);
      // Echo server: whatever arrives goes back.
      serverTls.pipe(serverTls);
      const sent = crypto.randomBytes(1 << 20);
      const back: Buffer[] = [];
      clientTls.on('data', (d: Buffer) => back.push(d));
      clientTls.write(sent);
      await until(() => back.reduce((n, b) => n + b.length, 0) >= sent.length, 20000, 'echo of 1 MB');
      expect(Buffer.concat(back).equals(sent)).to.equal(true);
      // A clean end from the client closes everything: TLS close_notify, FIN, both sockets.
      clientTls.end();
      await Promise.all([waitFor(clientTls, 'close', 5000), waitFor(serverTls, 'close', 5000)]);
      await until(() => pair.client.destroyed && pair.server.destroyed, 5000, 'sockets closed');
      expect(listeners(pair.client), 'listeners left on the client socket').to.equal(pair.baseline.client);
      expect(listeners(pair.server), 'listeners left on the server socket').to.equal(pair.baseline.server);
      expect(await pair.srv.open()).to.equal(0);
      await pair.close();
      await settle();
      expect(activeHandles(), 'handles (sockets, servers, timers) left').to.equal(handlesBefore);
    });
  }

  it('passes backpressure through: a reader that stops makes the writer stop, and nothing is lost', async () => {
    const pair = await tunnelPair();
    const serverTls = new tls.TLSSocket(pair.serverTunnel!, { isServer: true, cert: cert.cert, key: cert.key });
    const clientTls = tls.connect({ socket: pair.clientTunnel, rejectUnauthorized: false, checkServerIdentity: () => undefined });
    await waitFor(clientTls, 'secureConnect', 10000);
    serverTls.pause();
    const hash = crypto.createHash('sha256');
    let written = 0;
    const chunk = crypto.randomBytes(64 * 1024);
    while (clientTls.write(chunk)) {
      hash.update(chunk);
      written += chunk.length;
      if (written > 64 << 20) break;
    }
    hash.update(chunk);
    written += chunk.length;
    expect(written, 'write() said stop long before 64 MB').to.be.below(64 << 20);
    // The tunnel pauses the server socket once TLS stops reading; then measure what is held in memory on the receiving side.
    await until(() => pair.server.isPaused(), 10000, 'the server socket paused by backpressure');
    const held = pair.serverTunnel!.readableLength + pair.server.readableLength + serverTls.readableLength;
    expect(held, 'bytes buffered while the reader is paused').to.be.below(2 << 20);
    const received = crypto.createHash('sha256');
    let count = 0;
    serverTls.on('data', (d: Buffer) => {
      received.update(d);
      count += d.length;
    });
    serverTls.resume();
    await until(() => count === written, 20000, 'every byte received');
    expect(received.digest('hex')).to.equal(hash.digest('hex'));
    clientTls.destroy();
    await waitFor(serverTls, 'close', 5000);
    await pair.close();
    expect(await pair.srv.open()).to.equal(0);
  });

  const hostile: Array<[string, Buffer, RegExp]> = [
    ['a TPKT of version 4', Buffer.from([4, 0, 0, 10, 2, 0xf0, 0x80, 1, 2, 3]), /TPKT version 4/],
    ['a TPKT shorter than a COTP header', Buffer.from([3, 0, 0, 5, 2]), /shorter than a COTP header/],
    ['a COTP length indicator past the frame', Buffer.from([3, 0, 0, 8, 9, 0xf0, 0x80, 1]), /length indicator 9 runs past/],
    ['a COTP TPDU error', Buffer.from([3, 0, 0, 9, 4, 0x70, 0, 1, 2]), /TPDU error \(cause 2\)/],
    ['a COTP connection request in the middle', Buffer.from([3, 0, 0, 11, 6, 0xe0, 0, 0, 0, 1, 0]), /unexpected COTP CR/],
  ];
  for (const [what, bytes, message] of hostile) {
    it(`is destroyed with a ProtocolError on ${what}, and TLS above it fails`, async () => {
      const pair = await tunnelPair(0x0a, true);
      const clientTls = tls.connect({ socket: pair.clientTunnel, rejectUnauthorized: false, checkServerIdentity: () => undefined });
      const tunnelError = waitFor<Error & { code?: string }>(pair.clientTunnel, 'error');
      const tlsError = waitFor<Error>(clientTls, 'error');
      pair.server.write(bytes);
      const err = await tunnelError;
      expect(err.code).to.equal('PROTOCOL_ERROR');
      expect(err.message).to.match(message);
      expect(err.message).to.include('COTP tunnel from 127.0.0.1:');
      await tlsError;
      await until(() => pair.client.destroyed, 3000, 'client socket destroyed');
      expect(pair.client.listenerCount('data')).to.equal(0);
      await pair.close();
      expect(await pair.srv.open()).to.equal(0);
    });
  }

  it('ends on a COTP disconnect request, and closes its socket', async () => {
    const pair = await tunnelPair(0x0a, true);
    const ended = waitFor(pair.clientTunnel, 'end');
    const closed = waitFor(pair.clientTunnel, 'close');
    const data: Buffer[] = [];
    pair.clientTunnel.on('data', (d: Buffer) => data.push(d));
    pair.server.write(dt(Buffer.from('last')));
    pair.server.write(Buffer.from([3, 0, 0, 11, 6, 0x80, 0, 1, 0, 0x42, 0x80]));
    await ended;
    await closed;
    expect(Buffer.concat(data).toString()).to.equal('last');
    await until(() => pair.client.destroyed, 3000);
    await pair.close();
    expect(await pair.srv.open()).to.equal(0);
  });

  it('fails with CONNECTION_LOST when the peer resets the TCP connection', async () => {
    const pair = await tunnelPair(0x0a, true);
    const err = waitFor<Error & { code?: string }>(pair.clientTunnel, 'error');
    pair.server.resetAndDestroy();
    expect((await err).code).to.equal('CONNECTION_LOST');
    await pair.close();
    expect(await pair.srv.open()).to.equal(0);
  });

  it('refuses a TPDU size outside 128..65531 with a typed error', () => {
    const socket = new net.Socket();
    expect(() => new CotpTunnel(socket, { tpduSize: 64 }))
      .to.throw(/TPDU size.*64/)
      .with.property('code', 'INVALID_VALUE');
    expect(() => new CotpTunnel(socket, { tpduSize: 70000 })).to.throw(/70000/);
    socket.destroy();
  });

  describe('against the s7commplus server emulator (Python, MIT)', () => {
    let python: string | undefined;
    let dir: string;
    before(function () {
      const found = s7commplusPython();
      if (!found.python) skipBecause(this, found.reason!);
      python = found.python;
      dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-s7p-tls-'));
      fs.writeFileSync(path.join(dir, 'cert.pem'), cert.cert);
      fs.writeFileSync(path.join(dir, 'key.pem'), cert.key);
    });
    after(() => {
      if (dir) fs.rmSync(dir, { recursive: true, force: true });
    });

    it('COTP connect, InitSSL in clear, then a TLS handshake inside DT frames with our certificate; data flows inside', async () => {
      const peer = await startPythonServer(python!, path.join(dir, 'cert.pem'), path.join(dir, 'key.pem'));
      try {
        const socket = net.connect({ host: '127.0.0.1', port: peer.port });
        await waitFor(socket, 'connect');
        const { head, tpduSize } = await cotpConnect(socket);
        expect(tpduSize).to.equal(1024);
        const tunnel = new CotpTunnel(socket, { tpduSize, head });
        // InitSSL (function 0x05B3), V1 framing, transport flags 0x30 (s7commplus (MIT), connection.py _init_ssl).
        const initSsl = (seq: number) =>
          Buffer.from(`7201001231000005b30000${seq.toString(16).padStart(4, '0')}00000000300000000072010000`, 'hex');
        tunnel.write(initSsl(1));
        const reply: Buffer = await waitFor(tunnel, 'data', 5000);
        expect(reply.subarray(0, 2).toString('hex')).to.equal('7202'); // V2 emulation answers in V2 framing
        expect(reply.readUInt16BE(4 + 3)).to.equal(0x05b3);
        tunnel.pause();
        const clientTls = tls.connect({
          socket: tunnel,
          rejectUnauthorized: false,
          checkServerIdentity: () => undefined,
          minVersion: 'TLSv1.2',
        });
        await waitFor(clientTls, 'secureConnect', 10000);
        expect(fingerprint256(clientTls.getPeerX509Certificate()!.raw)).to.equal(cert.fingerprint);
        expect(['TLSv1.2', 'TLSv1.3']).to.include(clientTls.getProtocol());
        // The emulator answers requests inside TLS: an InitSSL again proves data both ways.
        clientTls.write(initSsl(2));
        const inside: Buffer = await waitFor(clientTls, 'data', 5000);
        expect(inside.readUInt16BE(4 + 3)).to.equal(0x05b3);
        expect(inside.readUInt16BE(4 + 7)).to.equal(2);
        clientTls.end();
        await waitFor(clientTls, 'close', 5000);
        await until(() => socket.destroyed, 5000);
      } finally {
        await peer.stop();
      }
    });
  });
});
