/**
 * Stale layout detection (lib/symbols/layout-check.ts): the client compares
 * the length of each DB of its symbol table with the PLC's block info on
 * each connect and on checkLayout(), reports it in events, and with
 * strictSymbols refuses names in a block that does not match.
 */
import { expect } from 'chai';
import * as net from 'node:net';
import { PlcError, TagErrors } from '../lib/errors';
import { FetchWriteClient } from '../lib/fetchwrite/client';
import { FetchWriteServer } from '../lib/fetchwrite/server';
import { S7Client } from '../lib/s7/client';
import { S7Server, type S7RequestEvent } from '../lib/s7/server';
import type { LayoutMismatchEvent, LayoutOkEvent, LayoutUnknownEvent } from '../lib/types';
import { parseUrl, type FetchWriteEndpoint, type S7Endpoint } from '../lib/url';
import { compileClientSources } from './support/symbol-sources';
import { SNAP7 } from './fixtures/s7-userdata';
import { settle, until, waitFor } from './support/wait';

const FAST = { backoff: { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 } };

/** DB1 "Tank" (40 bytes) and DB2 "Recipe" (8 bytes), compiled from test/fixtures/symbols/client/. */
const TABLE = compileClientSources('Motor.udt', 'Step.udt', 'Tank.db', 'Recipe.awl', 'Symbols.asc');

async function failure(p: Promise<unknown>): Promise<PlcError> {
  const outcome = await p.then(
    () => undefined,
    (e: unknown) => e,
  );
  if (!(outcome instanceof PlcError)) throw new Error(`expected a PlcError, got ${String(outcome)}`);
  return outcome;
}

/** Every layout event of a client, in order. */
function record(client: S7Client | FetchWriteClient): { name: string; event: unknown }[] {
  const seen: { name: string; event: unknown }[] = [];
  for (const name of ['layoutMismatch', 'layoutUnknown', 'layoutOk'] as const)
    client.on(name, (event: unknown) => seen.push({ name, event }));
  return seen;
}

