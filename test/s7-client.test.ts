import { expect } from 'chai';
import * as net from 'node:net';
import { parseAddress } from '../lib/address';
import { PlcError, TagErrors } from '../lib/errors';
import { S7Client, localTsapFor, type ItemLimitEvent } from '../lib/s7/client';
import { encodeConnectionConfirm, encodeDisconnectRequest, encodeReadResponse, encodeSetupAck } from '../lib/s7/codec';
import { lowerBoundPdus } from '../lib/s7/plan/bound';
import { S7Server, type S7RequestEvent } from '../lib/s7/server';
import { PlcMemory } from '../lib/sim/memory';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { collectGarbage, youngBytes } from './support/gc';
import { activeHandles, settle, until, waitFor } from './support/wait';

function endpoint(port: number, query = ''): S7Endpoint {
  return parseUrl(`s7://127.0.0.1:${port}?timeout=1500${query}`) as S7Endpoint;
}

const FAST = { backoff: { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 } };

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

  it('uses what the PLC negotiated (S7-1200: PDU 240, AmQ 3), not what it asked for', async () => {
    expect(client.pduSize).to.equal(0);
    await client.connect();
    expect(client.pduSize).to.equal(240);
    expect(client.maxJobs).to.equal(3);
    expect(server.connectionCount).to.equal(1);
  });

  it('an S7-1500 negotiates PDU 960 and AmQ 8', async () => {
    const big = new S7Server({ port: 0, profile: 's7-1500' });
    await big.listen();
    const c = new S7Client(endpoint(big.port, '&pdu=960'));
    try {
      await c.connect();
      expect([c.pduSize, c.maxJobs]).to.deep.equal([960, 8]);
    } finally {
      await c.close();
      await big.close();
    }
  });

  it('local TSAP follows the connection type (PG 0x0100, OP 0x0200, basic 0x0300)', () => {
    expect([localTsapFor('pg'), localTsapFor('op'), localTsapFor('basic')]).to.deep.equal([0x0100, 0x0200, 0x0300]);
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
      'DB1,REAL140.3': [0.5, -2, 1e10],
      'DB1.DBB160:CHAR[4]': ['a', 'b', 'c', 'd'],
      C5: 42,
      T3: 5000,
      MW10: 321,
      QB2: 7,
    };
    server.memory.area('DB', 1)![62] = 10; // the PLC's declared STRING[10]
    server.memory.area('DB', 1)!.writeUInt16BE(4, 74);
    await client.write(values);
    const back = await client.read(Object.keys(values));
    expect(back).to.deep.equal(values);
    expect(Object.keys(back)).to.deep.equal(Object.keys(values));
    expect(client.stats.requests).to.equal(2);
    expect(client.stats.pdusSent).to.equal(requests.length);
    expect(client.stats.bytesSent).to.equal(requests.reduce((n, r) => n + r.bytes, 0));
    expect(client.stats.bytesReceived).to.be.greaterThan(0);
  });

  it('plans a tag list once: polling it again reuses the plan and its request frames, a changed list is planned anew', async () => {
    await client.connect();
    const list = ['DB1,INT0', 'DB1,REAL2', 'DB1,X6.1', 'MW10', 'DB1,S8.4'];
    const frames = new Set<Buffer>();
    // The frames the session writes to its socket (the session owns the socket: its write is watched).
    const socket = (client as unknown as { session: { socket: { write: (f: Buffer) => boolean } } }).session.socket;
    const writing = socket.write;
    socket.write = function (this: unknown, f: Buffer) {
      frames.add(f);
      return writing.call(this, f);
    };
    for (let i = 0; i < 50; i++) await client.read(list);
    expect(client.stats.plansMade).to.equal(1);
    // 50 polls sent the plan's own frames again and again, not a new Buffer per poll.
    expect(frames.size).to.equal(client.planFor(list).pdus.length);
    await client.read([...list]); // the same addresses in a new array: the same plan
    expect(client.stats.plansMade).to.equal(1);
    list[1] = 'DB1,REAL4'; // the caller changed its array in place: noticed
    expect(await client.read(list)).to.have.property('DB1,REAL4');
    expect(client.stats.plansMade).to.equal(2);
    socket.write = writing;
  });

  it("a poll's answers and values die young: nothing links one poll to the next", async () => {
    // 1000 REALs 8 bytes apart: 10 PDUs at PDU 960, more than AmQ 8, so jobs keep entering and leaving the session.
    const big = new S7Server({ port: 0, profile: 's7-1500', memory: new PlcMemory({ dataBlocks: { 1: 8192 } }) });
    await big.listen();
    const c = new S7Client(endpoint(big.port, '&pdu=960'));
    try {
      await c.connect();
      const list = Array.from({ length: 1000 }, (_, i) => `DB1,REAL${i * 8}`);
      expect(c.planFor(list).pdus.length).to.be.above(c.maxJobs);
      for (let i = 0; i < 50; i++) await c.read(list);
      collectGarbage();
      for (let i = 0; i < 300; i++) await c.read(list);
      await settle();
      collectGarbage('minor');
      // Measured: 2-35 KiB; with the jobs in a Map (its dropped tables chained) 390-460 KiB of answers and values survived.
      expect(youngBytes()).to.be.below(128 * 1024);
    } finally {
      await c.close();
      await big.close();
    }
  });

  it("writing a STRING keeps the PLC's max-length byte; a too-long value is refused before anything is sent", async () => {
    await client.connect();
    const db = server.memory.area('DB', 1)!;
    db[200] = 5;
    await client.write({ 'DB1,S200.5': 'abc' });
    expect(db.subarray(200, 205).toString('hex')).to.equal('0503616263');
    const sent = requests.length;
    const r = await client.writeDetailed({ 'DB1,S200.5': 'toolong' });
    expect(r['DB1,S200.5']!.ok).to.equal(false);
    expect((r['DB1,S200.5'] as { error: PlcError }).error.code).to.equal('INVALID_VALUE');
    expect(requests.length).to.equal(sent);
  });

  it('writes bits one by one: neighbouring bits are never clobbered', async () => {
    await client.connect();
    const db = server.memory.area('DB', 1)!;
    db[300] = 0b1010_1010;
    db[301] = 0b0000_1111;
    await client.write({ 'DB1,X300.0': true, 'DB1,X300.7': false, 'DB1.DBX301.3:BOOL[2]': [false, true] });
    expect(db[300]).to.equal(0b0010_1011);
    expect(db[301]).to.equal(0b0001_0111);
    expect(await client.read(['DB1,X300.0', 'DB1,X300.1', 'DB1.DBX301.3:BOOL[2]'])).to.deep.equal({
      'DB1,X300.0': true,
      'DB1,X300.1': true,
      'DB1.DBX301.3:BOOL[2]': [false, true],
    });
  });

  it('one bad tag fails alone: missing DB and address out of range name the tag, its address and the return code in words', async () => {
    await client.connect();
    server.memory.area('DB', 1)!.writeInt16BE(77, 1020);
    const r = await client.readDetailed(['DB1.DBW1020:INT', 'DB1,INT1022.2', 'DB999,INT0', 'M0.0']);
    expect(r['DB1.DBW1020:INT']).to.deep.equal({ ok: true, value: 77 });
    expect(r['M0.0']).to.deep.equal({ ok: true, value: false });
    const range = r['DB1,INT1022.2']!;
    const missing = r['DB999,INT0']!;
    if (range.ok || missing.ok) throw new Error('expected failures');
    expect(range.error.code).to.equal('ADDRESS_OUT_OF_RANGE');
    expect(range.error.tag).to.equal('DB1,INT1022.2');
    expect(range.error.message).to.match(/^DB1,INT1022\.2 \(DB1\.DB[BW]1022:INT\[2\]\): .*0x05.*address out of range/);
    expect(missing.error.code).to.equal('OBJECT_DOES_NOT_EXIST');
    expect(missing.error.plcCode).to.equal(0x0a);
    expect(missing.error.message).to.match(/^DB999,INT0 .*0x0A.*object does not exist/);
    const err = await client.read(['DB999,INT0', 'M0.0']).catch((e: unknown) => e);
    expect(err).to.be.instanceOf(TagErrors);
    expect((err as TagErrors).results['M0.0']).to.deep.equal({ ok: true, value: false });
  });

  it('a DB the PLC reports missing fails only its tags, on writes too', async () => {
    await client.connect();
    server.faults.missingDb = 7;
    const r = await client.writeDetailed({ 'DB7,INT0': 1, 'DB8,INT0': 2 });
    expect(r['DB8,INT0']).to.deep.equal({ ok: true, value: undefined });
    const bad = r['DB7,INT0']!;
    if (bad.ok) throw new Error('expected failure');
    expect(bad.error.code).to.equal('OBJECT_DOES_NOT_EXIST');
    expect(bad.error.message).to.match(/^DB7,INT0 .*object does not exist/);
  });

  it('splits STRING[254] at PDU 240 into two jobs each way and reassembles it', async () => {
    await client.connect();
    const text = 'S7'.repeat(127);
    server.memory.area('DB', 2)![0] = 254;
    await client.write({ 'DB2,S0.254': text });
    expect(await client.read(['DB2,S0.254'])).to.deep.equal({ 'DB2,S0.254': text });
    expect(requests.filter((r) => r.kind === 'write').length).to.equal(2);
    expect(requests.filter((r) => r.kind === 'read').length).to.equal(2);
  });

  it('reads 100 scattered tags in the lower-bound number of PDUs, and plans them once', async () => {
    await client.connect();
    const addresses = Array.from({ length: 100 }, (_, i) => `DB1,INT${i * 10}`);
    await client.read(addresses);
    expect(requests.length).to.equal(lowerBoundPdus(addresses.map(parseAddress), 240));
    const plan = client.planFor(addresses);
    expect(client.planFor([...addresses])).to.equal(plan);
    await client.read(addresses);
    expect(client.planFor(addresses)).to.equal(plan);
    expect(requests.length).to.equal(2 * plan.pdus.length);
  });

  it('keeps at most AmQ (3) jobs at the PLC at once, and every queued write lands', async () => {
    server.faults.latencyMs = 25;
    await client.connect();
    let outstanding = 0;
    let most = 0;
    server.on('request', () => (most = Math.max(most, ++outstanding)));
    server.memory.on('write', () => outstanding--);
    server.memory.on('read', () => outstanding--);
    const writes = Array.from({ length: 30 }, (_, i) => client.write({ [`DB3,INT${i * 2}`]: i + 1 }));
    await Promise.all(writes);
    expect(most).to.equal(3);
    const back = await client.read(Array.from({ length: 30 }, (_, i) => `DB3,INT${i * 2}`));
    expect(Object.values(back)).to.deep.equal(Array.from({ length: 30 }, (_, i) => i + 1));
  });

  it('fails fast with NOT_CONNECTED while down, reconnects by itself and reads correct values after', async () => {
    await client.connect();
    server.memory.area('DB', 1)!.writeInt16BE(11, 0);
    const disconnected = waitFor(client, 'disconnected');
    server.dropConnections();
    await disconnected;
    const started = Date.now();
    const err = await client.read(['DB1,INT0']).catch((e: PlcError) => e);
    expect((err as PlcError).code).to.equal('NOT_CONNECTED');
    expect(Date.now() - started).to.be.below(50);
    await waitFor(client, 'connected', 3000);
    server.memory.area('DB', 1)!.writeInt16BE(12, 0);
    expect(await client.read(['DB1,INT0'])).to.deep.equal({ 'DB1,INT0': 12 });
  });

  it('a write in flight when the link drops is rejected, not lost', async () => {
    server.faults.latencyMs = 200;
    await client.connect();
    const pending = client.writeDetailed({ 'DB1,INT0': 5 });
    await until(() => requests.length === 1, 2000, 'the write reached the PLC');
    server.dropConnections();
    const r = (await pending)['DB1,INT0']!;
    expect(r.ok).to.equal(false);
    expect((r as { error: PlcError }).error.code).to.equal('CONNECTION_LOST');
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
    const r = await client.readDetailed(['DB1,INT0', 'M0.0']);
    for (const one of Object.values(r)) {
      if (one.ok) throw new Error('expected failure');
      expect(one.error.code).to.equal('ACCESS_DENIED');
      expect(one.error.message).to.include('PUT/GET access is not enabled on this S7-1200/1500');
    }
  });

  it('an aborted read rejects with ABORTED at once', async () => {
    server.faults.latencyMs = 300;
    await client.connect();
    const ac = new AbortController();
    const pending = client.read(['DB1,INT0'], { signal: ac.signal }).catch((e: PlcError) => e);
    ac.abort();
    expect(((await pending) as PlcError).code).to.equal('ABORTED');
  });

  it('close() resolves, fails pending requests with CLOSED, and leaves no handles', async () => {
    await settle();
    const before = activeHandles();
    await client.connect();
    server.faults.silent = true;
    const pending = client.read(['DB1,INT0']).catch((e: PlcError) => e);
    await until(() => requests.length === 1, 2000, 'the read reached the PLC');
    await client.close();
    expect(((await pending) as PlcError).code).to.equal('CLOSED');
    await until(() => server.connectionCount === 0, 2000, 'the simulator saw the close');
    await settle();
    expect(activeHandles()).to.equal(before);
  });
});

