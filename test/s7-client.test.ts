import { expect } from 'chai';
import fc from 'fast-check';
import * as net from 'node:net';
import { parseAddress } from '../lib/address';
import { PlcError, TagErrors } from '../lib/errors';
import { S7Client } from '../lib/s7/client';
import { lowerBoundPdus, maxReadItemData, planRead, planWrite } from '../lib/s7/planner';
import { S7Server, type S7RequestEvent } from '../lib/s7/server';
import type { Tag } from '../lib/types';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { activeHandles, settle, until, waitFor } from './support/wait';

function endpoint(port: number, query = ''): S7Endpoint {
  return parseUrl(`s7://127.0.0.1:${port}?timeout=1500${query}`) as S7Endpoint;
}

const FAST = { backoff: { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 } };

describe('S7 planner', () => {
  const tags = (addresses: string[]) => addresses.map(parseAddress);

  it('merges neighbours into one item and keeps distant tags apart', () => {
    const plan = planRead(tags(['DB1,INT0', 'DB1,INT2', 'DB1,REAL10', 'DB1,INT200', 'M0.1', 'M0.2']), 240);
    expect(plan.ranges.map((r) => [r.area, r.start, r.length])).to.deep.equal([
      [0x83, 0, 1],
      [0x84, 0, 14],
      [0x84, 200, 2],
    ]);
    expect(plan.pdus).to.have.length(1);
  });

  it('splits STRING[254] at PDU 240 into chunks of at most 222 bytes', () => {
    const plan = planRead(tags(['DB1,S0.254']), 240);
    const lengths = plan.pdus.flat().map((c) => c.length);
    expect(lengths.reduce((a, b) => a + b)).to.equal(256);
    expect(Math.max(...lengths)).to.be.at.most(maxReadItemData(240));
    expect(plan.pdus.length).to.equal(2);
  });

  it('property: every read plan respects both PDU limits and covers each tag exactly once', () => {
    const tagArb = fc.array(
      fc.tuple(fc.integer({ min: 1, max: 3 }), fc.integer({ min: 0, max: 2000 }), fc.constantFrom('INT', 'REAL', 'X0', 'S0.40', 'B', 'LREAL', 'S0.254')),
      { minLength: 1, maxLength: 120 },
    );
    fc.assert(
      fc.property(tagArb, fc.constantFrom(240, 480, 960), (specs, pdu) => {
        const list: Tag[] = specs.map(([db, off, t]) =>
          t === 'X0' ? parseAddress(`DB${db},X${off}.3`) : t.startsWith('S') ? parseAddress(`DB${db},S${off}.${t.split('.')[1]}`) : parseAddress(`DB${db},${t}${off}`),
        );
        const plan = planRead(list, pdu);
        for (const chunks of plan.pdus) {
          expect(12 + 12 * chunks.length).to.be.at.most(pdu);
          let response = 14;
          chunks.forEach((c, i) => (response += 4 + c.length + (c.length % 2 && i < chunks.length - 1 ? 1 : 0)));
          expect(response).to.be.at.most(pdu);
        }
        const covered = new Map<number, number>();
        plan.ranges.forEach((r) => r.tags.forEach((i) => covered.set(i, (covered.get(i) ?? 0) + 1)));
        expect(covered.size).to.equal(list.length);
        plan.ranges.forEach((r, ri) => {
          const bytes = plan.pdus.flat().filter((c) => c.range === ri).reduce((n, c) => n + c.length, 0);
          expect(bytes).to.equal(r.length);
          for (const i of r.tags) {
            const t = list[i]!;
            expect(t.byteOffset).to.be.at.least(r.start);
            expect(t.byteOffset + t.byteLength).to.be.at.most(r.start + r.length);
          }
        });
        expect(plan.pdus.length).to.be.at.least(lowerBoundPdus(list, pdu));
      }),
      { numRuns: 300 },
    );
  });

  it('write plans respect the request limit and send bits as single BIT items', () => {
    const plan = planWrite(
      [
        { tag: parseAddress('DB1.DBX0.6:BOOL[3]'), value: [true, false, true] },
        { tag: parseAddress('DB1,S10.254'), value: 'x'.repeat(254) },
      ],
      240,
    );
    const items = plan.pdus.flat();
    expect(items.filter((c) => c.tag === 0).map((c) => c.item.address)).to.deep.equal([6, 7, 8]);
    for (const chunks of plan.pdus) {
      let request = 12;
      chunks.forEach((c, i) => (request += 16 + c.item.data.length + (c.item.data.length % 2 && i < chunks.length - 1 ? 1 : 0)));
      expect(request).to.be.at.most(240);
    }
    // STRING write skips the max-length byte: starts at byte 11.
    const str = items.filter((c) => c.tag === 1).sort((a, b) => a.item.address - b.item.address);
    expect(str[0]!.item.address).to.equal(11 * 8);
    expect(str.reduce((n, c) => n + c.item.data.length, 0)).to.equal(255);
  });
});

