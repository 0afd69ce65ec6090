import { expect } from 'chai';
import * as net from 'node:net';
import { PlcError, TagErrors } from '../lib/errors';
import { FetchWriteClient } from '../lib/fetchwrite/client';
import { OpCode, encodeRequest, encodeResponse } from '../lib/fetchwrite/codec';
import { FetchWriteServer, type FetchWriteRequestEvent } from '../lib/fetchwrite/server';
import { parseUrl, type FetchWriteEndpoint } from '../lib/url';
import { activeHandles, settle, until, waitFor } from './support/wait';

const hex = (s: string) => Buffer.from(s.replace(/\s+/g, ''), 'hex');
const FAST = { backoff: { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 } };
const endpoint = (query: string) => parseUrl(`fetchwrite://127.0.0.1?${query}`) as FetchWriteEndpoint;
const jobText = (j: FetchWriteRequestEvent) => `${j.kind} ${j.org}/${j.dbNumber}@${j.start}+${j.length}`;

async function failure(p: Promise<unknown>): Promise<PlcError> {
  const outcome = await p.then(
    () => undefined,
    (e: unknown) => e,
  );
  if (!(outcome instanceof PlcError)) throw new Error(`expected a PlcError, got ${String(outcome)}`);
  return outcome;
}

describe('FETCH/WRITE client against the CP simulator', function () {
  this.timeout(10000);
  let server: FetchWriteServer;
  let client: FetchWriteClient;
  let jobs: FetchWriteRequestEvent[];

  async function start(options: { port?: boolean; dbUnit?: 'word' | 'byte'; query?: string } = {}) {
    const dbUnit = options.dbUnit ? { dbUnit: options.dbUnit } : {};
    server = new FetchWriteServer(options.port ? { port: 0, ...dbUnit } : { fetchPort: 0, writePort: 0, ...dbUnit });
    const ports = await server.listen();
    jobs = [];
    server.on('request', (r: FetchWriteRequestEvent) => jobs.push(r));
    const q = options.port ? `port=${ports.fetchPort}` : `fetchPort=${ports.fetchPort}&writePort=${ports.writePort}`;
    client = new FetchWriteClient(
      endpoint(`${q}&timeout=1500${options.dbUnit ? `&dbUnit=${options.dbUnit}` : ''}${options.query ?? ''}`),
      FAST,
    );
    await client.connect();
  }

  afterEach(async () => {
    await client?.close();
    await server?.close();
  });

  it('reads and writes every area and several types', async () => {
    await start();
    const values: Record<string, unknown> = {
      'DB10,INT4': -321,
      'DB10.DBD8:REAL': 1.25,
      'DB10,S20.10': 'abc',
      'DB10.DBB40:LINT': -5n,
      'DB10.DBW60:INT[3]': [1, -2, 3],
      'DB10,X70.3': true,
      MB0: 0x5a,
      'MW2:INT': -2,
      'MD4:DINT': -100000,
      'I1.5': true,
      IW4: 0x1234,
      QW2: 0xbeef,
      'QD8:REAL': -0.5,
      C5: 42,
      T3: 2000,
    };
    server.memory.area('DB', 10)![20] = 10; // the STRING's max length, as the PLC's DB declares it
    await client.write(values);
    expect(await client.read(Object.keys(values))).to.deep.equal(values);
    expect(server.memory.area('DB', 10)!.readInt16BE(4)).to.equal(-321);
    expect(server.memory.area('M')!.readInt32BE(4)).to.equal(-100000);
    expect(server.memory.area('Q')!.readUInt16BE(2)).to.equal(0xbeef);
    expect(server.memory.area('C')!.readUInt16BE(10)).to.equal(0x0042); // BCD
  });

  it('ORG 5: writes go to the output modules, reads come from the input modules; the other direction is refused before sending', async () => {
    await start();
    server.memory.area('PE')!.writeUInt16BE(4321, 130);
    await client.write({ PQW4: 1234 });
    expect(server.memory.area('PA')!.readUInt16BE(4)).to.equal(1234);
    expect(await client.read(['PIW130'])).to.deep.equal({ PIW130: 4321 });
    expect(jobs.map(jobText)).to.deep.equal(['write 5/0@4+2', 'fetch 5/0@130+2']);
    const r = await client.readDetailed(['PQW4']);
    const w = await client.writeDetailed({ PIW4: 1 });
    expect(r.PQW4!.ok || r.PQW4!.error.code).to.equal('INVALID_ADDRESS');
    expect(w.PIW4!.ok || w.PIW4!.error.message).to.match(/cannot write the input modules/);
    expect(jobs).to.have.length(2);
  });

  it('counts DB addresses in words on the wire; odd byte offsets fetch the enclosing words', async () => {
    await start();
    const db = server.memory.area('DB', 1)!;
    db.writeUInt8(0x7e, 5);
    db.writeInt16BE(-2, 7);
    expect(await client.read(['DB1.DBB5'])).to.deep.equal({ 'DB1.DBB5': 0x7e });
    expect(await client.read(['DB1,INT7'])).to.deep.equal({ 'DB1,INT7': -2 });
    expect(jobs.map(jobText)).to.deep.equal(['fetch 1/1@2+1', 'fetch 1/1@3+2']);
  });

  it('dbUnit=byte counts DB addresses in bytes (VIPA and some gateways)', async () => {
    await start({ dbUnit: 'byte' });
    server.memory.area('DB', 1)!.writeUInt8(0x7e, 5);
    expect(await client.read(['DB1.DBB5'])).to.deep.equal({ 'DB1.DBB5': 0x7e });
    await client.write({ 'DB1.DBB7': 9 });
    expect(server.memory.area('DB', 1)![7]).to.equal(9);
    expect(jobs.map(jobText)).to.deep.equal(['fetch 1/1@5+1', 'write 1/1@7+1']);
  });

  it('writes bits in every area by read-modify-write of the enclosing byte (DB: word), keeping the neighbours', async () => {
    await start();
    const m = server.memory;
    m.area('DB', 1)!.writeUInt16BE(0xa5a5, 12);
    m.area('M')![3] = 0xff;
    m.area('I')![1] = 0x0f;
    m.area('Q')![2] = 0x00;
    await client.write({ 'DB1,X13.1': false, 'M3.0': false, 'I1.7': true, 'Q2.2': true });
    expect(m.area('DB', 1)!.readUInt16BE(12)).to.equal(0xa5a5 & ~0x0002);
    expect(m.area('M')![3]).to.equal(0xfe);
    expect(m.area('I')![1]).to.equal(0x8f);
    expect(m.area('Q')![2]).to.equal(0x04);
    expect(jobs.map(jobText)).to.deep.equal([
      'fetch 1/1@6+1',
      'write 1/1@6+1',
      'fetch 2/0@3+1',
      'write 2/0@3+1',
      'fetch 3/0@1+1',
      'write 3/0@1+1',
      'fetch 4/0@2+1',
      'write 4/0@2+1',
    ]);
  });

  it('writes odd-offset DB bytes, words and STRINGs by read-modify-write of the enclosing words', async () => {
    await start();
    const db = server.memory.area('DB', 1)!;
    db.writeUInt32BE(0xa1a2a3a4, 12);
    await client.write({ 'DB1.DBB13': 0x11 });
    expect(db.readUInt32BE(12)).to.equal(0xa111a3a4);
    await client.write({ 'DB1,INT13': 0x2233 });
    expect(db.readUInt32BE(12)).to.equal(0xa12233a4);
    // STRING[4] at 20: the write sends [length, chars] from byte 21 and keeps the max-length byte.
    db[20] = 4;
    db.writeUInt16BE(0xeeee, 24);
    await client.write({ 'DB1,S20.4': 'hi' });
    expect(db.subarray(20, 26).toString('hex')).to.equal('04026869eeee');
    expect(jobs.map(jobText)).to.deep.equal([
      'fetch 1/1@6+1',
      'write 1/1@6+1',
      'fetch 1/1@6+2',
      'write 1/1@6+2',
      'fetch 1/1@10+2',
      'write 1/1@10+2',
    ]);
  });

  it('serialises read-modify-writes so concurrent bit writes to one byte both land', async () => {
    await start();
    server.faults.latencyMs = 5;
    await Promise.all([0, 1, 2, 3, 4, 5, 6, 7].map((bit) => client.write({ [`M9.${bit}`]: true })));
    expect(server.memory.area('M')![9]).to.equal(0xff);
  });

  it('merges several tags into as few fetches as the ranges allow', async () => {
    await start();
    server.memory.createDataBlock(3, 4096);
    await client.read([
      'DB1,INT0',
      'DB1,INT2',
      'DB1,REAL40',
      'DB1,INT1000',
      'MB0',
      'MB10',
      'MW200',
      'DB2,INT0',
      'DB3,INT0',
      'DB3,INT3000',
      'IB0',
      'IB127',
    ]);
    expect(jobs.map(jobText)).to.deep.equal([
      'fetch 1/1@0+501',
      'fetch 1/2@0+1',
      'fetch 1/3@0+1',
      'fetch 1/3@1500+1',
      'fetch 2/0@0+202',
      'fetch 3/0@0+128',
    ]);
  });

  it('splits a read beyond the ORG length range into several jobs, and C/T one cell per job as the table permits', async () => {
    await start({ dbUnit: 'byte' });
    server.memory.createDataBlock(5, 8000);
    server.memory.area('DB', 5)!.fill(7);
    const v = (await client.read(['DB5.DBB0:BYTE[6000]']))['DB5.DBB0:BYTE[6000]'] as number[];
    expect(v.length).to.equal(6000);
    expect(v.every((b) => b === 7)).to.equal(true);
    expect(jobs.map(jobText)).to.deep.equal(['fetch 1/5@0+2048', 'fetch 1/5@2048+2048', 'fetch 1/5@4096+1904']);
    jobs.length = 0;
    await client.write({ 'C0:COUNTER[3]': [1, 2, 3] });
    expect(await client.read(['C0:COUNTER[3]'])).to.deep.equal({ 'C0:COUNTER[3]': [1, 2, 3] });
    expect(jobs.map(jobText)).to.deep.equal([
      'write 6/0@0+1',
      'write 6/0@1+1',
      'write 6/0@2+1',
      'fetch 6/0@0+1',
      'fetch 6/0@1+1',
      'fetch 6/0@2+1',
    ]);
  });

  it('splits a write beyond the ORG length range', async () => {
    await start({ dbUnit: 'byte' });
    server.memory.createDataBlock(5, 8000);
    const data = Array.from({ length: 5000 }, (_, i) => i & 0xff);
    await client.write({ 'DB5.DBB100:BYTE[5000]': data });
    expect([...server.memory.area('DB', 5)!.subarray(100, 5100)]).to.deep.equal(data);
    expect(jobs.map(jobText)).to.deep.equal(['write 1/5@100+2048', 'write 1/5@2148+2048', 'write 1/5@4196+904']);
  });

  it('reads analog inputs from byte 256 up (PIW256), where S7 CPUs put them', async () => {
    await start();
    server.memory.area('PE')!.writeInt16BE(13824, 256);
    expect(await client.read(['PIW256'])).to.deep.equal({ PIW256: 13824 });
  });

  it('refuses impossible addresses before sending anything', async () => {
    await start();
    const r = await client.readDetailed(['DB0,INT0', 'DB256,INT0', 'MB256', 'IB200', 'QB128', 'DB1.DBW4095', 'C256', 'T300']);
    for (const [address, result] of Object.entries(r)) {
      expect(result.ok, address).to.equal(false);
      if (!result.ok) {
        expect(result.error.code, address).to.equal('INVALID_ADDRESS');
        expect(result.error.message, address).to.include(address);
      }
    }
    expect(r['DB256,INT0']!.ok || r['DB256,INT0']!.error.message).to.match(/DB 1\.\.255/);
    expect(jobs).to.deep.equal([]);
  });

  it('a CP error fails only the tags of that job, with the code in words', async () => {
    await start();
    server.memory.area('DB', 99)!.writeInt16BE(5, 0);
    const r = await client.readDetailed(['DB99,INT0', 'DB200,INT0', 'DB1.DBW2000']);
    expect(r['DB99,INT0']).to.deep.equal({ ok: true, value: 5 });
    const missing = r['DB200,INT0']!;
    if (missing.ok) throw new Error('expected failure');
    expect(missing.error.code).to.equal('OBJECT_DOES_NOT_EXIST');
    expect(missing.error.plcCode).to.equal(2);
    expect(missing.error.message).to.match(/^DB200,INT0: .*area does not exist/);
    expect(r['DB1.DBW2000']!.ok || r['DB1.DBW2000']!.error.code).to.equal('ADDRESS_OUT_OF_RANGE');
    const w = await client.writeDetailed({ 'DB200,INT0': 1, 'DB1,INT0': 7 });
    expect(w['DB200,INT0']!.ok).to.equal(false);
    expect(w['DB1,INT0']!.ok).to.equal(true);
    expect(server.memory.area('DB', 1)!.readInt16BE(0)).to.equal(7);
  });

  it('a merged fetch that the CP refuses is retried tag by tag, so one bad tag does not fail its neighbours', async () => {
    await start();
    server.memory.createDataBlock(4, 10);
    server.memory.area('DB', 4)!.writeInt16BE(11, 0);
    const r = await client.readDetailed(['DB4,INT0', 'DB4,INT20']);
    expect(r['DB4,INT0']).to.deep.equal({ ok: true, value: 11 });
    expect(r['DB4,INT20']!.ok || r['DB4,INT20']!.error.code).to.equal('ADDRESS_OUT_OF_RANGE');
    expect(jobs.map(jobText)).to.deep.equal(['fetch 1/4@0+11', 'fetch 1/4@0+1', 'fetch 1/4@10+1']);
  });

  it('injected error bytes, known and unknown, become typed per-tag errors and leave the link up', async () => {
    await start();
    server.faults.errorCode = 0x06;
    const e6 = await failure(client.read(['MW0']));
    expect(e6).to.be.instanceOf(TagErrors);
    const r = await client.readDetailed(['MW0']);
    expect(r.MW0!.ok || r.MW0!.error.code).to.equal('TYPE_NOT_SUPPORTED');
    server.faults.errorCode = 0x42;
    const w = await client.writeDetailed({ MW0: 1 });
    expect(w.MW0!.ok || w.MW0!.error.message).to.match(/error 42 \(unknown code\)/);
    server.faults.errorCode = 0;
    expect(await client.read(['MW0'])).to.deep.equal({ MW0: 0 });
    expect(client.state).to.equal('connected');
  });

  it('works with one port serving fetch and write', async () => {
    await start({ port: true });
    await client.write({ MW0: 77 });
    expect(await client.read(['MW0'])).to.deep.equal({ MW0: 77 });
    expect(server.connectionCount).to.equal(1);
    expect(server.socketCount).to.equal(1);
  });

  it('two ports: one client counts once, with two sockets', async () => {
    await start();
    expect(server.connectionCount).to.equal(1);
    expect(server.socketCount).to.equal(2);
  });

  it('a read-only connection refuses writes before anything is sent', async () => {
    await start({ query: '&readOnly=true' });
    const w = await client.writeDetailed({ MW0: 1 });
    expect(w.MW0!.ok || w.MW0!.error.code).to.equal('WRITE_NOT_ALLOWED');
    expect(jobs).to.deep.equal([]);
  });

  it('a job slower than the timeout: TIMEOUT, the link is dropped (no request ids), then it recovers', async () => {
    await start();
    server.faults.latencyMs = 2500;
    const started = Date.now();
    const err = await failure(client.read(['MW0']));
    expect(err.code).to.equal('TIMEOUT');
    expect(Date.now() - started).to.be.within(1400, 2400);
    server.faults.latencyMs = 0;
    await until(() => client.state === 'connected' && server.connectionCount === 1, 4000, 'reconnected');
    expect(await client.read(['MW0'])).to.deep.equal({ MW0: 0 });
  });

  it('an answer cut in half and a reset: CONNECTION_LOST, never a hang; then it recovers', async () => {
    await start();
    server.faults.truncateAnswers = 1;
    const err = await failure(client.write({ MW0: 5 }));
    expect(err).to.be.instanceOf(TagErrors);
    const detail = (err as TagErrors).results?.MW0;
    expect(detail && !detail.ok && detail.error.code).to.equal('CONNECTION_LOST');
    await waitFor(client, 'connected', 3000);
    await client.write({ MW0: 6 });
    expect(server.memory.area('M')!.readUInt16BE(0)).to.equal(6);
    // Several writes when the link fails at the first: every one is reported failed, none silently skipped.
    server.faults.truncateAnswers = 1;
    const w = await client.writeDetailed({ MW2: 1, MW4: 2, 'M6.0': true });
    expect(Object.values(w).map((r) => r.ok || r.error.code)).to.deep.equal(['CONNECTION_LOST', 'CONNECTION_LOST', 'CONNECTION_LOST']);
    expect(server.memory.area('M')!.readUInt16BE(4)).to.equal(0);
    await waitFor(client, 'connected', 3000);
  });

  it('reconnects after the CP drops the connections, failing fast meanwhile', async () => {
    await start();
    const lost = waitFor(client, 'disconnected');
    server.faults.dropConnections();
    await lost;
    expect((await failure(client.read(['MW0']))).code).to.equal('NOT_CONNECTED');
    await waitFor(client, 'connected', 3000);
    server.memory.area('M')!.writeUInt16BE(9, 0);
    expect(await client.read(['MW0'])).to.deep.equal({ MW0: 9 });
  });

  it('close() fails a pending job with CLOSED and leaves no handles, also after reconnects', async () => {
    await settle();
    const before = activeHandles();
    await start();
    for (let i = 0; i < 3; i++) {
      const lost = waitFor(client, 'disconnected');
      server.dropConnections();
      await lost;
      await waitFor(client, 'connected', 3000);
    }
    server.faults.silent = true;
    const pending = failure(client.read(['MW0']));
    await until(() => jobs.length === 1);
    await client.close();
    expect((await pending).code).to.equal('CLOSED');
    await server.close();
    await until(() => server.connectionCount === 0);
    await settle();
    expect(activeHandles()).to.equal(before);
  });
});

