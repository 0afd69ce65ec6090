/**
 * lib/iso/: the COTP connection request with TSAPs of any length, and the ISO
 * connect step (TCP, then CR → CC) against a loopback peer that answers each
 * way a peer can: a confirm, a disconnect, a TPDU error, another TPDU, bytes of
 * another protocol, silence, a closed connection.
 */
import { expect } from 'chai';
import * as net from 'node:net';
import { PlcError, ProtocolError, ValueError } from '../lib/errors';
import { IsoConnectError, isoConnect, type IsoConnectOptions } from '../lib/iso/connect';
import { decodeCotp, encodeConnectionConfirm, encodeConnectionRequest, encodeCotpError, encodeDisconnectRequest } from '../lib/iso/cotp';
import { tpktFrame } from '../lib/iso/tpkt';
import { hex, show } from './fixtures/s7';

/** S7CommPlus's called TSAP: s7commplus (MIT), s7commplus/protocol.py, S7COMMPLUS_REMOTE_TSAP. */
const ROOT_HMI = Buffer.from('SIMATIC-ROOT-HMI', 'ascii');

/**
 * The CR s7commplus sends (s7commplus (MIT), s7commplus/transport.py, _build_cotp_cr): calling TSAP 0x0600
 * (2 bytes), called TSAP "SIMATIC-ROOT-HMI" (16 bytes), then the TPDU size 0x0A; LI 31, TPKT length 36.
 */
const ROOT_HMI_CR = hex(`03 00 00 24 | 1F E0 00 00 00 01 00 | C1 02 06 00 | C2 10 ${ROOT_HMI.toString('hex')} | C0 01 0A`);

interface Peer {
  port: number;
  /** The first chunk of each connection: the client's CR. */
  requests: Buffer[];
  /** The peer's end of each connection. */
  sockets: net.Socket[];
  /** Resolves when a connection's client end is gone. */
  closed: Promise<void>;
  server: net.Server;
}

/** A loopback peer that answers the first frame with `answer` (or nothing). */
async function peer(answer: (socket: net.Socket, request: Buffer) => void): Promise<Peer> {
  const requests: Buffer[] = [];
  const sockets: net.Socket[] = [];
  let closedResolve!: () => void;
  const closed = new Promise<void>((r) => (closedResolve = r));
  const server = net.createServer((s) => {
    sockets.push(s);
    s.on('error', () => undefined);
    s.once('data', (chunk) => {
      requests.push(chunk);
      answer(s, chunk);
    });
    s.on('close', () => closedResolve());
  });
  await new Promise<void>((r) => server.listen(0, '127.0.0.1', r));
  return { port: (server.address() as net.AddressInfo).port, requests, sockets, closed, server };
}

function options(port: number, more: Partial<IsoConnectOptions> = {}): IsoConnectOptions {
  return {
    name: `iso://127.0.0.1:${port}`,
    host: '127.0.0.1',
    port,
    timeout: 5000,
    callingTsap: 0x0600,
    calledTsap: ROOT_HMI,
    tpduSize: 0x0a,
    ...more,
  };
}

async function refusedWith(p: Peer, more: Partial<IsoConnectOptions> = {}): Promise<IsoConnectError> {
  try {
    const err = await isoConnect(options(p.port, more)).then(
      (c) => {
        c.frames.stop();
        c.socket.destroy();
        return undefined;
      },
      (e: unknown) => e,
    );
    expect(err).to.be.instanceOf(IsoConnectError);
    await p.closed; // the step left no socket open
    return err as IsoConnectError;
  } finally {
    p.server.close();
  }
}

