/**
 * The S7CommPlus simulator speaks through the client's transport (issue #32): the CR and CC are lib/iso's, the COTP
 * tunnel (CotpTunnel) cuts every DT frame to the TPDU size the CC confirmed, in plain text and in TLS alike, and the
 * TLS acceptor (acceptTls) runs the handshake. Before, the simulator confirmed 1024 bytes whatever was asked, sent a
 * plain-text answer in one DT frame of any length and TLS records in frames of 1028 bytes.
 */
import { expect } from 'chai';
import * as net from 'node:net';
import * as tls from 'node:tls';
import { TPDU_SIZE_CODE, TPKT_HEADER } from '../lib/iso/constants';
import { decodeCotp, encodeConnectionRequest } from '../lib/iso/cotp';
import { checkTpkt } from '../lib/iso/tpkt';
import { FrameReader } from '../lib/link/framer';
import { S7Server, type S7RefusedEvent } from '../lib/s7/server';
import { initSsl } from '../lib/s7plus/client/handshake';
import { S7PlusService } from '../lib/s7plus/server';
import { generateCertificate } from '../lib/s7plus/transport/cert';
import { CotpTunnel } from '../lib/s7plus/transport/tunnel';
import { readFrame } from './support/s7plus-tls';
import { until } from './support/wait';

describe('S7CommPlus simulator: the client transport on its side (issue #32)', function () {
  this.timeout(20000);
  let server: S7Server;
  let service: S7PlusService;
  const refused: S7RefusedEvent[] = [];

  before(async () => {
    const cert = await generateCertificate({ commonName: 'plcwire transport test' });
    service = new S7PlusService({ sources: [], tls: { cert: cert.cert, key: cert.key } });
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    server.on('refused', (e: S7RefusedEvent) => refused.push(e));
    await server.listen();
  });
  after(() => server.close());

  /** A CR calling SIMATIC-ROOT-HMI with `tpduSize`; the CC and every TPKT frame the simulator sends after it. */
  async function connect(tpduSize: number) {
    const socket = net.connect(server.port, '127.0.0.1');
    await new Promise((resolve) => socket.once('connect', resolve));
    socket.write(encodeConnectionRequest({ sourceRef: 7, callingTsap: 0x0600, calledTsap: Buffer.from('SIMATIC-ROOT-HMI'), tpduSize }));
    const { frame, rest } = await readFrame(socket);
    const sizes: number[] = [];
    const spy = new FrameReader(checkTpkt);
    for (const f of spy.push(rest)) sizes.push(f.length);
    socket.on('data', (chunk: Buffer) => {
      for (const f of spy.push(chunk)) sizes.push(f.length);
    });
    return { socket, cc: decodeCotp(frame), rest, sizes };
  }

  for (const code of [0x09, TPDU_SIZE_CODE] as const) {
    const bytes = 1 << code;
    it(`confirms the TPDU size asked for (${bytes} bytes) and keeps every frame within it, InitSSL in clear and the TLS handshake`, async () => {
      const { socket, cc, rest, sizes } = await connect(code);
      expect(cc).to.include({ type: 'CC', tpduSize: code, destinationRef: 7 });
      const tunnel = new CotpTunnel(socket, { tpduSize: bytes, head: rest });
      const signal = new AbortController().signal;
      await initSsl(tunnel, { name: 'the simulator', signal });
      const secure = tls.connect({ socket: tunnel, rejectUnauthorized: false, servername: 'localhost' });
      try {
        await new Promise<void>((resolve, reject) => {
          secure.once('secureConnect', resolve);
          secure.once('error', reject);
        });
        expect(secure.getPeerX509Certificate()!.fingerprint256.replace(/:/g, '')).to.equal(service.fingerprint);
        // The certificate flight alone is longer than one TPDU: cut, never over the confirmed size (ISO 8073 counts
        // the TPDU, COTP header and data, without TPKT's 4 bytes).
        expect(sizes.length).to.be.greaterThan(2);
        expect(Math.max(...sizes) - TPKT_HEADER).to.equal(bytes);
      } finally {
        secure.destroy();
      }
      await until(() => server.connectionCount === 0, 5000, 'the simulator to drop the connection');
      expect(refused, 'a client that leaves is not a refusal').to.deep.equal([]);
    });
  }

  it('a CR without a TPDU size gets 1024 bytes, as the S7 side confirms', async () => {
    const socket = net.connect(server.port, '127.0.0.1');
    await new Promise((resolve) => socket.once('connect', resolve));
    // The CR of lib/iso with the size parameter cut off: the length indicator lowered by 3.
    const cr = encodeConnectionRequest(
      { sourceRef: 9, callingTsap: 0x0600, calledTsap: Buffer.from('SIMATIC-ROOT-HMI'), tpduSize: 0x0a },
      'size-first',
    );
    const withoutSize = Buffer.concat([cr.subarray(0, 11), cr.subarray(14)]);
    withoutSize.writeUInt16BE(withoutSize.length, 2);
    withoutSize[4] = cr[4]! - 3;
    socket.write(withoutSize);
    const { frame } = await readFrame(socket);
    expect(decodeCotp(frame)).to.include({ type: 'CC', tpduSize: TPDU_SIZE_CODE });
    socket.destroy();
    await until(() => server.connectionCount === 0, 5000, 'the simulator to drop the connection');
  });
});