describe('S7 client against the S7 simulator', function () {
  this.timeout(10000);
  let server: S7Server;
  let client: S7Client;
  let requests: S7RequestEvent[];

  beforeEach(async () => {
    server = new S7Server({ port: 0, profile: 's7-1200' });
    await server.listen();
    requests = [];
    server.on('request', (r: S7RequestEvent) => requests.push(r));
    client = new S7Client(endpoint(server.port), FAST);
  });

  afterEach(async () => {
    await client.close();
    await server.close();
  });

  it('uses what the PLC negotiated, not what it asked for', async () => {
    await client.connect();
    expect(client.pduSize).to.equal(240);
    expect(client.maxJobs).to.equal(3);
    expect(server.connectionCount).to.equal(1);
  });

  it('reads and writes every data type, keyed as given', async () => {
    await client.connect();
    const values: Record<string, unknown> = {
      'DB1,X0.0': true,
      'DB1.DBB1': 0xab,
      'DB1.DBB2:SINT': -5,
      'DB1.DBB3:USINT': 250,
      'DB1.DBW4': 0xbeef,
      'DB1.DBW6:INT': -1234,
      'DB1.DBW8:UINT': 65000,
      'DB1.DBD10': 0xdeadbeef,
      'DB1.DBD14:DINT': -123456,
      'DB1.DBD18:UDINT': 4000000000,
      'DB1.DBB22:LWORD': 0x0102030405060708n,
      'DB1.DBB30:LINT': -(2n ** 62n),
      'DB1.DBB38:ULINT': 2n ** 64n - 1n,
      'DB1.DBD46:REAL': 1.5,
      'DB1.DBB50:LREAL': Math.PI,
      'DB1.DBB58:CHAR': 'Z',
      'DB1.DBW60:WCHAR': 'Ж',
      'DB1.DBB62:STRING[10]': 'hello',
      'DB1.DBB74:WSTRING[4]': 'héé',
      'DB1.DBW86:S5TIME': 2500,
      'DB1.DBD88:TIME': -60000,
      'DB1.DBB92:LTIME': 5_000_000_000n,
      'DB1.DBW100:DATE': new Date('2024-02-29T00:00:00Z'),
      'DB1.DBD102:TIME_OF_DAY': 43_200_000,
      'DB1.DBB106:DATE_AND_TIME': new Date('2024-05-17T13:45:30.120Z'),
      'DB1.DBB114:DTL': new Date('2025-12-31T23:59:59.999Z'),
      'DB1.DBW126:INT[3]': [1, -2, 3],
      'DB1.DBX132.6:BOOL[4]': [true, false, true, true],
      C5: 42,
      T3: 5000,
      MW10: 321,
      'QB2': 7,
    };
    server.memory.area('DB', 1)![62] = 10; // the PLC's declared STRING[10]
    server.memory.area('DB', 1)!.writeUInt16BE(4, 74);
    await client.write(values);
    const back = await client.read(Object.keys(values));
    expect(back).to.deep.equal(values);
    expect(Object.keys(back)).to.deep.equal(Object.keys(values));
  });

  it('one bad tag fails alone: missing DB and address out of range name the tag and the return code', async () => {
    await client.connect();
    server.memory.area('DB', 1)!.writeInt16BE(77, 1020);
    const r = await client.readDetailed(['DB1.DBW1020:INT', 'DB1.DBW1022:INT[2]', 'DB999,INT0', 'M0.0']);
    expect(r['DB1.DBW1020:INT']).to.deep.equal({ ok: true, value: 77 });
    expect(r['M0.0']).to.deep.equal({ ok: true, value: false });
    const range = r['DB1.DBW1022:INT[2]']!;
    const missing = r['DB999,INT0']!;
    if (range.ok || missing.ok) throw new Error('expected failures');
    expect(range.error.code).to.equal('ADDRESS_OUT_OF_RANGE');
    expect(range.error.message).to.match(/^DB1\.DBW1022:INT\[2\] \(DB1 byte 1022\): address out of range .*0x05/);
    expect(missing.error.code).to.equal('OBJECT_DOES_NOT_EXIST');
    expect(missing.error.plcCode).to.equal(0x0a);
    const err = await client.read(['DB999,INT0', 'M0.0']).catch((e: unknown) => e);
    expect(err).to.be.instanceOf(TagErrors);
    expect((err as TagErrors).results['M0.0']).to.deep.equal({ ok: true, value: false });
  });

  it('splits STRING[254] at PDU 240 into several jobs and reassembles it', async () => {
    await client.connect();
    const text = 'S7'.repeat(127);
    server.memory.area('DB', 2)![0] = 254;
    await client.write({ 'DB2,S0.254': text });
    expect(await client.read(['DB2,S0.254'])).to.deep.equal({ 'DB2,S0.254': text });
    expect(requests.filter((r) => r.kind === 'write').length).to.equal(2);
    expect(requests.filter((r) => r.kind === 'read').length).to.equal(2);
  });

  it('packs 100 scattered tags into the planned number of PDUs, equal to the lower bound', async () => {
    await client.connect();
    const addresses = Array.from({ length: 100 }, (_, i) => `DB1,INT${i * 10}`);
    await client.read(addresses);
    const bound = lowerBoundPdus(addresses.map(parseAddress), 240);
    expect(requests.length).to.equal(bound);
  });

  it('keeps at most AmQ (3) jobs in flight, and the writes queued behind them all land', async () => {
    server.faults.latencyMs = 30;
    await client.connect();
    let inFlight = 0;
    let most = 0;
    server.on('request', () => {
      inFlight++;
      most = Math.max(most, inFlight);
    });
    const origWrite = server.memory.write.bind(server.memory);
    server.memory.write = (...args: Parameters<typeof origWrite>) => {
      inFlight--;
      origWrite(...args);
    };
    const writes = Array.from({ length: 12 }, (_, i) => client.write({ [`DB3,INT${i * 2}`]: i + 1 }));
    await Promise.all(writes);
    expect(most).to.equal(3);
    const back = await client.read(Array.from({ length: 12 }, (_, i) => `DB3,INT${i * 2}`));
    expect(Object.values(back)).to.deep.equal(Array.from({ length: 12 }, (_, i) => i + 1));
  });

  it('fails fast with NOT_CONNECTED while down, reconnects by itself and reads correct values after', async () => {
    await client.connect();
    server.memory.area('DB', 1)!.writeInt16BE(11, 0);
    const disconnected = waitFor(client, 'disconnected');
    server.dropConnections();
    await disconnected;
    const err = await client.read(['DB1,INT0']).catch((e: PlcError) => e);
    expect((err as PlcError).code).to.equal('NOT_CONNECTED');
    await waitFor(client, 'connected', 3000);
    server.memory.area('DB', 1)!.writeInt16BE(12, 0);
    expect(await client.read(['DB1,INT0'])).to.deep.equal({ 'DB1,INT0': 12 });
  });

  it('refuses the 9th connection on an S7-1200', async () => {
    const clients = Array.from({ length: 8 }, () => new S7Client(endpoint(server.port)));
    try {
      await Promise.all(clients.map((c) => c.connect()));
      expect(server.connectionCount).to.equal(8);
      const ninth = new S7Client(endpoint(server.port));
      const err = await ninth.connect().catch((e: PlcError) => e);
      expect((err as PlcError).code).to.equal('CONNECT_FAILED');
      expect((err as PlcError).message).to.match(/connection limit/);
      await ninth.close();
    } finally {
      await Promise.all(clients.map((c) => c.close()));
    }
  });

  it('refuses a wrong slot like a real CPU', async () => {
    const wrong = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?slot=5&timeout=1000`) as S7Endpoint);
    const err = await wrong.connect().catch((e: PlcError) => e);
    expect((err as PlcError).code).to.equal('CONNECT_FAILED');
    expect((err as PlcError).message).to.match(/rack 0, slot 5/);
    await wrong.close();
  });

  it('turns PUT/GET access refused into ACCESS_DENIED with the words users search for', async () => {
    await client.connect();
    server.faults.accessDenied = true;
    const r = await client.readDetailed(['DB1,INT0']);
    const one = r['DB1,INT0']!;
    if (one.ok) throw new Error('expected failure');
    expect(one.error.code).to.equal('ACCESS_DENIED');
    expect(one.error.message).to.include('PUT/GET access is not enabled on this S7-1200/1500');
  });

  it('close() resolves, fails pending requests with CLOSED, and leaves no handles', async () => {
    await settle();
    const before = activeHandles();
    await client.connect();
    server.faults.silent = true;
    const pending = client.read(['DB1,INT0']).catch((e: PlcError) => e);
    await client.close();
    expect(((await pending) as PlcError).code).to.equal('CLOSED');
    await until(() => server.connectionCount === 0, 2000, 'the simulator saw the close');
    await settle();
    expect(activeHandles()).to.equal(before);
  });
});

describe('S7 client against hostile peers', function () {
  this.timeout(10000);
  const peers: net.Server[] = [];
  afterEach(async () => {
    await Promise.all(peers.splice(0).map((p) => new Promise((r) => p.close(r))));
  });

  /** A peer that completes the handshake, then does `then` with each job. */
  async function peer(then: (socket: net.Socket, job: Buffer) => void, handshake = true): Promise<number> {
    const { encodeConnectionConfirm, encodeSetupAck } = await import('../lib/s7/codec');
    const server = net.createServer((socket) => {
      let stage = 0;
      socket.on('error', () => undefined);
      socket.on('data', (chunk) => {
        if (!handshake) return then(socket, chunk);
        if (stage === 0) {
          stage = 1;
          socket.write(encodeConnectionConfirm({ sourceRef: 1, destinationRef: 1, callingTsap: 0x1000, calledTsap: 0x0301, tpduSize: 0x0a }));
        } else if (stage === 1) {
          stage = 2;
          socket.write(encodeSetupAck(chunk.readUInt16BE(11), { maxAmqCalling: 1, maxAmqCalled: 1, pduSize: 240 }));
        } else then(socket, chunk);
      });
    });
    peers.push(server);
    await new Promise<void>((r) => server.listen(0, '127.0.0.1', r));
    return (server.address() as net.AddressInfo).port;
  }

  async function expectLinkError(answer: (socket: net.Socket, job: Buffer) => void, code: RegExp): Promise<PlcError> {
    const port = await peer(answer);
    const client = new S7Client(endpoint(port), FAST);
    let uncaught: unknown;
    const onUncaught = (e: unknown) => (uncaught = e);
    process.on('uncaughtException', onUncaught);
    try {
      await client.connect();
      const started = Date.now();
      const err = (await client.read(['DB1,INT0']).catch((e: unknown) => e)) as PlcError;
      expect(err).to.be.instanceOf(PlcError);
      expect(err.code).to.match(code);
      expect(Date.now() - started).to.be.below(2500);
      return err;
    } finally {
      process.removeListener('uncaughtException', onUncaught);
      await client.close();
      expect(uncaught).to.equal(undefined);
    }
  }

  it('a peer that stays silent: TIMEOUT within the configured timeout', async () => {
    await expectLinkError(() => undefined, /^TIMEOUT$/);
  });

  it('TPKT length 0: a connection error', async () => {
    await expectLinkError((s) => s.write(Buffer.from('03000000', 'hex')), /PROTOCOL_ERROR|CONNECTION_LOST/);
  });

  it('TPKT length 65535 with fewer bytes, then silence: TIMEOUT, no hang', async () => {
    await expectLinkError((s) => s.write(Buffer.from('0300FFFF02F080', 'hex')), /^TIMEOUT$/);
  });

  it('garbage after the handshake: a connection error', async () => {
    await expectLinkError((s) => s.write(Buffer.from('deadbeefdeadbeef', 'hex')), /PROTOCOL_ERROR|CONNECTION_LOST/);
  });

  it('reset in the middle of a response: CONNECTION_LOST', async () => {
    await expectLinkError((s) => {
      s.write(Buffer.from('0300001902F080320300', 'hex'));
      s.resetAndDestroy();
    }, /CONNECTION_LOST/);
  });

  it('an answer with the wrong PDU reference is ignored; the request times out', async () => {
    const { encodeReadResponse } = await import('../lib/s7/codec');
    await expectLinkError((s, job) => s.write(encodeReadResponse(job.readUInt16BE(11) + 1, [{ returnCode: 0xff, transportSize: 4, data: Buffer.alloc(2) }])), /^TIMEOUT$/);
  });

  it('an answer dripped one byte at a time is read correctly', async () => {
    const { encodeReadResponse } = await import('../lib/s7/codec');
    const port = await peer((s, job) => {
      const frame = encodeReadResponse(job.readUInt16BE(11), [{ returnCode: 0xff, transportSize: 4, data: Buffer.from('04D2', 'hex') }]);
      let i = 0;
      const drip = () => {
        if (i < frame.length && !s.destroyed) {
          s.write(frame.subarray(i, ++i));
          setImmediate(drip);
        }
      };
      drip();
    });
    const client = new S7Client(endpoint(port), FAST);
    try {
      await client.connect();
      expect(await client.read(['DB1,INT0'])).to.deep.equal({ 'DB1,INT0': 1234 });
    } finally {
      await client.close();
    }
  });

  it('connection refused: CONNECT_FAILED naming host and port', async () => {
    const s = net.createServer();
    await new Promise<void>((r) => s.listen(0, '127.0.0.1', r));
    const port = (s.address() as net.AddressInfo).port;
    await new Promise((r) => s.close(r));
    const client = new S7Client(endpoint(port));
    const err = (await client.connect().catch((e: unknown) => e)) as PlcError;
    expect(err.code).to.equal('CONNECT_FAILED');
    expect(err.message).to.include(`127.0.0.1:${port}`);
    await client.close();
  });

  it('COTP disconnect during the handshake: CONNECT_FAILED', async () => {
    const { encodeDisconnectRequest } = await import('../lib/s7/codec');
    const port = await peer((s) => s.end(encodeDisconnectRequest(1, 1, 0x80)), false);
    const client = new S7Client(endpoint(port));
    const err = (await client.connect().catch((e: unknown) => e)) as PlcError;
    expect(err.code).to.equal('CONNECT_FAILED');
    await client.close();
    await until(() => true);
  });
});