describe('FETCH/WRITE over fragmented and coalesced TCP segments', function () {
  this.timeout(10000);
  let server: FetchWriteServer;
  let client: FetchWriteClient | undefined;
  let proxy: net.Server | undefined;
  const sockets = new Set<net.Socket>();

  beforeEach(async () => {
    server = new FetchWriteServer({ port: 0 });
    await server.listen();
  });

  afterEach(async () => {
    await client?.close();
    client = undefined;
    for (const s of sockets) s.destroy();
    sockets.clear();
    if (proxy) await new Promise((r) => proxy!.close(r));
    proxy = undefined;
    await server.close();
  });

  /** A proxy that re-chunks both directions: bytes one at a time towards the CP, odd-sized pieces towards the client. */
  async function dripProxy(): Promise<number> {
    proxy = net.createServer((inbound) => {
      const outbound = net.connect(server.fetchPort, '127.0.0.1');
      sockets.add(inbound).add(outbound);
      for (const s of [inbound, outbound]) {
        s.setNoDelay(true);
        s.on('error', () => undefined);
        s.on('close', () => (inbound.destroy(), outbound.destroy()));
      }
      const pipe = (from: net.Socket, to: net.Socket, size: () => number) => {
        let queue = Buffer.alloc(0);
        let flushing = false;
        const flush = () => {
          if (queue.length === 0 || to.destroyed) return void (flushing = false);
          flushing = true;
          const n = size();
          to.write(queue.subarray(0, n));
          queue = queue.subarray(n);
          setImmediate(flush);
        };
        from.on('data', (chunk: Buffer) => {
          queue = Buffer.concat([queue, chunk]);
          if (!flushing) flush();
        });
      };
      let k = 0;
      pipe(inbound, outbound, () => 1);
      pipe(outbound, inbound, () => [3, 1, 7, 16, 2][k++ % 5]!);
    });
    await new Promise<void>((r) => proxy!.listen(0, '127.0.0.1', r));
    return (proxy.address() as net.AddressInfo).port;
  }

  it('the client reads and writes through a proxy that fragments every frame', async () => {
    const port = await dripProxy();
    client = new FetchWriteClient(endpoint(`port=${port}&timeout=3000`), FAST);
    await client.connect();
    const values = { 'DB1,REAL0': 3.5, 'DB1.DBW10:INT[4]': [1, 2, 3, -4], MD4: 0xdeadbeef, 'M8.1': true, 'DB1,S40.8': 'frag' };
    server.memory.area('DB', 1)![40] = 8;
    await client.write(values);
    expect(await client.read(Object.keys(values))).to.deep.equal(values);
  });

  it('the simulator cuts requests sent byte by byte and several requests coalesced in one segment', async () => {
    server.memory.area('M')!.writeUInt16BE(0xcafe, 0);
    const raw = net.connect(server.fetchPort, '127.0.0.1');
    sockets.add(raw);
    await new Promise((r) => raw.once('connect', r));
    const received: Buffer[] = [];
    raw.on('data', (c: Buffer) => received.push(c));
    const fetch = encodeRequest({ op: OpCode.FetchRequest, org: 2, dbNumber: 0, start: 0, length: 2 });
    const write = encodeRequest({ op: OpCode.WriteRequest, org: 2, dbNumber: 0, start: 2, length: 2, data: hex('0102') });
    for (const byte of fetch) raw.write(Buffer.of(byte));
    raw.write(Buffer.concat([write, fetch, fetch.subarray(0, 7)]));
    raw.write(fetch.subarray(7));
    const expected = Buffer.concat([
      encodeResponse(OpCode.FetchResponse, 0, hex('cafe')),
      encodeResponse(OpCode.WriteAck, 0),
      encodeResponse(OpCode.FetchResponse, 0, hex('cafe')),
      encodeResponse(OpCode.FetchResponse, 0, hex('cafe')),
    ]);
    await until(() => Buffer.concat(received).length >= expected.length);
    expect(Buffer.concat(received).toString('hex')).to.equal(expected.toString('hex'));
    expect(server.memory.area('M')!.readUInt16BE(2)).to.equal(0x0102);
  });
});

