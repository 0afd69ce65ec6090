/**
 * client.subscribe() over s7plus:// against our simulator (issue #25): the
 * PLC pushes changes of names (optimized and standard, a struct as an object)
 * and addresses on a session of their own; credits are renewed so
 * notifications never stop; an unknown name is refused naming it; a reset
 * link or a restarted PLC is subscribed again and its first notification
 * carries every value; close() leaves no socket and no timer.
 */
import { expect } from 'chai';
import * as net from 'node:net';
import { createClient } from '../lib/connect';
import { PlcError, TagErrors } from '../lib/errors';
import type { S7PlusClient, S7PlusSubscription, SubscriptionChange, SubscriptionData } from '../lib';
import { S7Server } from '../lib/s7/server';
import { S7PlusService } from '../lib/s7plus/server';
import { generateCertificate } from '../lib/s7plus/transport/cert';
import { encodeCreditRequest, encodeSubscriptionDeleteRequest, subscriptionCreditRequest } from '../lib/s7plus/codec/subscription';
import { FunctionCode, TransportFlags } from '../lib/s7plus/constants';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { settle, until, waitFor } from './support/wait';

/** Our sockets to `port` still open. */
function socketsTo(port: number): number {
  const handles = (process as unknown as { _getActiveHandles(): unknown[] })._getActiveHandles();
  return handles.filter((h) => h instanceof net.Socket && !h.destroyed && h.remotePort === port).length;
}

/** Timers of this process still pending (a subscription must leave none). */
function timers(): number {
  const handles = (process as unknown as { _getActiveHandles(): unknown[] })._getActiveHandles();
  return handles.filter((h) => (h as { constructor?: { name?: string } })?.constructor?.name === 'Timeout').length;
}

/** The next `data` event whose results satisfy `match`, within `ms`. */
function dataWhere(sub: S7PlusSubscription, match: (d: SubscriptionData) => boolean, ms = 5000): Promise<SubscriptionData> {
  return waitFor<SubscriptionData>(sub, 'data', ms, (d: SubscriptionData) => match(d));
}

const valueOf = (d: SubscriptionData, tag: string): unknown => {
  const r = d.results[tag];
  return r?.ok ? r.value : undefined;
};

describe('S7CommPlus subscription requests (codec)', () => {
  // Payloads (after the 14-byte request header) as s7commplus 0.3.0 (MIT) builds them: connection.py
  // _build_set_variable_payload(0x70000001, SUBSCRIPTION_CREDIT_LIMIT, Int 15) and subscription.py
  // build_delete_subscription_request(0x12345, V2 / V1), printed by the package in our venv.
  const head = { sequence: 1, sessionId: 0x10, transportFlags: TransportFlags.Normal, functionCode: FunctionCode.DeleteObject };
  it('the credit update is a SetVariable of attribute 1053 with transport flags 0x74, byte for byte as s7commplus sends it', () => {
    const frame = encodeCreditRequest(subscriptionCreditRequest(1, 0x10, { subscriptionId: 0x70000001, creditLimit: 15 }));
    expect(frame.readUInt16BE(3)).to.equal(FunctionCode.SetVariable);
    expect(frame[13]).to.equal(0x74);
    expect(frame.subarray(14).toString('hex')).to.equal('7000000101881d0007000f000004e88969001200000000896a001300896b000400000000000000');
    expect(() => encodeCreditRequest(subscriptionCreditRequest(1, 0x10, { subscriptionId: 1, creditLimit: 0 }))).to.throw(RangeError);
  });
  it('the DeleteObject of the subscription container, V2 and V1, byte for byte as s7commplus sends it', () => {
    expect(
      encodeSubscriptionDeleteRequest({ header: head, body: { objectId: 0x12345 } })
        .subarray(14)
        .toString('hex'),
    ).to.equal('0001234500000004e88969001200000000896a001300896b0004000000000000');
    expect(
      encodeSubscriptionDeleteRequest({ header: head, body: { objectId: 0x12345, v1: true } })
        .subarray(14)
        .toString('hex'),
    ).to.equal('0001234500000004e88969001200000000896a001300896b00040000000000000000');
  });
});