describe('S7 client: items per job', function () {
  this.timeout(10000);
  let server: S7Server;
  let requests: S7RequestEvent[];
  const clients: S7Client[] = [];
  /** 60 INTs in 60 DBs: each its own item, never merged. */
  const scattered = (n: number) => Array.from({ length: n }, (_, i) => `DB${i + 1},INT${2 * (i % 7)}`);
  const open = async (query = '') => {
    const c = new S7Client(endpoint(server.port, query), FAST);
    clients.push(c);
    await c.connect();
    return c;
  };

  beforeEach(async () => {
    server = new S7Server({ port: 0, profile: 's7-1500' });
    await server.listen();
    for (let db = 1; db <= 60; db++) server.memory.area('DB', db)!.writeInt16BE(db * 100 + 1, 2 * ((db - 1) % 7));
    requests = [];
    server.on('request', (r: S7RequestEvent) => requests.push(r));
  });

  afterEach(async () => {
    for (const c of clients.splice(0)) await c.close();
    await server.close();
  });

  const expected = (addresses: string[]) => Object.fromEntries(addresses.map((a, i) => [a, (i + 1) * 100 + 1]));

  it('sends at most 20 items per read and write job by default, though PDU 960 carries 79', async () => {
    const c = await open();
    expect([c.pduSize, c.maxItems]).to.deep.equal([960, 20]);
    const list = scattered(60);
    expect(await c.read(list)).to.deep.equal(expected(list));
    expect(requests.map((r) => r.items)).to.deep.equal([20, 20, 20]);
    requests = [];
    await c.write(Object.fromEntries(list.slice(0, 30).map((a, i) => [a, -i])));
    expect(requests.every((r) => r.kind === 'write' && r.items <= 20)).to.equal(true);
    expect(requests.reduce((n, r) => n + r.items, 0)).to.equal(30);
    expect(Object.values(await c.read(list.slice(0, 30)))).to.deep.equal(list.slice(0, 30).map((_, i) => -i || 0));
  });

  it('maxItems=N in the URL raises or lowers the limit; the PDU still caps it', async () => {
    const wide = await open('&maxItems=255');
    const list = scattered(60);
    expect(await wide.read(list)).to.deep.equal(expected(list));
    expect(requests.map((r) => r.items)).to.deep.equal([60]);
    requests = [];
    const narrow = await open('&maxItems=7');
    expect(await narrow.read(list)).to.deep.equal(expected(list));
    expect(Math.max(...requests.map((r) => r.items))).to.equal(7);
    expect(requests).to.have.length(9);
    requests = [];
    const small = await open('&maxItems=255&pdu=240');
    await small.read(list);
    expect(Math.max(...requests.map((r) => r.items))).to.equal(19);
  });

  it('a PLC that answers a read with fewer items: itemLimit event, a new plan, and that same poll returns every value', async () => {
    server.maxItems = 7;
    const c = await open('&maxItems=60');
    const limits: ItemLimitEvent[] = [];
    c.on('itemLimit', (e: ItemLimitEvent) => limits.push(e));
    const list = scattered(60);
    expect(await c.read(list)).to.deep.equal(expected(list));
    expect(limits).to.deep.equal([{ limit: 7, was: 60 }]);
    expect(c.maxItems).to.equal(7);
    // One job of 60 answered with 7 items, then 9 jobs of at most 7.
    expect(requests.map((r) => r.items)).to.deep.equal([60, ...c.planFor(list).pdus.map((p) => p.items.length)]);
    expect(c.planFor(list).pdus).to.have.length(9);
    requests = [];
    expect(await c.readDetailed(list.slice(0, 20))).to.deep.equal(
      Object.fromEntries(list.slice(0, 20).map((a, i) => [a, { ok: true, value: (i + 1) * 100 + 1 }])),
    );
    expect(Math.max(...requests.map((r) => r.items))).to.equal(7);
    expect(limits).to.have.length(1);
  });

  it('learns again when the PLC serves fewer still, and the limit outlives a reconnect', async () => {
    server.maxItems = 12;
    const c = await open('&maxItems=60');
    const limits: ItemLimitEvent[] = [];
    c.on('itemLimit', (e: ItemLimitEvent) => limits.push(e));
    const list = scattered(40);
    expect(await c.read(list)).to.deep.equal(expected(list));
    server.maxItems = 5;
    expect(await c.read(list)).to.deep.equal(expected(list));
    expect(limits).to.deep.equal([
      { limit: 12, was: 60 },
      { limit: 5, was: 12 },
    ]);
    const reconnected = waitFor(c, 'connected');
    server.dropConnections();
    await reconnected;
    requests = [];
    expect(await c.read(list)).to.deep.equal(expected(list));
    expect(Math.max(...requests.map((r) => r.items))).to.equal(5);
  });

  it('a write answered with fewer return codes: the items left out are sent again, none twice, and every value lands', async () => {
    server.maxItems = 7;
    const c = await open('&maxItems=60');
    const limits: ItemLimitEvent[] = [];
    c.on('itemLimit', (e: ItemLimitEvent) => limits.push(e));
    const writes = new Map<string, number>();
    server.memory.on('write', (w: { dbNumber: number; offset: number }) =>
      writes.set(`${w.dbNumber}.${w.offset}`, (writes.get(`${w.dbNumber}.${w.offset}`) ?? 0) + 1),
    );
    const list = scattered(30);
    const values = Object.fromEntries(list.map((a, i) => [a, 1000 + i]));
    const results = await c.writeDetailed(values);
    expect(Object.values(results).every((r) => r.ok)).to.equal(true);
    expect(limits).to.deep.equal([{ limit: 7, was: 60 }]);
    expect(requests.map((r) => r.items)).to.deep.equal([30, 7, 7, 7, 2]);
    expect(writes.size).to.equal(30);
    expect([...writes.values()].every((n) => n === 1)).to.equal(true);
    expect(await c.read(list)).to.deep.equal(values);
  });
});