describe('FETCH/WRITE simulator against hostile clients', function () {
  this.timeout(10000);
  let server: FetchWriteServer;
  const sockets = new Set<net.Socket>();

  beforeEach(async () => {
    server = new FetchWriteServer({ fetchPort: 0, writePort: 0 });
    await server.listen();
  });

  afterEach(async () => {
    for (const s of sockets) s.destroy();
    sockets.clear();
    await server.close();
  });

  async function raw(port: number): Promise<net.Socket> {
    const s = net.connect(port, '127.0.0.1');
    sockets.add(s);
    s.on('error', () => undefined);
    await new Promise((r) => s.once('connect', r));
    return s;
  }

  it('garbage, a write on the fetch port and a huge write header close only that connection', async () => {
    const good = new FetchWriteClient(endpoint(`fetchPort=${server.fetchPort}&writePort=${server.writePort}&timeout=1000`), FAST);
    await good.connect();
    try {
      const victims = [
        [await raw(server.fetchPort), Buffer.from('GET / HTTP/1.1\r\nHost: x\r\n\r\n')],
        [
          await raw(server.fetchPort),
          encodeRequest({ op: OpCode.WriteRequest, org: 2, dbNumber: 0, start: 0, length: 1, data: hex('01') }),
        ],
        [await raw(server.writePort), encodeRequest({ op: OpCode.FetchRequest, org: 2, dbNumber: 0, start: 0, length: 1 })],
      ] as const;
      for (const [socket, bytes] of victims) {
        const closed = new Promise((r) => socket.once('close', r));
        socket.write(bytes);
        await closed;
      }
      // A write header announcing 65535 words, then 100 KiB of data that never completes it: dropped at the buffer limit or left waiting, never a crash.
      const huge = await raw(server.writePort);
      huge.write(encodeRequest({ op: OpCode.WriteRequest, org: 1, dbNumber: 1, start: 0, length: 0xffff }));
      huge.write(Buffer.alloc(100_000));
      await client_roundtrip(good);
      expect(server.memory.area('M')![0]).to.equal(0);
    } finally {
      await good.close();
    }
  });

  async function client_roundtrip(c: FetchWriteClient): Promise<void> {
    await c.write({ MW10: 321 });
    expect(await c.read(['MW10'])).to.deep.equal({ MW10: 321 });
  }

  it('refuseConnections: a client that cannot keep its connection gets typed errors, then recovers when the CP accepts again', async () => {
    server.faults.refuseConnections = true;
    const c = new FetchWriteClient(endpoint(`fetchPort=${server.fetchPort}&writePort=${server.writePort}&timeout=500`), FAST);
    try {
      c.start();
      const errors: PlcError[] = [];
      c.on('error', (e: PlcError) => errors.push(e));
      await until(() => errors.length > 0 || c.state === 'reconnecting', 3000, 'a connection error');
      expect(server.connectionCount).to.equal(0);
      server.faults.refuseConnections = false;
      await until(() => server.connectionCount === 1 && c.state === 'connected', 4000, 'connected');
      await client_roundtrip(c);
    } finally {
      await c.close();
    }
  });
});

