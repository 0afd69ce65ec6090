import { expect } from 'chai';
import { MockBinding } from '@serialport/binding-mock';
import { PlcError, TagErrors } from '../lib/errors';
import { FetchWriteClient } from '../lib/fetchwrite/client';
import { FetchWriteServer, type FetchWriteRequestEvent } from '../lib/fetchwrite/server';
import { FreeportBus } from '../lib/freeport/bus';
import { FreeportClient } from '../lib/freeport/client';
import type { FreeportRequest } from '../lib/freeport/codec';
import type { PreparedRead } from '../lib/client/base';
import { S7Client, type ItemLimitEvent } from '../lib/s7/client';
import { S7Server, type S7RequestEvent } from '../lib/s7/server';
import { PlcMemory } from '../lib/sim/memory';
import { parseUrl, type FetchWriteEndpoint, type FreeportEndpoint, type S7Endpoint } from '../lib/url';
import { waitFor } from './support/wait';

const FAST = { backoff: { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 } };

async function failure(p: Promise<unknown>): Promise<PlcError> {
  const outcome = await p.then(
    () => undefined,
    (e: unknown) => e,
  );
  if (!(outcome instanceof PlcError)) throw new Error(`expected a PlcError, got ${String(outcome)}`);
  return outcome;
}

function thrown(f: () => unknown): PlcError {
  try {
    f();
  } catch (err) {
    if (err instanceof PlcError) return err;
    throw err;
  }
  throw new Error('expected a PlcError, nothing was thrown');
}

/** 40 INTs in 40 DBs (each its own item) and a few merged tags of DB1: several PDUs at PDU 240. */
const LIST = [...Array.from({ length: 40 }, (_, i) => `DB${i + 1},INT${2 * (i % 5)}`), 'DB1,REAL20', 'DB1,X24.3', 'MW10'];

function memory(): PlcMemory {
  const dataBlocks: Record<number, number> = {};
  for (let db = 1; db <= 40; db++) dataBlocks[db] = 64;
  const m = new PlcMemory({ dataBlocks });
  for (let db = 1; db <= 40; db++) m.area('DB', db)!.writeInt16BE(db * 100 + 1, 2 * ((db - 1) % 5));
  m.area('DB', 1)!.writeFloatBE(2.5, 20);
  m.area('DB', 1)![24] = 0x08;
  m.area('M', 0)!.writeUInt16BE(4321, 10);
  return m;
}

const EXPECTED: Record<string, unknown> = {
  ...Object.fromEntries(LIST.slice(0, 40).map((a, i) => [a, (i + 1) * 100 + 1])),
  'DB1,REAL20': 2.5,
  'DB1,X24.3': true,
  MW10: 4321,
};