describe('S7 client against hostile peers', function () {
  this.timeout(10000);
  const peers: net.Server[] = [];
  const sockets = new Set<net.Socket>();
  let uncaught: unknown[] = [];
  const onUncaught = (e: unknown) => uncaught.push(e);

  beforeEach(() => {
    uncaught = [];
    process.on('uncaughtException', onUncaught);
    process.on('unhandledRejection', onUncaught);
  });

  afterEach(async () => {
    process.removeListener('uncaughtException', onUncaught);
    process.removeListener('unhandledRejection', onUncaught);
    for (const s of sockets) s.destroy();
    sockets.clear();
    await Promise.all(peers.splice(0).map((p) => new Promise((r) => p.close(r))));
    expect(uncaught).to.deep.equal([]);
  });

  /** A peer that completes the handshake (PDU 240, AmQ 1), then does `then` with each job's bytes. */
  async function peer(then: (socket: net.Socket, job: Buffer) => void, handshake = true): Promise<number> {
    const server = net.createServer((socket) => {
      sockets.add(socket);
      let stage = 0;
      socket.on('error', () => undefined);
      socket.on('data', (chunk) => {
        if (!handshake) return then(socket, chunk);
        if (stage === 0) {
          stage = 1;
          socket.write(
            encodeConnectionConfirm({ sourceRef: 1, destinationRef: 1, callingTsap: 0x0100, calledTsap: 0x0301, tpduSize: 0x0a }),
          );
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

  async function readError(answer: (socket: net.Socket, job: Buffer) => void, code: RegExp): Promise<{ err: PlcError; client: S7Client }> {
    const port = await peer(answer);
    const client = new S7Client(endpoint(port), FAST);
    try {
      await client.connect();
      const started = Date.now();
      const err = (await client.read(['DB1,INT0']).catch((e: unknown) => e)) as PlcError;
      expect(err).to.be.instanceOf(PlcError);
      expect(err.code).to.match(code);
      expect(Date.now() - started).to.be.below(2500);
      return { err, client };
    } finally {
      await client.close();
    }
  }

  it('a peer that accepts and says nothing: connect() rejects with TIMEOUT within the timeout, no handle left', async () => {
    await settle();
    const before = activeHandles();
    const server = net.createServer((s) => {
      sockets.add(s);
      s.on('error', () => undefined);
    });
    peers.push(server);
    await new Promise<void>((r) => server.listen(0, '127.0.0.1', r));
    const client = new S7Client(parseUrl(`s7://127.0.0.1:${(server.address() as net.AddressInfo).port}?timeout=300`) as S7Endpoint);
    const started = Date.now();
    const err = (await client.connect().catch((e: unknown) => e)) as PlcError;
    expect(err.code).to.equal('TIMEOUT');
    expect(Date.now() - started).to.be.within(250, 1500);
    await client.close();
    for (const s of sockets) s.destroy();
    server.close();
    peers.splice(0);
    await settle();
    expect(activeHandles()).to.equal(before);
  });

  it('a peer that stops answering jobs: TIMEOUT, then the link is dropped and rebuilt', async () => {
    const port = await peer(() => undefined);
    const client = new S7Client(endpoint(port, '&timeout=300'), FAST);
    try {
      await client.connect();
      const err = (await client.read(['DB1,INT0']).catch((e: unknown) => e)) as PlcError;
      expect(err.code).to.equal('TIMEOUT');
      await waitFor(client, 'connected', 3000);
    } finally {
      await client.close();
    }
  });

  it('TPKT length 0: a connection error', async () => {
    await readError((s) => s.write(Buffer.from('03000000', 'hex')), /PROTOCOL_ERROR|CONNECTION_LOST/);
  });

  it('TPKT length 65535 with fewer bytes, then silence: TIMEOUT, no hang', async () => {
    await readError((s) => s.write(Buffer.from('0300FFFF02F080', 'hex')), /^TIMEOUT$/);
  });

  it('garbage after the handshake: a connection error', async () => {
    await readError((s) => s.write(Buffer.from('deadbeefdeadbeef', 'hex')), /PROTOCOL_ERROR|CONNECTION_LOST/);
  });

  it('a well-framed but malformed S7 answer: PROTOCOL_ERROR', async () => {
    await readError((s) => s.write(Buffer.from('0300000b02f08032030000', 'hex')), /PROTOCOL_ERROR/);
  });

  it('a COTP disconnect after the handshake: CONNECTION_LOST', async () => {
    await readError((s) => s.write(encodeDisconnectRequest(1, 1, 0x80)), /CONNECTION_LOST/);
  });

  it('reset in the middle of a response: CONNECTION_LOST', async () => {
    await readError((s) => {
      s.write(Buffer.from('0300001902F080320300', 'hex'));
      s.resetAndDestroy();
    }, /CONNECTION_LOST/);
  });

  it('an answer with the wrong PDU reference is ignored (counted); the request times out', async () => {
    const { client } = await readError(
      (s, job) => s.write(encodeReadResponse(job.readUInt16BE(11) + 1, [{ returnCode: 0xff, transportSize: 4, data: Buffer.alloc(2) }])),
      /^TIMEOUT$/,
    );
    expect(client.stats.ignoredReplies).to.equal(1);
  });

  it('a duplicated answer is ignored; the value and the link stay good', async () => {
    const port = await peer((s, job) => {
      const frame = encodeReadResponse(job.readUInt16BE(11), [{ returnCode: 0xff, transportSize: 4, data: Buffer.from('04D2', 'hex') }]);
      s.write(Buffer.concat([frame, frame]));
    });
    const client = new S7Client(endpoint(port), FAST);
    try {
      await client.connect();
      expect(await client.read(['DB1,INT0'])).to.deep.equal({ 'DB1,INT0': 1234 });
      await until(() => client.stats.ignoredReplies === 1, 1000, 'the duplicate was seen');
      expect(await client.read(['DB1,INT0'])).to.deep.equal({ 'DB1,INT0': 1234 });
      expect(client.state).to.equal('connected');
    } finally {
      await client.close();
    }
  });

  it('an answer dripped one byte at a time is read correctly', async () => {
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
    const port = await peer((s) => s.end(encodeDisconnectRequest(1, 1, 0x80)), false);
    const client = new S7Client(endpoint(port));
    const err = (await client.connect().catch((e: unknown) => e)) as PlcError;
    expect(err.code).to.equal('CONNECT_FAILED');
    await client.close();
  });

  it('garbage instead of a connection confirm: CONNECT_FAILED, no uncaught exception', async () => {
    const port = await peer((s) => s.write(Buffer.from('0300000000', 'hex')), false);
    const client = new S7Client(endpoint(port));
    const err = (await client.connect().catch((e: unknown) => e)) as PlcError;
    expect(err).to.be.instanceOf(PlcError);
    expect(err.code).to.equal('CONNECT_FAILED');
    await client.close();
  });
});
