/**
 * The S7CommPlus session (lib/s7plus/client/session.ts) against a scripted
 * PLC on the other end of a stream pair: sequence numbers and the two
 * IntegrityIds exactly as s7commplus (MIT) connection.py numbers them, one
 * request in flight, stale answers ignored, and every hostile answer (a
 * future sequence number, another function, garbage, a short SystemEvent,
 * silence) dropping the link with a typed error, the stream destroyed and
 * the client told once.
 */
import { expect } from 'chai';
import { duplexPair, type Duplex } from 'node:stream';
import { ConnectionError, PlcError } from '../lib/errors';
import { createClient } from '../lib/connect';
import { encodeFrames, S7pFrameReader } from '../lib/s7plus/codec/frame';
import { encodeInitSslResponse } from '../lib/s7plus/codec/session';
import { decodeUVlq32, encodeUVlq32 } from '../lib/s7plus/codec/vlq';
import { FunctionCode, ProtocolVersion } from '../lib/s7plus/constants';
import { S7PlusSession, type Ask } from '../lib/s7plus/client/session';
import { cotpAccept, countingServer } from './support/s7plus-tls';
import { until } from './support/wait';

interface Seen {
  version: number;
  fn: number;
  seq: number;
  sessionId: number;
  flags: number;
  body: Buffer;
}

/** The far end: every request it reads, and ways to answer. */
class FakePlc {
  readonly seen: Seen[] = [];
  private readonly reader = new S7pFrameReader();
  constructor(readonly end: Duplex) {
    end.on('data', (chunk: Buffer) => {
      for (const m of this.reader.push(chunk)) {
        const d = m.data;
        this.seen.push({
          version: m.version,
          fn: d.readUInt16BE(3),
          seq: d.readUInt16BE(7),
          sessionId: d.readUInt32BE(9),
          flags: d[13]!,
          body: d.subarray(14),
        });
      }
    });
    end.on('error', () => {});
  }
  /** A response to request `seq` of function `fn` with `payload` after the header. */
  answer(fn: number, seq: number, payload = Buffer.from([0x00]), version: number = ProtocolVersion.V2): void {
    const head = Buffer.alloc(10);
    head[0] = 0x32;
    head.writeUInt16BE(fn, 3);
    head.writeUInt16BE(seq, 7);
    this.end.write(encodeFrames(version, Buffer.concat([head, payload])));
  }
}

function open(timeout = 5000) {
  const [ours, theirs] = duplexPair();
  const lost: PlcError[] = [];
  const session = new S7PlusSession(
    ours,
    { sessionId: 0x1234, version: ProtocolVersion.V2, nextSeq: 5 },
    { name: 's7plus://test:102', timeout, lossError: (e) => e, lost: (_s, e) => lost.push(e) },
  );
  return { session, plc: new FakePlc(theirs), lost, ours };
}