describe('layout check of the symbol table against the S7 simulator', function () {
  this.timeout(10000);
  let server: S7Server;
  let client: S7Client | undefined;

  const open = (query = '', profile: 's7-300' | 's7-1500' = 's7-300') => {
    const slot = profile === 's7-300' ? 2 : 1;
    return new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?rack=0&slot=${slot}&timeout=1500${query}`) as S7Endpoint, {
      ...FAST,
      symbols: TABLE,
    });
  };

  beforeEach(async () => {
    // The blocks of the sources, and DB3 the sources do not declare.
    server = new S7Server({ port: 0, profile: 's7-300', symbols: TABLE });
    server.memory.createDataBlock(3, 16);
    await server.listen();
    server.memory.area('DB', 1)!.writeFloatBE(12.5, 0);
    server.memory.area('DB', 1)!.writeInt16BE(3, 4);
  });

  afterEach(async () => {
    await client?.close();
    client = undefined;
    await server.close();
  });

  it('a PLC whose blocks match the sources: layoutOk once per connect, checkLayout() says ok for each', async () => {
    client = open();
    const seen = record(client);
    const ok = waitFor<LayoutOkEvent>(client, 'layoutOk');
    await client.connect();
    expect((await ok).checks.map((c) => [c.block, c.status])).to.deep.equal([
      ['Tank', 'ok'],
      ['Recipe', 'ok'],
    ]);
    const checks = await client.checkLayout();
    expect(checks).to.deep.equal([
      { block: 'Tank', db: 1, declared: 40, actual: 40, status: 'ok' },
      { block: 'Recipe', db: 2, declared: 8, actual: 8, status: 'ok' },
    ]);
    expect(seen.map((s) => s.name)).to.deep.equal(['layoutOk']);
  });

  it('a block of another length: layoutMismatch; without strictSymbols the names still read', async () => {
    server.memory.createDataBlock(1, 44);
    server.memory.area('DB', 1)!.writeFloatBE(12.5, 0);
    client = open();
    const mismatch = waitFor<LayoutMismatchEvent>(client, 'layoutMismatch');
    await client.connect();
    expect(await mismatch).to.deep.equal({ block: 'Tank', db: 1, declared: 40, actual: 44 });
    expect(await client.read(['"Tank".Level'])).to.deep.equal({ '"Tank".Level': 12.5 });
  });

  it('strictSymbols: names in a block that does not match fail with LAYOUT_MISMATCH; its addresses and other blocks stay allowed', async () => {
    server.memory.createDataBlock(1, 44);
    client = open('&strictSymbols=true');
    await client.connect();
    // No wait for the event: a read by name waits for the check under way.
    const results = await client.readDetailed(['"Tank".Level', 'DB1.DBW4', '"Recipe".Mode']);
    const level = results['"Tank".Level']!;
    expect(level.ok).to.equal(false);
    if (level.ok) return;
    expect(level.error.code).to.equal('LAYOUT_MISMATCH');
    expect(level.error.tag).to.equal('"Tank".Level');
    expect(level.error.message).to.equal(
      '"Tank".Level: DB1 "Tank": the PLC\'s block is 44 bytes, the sources declare 40; recompile the sources or download the block',
    );
    expect(results['DB1.DBW4']).to.deep.equal({ ok: true, value: 0 });
    expect(results['"Recipe".Mode']).to.deep.equal({ ok: true, value: 0 });
    const err = await failure(client.read(['"Tank".Count']));
    expect(err).to.be.instanceOf(TagErrors);
    expect((err as TagErrors).errors['"Tank".Count']!.code).to.equal('LAYOUT_MISMATCH');
    const poll = client.prepare(['"Tank".Count', '"Recipe".Mode']);
    expect((await poll.readDetailed())['"Tank".Count']!.ok).to.equal(false);
    const writes = await client.writeDetailed({ '"Tank".Count': 1, 'DB1.DBW4': 2, '"Recipe".Mode': 3 });
    expect(!writes['"Tank".Count']!.ok && writes['"Tank".Count']!.error.code).to.equal('LAYOUT_MISMATCH');
    expect([writes['DB1.DBW4']!.ok, writes['"Recipe".Mode']!.ok]).to.deep.equal([true, true]);
    expect(server.memory.area('DB', 1)!.readInt16BE(4)).to.equal(2);
  });

  it('a DB the PLC does not have is a mismatch with actual null', async () => {
    server.memory.deleteDataBlock(2);
    client = open('&strictSymbols=true');
    const mismatch = waitFor<LayoutMismatchEvent>(client, 'layoutMismatch');
    await client.connect();
    expect(await mismatch).to.deep.equal({ block: 'Recipe', db: 2, declared: 8, actual: null });
    const r = (await client.readDetailed(['"Recipe".Mode']))['"Recipe".Mode']!;
    expect(!r.ok && r.error.message).to.contain('DB2 "Recipe": the PLC has no DB2, the sources declare it with 8 bytes');
  });

  it('reports a mismatch once per connection; a reconnect checks again, and checkLayout() sees the block fixed', async () => {
    client = open('&strictSymbols=true');
    const seen = record(client);
    await client.connect();
    await until(() => seen.length === 1, 3000, 'layoutOk');
    server.memory.createDataBlock(1, 42);
    // Still the connection the check found in order: nothing refused until checked again.
    expect((await client.readDetailed(['"Tank".Level']))['"Tank".Level']!.ok).to.equal(true);
    const checks = await client.checkLayout();
    expect(checks[0]).to.deep.equal({ block: 'Tank', db: 1, declared: 40, actual: 42, status: 'mismatch' });
    await client.checkLayout();
    expect(seen.map((s) => s.name)).to.deep.equal(['layoutOk', 'layoutMismatch']);
    const again = waitFor<LayoutMismatchEvent>(client, 'layoutMismatch');
    server.faults.dropConnections();
    expect(await again).to.deep.equal({ block: 'Tank', db: 1, declared: 40, actual: 42 });
    expect((await client.readDetailed(['"Tank".Level']))['"Tank".Level']!.ok).to.equal(false);
    server.memory.createDataBlock(1, 40);
    const ok = waitFor<LayoutOkEvent>(client, 'layoutOk');
    await client.checkLayout();
    await ok;
    expect((await client.readDetailed(['"Tank".Level']))['"Tank".Level']).to.deep.equal({ ok: true, value: 0 });
    expect(seen.map((s) => s.name)).to.deep.equal(['layoutOk', 'layoutMismatch', 'layoutMismatch', 'layoutOk']);
  });

  it('a CPU without block functions (S7-1500 over PUT/GET): layoutUnknown once, nothing refused even with strictSymbols', async () => {
    await server.close();
    server = new S7Server({ port: 0, profile: 's7-1500', symbols: TABLE });
    server.memory.createDataBlock(1, 44);
    await server.listen();
    const userdata: S7RequestEvent[] = [];
    server.on('request', (r: S7RequestEvent) => r.kind === 'userdata' && userdata.push(r));
    client = open('&strictSymbols=true', 's7-1500');
    const seen = record(client);
    const unknown = waitFor<LayoutUnknownEvent>(client, 'layoutUnknown');
    await client.connect();
    const event = await unknown;
    expect(event.error.code).to.equal('NOT_SUPPORTED');
    expect(event.checks.map((c) => [c.db, c.status, c.actual])).to.deep.equal([
      [1, 'unknown', undefined],
      [2, 'unknown', undefined],
    ]);
    expect((await client.readDetailed(['"Tank".Level']))['"Tank".Level']!.ok).to.equal(true);
    const checks = await client.checkLayout();
    expect(checks.every((c) => c.status === 'unknown' && c.error?.code === 'NOT_SUPPORTED')).to.equal(true);
    expect(seen.map((s) => s.name)).to.deep.equal(['layoutUnknown']);
  });

  it('close() during the check leaves no connection and reports nothing', async () => {
    server.faults.latencyMs = 150;
    client = open('&strictSymbols=true');
    const seen = record(client);
    const requests: S7RequestEvent[] = [];
    server.on('request', (r: S7RequestEvent) => requests.push(r));
    await client.connect();
    await until(() => requests.some((r) => r.kind === 'userdata'), 2000, 'a block info request');
    const waiting = client.readDetailed(['"Tank".Level']);
    await client.close();
    expect((await failure(waiting)).code).to.match(/CLOSED|NOT_CONNECTED/);
    await until(() => server.connectionCount === 0, 2000, 'no connection left');
    // The check's requests failed with CLOSED when the client closed: what they would report is settled by now.
    await settle();
    expect(seen).to.deep.equal([]);
  });

  it('checkLayout() right after connect shares the check the connect started: the PLC is asked once, not twice', async () => {
    server.faults.latencyMs = 50;
    const userdata: S7RequestEvent[] = [];
    server.on('request', (r: S7RequestEvent) => r.kind === 'userdata' && userdata.push(r));
    client = open();
    await client.connect();
    const shared = await client.checkLayout();
    const once = userdata.length;
    expect(once, 'the block list and a block info per DB').to.be.greaterThan(1);
    // No check under way now: this one asks the PLC again, exactly as many requests as one check takes.
    expect(await client.checkLayout()).to.deep.equal(shared);
    expect(userdata.length).to.equal(2 * once);
  });

  it('an aborted checkLayout() rejects ABORTED; a read by name that waits for a check can be aborted too', async () => {
    server.faults.latencyMs = 150;
    client = open('&strictSymbols=true');
    await client.connect();
    const controller = new AbortController();
    const check = client.checkLayout({ signal: controller.signal });
    const read = client.read(['"Tank".Level'], { signal: controller.signal });
    controller.abort();
    expect((await failure(check)).code).to.equal('ABORTED');
    expect((await failure(read)).code).to.equal('ABORTED');
    await client.close();
    await until(() => server.connectionCount === 0, 2000, 'no connection left');
  });

  it('checkLayout() without a link rejects NOT_CONNECTED; without a symbol table it resolves []', async () => {
    client = open();
    expect((await failure(client.checkLayout())).code).to.equal('NOT_CONNECTED');
    const plain = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?rack=0&slot=2`) as S7Endpoint);
    try {
      await plain.connect();
      expect(await plain.checkLayout()).to.deep.equal([]);
    } finally {
      await plain.close();
    }
  });
});

