/**
 * Stale layout detection (lib/symbols/layout-check.ts): the client compares
 * the length of each DB of its symbol table with the PLC's block info on
 * each connect and on checkLayout(), reports it in events, and with
 * strictSymbols refuses names in a block that does not match.
 */
import { expect } from 'chai';
import { PlcError, TagErrors } from '../lib/errors';
import { FetchWriteClient } from '../lib/fetchwrite/client';
import { FetchWriteServer } from '../lib/fetchwrite/server';
import { S7Client } from '../lib/s7/client';
import { S7Server, type S7RequestEvent } from '../lib/s7/server';
import type { LayoutMismatchEvent, LayoutOkEvent, LayoutUnknownEvent } from '../lib/types';
import { parseUrl, type FetchWriteEndpoint, type S7Endpoint } from '../lib/url';
import { symbolTable, type Block } from './support/symbol-table';
import { settle, until, waitFor } from './support/wait';

const FAST = { backoff: { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 } };

const TANK: Block = {
  name: 'Tank',
  db: 1,
  length: 20,
  members: [
    { name: 'Level', type: 'REAL', byte: 0 },
    { name: 'Count', type: 'INT', byte: 4 },
  ],
};
const RECIPE: Block = { name: 'Recipe', db: 2, length: 8, members: [{ name: 'Mode', type: 'INT', byte: 4 }] };
const TABLE = symbolTable([TANK, RECIPE]);

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
  for (const name of ['layoutMismatch', 'layoutUnknown', 'layoutOk']) client.on(name, (event: unknown) => seen.push({ name, event }));
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
    server = new S7Server({ port: 0, profile: 's7-300', layout: { dbs: { 1: 20, 2: 8, 3: 16 } } });
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
      { block: 'Tank', db: 1, declared: 20, actual: 20, status: 'ok' },
      { block: 'Recipe', db: 2, declared: 8, actual: 8, status: 'ok' },
    ]);
    expect(seen.map((s) => s.name)).to.deep.equal(['layoutOk']);
  });

  it('a block of another length: layoutMismatch; without strictSymbols the names still read', async () => {
    server.memory.createDataBlock(1, 24);
    server.memory.area('DB', 1)!.writeFloatBE(12.5, 0);
    client = open();
    const mismatch = waitFor<LayoutMismatchEvent>(client, 'layoutMismatch');
    await client.connect();
    expect(await mismatch).to.deep.equal({ block: 'Tank', db: 1, declared: 20, actual: 24 });
    expect(await client.read(['"Tank".Level'])).to.deep.equal({ '"Tank".Level': 12.5 });
  });

  it('strictSymbols: names in a block that does not match fail with LAYOUT_MISMATCH; its addresses and other blocks stay allowed', async () => {
    server.memory.createDataBlock(1, 24);
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
      '"Tank".Level: DB1 "Tank": the PLC\'s block is 24 bytes, the sources declare 20; recompile the sources or download the block',
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
    server.memory.createDataBlock(1, 22);
    // Still the connection the check found in order: nothing refused until checked again.
    expect((await client.readDetailed(['"Tank".Level']))['"Tank".Level']!.ok).to.equal(true);
    const checks = await client.checkLayout();
    expect(checks[0]).to.deep.equal({ block: 'Tank', db: 1, declared: 20, actual: 22, status: 'mismatch' });
    await client.checkLayout();
    expect(seen.map((s) => s.name)).to.deep.equal(['layoutOk', 'layoutMismatch']);
    const again = waitFor<LayoutMismatchEvent>(client, 'layoutMismatch');
    server.faults.dropConnections();
    expect(await again).to.deep.equal({ block: 'Tank', db: 1, declared: 20, actual: 22 });
    expect((await client.readDetailed(['"Tank".Level']))['"Tank".Level']!.ok).to.equal(false);
    server.memory.createDataBlock(1, 20);
    const ok = waitFor<LayoutOkEvent>(client, 'layoutOk');
    await client.checkLayout();
    await ok;
    expect((await client.readDetailed(['"Tank".Level']))['"Tank".Level']).to.deep.equal({ ok: true, value: 0 });
    expect(seen.map((s) => s.name)).to.deep.equal(['layoutOk', 'layoutMismatch', 'layoutMismatch', 'layoutOk']);
  });

  it('a CPU without block functions (S7-1500 over PUT/GET): layoutUnknown once, nothing refused even with strictSymbols', async () => {
    await server.close();
    server = new S7Server({ port: 0, profile: 's7-1500', layout: { dbs: { 1: 24, 2: 8 } } });
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

describe('layout check over FETCH/WRITE', function () {
  this.timeout(10000);
  it('FETCH/WRITE cannot tell block lengths: layoutUnknown, and strictSymbols refuses nothing', async () => {
    const server = new FetchWriteServer({ port: 0, layout: { dataBlocks: { 1: 20, 2: 8 } } });
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
      expect(event.error.message).to.contain('the protocol has no service that tells the length of a data block');
      server.memory.area('DB', 2)!.writeInt16BE(4, 4);
      expect(await client.read(['"Recipe".Mode'])).to.deep.equal({ '"Recipe".Mode': 4 });
    } finally {
      await client.close();
      await server.close();
    }
  });
});