describe('FETCH/WRITE client against hostile peers', function () {
  this.timeout(10000);
  const servers: net.Server[] = [];
  const peers = new Set<net.Socket>();
  afterEach(async () => {
    for (const s of peers) s.destroy();
    peers.clear();
    await Promise.all(servers.splice(0).map((s) => new Promise((r) => s.close(r))));
  });

  async function peer(answer: (socket: net.Socket, job: Buffer) => void): Promise<number> {
    const server = net.createServer((socket) => {
      peers.add(socket);
      socket.on('error', () => undefined);
      socket.on('data', (job) => answer(socket, job));
    });
    servers.push(server);
    await new Promise<void>((r) => server.listen(0, '127.0.0.1', r));
    return (server.address() as net.AddressInfo).port;
  }

  async function readFrom(port: number, addresses = ['MW0']): Promise<unknown> {
    const client = new FetchWriteClient(endpoint(`port=${port}&timeout=800`), FAST);
    try {
      await client.connect();
      return await client.read(addresses).catch((e: unknown) => e);
    } finally {
      await client.close();
    }
  }

  const linkError = (e: unknown) => {
    expect(e).to.be.instanceOf(PlcError);
    const err = e as PlcError;
    expect(err.code).to.be.oneOf(['PROTOCOL_ERROR', 'CONNECTION_LOST']);
    return err;
  };

  it('a response dripped one byte at a time is cut correctly', async () => {
    const reply = encodeResponse(OpCode.FetchResponse, 0, hex('1234'));
    const port = await peer((socket) => {
      let i = 0;
      const drip = () => {
        if (i < reply.length && !socket.destroyed) {
          socket.write(reply.subarray(i, ++i));
          setImmediate(drip);
        }
      };
      drip();
    });
    expect(await readFrom(port)).to.deep.equal({ MW0: 0x1234 });
  });

  it('a silent CP: TIMEOUT within the timeout', async () => {
    const port = await peer(() => undefined);
    const started = Date.now();
    const err = (await readFrom(port)) as PlcError;
    expect(err.code).to.equal('TIMEOUT');
    expect(Date.now() - started).to.be.below(2000);
  });

  it('fewer data bytes than the fetch asked for: TIMEOUT, not a short value', async () => {
    const port = await peer((socket) => socket.write(encodeResponse(OpCode.FetchResponse, 0, hex('12'))));
    expect(((await readFrom(port)) as PlcError).code).to.equal('TIMEOUT');
  });

  it('garbage instead of a response: a link error, no crash', async () => {
    const port = await peer((socket) => socket.write(Buffer.from('HTTP/1.1 400 Bad Request\r\n\r\n')));
    linkError(await readFrom(port));
  });

  it('a wrong system id or header length: a protocol error', async () => {
    for (const patch of [
      [0, 0x54],
      [2, 0x11],
      [6, 0x00],
      [9, 0x00],
    ] as const) {
      const bad = encodeResponse(OpCode.FetchResponse, 0, hex('0000'));
      bad[patch[0]] = patch[1];
      const port = await peer((socket) => socket.write(bad));
      linkError(await readFrom(port));
    }
  });

  it('a write ack where a fetch response is due: a protocol error', async () => {
    const port = await peer((socket) => socket.write(encodeResponse(OpCode.WriteAck, 0)));
    linkError(await readFrom(port));
  });

  it('an error response followed by data it must not carry: the trailing bytes drop the link', async () => {
    const port = await peer((socket) => socket.write(Buffer.concat([encodeResponse(OpCode.FetchResponse, 2), hex('1234')])));
    const client = new FetchWriteClient(endpoint(`port=${port}&timeout=800`), FAST);
    try {
      await client.connect();
      const lost = waitFor(client, 'disconnected', 2000);
      expect((await failure(client.readDetailed(['MW0']))).code).to.equal('PROTOCOL_ERROR');
      await lost;
    } finally {
      await client.close();
    }
  });

  it('unsolicited bytes with no job pending drop the link', async () => {
    let first = true;
    const port = await peer(() => undefined);
    const client = new FetchWriteClient(endpoint(`port=${port}&timeout=800`), FAST);
    servers[0]!.on('connection', (s: net.Socket) => {
      if (first) setTimeout(() => s.write(hex('5335')), 20);
      first = false;
    });
    try {
      await client.connect();
      await waitFor(client, 'disconnected', 2000);
    } finally {
      await client.close();
    }
  });

  it('a peer that resets in the middle of a response: CONNECTION_LOST', async () => {
    const port = await peer((socket) =>
      socket.write(encodeResponse(OpCode.FetchResponse, 0, hex('1234')).subarray(0, 9), () => socket.resetAndDestroy()),
    );
    expect(((await readFrom(port)) as PlcError).code).to.equal('CONNECTION_LOST');
  });

  it('connection refused: connect() rejects with CONNECT_FAILED', async () => {
    const port = await peer(() => undefined);
    await new Promise((r) => servers.pop()!.close(r));
    const client = new FetchWriteClient(endpoint(`port=${port}&timeout=800`), FAST);
    const err = await failure(client.connect());
    expect(err.code).to.equal('CONNECT_FAILED');
    await client.close();
  });
});