describe('ISO-on-TCP (lib/iso/)', () => {
  describe('connection request with TSAPs of any length', () => {
    it('encodes the CR with the TSAP SIMATIC-ROOT-HMI byte for byte as s7commplus sends it', () => {
      const frame = encodeConnectionRequest({ sourceRef: 1, callingTsap: 0x0600, calledTsap: ROOT_HMI, tpduSize: 0x0a });
      expect(show(frame)).to.equal(show(ROOT_HMI_CR));
      // A TSAP that is not 2 bytes long decodes as -1 (a CotpConnection's TSAPs are numbers), the rest as sent.
      expect(decodeCotp(frame)).to.deep.equal({
        type: 'CR',
        sourceRef: 1,
        destinationRef: 0,
        callingTsap: 0x0600,
        calledTsap: -1,
        tpduSize: 0x0a,
      });
    });

    it('a TSAP given as 2 bytes is the same frame as the number', () => {
      const asBytes = encodeConnectionRequest({
        sourceRef: 1,
        callingTsap: Buffer.from([0x10, 0x00]),
        calledTsap: Buffer.from([0x03, 0x01]),
        tpduSize: 0x0a,
      });
      expect(show(asBytes)).to.equal(
        show(encodeConnectionRequest({ sourceRef: 1, callingTsap: 0x1000, calledTsap: 0x0301, tpduSize: 0x0a })),
      );
    });

    it('refuses an empty TSAP and one longer than a parameter can carry (ValueError)', () => {
      expect(() => encodeConnectionRequest({ sourceRef: 1, callingTsap: 0x0600, calledTsap: Buffer.alloc(0), tpduSize: 0x0a })).to.throw(
        ValueError,
        /called TSAP.*0 bytes/,
      );
      expect(() => encodeConnectionRequest({ sourceRef: 1, callingTsap: Buffer.alloc(256), calledTsap: 1, tpduSize: 0x0a })).to.throw(
        ValueError,
        /calling TSAP.*256 bytes/,
      );
      // Two TSAPs of 255 bytes fit no length indicator (at most 254).
      expect(() =>
        encodeConnectionRequest({ sourceRef: 1, callingTsap: Buffer.alloc(255), calledTsap: Buffer.alloc(255), tpduSize: 0x0a }),
      ).to.throw(ValueError, /length indicator/);
    });
  });

  describe('isoConnect: TCP, then CR → CC', () => {
    it('a confirm: the socket, its frames and what the peer confirmed; the peer got our TSAPs', async () => {
      const p = await peer((s) =>
        s.write(encodeConnectionConfirm({ destinationRef: 1, sourceRef: 0x44, callingTsap: 0x0600, calledTsap: 0x0301, tpduSize: 0x09 })),
      );
      try {
        const c = await isoConnect(options(p.port));
        try {
          expect(show(p.requests[0]!)).to.equal(show(ROOT_HMI_CR));
          expect(c.confirm).to.deep.include({ type: 'CC', sourceRef: 0x44, destinationRef: 1, tpduSize: 0x09 });
          expect(c.tpduBytes).to.equal(512);
          expect(c.socket.destroyed).to.equal(false);
          // The frames keep listening: the driver's next answer comes through them.
          const dt = tpktFrame(4);
          dt.set([2, 0xf0, 0x80, 0x32], 4);
          const next = c.frames.next();
          p.sockets[0]!.write(dt);
          expect(show(((await next) as { frame: Buffer }).frame)).to.equal(show(dt));
        } finally {
          c.frames.stop();
          c.socket.destroy();
        }
      } finally {
        p.server.close();
      }
    });

    it('a disconnect request: CONNECT_FAILED with the reason, in words', async () => {
      const err = await refusedWith(await peer((s) => s.end(encodeDisconnectRequest(1, 0, 3))));
      expect(err.code).to.equal('CONNECT_FAILED');
      expect(err.refusal).to.deep.equal({ kind: 'disconnect', reason: 3 });
      expect(err.message).to.match(/^iso:\/\/127\.0\.0\.1:\d+: .*COTP disconnect, reason 3: the called TSAP is unknown/);
    });

    it('a disconnect for congestion says all connections are in use', async () => {
      const err = await refusedWith(await peer((s) => s.end(encodeDisconnectRequest(1, 0, 1))));
      expect(err.refusal).to.deep.equal({ kind: 'disconnect', reason: 1 });
      expect(err.message).to.include('all connections in use');
    });

    it('a TPDU error: CONNECT_FAILED with the reject cause', async () => {
      const err = await refusedWith(await peer((s) => s.write(encodeCotpError(1, 2))));
      expect(err.code).to.equal('CONNECT_FAILED');
      expect(err.refusal).to.deep.equal({ kind: 'error', cause: 2 });
    });

    it('another TPDU where the confirm belongs (a DT): unexpected', async () => {
      const err = await refusedWith(await peer((s) => s.write(hex('03 00 00 07 02 F0 80'))));
      expect(err.refusal).to.deep.equal({ kind: 'unexpected', type: 'DT' });
    });

    it('another protocol (an HTTP answer): garbage, with the ProtocolError as cause', async () => {
      const err = await refusedWith(await peer((s) => s.write('HTTP/1.1 400 Bad Request\r\n\r\n')));
      expect(err.code).to.equal('CONNECT_FAILED');
      expect(err.refusal.kind).to.equal('garbage');
      expect(err.cause).to.be.instanceOf(ProtocolError);
      expect(err.message).to.include('not ISO-on-TCP: TPKT version 72, expected 3');
    });

    it('a TPKT whose COTP is malformed: garbage too', async () => {
      const err = await refusedWith(await peer((s) => s.write(hex('03 00 00 07 7F D0 00'))));
      expect(err.refusal.kind).to.equal('garbage');
    });

    it('the peer closes without an answer: closed', async () => {
      const err = await refusedWith(await peer((s) => s.end()));
      expect(err.code).to.equal('CONNECT_FAILED');
      expect(err.refusal.kind).to.equal('closed');
    });

    it('silence: TIMEOUT after answerTimeout, the socket closed', async () => {
      const err = await refusedWith(await peer(() => undefined), { answerTimeout: 50 });
      expect(err.code).to.equal('TIMEOUT');
      expect(err.refusal).to.deep.equal({ kind: 'silent', ms: 50 });
      expect(err.message).to.include('no answer to the connection request within 50 ms');
    });

    it('an abort while waiting for the answer: ABORTED naming the peer, the socket closed', async () => {
      const p = await peer(() => ctl.abort());
      const ctl = new AbortController();
      try {
        const err = (await isoConnect(options(p.port, { signal: ctl.signal })).catch((e: unknown) => e)) as PlcError;
        expect(err).to.be.instanceOf(PlcError).and.not.instanceOf(IsoConnectError);
        expect(err.code).to.equal('ABORTED');
        expect(err.message).to.equal(`connecting to iso://127.0.0.1:${p.port} was aborted`);
        await p.closed;
      } finally {
        p.server.close();
      }
    });

    it('nothing listening: the TCP step fails (CONNECT_FAILED naming host and port), not the COTP step', async () => {
      const s = net.createServer();
      await new Promise<void>((r) => s.listen(0, '127.0.0.1', r));
      const port = (s.address() as net.AddressInfo).port;
      await new Promise((r) => s.close(r));
      const err = (await isoConnect(options(port)).catch((e: unknown) => e)) as PlcError;
      expect(err).to.be.instanceOf(PlcError).and.not.instanceOf(IsoConnectError);
      expect(err.code).to.equal('CONNECT_FAILED');
      expect(err.message).to.include(`127.0.0.1:${port}`);
    });
  });
});