describe('prepared reads (client.prepare) on S7', function () {
  this.timeout(10000);
  let server: S7Server;
  let requests: S7RequestEvent[];
  const clients: S7Client[] = [];
  const servers: S7Server[] = [];

  async function serve(profile: 's7-1200' | 's7-1500', port = 0, plc = memory()): Promise<S7Server> {
    const s = new S7Server({ port, profile, memory: plc });
    await s.listen();
    servers.push(s);
    s.on('request', (r: S7RequestEvent) => requests.push(r));
    return s;
  }

  function client(query = ''): S7Client {
    const c = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?timeout=1500${query}`) as S7Endpoint, FAST);
    clients.push(c);
    return c;
  }

  beforeEach(async () => {
    requests = [];
    server = await serve('s7-1200');
  });

  afterEach(async () => {
    for (const c of clients.splice(0)) await c.close();
    for (const s of servers.splice(0)) await s.close();
  });

  it('plans once for 50 reads, sends the same request frames every time, and reads what read() reads', async () => {
    const c = client();
    await c.connect();
    const prepared = c.prepare(LIST);
    const frames = new Set<Buffer>();
    // The frames the session writes to its socket (the session owns the socket: its write is watched).
    const socket = (c as unknown as { session: { socket: { write: (f: Buffer) => boolean } } }).session.socket;
    const writing = socket.write;
    socket.write = function (this: unknown, f: Buffer) {
      frames.add(f);
      return writing.call(this, f);
    };
    for (let i = 0; i < 50; i++) expect(await prepared.read()).to.deep.equal(EXPECTED);
    const pdus = c.planFor(LIST).pdus.length;
    expect(pdus).to.be.greaterThan(1);
    expect(frames.size).to.equal(pdus);
    expect(requests).to.have.length(50 * pdus);
    // read() of the same addresses in new arrays finds the plan and its frames in the cache.
    expect(await c.read([...LIST])).to.deep.equal(EXPECTED);
    expect(await c.read([...LIST])).to.deep.equal(EXPECTED);
    socket.write = writing;
    expect(frames.size).to.equal(pdus);
    expect(c.stats.plansMade).to.equal(1);
    expect(Object.keys(await prepared.read())).to.deep.equal(LIST);
  });

  it('readDetailed gives a result per tag, like client.readDetailed, and read rejects with TagErrors keeping the good values', async () => {
    const c = client();
    await c.connect();
    const list = ['DB1,INT0', 'DB99,INT0', 'MW10'];
    const prepared = c.prepare(list);
    const detailed = await prepared.readDetailed();
    expect(detailed).to.deep.equal(await c.readDetailed(list));
    expect(detailed['DB1,INT0']).to.deep.equal({ ok: true, value: 101 });
    expect(detailed['DB99,INT0']!.ok).to.equal(false);
    const err = await failure(prepared.read());
    expect(err).to.be.instanceOf(TagErrors);
    const results = (err as TagErrors).results;
    expect(results['MW10']).to.deep.equal({ ok: true, value: 4321 });
    expect(results['DB99,INT0']!.ok === false && results['DB99,INT0']!.error.code).to.equal('OBJECT_DOES_NOT_EXIST');
  });

  it('throws INVALID_ADDRESS naming a bad address at prepare(), before anything is sent', async () => {
    const c = client();
    await c.connect();
    const err = thrown(() => c.prepare(['DB1,INT0', 'DB1,NOPE3', 'MW10']));
    expect(err.code).to.equal('INVALID_ADDRESS');
    expect(err.tag).to.equal('DB1,NOPE3');
    expect(err.message).to.contain('DB1,NOPE3');
    expect(thrown(() => c.prepare('DB1,INT0' as unknown as string[])).code).to.equal('INVALID_ADDRESS');
    expect(requests).to.have.length(0);
  });

  it('keeps its own copy of the addresses: changing the array given to prepare() changes nothing', async () => {
    const c = client();
    await c.connect();
    const list = ['DB1,INT0', 'MW10'];
    const prepared = c.prepare(list);
    list[0] = 'DB2,INT2';
    expect(prepared.addresses).to.deep.equal(['DB1,INT0', 'MW10']);
    expect(Object.isFrozen(prepared.addresses)).to.equal(true);
    expect(await prepared.read()).to.deep.equal({ 'DB1,INT0': 101, MW10: 4321 });
  });

  it('re-plans after a reconnect to a CPU with another PDU size on the same port', async () => {
    const big = await serve('s7-1500');
    server = big;
    const plc = memory();
    const c = client('&pdu=960&maxItems=60');
    await c.connect();
    expect(c.pduSize).to.equal(960);
    const prepared = c.prepare(LIST);
    requests = [];
    expect(await prepared.read()).to.deep.equal(EXPECTED);
    const at960 = requests.length;
    expect(c.stats.plansMade).to.equal(1);

    const port = big.port;
    const lost = waitFor(c, 'disconnected');
    await big.close();
    servers.splice(servers.indexOf(big), 1);
    await lost;
    const back = waitFor(c, 'connected');
    server = await serve('s7-1200', port, plc);
    await back;
    expect(c.pduSize).to.equal(240);
    requests = [];
    expect(await prepared.read()).to.deep.equal(EXPECTED);
    expect(c.stats.plansMade).to.equal(2);
    expect(requests.length).to.equal(c.planFor(LIST).pdus.length);
    expect(requests.length).to.be.greaterThan(at960);
    // Every Read Var job fits the new PDU (the frame adds TPKT 4 and COTP 3 bytes).
    expect(Math.max(...requests.map((r) => r.bytes))).to.be.at.most(240 + 7);
    for (let i = 0; i < 5; i++) await prepared.read();
    expect(c.stats.plansMade).to.equal(2);
  });

  it('re-plans once the PLC has taught a lower item limit, and keeps that plan', async () => {
    const c = client('&maxItems=60');
    await c.connect();
    const prepared = c.prepare(LIST);
    expect(await prepared.read()).to.deep.equal(EXPECTED);
    expect(c.stats.plansMade).to.equal(1);
    expect(Math.max(...requests.map((r) => r.items))).to.be.greaterThan(5);
    const limits: ItemLimitEvent[] = [];
    c.on('itemLimit', (e: ItemLimitEvent) => limits.push(e));
    server.maxItems = 5;
    expect(await prepared.read()).to.deep.equal(EXPECTED);
    expect(limits).to.have.length(1);
    expect(limits[0]!.limit).to.equal(5);
    const plans = c.stats.plansMade;
    expect(plans).to.be.greaterThan(1);
    requests = [];
    for (let i = 0; i < 5; i++) expect(await prepared.read()).to.deep.equal(EXPECTED);
    expect(c.stats.plansMade).to.equal(plans);
    expect(Math.max(...requests.map((r) => r.items))).to.equal(5);
  });

  it('fails fast with NOT_CONNECTED while the link is down, reads again once it is back, and CLOSED after its own close()', async () => {
    const c = client();
    const prepared: PreparedRead = c.prepare(LIST); // no link needed to prepare
    expect((await failure(prepared.read())).code).to.equal('NOT_CONNECTED');
    expect((await failure(prepared.readDetailed())).code).to.equal('NOT_CONNECTED');
    await c.connect();
    expect(await prepared.read()).to.deep.equal(EXPECTED);

    const port = server.port;
    const lost = waitFor(c, 'disconnected');
    await server.close();
    servers.splice(servers.indexOf(server), 1);
    await lost;
    requests = [];
    const err = await failure(prepared.read());
    expect(err.code).to.equal('NOT_CONNECTED');
    expect(err.message).to.contain(c.name);
    const back = waitFor(c, 'connected');
    server = await serve('s7-1200', port);
    await back;
    expect(await prepared.read()).to.deep.equal(EXPECTED);

    prepared.close();
    expect((await failure(prepared.read())).code).to.equal('CLOSED');
    await c.close();
    expect((await failure(c.prepare(LIST).read())).code).to.equal('NOT_CONNECTED');
  });
});

describe('prepared reads (client.prepare) on FETCH/WRITE', function () {
  this.timeout(10000);
  let server: FetchWriteServer;
  let client: FetchWriteClient;
  let jobs: FetchWriteRequestEvent[];
  const list = ['DB10,INT4', 'DB10.DBD8:REAL', 'DB10,INT600', 'MB0', 'I1.5', 'DB20,INT0'];

  beforeEach(async () => {
    const plc = new PlcMemory({ dataBlocks: { 10: 2048, 20: 16 } });
    plc.area('DB', 10)!.writeInt16BE(-321, 4);
    plc.area('DB', 10)!.writeFloatBE(1.25, 8);
    plc.area('DB', 10)!.writeInt16BE(600, 600);
    plc.area('M', 0)![0] = 7;
    plc.area('I', 0)![1] = 0x20;
    plc.area('DB', 20)!.writeInt16BE(20, 0);
    server = new FetchWriteServer({ fetchPort: 0, writePort: 0, memory: plc });
    const ports = await server.listen();
    jobs = [];
    server.on('request', (r: FetchWriteRequestEvent) => jobs.push(r));
    const url = `fetchwrite://127.0.0.1?fetchPort=${ports.fetchPort}&writePort=${ports.writePort}&timeout=1500`;
    client = new FetchWriteClient(parseUrl(url) as FetchWriteEndpoint, FAST);
  });

  afterEach(async () => {
    await client.close();
    await server.close();
  });

  const expected = { 'DB10,INT4': -321, 'DB10.DBD8:REAL': 1.25, 'DB10,INT600': 600, MB0: 7, 'I1.5': true, 'DB20,INT0': 20 };

  it('merges the fetch ranges once for 50 reads and reads what read() reads', async () => {
    await client.connect();
    let merges = 0;
    // The range merging is the driver's prepareRead (lib/fetchwrite/plan.ts planRead): count its calls.
    const driver = (client as unknown as { driver: { prepareRead: (...a: unknown[]) => unknown } }).driver;
    const merge = driver.prepareRead.bind(driver);
    driver.prepareRead = (...a) => {
      merges++;
      return merge(...a);
    };
    const prepared = client.prepare(list);
    expect(merges).to.equal(1);
    for (let i = 0; i < 50; i++) expect(await prepared.read()).to.deep.equal(expected);
    expect(merges).to.equal(1);
    // DB10 bytes 4..601 in one job, DB20, M and I: four jobs a poll.
    expect(jobs).to.have.length(50 * 4);
    expect(await client.read(list)).to.deep.equal(expected);
  });

  it('throws INVALID_ADDRESS at prepare() for an address FETCH/WRITE cannot reach, and readDetailed keeps a PA tag as its own error', async () => {
    const err = thrown(() => client.prepare(['DB10,INT4', 'DB300,INT0']));
    expect(err.code).to.equal('INVALID_ADDRESS');
    expect(err.tag).to.equal('DB300,INT0');
    await client.connect();
    const prepared = client.prepare(['DB10,INT4', 'PAW0']);
    const results = await prepared.readDetailed();
    expect(results['DB10,INT4']).to.deep.equal({ ok: true, value: -321 });
    expect(results['PAW0']!.ok === false && results['PAW0']!.error.code).to.equal('INVALID_ADDRESS');
    expect(results).to.deep.equal(await client.readDetailed(['DB10,INT4', 'PAW0']));
  });

  it('fails fast with NOT_CONNECTED while not connected, and reads once connected', async () => {
    const prepared = client.prepare(list);
    expect((await failure(prepared.read())).code).to.equal('NOT_CONNECTED');
    expect(jobs).to.have.length(0);
    await client.connect();
    expect(await prepared.read()).to.deep.equal(expected);
  });
});