/**
 * A TCP proxy in front of `port` that answers the block info request of DB
 * `db` itself with `answer` (its PDU reference set to the request's) and
 * forwards everything else; `asked` counts those requests.
 */
async function blockInfoProxy(
  port: number,
  db: number,
  answer: Buffer,
): Promise<{ port: number; asked: () => number; close: () => Promise<void> }> {
  const request = Buffer.from(`0A${String(db).padStart(5, '0')}A`, 'latin1');
  const sockets = new Set<net.Socket>();
  let asked = 0;
  const proxy = net.createServer((client) => {
    const plc = net.connect(port, '127.0.0.1');
    for (const s of [client, plc]) {
      sockets.add(s);
      s.on('error', () => undefined);
      s.on('close', () => (client.destroy(), plc.destroy()));
    }
    plc.on('data', (chunk) => client.write(chunk));
    let pending = Buffer.alloc(0);
    client.on('data', (chunk) => {
      pending = Buffer.concat([pending, chunk]);
      while (pending.length >= 4 && pending.length >= pending.readUInt16BE(2)) {
        const frame = pending.subarray(0, pending.readUInt16BE(2));
        pending = pending.subarray(frame.length);
        // A userdata (ROSCTR 7) request whose data is '0' 'A' (DB), the block number in 5 digits, 'A'.
        if (frame[8] === 0x07 && frame.subarray(frame.length - 8).equals(request)) {
          asked++;
          const reply = Buffer.from(answer);
          frame.copy(reply, 11, 11, 13);
          client.write(reply);
        } else plc.write(frame);
      }
    });
  });
  await new Promise<void>((resolve) => proxy.listen(0, '127.0.0.1', resolve));
  return {
    port: (proxy.address() as net.AddressInfo).port,
    asked: () => asked,
    close: async () => {
      for (const s of sockets) s.destroy();
      await new Promise((resolve) => proxy.close(resolve));
    },
  };
}