/** The IntegrityId of a request: the VLQ just before the body's trailing 4 bytes. */
function integrityOf(body: Buffer, payloadLength: number): number {
  const id = decodeUVlq32(body, payloadLength - 4);
  expect(id.length + payloadLength, 'the id is all that was added').to.equal(body.length);
  return id.value;
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

const PAYLOAD = Buffer.from([1, 2, 3, 0, 0, 0, 0]);

/**
 * A request of function `fn` with PAYLOAD, its IntegrityId before the trailing 4 bytes (as the codec's encoders place
 * it); its answer is the message as it came.
 */
function ask(fn: number): Ask<null, Buffer> {
  return {
    functionCode: fn,
    body: null,
    encode: ({ header, integrityId }) => {
      const head = Buffer.alloc(14);
      head[0] = 0x31;
      head.writeUInt16BE(header.functionCode, 3);
      head.writeUInt16BE(header.sequence, 7);
      head.writeUInt32BE(header.sessionId, 9);
      head[13] = header.transportFlags;
      const id = integrityId === undefined ? Buffer.alloc(0) : encodeUVlq32(integrityId);
      return Buffer.concat([head, PAYLOAD.subarray(0, 3), id, PAYLOAD.subarray(3)]);
    },
    decode: (data) => ({ header: { functionCode: fn, sequence: data.readUInt16BE(7), transportFlags: data[9]! }, body: data }),
  };
}

describe('s7plus client: the session', () => {
  it('numbers requests one by one and sends the next only once the one before is answered', async () => {
    const { session, plc } = open();
    const a = session.request(ask(FunctionCode.GetMultiVariables));
    const b = session.request(ask(FunctionCode.SetMultiVariables));
    await until(() => plc.seen.length === 1);
    await new Promise((r) => setImmediate(r));
    expect(plc.seen, 'one in flight').to.have.length(1);
    expect(plc.seen[0]).to.include({ fn: FunctionCode.GetMultiVariables, seq: 5, sessionId: 0x1234, flags: 0x34, version: 2 });
    plc.answer(FunctionCode.GetMultiVariables, 5, Buffer.from([0x00, 0xaa]));
    expect([...(await a).subarray(10)]).to.deep.equal([0x00, 0xaa]);
    await until(() => plc.seen.length === 2);
    expect(plc.seen[1]).to.include({ fn: FunctionCode.SetMultiVariables, seq: 6 });
    plc.answer(FunctionCode.SetMultiVariables, 6);
    await b;
    session.destroy();
  });

  it('once started, reads carry the read IntegrityId and the rest the write one, each counting from 0, before the trailing 4 bytes', async () => {
    const { session, plc } = open();
    expect(session.integrityIds).to.equal(undefined);
    session.startIntegrity();
    const order = [
      FunctionCode.GetMultiVariables,
      FunctionCode.SetMultiVariables,
      FunctionCode.Explore,
      FunctionCode.GetMultiVariables,
      FunctionCode.SetMultiVariables,
    ];
    for (const [i, fn] of order.entries()) {
      const p = session.request(ask(fn));
      await until(() => plc.seen.length === i + 1);
      plc.answer(fn, plc.seen[i]!.seq);
      await p;
    }
    expect(plc.seen.map((s) => integrityOf(s.body, PAYLOAD.length))).to.deep.equal([0, 0, 1, 2, 1]);
    expect(plc.seen.map((s) => [...s.body.subarray(0, 3)])).to.deep.equal(order.map(() => [1, 2, 3]));
    expect(session.integrityIds).to.deep.equal({ read: 3, write: 2 });
    // The session setup write carries none and advances neither counter.
    const setup = session.request(ask(FunctionCode.SetMultiVariables), { integrity: false });
    await until(() => plc.seen.length === 6);
    expect(plc.seen[5]!.body).to.deep.equal(PAYLOAD);
    plc.answer(FunctionCode.SetMultiVariables, plc.seen[5]!.seq);
    await setup;
    expect(session.integrityIds).to.deep.equal({ read: 3, write: 2 });
    session.destroy();
  });

  it('wraps the sequence number at 65535 → 0', async () => {
    const [ours, theirs] = duplexPair();
    const session = new S7PlusSession(
      ours,
      { sessionId: 1, version: 2, nextSeq: 0xffff },
      { name: 't', timeout: 5000, lossError: (e) => e, lost: () => {} },
    );
    const plc = new FakePlc(theirs);
    for (const seq of [0xffff, 0]) {
      const p = session.request(ask(FunctionCode.GetMultiVariables));
      await until(() => plc.seen.at(-1)?.seq === seq);
      plc.answer(FunctionCode.GetMultiVariables, seq);
      await p;
    }
    session.destroy();
  });

  it('ignores an answer to an earlier sequence number (a request given up on) and takes the right one', async () => {
    const { session, plc } = open();
    const p = session.request(ask(FunctionCode.GetMultiVariables));
    await until(() => plc.seen.length === 1);
    plc.answer(FunctionCode.GetMultiVariables, 4, Buffer.from([0x00, 0x01]));
    plc.answer(FunctionCode.GetMultiVariables, 5, Buffer.from([0x00, 0x02]));
    expect([...(await p).subarray(10)]).to.deep.equal([0x00, 0x02]);
    expect(session.stats.ignored).to.equal(1);
    expect(session.alive).to.equal(true);
    session.destroy();
  });

  for (const [what, act, code, text] of [
    [
      'an answer to a later sequence number',
      (plc: FakePlc) => plc.answer(FunctionCode.GetMultiVariables, 9),
      'PROTOCOL_ERROR',
      'sequence 9 while waiting for 5',
    ],
    ['an answer for another function', (plc: FakePlc) => plc.answer(FunctionCode.Explore, 5), 'PROTOCOL_ERROR', 'is for function 0x4bb'],
    ['bytes that are no S7CommPlus frame', (plc: FakePlc) => plc.end.write(Buffer.from('HTTP/1.1 400\r\n')), 'PROTOCOL_ERROR', 'not 0x72'],
    [
      'a SystemEvent of 3 bytes',
      (plc: FakePlc) => plc.end.write(Buffer.from([0x72, 0xfe, 0, 3, 1, 2, 3])),
      'PROTOCOL_ERROR',
      'a SystemEvent of 3 bytes',
    ],
    [
      'an answer too short for a response header',
      (plc: FakePlc) => plc.end.write(encodeFrames(2, Buffer.from([0x32, 0]))),
      'PROTOCOL_ERROR',
      'has no response header',
    ],
    ['the PLC closing the connection', (plc: FakePlc) => plc.end.end(), 'CONNECTION_LOST', 'closed the connection'],
  ] as const) {
    it(`${what} drops the link: every request fails with ${code}, the stream is destroyed, the client told once`, async () => {
      const { session, plc, lost, ours } = open();
      const inFlight = session.request(ask(FunctionCode.GetMultiVariables));
      const queued = session.request(ask(FunctionCode.SetMultiVariables));
      await until(() => plc.seen.length === 1);
      act(plc);
      const err = await rejection(inFlight);
      expect(err.code).to.equal(code);
      expect(err.message).to.contain(text);
      expect((await rejection(queued)).code).to.equal(code);
      expect(lost).to.have.length(1);
      expect(session.alive).to.equal(false);
      expect(ours.destroyed).to.equal(true);
      expect((await rejection(session.request(ask(FunctionCode.GetMultiVariables)))).code).to.equal(code);
    });
  }

  it('a request unanswered within the timeout drops the link with TIMEOUT (its numbers are spent on both sides)', async () => {
    const { session, plc, lost } = open(50);
    const err = await rejection(session.request(ask(FunctionCode.GetMultiVariables)));
    expect(err.code).to.equal('TIMEOUT');
    expect(err.message).to.contain('did not answer request 0x54c (sequence 5) within 50 ms');
    expect(plc.seen).to.have.length(1);
    expect(lost).to.have.length(1);
  });

  it('a request aborted while it waits leaves the queue without spending a sequence number', async () => {
    const { session, plc } = open();
    const first = session.request(ask(FunctionCode.GetMultiVariables));
    const ac = new AbortController();
    const second = session.request(ask(FunctionCode.GetMultiVariables), { signal: ac.signal });
    const third = session.request(ask(FunctionCode.GetMultiVariables));
    ac.abort();
    expect((await rejection(second)).code).to.equal('ABORTED');
    await until(() => plc.seen.length === 1);
    plc.answer(FunctionCode.GetMultiVariables, 5);
    await first;
    await until(() => plc.seen.length === 2);
    expect(plc.seen[1]!.seq).to.equal(6);
    plc.answer(FunctionCode.GetMultiVariables, 6);
    await third;
    session.destroy();
  });

  it('goodbye() sends DeleteObject of the session (with the next write IntegrityId), then closes; a silent PLC is closed at the deadline', async () => {
    const { session, plc, lost, ours } = open();
    session.startIntegrity();
    const bye = session.goodbye(5000);
    await until(() => plc.seen.length === 1);
    expect(plc.seen[0]).to.include({ fn: FunctionCode.DeleteObject, sessionId: 0x1234, flags: 0x34 });
    // ObjectId (the session), IntegrityId 0, the closing fill.
    expect([...plc.seen[0]!.body]).to.deep.equal([0, 0, 0x12, 0x34, 0, 0, 0, 0, 0]);
    plc.answer(FunctionCode.DeleteObject, plc.seen[0]!.seq);
    await bye;
    expect(ours.destroyed).to.equal(true);
    expect(lost, 'a close is no loss').to.have.length(0);

    const silent = open();
    const started = Date.now();
    await silent.session.goodbye(30);
    expect(Date.now() - started).to.be.below(3000);
    expect(silent.ours.destroyed).to.equal(true);
  });

  it('destroy() fails what waits with CLOSED and never throws twice', async () => {
    const { session } = open();
    const p = session.request(ask(FunctionCode.GetMultiVariables));
    session.destroy();
    session.destroy();
    const err = await rejection(p);
    expect(err).to.be.instanceOf(ConnectionError);
    expect(err.code).to.equal('CLOSED');
  });
});

describe('s7plus client: a handshake that stops', () => {
  /** A PLC that confirms COTP and answers InitSSL, then reads everything and answers nothing. */
  async function mute() {
    const seen: Buffer[] = [];
    const plc = await countingServer((socket) => {
      socket.on('error', () => {});
      void cotpAccept(socket).then(() => {
        const reader = new S7pFrameReader();
        socket.on('data', (chunk: Buffer) => {
          // Each COTP DT carries one S7CommPlus frame here: skip TPKT (4) and DT (3).
          for (const m of reader.push(chunk.subarray(7))) {
            seen.push(m.data);
            if (m.data.readUInt16BE(3) === FunctionCode.InitSsl) {
              const answer = encodeFrames(
                1,
                encodeInitSslResponse({
                  header: { functionCode: FunctionCode.InitSsl, sequence: 0, transportFlags: 0 },
                  body: { returnValue: 0n },
                }),
              );
              socket.write(Buffer.concat([Buffer.from([3, 0, 0, 7 + answer.length, 2, 0xf0, 0x80]), answer]));
            }
          }
        });
        socket.resume();
      });
    });
    return { ...plc, seen };
  }

  it('close() during the CreateObject ends the connect at once, with no connection left', async () => {
    const plc = await mute();
    const client = createClient(`s7plus://127.0.0.1:${plc.port}?tls=false&timeout=20000`);
    client.on('error', () => {});
    const connecting = client.connect().then(
      () => undefined,
      (err: PlcError) => err,
    );
    await until(() => plc.seen.some((d) => d.readUInt16BE(3) === FunctionCode.CreateObject), 10_000, 'the CreateObject');
    const started = Date.now();
    await client.close();
    const err = await connecting;
    expect(Date.now() - started, 'not at the 20 s timeout').to.be.below(2000);
    expect(err).to.be.instanceOf(PlcError);
    expect(['CLOSED', 'ABORTED']).to.include(err!.code);
    for (let i = 0; i < 200 && (await plc.open()) > 0; i++) await new Promise((r) => setTimeout(r, 10));
    expect(await plc.open()).to.equal(0);
    plc.server.close();
  });

  it('a CreateObject never answered fails at the timeout, with no connection left', async () => {
    const plc = await mute();
    const client = createClient(`s7plus://127.0.0.1:${plc.port}?tls=false&timeout=300`);
    client.on('error', () => {});
    let err: PlcError | undefined;
    try {
      await client.connect();
    } catch (e) {
      err = e as PlcError;
    }
    expect(err).to.be.instanceOf(PlcError);
    expect(err!.code).to.equal('TIMEOUT');
    await client.close();
    for (let i = 0; i < 200 && (await plc.open()) > 0; i++) await new Promise((r) => setTimeout(r, 10));
    expect(await plc.open()).to.equal(0);
    plc.server.close();
  });
});