describe('prepared reads (client.prepare) on freeport, in-process (@serialport/binding-mock)', () => {
  const PATH = '/dev/ttyPREPARED';
  let bus: FreeportBus;
  let client: FreeportClient;
  let requests: FreeportRequest[];

  beforeEach(() => {
    MockBinding.reset();
    MockBinding.createPort(PATH, { echo: false, record: true });
    bus = new FreeportBus({
      stations: {
        5: Buffer.from([0x41, 0x20, 0x00, 0x00]), // REAL 10.0
        6: Buffer.from([0x12, 0x34, 0x56, 0x78]),
      },
    });
    requests = [];
    bus.on('request', (r: FreeportRequest) => requests.push(r));
    const endpoint: FreeportEndpoint = {
      protocol: 'freeport',
      transport: { kind: 'serial', path: PATH, baudRate: 9600, parity: 'none', dataBits: 8, stopBits: 1 },
      timeout: 100,
      retries: 1,
      interFrameGapMs: 0,
    };
    client = new FreeportClient(endpoint, {
      binding: bus.mockBinding(MockBinding),
      backoff: { initialDelay: 10, maxDelay: 50, jitter: 0 },
    });
  });

  afterEach(async () => {
    await client.close();
    await bus.close();
    MockBinding.reset();
  });

  const list = ['ST6,DWORD0', 'ST6,X0.4', 'ST5,REAL0', 'ST6,INT2'];
  const expected = { 'ST6,DWORD0': 0x12345678, 'ST6,X0.4': true, 'ST5,REAL0': 10, 'ST6,INT2': 0x5678 };

  it('reads each station once a poll for 50 reads, and reads what read() reads', async () => {
    await client.connect();
    const prepared = client.prepare(list);
    for (let i = 0; i < 50; i++) expect(await prepared.read()).to.deep.equal(expected);
    expect(requests).to.have.length(100);
    expect(requests.every((r) => r.command === 'read')).to.equal(true);
    expect(await client.read(list)).to.deep.equal(expected);
    expect(await prepared.readDetailed()).to.deep.equal(await client.readDetailed(list));
  });

  it('throws INVALID_ADDRESS at prepare() for an address past the station data area', () => {
    const err = thrown(() => client.prepare(['ST5,REAL0', 'ST5,DWORD2']));
    expect(err.code).to.equal('INVALID_ADDRESS');
    expect(err.tag).to.equal('ST5,DWORD2');
  });

  it('fails fast with NOT_CONNECTED while not connected and after the client closed', async () => {
    const prepared = client.prepare(list);
    expect((await failure(prepared.read())).code).to.equal('NOT_CONNECTED');
    await client.connect();
    expect(await prepared.read()).to.deep.equal(expected);
    await client.close();
    expect((await failure(prepared.read())).code).to.equal('NOT_CONNECTED');
    expect(requests).to.have.length(2);
  });
});
