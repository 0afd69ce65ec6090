/**
 * The S7 client's handshake in S7's words: each way a peer can answer the COTP
 * connection request or setup communication, against a scripted loopback
 * peer, with the error code, the words and the cause the client gives. The
 * COTP step is the ISO connect step of lib/iso/connect.ts; these pin what the
 * client makes of its answers.
 */
import { expect } from 'chai';
import * as net from 'node:net';
import type { PlcError } from '../lib/errors';
import { ProtocolError } from '../lib/errors';
import { S7Client } from '../lib/s7/client';
import { encodeConnectionConfirm, encodeCotpError, encodeDisconnectRequest, encodeErrorAck, encodeSetupAck } from '../lib/s7/codec';
import { parseUrl, type S7Endpoint } from '../lib/url';

/** A peer that answers the client's first frame (the CR) with `cotp`, its second (setup communication) with `setup`. */
async function scripted(
  cotp: (s: net.Socket) => void,
  setup: (s: net.Socket) => void = () => undefined,
): Promise<{ port: number; server: net.Server }> {
  const server = net.createServer((s) => {
    s.on('error', () => undefined);
    let frames = 0;
    s.on('data', () => (++frames === 1 ? cotp(s) : frames === 2 ? setup(s) : undefined));
  });
  await new Promise<void>((r) => server.listen(0, '127.0.0.1', r));
  return { port: (server.address() as net.AddressInfo).port, server };
}

/** The error of one connect to the scripted peer (the client closed after it). */
async function connectError(cotp: (s: net.Socket) => void, setup?: (s: net.Socket) => void, query = 'slot=1'): Promise<PlcError> {
  const { port, server } = await scripted(cotp, setup);
  const client = new S7Client(parseUrl(`s7://127.0.0.1:${port}?${query}&timeout=1500`) as S7Endpoint);
  try {
    return (await client.connect().then(
      () => expect.fail('connected'),
      (e: unknown) => e,
    )) as PlcError;
  } finally {
    await client.close();
    await new Promise((r) => server.close(r));
  }
}

const confirm = (s: net.Socket) =>
  s.write(encodeConnectionConfirm({ destinationRef: 1, sourceRef: 0x11, callingTsap: 0x0100, calledTsap: 0x0101, tpduSize: 0x0a }));

describe('S7 client handshake, each answer in its words', function () {
  this.timeout(10000);

  it('a COTP disconnect: CONNECT_FAILED naming rack and slot', async () => {
    const err = await connectError((s) => s.end(encodeDisconnectRequest(1, 0, 3)), undefined, 'rack=0&slot=3');
    expect(err.code).to.equal('CONNECT_FAILED');
    expect(err.message).to.match(
      /^s7:\/\/127\.0\.0\.1:\d+ refused the connection \(rack 0, slot 3\): wrong rack\/slot or TSAP, or the PLC's connection limit is reached$/,
    );
  });

  it('a COTP disconnect with configured TSAPs: CONNECT_FAILED naming the called TSAP', async () => {
    const err = await connectError((s) => s.end(encodeDisconnectRequest(1, 0, 3)), undefined, 'localTsap=0100&remoteTsap=0200');
    expect(err.code).to.equal('CONNECT_FAILED');
    expect(err.message).to.include('refused the connection (TSAP 0x0200)');
  });

  it('a COTP TPDU error: a refusal too', async () => {
    const err = await connectError((s) => s.write(encodeCotpError(1, 2)));
    expect(err.code).to.equal('CONNECT_FAILED');
    expect(err.message).to.include('refused the connection (rack 0, slot 1)');
  });

  it('the connection closed without an answer: CONNECT_FAILED, closed during the handshake', async () => {
    const err = await connectError((s) => s.end());
    expect(err.code).to.equal('CONNECT_FAILED');
    expect(err.message).to.match(
      /^s7:\/\/127\.0\.0\.1:\d+ closed the connection during the handshake \(wrong rack\/slot or TSAP, or the connection limit is reached\)$/,
    );
  });

  it('another protocol: CONNECT_FAILED with the ProtocolError as cause', async () => {
    const err = await connectError((s) => s.write('HTTP/1.1 400 Bad Request\r\n\r\n'));
    expect(err.code).to.equal('CONNECT_FAILED');
    expect(err.message).to.match(/^s7:\/\/127\.0\.0\.1:\d+: TPKT version 72, expected 3$/);
    expect(err.cause).to.be.instanceOf(ProtocolError);
  });

  it('setup communication refused by a header error: the PLC error, in its words', async () => {
    const err = await connectError(confirm, (s) => s.write(encodeErrorAck(0, 0x85, 0x00)));
    expect(err.code).to.equal('PDU_TOO_LARGE');
    expect(err.message).to.match(/^s7:\/\/127\.0\.0\.1:\d+ setup communication: the PLC answered 0x8500: /);
  });

  it('an unusable PDU size: CONNECT_FAILED saying so', async () => {
    const err = await connectError(confirm, (s) => s.write(encodeSetupAck(0, { maxAmqCalling: 1, maxAmqCalled: 1, pduSize: 32 })));
    expect(err.code).to.equal('CONNECT_FAILED');
    expect(err.message).to.match(/negotiated an unusable PDU size of 32$/);
  });

  it('the connection closed at setup communication: CONNECT_FAILED, closed during the handshake', async () => {
    const err = await connectError(confirm, (s) => s.end());
    expect(err.code).to.equal('CONNECT_FAILED');
    expect(err.message).to.include('closed the connection during the handshake');
  });
});