describe('S7CommPlus subscriptions (our client, our simulator)', function () {
  this.timeout(30000);
  let server: S7Server;
  let service: S7PlusService;
  let client: S7PlusClient;
  let writer: S7PlusClient;
  let url: string;

  const start = async (port = 0) => {
    server = new S7Server({ port, profile: 's7-1500', s7plus: service });
    await server.listen();
  };

  before(async () => {
    const cert = await generateCertificate();
    service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
    await start();
    url = `s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=5000`;
  });
  beforeEach(async () => {
    client = createClient(url, { backoff: { initialDelay: 50, maxDelay: 200 } }) as S7PlusClient;
    writer = createClient(url) as S7PlusClient;
    await client.connect();
    await writer.connect();
  });
  afterEach(async () => {
    await client?.close();
    await writer?.close();
  });
  after(async () => {
    await server?.close();
  });

  it('delivers every value first, then a change written through a second client, on a session of its own', async () => {
    await writer.write({ '"Recipe".Step': 3, '"Tank".Count': 7 });
    const before = server.connectionCount;
    const tags = ['"Recipe".Step', '"Tank".Count', 'DB1.DBW4', '"Recipe".Inlet'];
    const changes: SubscriptionChange[] = [];
    const sub = await client.subscribe(tags, { cycle: 20 }, (c) => changes.push(c));
    expect(sub.state).to.equal('active');
    // Its own session: one connection more than the client's and the writer's.
    expect(server.connectionCount).to.equal(before + 1);
    const first = await dataWhere(sub, (d) => d.initial);
    expect(Object.keys(first.results)).to.have.members(tags);
    expect(valueOf(first, '"Recipe".Step')).to.equal(3);
    expect(valueOf(first, '"Tank".Count')).to.equal(7);
    expect(valueOf(first, 'DB1.DBW4')).to.equal(7);
    expect(valueOf(first, '"Recipe".Inlet')).to.have.keys('Open', 'Position');
    expect(changes.map((c) => c.tag)).to.have.members(tags);

    const changed = dataWhere(sub, (d) => valueOf(d, '"Recipe".Step') === 42);
    await writer.write({ '"Recipe".Step': 42, '"Recipe".Inlet': { Open: true, Position: 5 } });
    const next = await changed;
    expect(next.initial).to.equal(false);
    expect(next.changed).to.include('"Recipe".Step');
    expect(next.changed).to.not.include('"Tank".Count');
    await until(() =>
      changes.some((c) => c.tag === '"Recipe".Inlet' && c.result.ok && (c.result.value as unknown as { Open: boolean }).Open),
    );
    const inlet = changes.filter((c) => c.tag === '"Recipe".Inlet').pop()!;
    expect(inlet.result).to.deep.equal({ ok: true, value: { Open: true, Position: 5 } });
    expect(inlet.previous?.ok).to.equal(true);
    // The client's own session writes and reads as before.
    await client.write({ '"Tank".Count': 8 });
    await dataWhere(sub, (d) => valueOf(d, 'DB1.DBW4') === 8);
    await sub.close();
    expect(sub.state).to.equal('closed');
  });

  it('renews credits: 40 changes in a row all arrive (the PLC grants 10 at creation)', async () => {
    await writer.write({ '"Recipe".Step': 0 });
    const sub = await client.subscribe(['"Recipe".Step'], { cycle: 10 });
    await dataWhere(sub, (d) => d.initial);
    for (let i = 1; i <= 40; i++) {
      const seen = dataWhere(sub, (d) => valueOf(d, '"Recipe".Step') === i);
      await writer.write({ '"Recipe".Step': i });
      await seen;
    }
    expect(sub.latest['"Recipe".Step']).to.deep.equal({ ok: true, value: 40 });
  });

  it('refuses a name the PLC does not have with TagErrors naming it, and subscribes nothing', async () => {
    const before = server.connectionCount;
    const err = await client.subscribe(['"Recipe".Step', '"Recipe".Stepp']).catch((e: unknown) => e);
    expect(err).to.be.instanceOf(TagErrors);
    expect((err as TagErrors).errors).to.have.keys('"Recipe".Stepp');
    expect((err as TagErrors).errors['"Recipe".Stepp']).to.include({ code: 'INVALID_ADDRESS', tag: '"Recipe".Stepp' });
    expect((err as Error).message).to.match(/"Recipe"\.Stepp.*did you mean "Recipe"\.Step/);
    // Its session is gone again.
    await until(() => server.connectionCount === before, 5000, 'the subscription session closed');
    const addressErr = await client.subscribe(['DB1.DBX99999.9.9']).catch((e: unknown) => e);
    expect(addressErr).to.be.instanceOf(TagErrors);
    const cycleErr = await client.subscribe(['"Recipe".Step'], { cycle: 1 }).catch((e: unknown) => e);
    expect(cycleErr).to.be.instanceOf(PlcError).and.include({ code: 'INVALID_VALUE' });
    expect((cycleErr as Error).message).to.equal('subscribe(): cycle is 1 ms; give whole ms from 10 to 3600000');
  });

  it("cycle: '100' (a string, as a form gives it) is refused as a string, not as if 100 were out of range", async () => {
    const err = await client.subscribe(['"Recipe".Step'], { cycle: '100' as unknown as number }).catch((e: unknown) => e);
    expect(err).to.be.instanceOf(PlcError).and.include({ code: 'INVALID_VALUE' });
    expect((err as Error).message).to.equal('subscribe(): cycle must be a number (whole ms from 10 to 3600000), not the string "100"');
  });

  it("an item the PLC does not report is that tag's error (NOT_SUPPORTED), the others flow", async () => {
    const sub = await client.subscribe(['"Recipe".Step', 'DB99.DBW0'], { cycle: 20 });
    const first = await dataWhere(sub, (d) => d.initial);
    expect(first.results['DB99.DBW0']).to.have.property('ok', false);
    expect((first.results['DB99.DBW0'] as { error: PlcError }).error).to.include({ code: 'NOT_SUPPORTED', tag: 'DB99.DBW0' });
    expect(first.results['"Recipe".Step']!.ok).to.equal(true);
  });

  it('a reset link is subscribed again: lost, then active, and the first notification after it carries every value', async () => {
    await writer.write({ '"Recipe".Step': 5 });
    const sub = await client.subscribe(['"Recipe".Step', '"Tank".Count'], { cycle: 20 });
    await dataWhere(sub, (d) => d.initial);
    const states: string[] = [];
    sub.on('state', (s: string) => states.push(s));
    const lost = waitFor(sub, 'lost', 5000);
    const again = dataWhere(sub, (d) => d.initial, 10000);
    const writerBack = waitFor(writer, 'connected', 10000);
    server.dropConnections();
    expect(await lost).to.be.instanceOf(PlcError);
    const first = await again;
    expect(Object.keys(first.results)).to.have.members(['"Recipe".Step', '"Tank".Count']);
    expect(first.results['"Recipe".Step']).to.deep.equal({ ok: true, value: 5 });
    expect(states).to.deep.equal(['lost', 'active']);
    await writerBack;
    const changed = dataWhere(sub, (d) => valueOf(d, '"Recipe".Step') === 6);
    await writer.write({ '"Recipe".Step': 6 });
    await changed;
  });

  it('a restarted PLC is subscribed again once it listens', async () => {
    const sub = await client.subscribe(['"Recipe".Step'], { cycle: 20 });
    await dataWhere(sub, (d) => d.initial);
    const port = server.port;
    const lost = waitFor(sub, 'lost', 5000);
    const active = waitFor(sub, 'active', 10000);
    const again = dataWhere(sub, (d) => d.initial, 10000);
    await server.close();
    await lost;
    await start(port);
    await active;
    const first = await again;
    expect(first.results['"Recipe".Step']!.ok).to.equal(true);
  });

  it('closing one subscription keeps the other one going; closing the client closes it and leaves no socket or timer', async () => {
    await settle();
    const timersBefore = timers();
    const a = await client.subscribe(['"Recipe".Step'], { cycle: 20 });
    const b = await client.subscribe(['"Tank".Count'], { cycle: 20 });
    await dataWhere(b, (d) => d.initial);
    await a.close();
    expect(a.state).to.equal('closed');
    const seen = dataWhere(b, (d) => valueOf(d, '"Tank".Count') === 99);
    await writer.write({ '"Tank".Count': 99 });
    await seen;
    const closed = waitFor(b, 'closed', 5000);
    await client.close();
    await closed;
    expect(b.state).to.equal('closed');
    await writer.close();
    await settle();
    expect(socketsTo(server.port)).to.equal(0);
    expect(timers()).to.be.at.most(timersBefore);
    const late = await client.subscribe(['"Recipe".Step']).catch((e: unknown) => e);
    expect(late).to.be.instanceOf(PlcError).and.include({ code: 'NOT_CONNECTED' });
  });
});