describe("layout check against snap7's answer to block info of a DB it does not have", function () {
  this.timeout(10000);
  let server: S7Server;
  let proxy: Awaited<ReturnType<typeof blockInfoProxy>>;
  let client: S7Client;
  // DB 2 is listed (so the check asks for it), and its block info is answered as snap7 answers a DB it does not have.
  const connect = async (answer: Buffer) => {
    server = new S7Server({ port: 0, profile: 's7-300', symbols: TABLE });
    await server.listen();
    proxy = await blockInfoProxy(server.port, 2, answer);
    client = new S7Client(parseUrl(`s7://127.0.0.1:${proxy.port}?rack=0&slot=2&timeout=1500&strictSymbols=true`) as S7Endpoint, {
      ...FAST,
      symbols: TABLE,
    });
  };

  afterEach(async () => {
    await client.close();
    await proxy.close();
    await server.close();
  });

  it("snap7's frame (78 bytes beyond its S7 lengths) drops the link with PROTOCOL_ERROR once; the block is then unknown and not asked again", async () => {
    await connect(SNAP7.blockInfoMissingAfterAnswer);
    const seen = record(client);
    const dropped = waitFor<PlcError>(client, 'disconnected');
    await client.connect();
    const err = await dropped;
    expect(err.code).to.equal('PROTOCOL_ERROR');
    expect(err.message).to.contain('S7 lengths (header 10 + parameters 12 + data 4) do not match the PDU (104)');
    await waitFor(client, 'connected');
    // One layoutUnknown per connection: the one the frame dropped, and the next, which does not ask for the block again.
    await until(() => seen.length === 2, 3000, 'layoutUnknown on both connections');
    for (const { name, event } of seen) {
      expect(name).to.equal('layoutUnknown');
      expect((event as LayoutUnknownEvent).checks.map((c) => [c.db, c.status, c.error?.code])).to.deep.equal([
        [2, 'unknown', 'PROTOCOL_ERROR'],
      ]);
    }
    expect(proxy.asked()).to.equal(1);
    expect(await client.read(['"Recipe".Mode', '"Tank".Level'])).to.deep.equal({ '"Recipe".Mode': 0, '"Tank".Level': 0 });
    expect((await client.checkLayout()).map((c) => [c.db, c.status])).to.deep.equal([
      [1, 'ok'],
      [2, 'unknown'],
    ]);
    expect(proxy.asked()).to.equal(1);
  });

  it('the same error answer framed as its S7 header says reads as no such block: a mismatch with actual null, the link stays up', async () => {
    await connect(SNAP7.blockInfoMissingWellFormed);
    const disconnects: unknown[] = [];
    client.on('disconnected', (e: unknown) => disconnects.push(e));
    const mismatch = waitFor<LayoutMismatchEvent>(client, 'layoutMismatch');
    await client.connect();
    expect(await mismatch).to.deep.equal({ block: 'Recipe', db: 2, declared: 8, actual: null });
    expect([client.state, disconnects.length, proxy.asked()]).to.deep.equal(['connected', 0, 1]);
  });
});

describe('layout check over FETCH/WRITE', function () {
  this.timeout(10000);
  it('FETCH/WRITE cannot tell block lengths: layoutUnknown, and strictSymbols refuses nothing', async () => {
    const server = new FetchWriteServer({ port: 0, symbols: TABLE });
    const { fetchPort } = await server.listen();
    const client = new FetchWriteClient(
      parseUrl(`fetchwrite://127.0.0.1?port=${fetchPort}&timeout=1500&strictSymbols=true`) as FetchWriteEndpoint,
      { ...FAST, symbols: TABLE },
    );
    try {
      const unknown = waitFor<LayoutUnknownEvent>(client, 'layoutUnknown');
      await client.connect();
      const event = await unknown;
      expect(event.error.code).to.equal('NOT_SUPPORTED');
      expect(event.error.message).to.equal(
        `${client.name}: FETCH/WRITE has no service that tells the length of a data block, so the symbols' layout cannot be ` +
          'checked against the PLC: names are read and written at the offsets of the sources, unchecked (strictSymbols refuses nothing)',
      );
      expect(client.name).to.contain(String(fetchPort));
      expect(event.checks.map((c) => [c.block, c.status, c.error?.message])).to.deep.equal([
        ['Tank', 'unknown', event.error.message],
        ['Recipe', 'unknown', event.error.message],
      ]);
      server.memory.area('DB', 2)!.writeInt16BE(4, 4);
      expect(await client.read(['"Recipe".Mode'])).to.deep.equal({ '"Recipe".Mode': 4 });
    } finally {
      await client.close();
      await server.close();
    }
  });
});
