import { expect } from 'chai';
import type { AlarmDefinition, AlarmEvent, AlarmSubscription } from '../lib/alarms/model';
import { PlcError } from '../lib/errors';
import { S7Client } from '../lib/s7/client';
import { S7Server, type S7Profile } from '../lib/s7/server';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { until, waitFor } from './support/wait';

const DEFINITIONS: AlarmDefinition[] = [
  {
    id: 0x101,
    kind: 'ALARM_SQ',
    texts: { 'en-US': 'Tank high @1%d@' },
    needsAck: true,
    trigger: 'M10.0',
    values: ['MW20:INT', 'MD24:REAL'],
  },
  { id: 0x102, kind: 'ALARM_S', texts: { 'en-US': 'Pump running' }, needsAck: false, trigger: 'DB1.DBX0.1' },
  { id: 0x200, kind: 'ALARM_8', signal: 3, texts: { 'en-US': 'Motor 3 fault' }, needsAck: true, trigger: 'M11.2' },
];

/** The TSAP pairs the TSAP-addressed profiles accept (test/s7-server.test.ts). */
const TSAPS: Partial<Record<S7Profile, string>> = { 's7-200': 'localTsap=1000&remoteTsap=1001', logo: 'localTsap=0100&remoteTsap=0200' };

describe('S7 classic alarms (userdata group 4) against the S7-300/400 simulator', function () {
  this.timeout(20000);
  const open: { close(): Promise<void> }[] = [];

  afterEach(async () => {
    for (const x of open.splice(0).reverse()) await x.close();
  });

  async function start(profile: S7Profile = 's7-300', url = '') {
    const server = new S7Server({ port: 0, profile, alarms: DEFINITIONS, layout: { dbs: { 1: 16 } } });
    await server.listen();
    open.push(server);
    const address = TSAPS[profile] ?? `slot=${profile === 's7-300' || profile === 's7-400' ? 2 : 1}`;
    const client = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?${address}&timeout=3000${url}`) as S7Endpoint);
    open.push(client);
    await client.connect();
    return { server, client };
  }

  function collect(sub: AlarmSubscription): AlarmEvent[] {
    const events: AlarmEvent[] = [];
    sub.on('event', (e) => events.push(e));
    return events;
  }

  it('a trigger going TRUE pushes a coming ALARM_SQ with its values; the query lists it; acknowledge and going follow', async () => {
    const { server, client } = await start();
    const events: AlarmEvent[] = [];
    const sub = await client.subscribeAlarms({}, (e) => events.push(e));
    open.unshift(sub);
    expect(sub.active).to.deep.equal([]);
    server.memory.write('M', 0, 20, Buffer.of(0xff, 0xfe));
    const real = Buffer.alloc(4);
    real.writeFloatBE(2.5);
    server.memory.write('M', 0, 24, real);
    server.memory.writeBit('M', 0, 10, 0, true);
    await until(() => events.length === 1, 3000, 'the coming event');
    const coming = events[0]!;
    expect(coming).to.include({ type: 'alarm', change: 'coming' });
    if (coming.type !== 'alarm') throw new Error('not an alarm event');
    expect(coming.alarm).to.include({ id: 0x101, kind: 'ALARM_SQ', state: 'coming', needsAck: true, acknowledged: false });
    expect(coming.alarm.values).to.deep.equal([
      { type: 'INT', value: -2 },
      { type: 'REAL', value: 2.5 },
    ]);
    expect(coming.alarm.coming).to.be.instanceOf(Date);
    expect(sub.active.map((a) => a.id)).to.deep.equal([0x101]);

    const listed = await client.alarms();
    expect(listed).to.have.length(1);
    expect(listed[0]).to.include({ id: 0x101, kind: 'ALARM_SQ', state: 'coming', acknowledged: false, needsAck: true });
    expect(listed[0]!.values).to.deep.equal([{ type: 'INT', value: -2 }]);

    await client.acknowledge(0x101);
    await until(() => events.length === 2, 3000, 'the acknowledged event');
    expect(events[1]).to.include({ type: 'alarm', change: 'acknowledged' });
    server.memory.writeBit('M', 0, 10, 0, false);
    await until(() => events.length === 3, 3000, 'the going event');
    expect(events[2]).to.include({ type: 'alarm', change: 'going' });
    expect(sub.active).to.deep.equal([]);
    expect(await client.alarms()).to.deep.equal([]);
  });

  it('an alarm that went unacknowledged stays in the query; ALARM_S needs no acknowledgement; ALARM_8 reports its signal', async () => {
    const { server, client } = await start('s7-400');
    const sub = await client.subscribeAlarms({}, () => undefined);
    open.unshift(sub);
    const events = collect(sub);
    server.memory.writeBit('M', 0, 10, 0, true);
    server.memory.writeBit('M', 0, 10, 0, false);
    server.memory.writeBit('DB', 1, 0, 1, true);
    server.memory.writeBit('M', 0, 11, 2, true);
    await until(() => events.length === 4, 3000, 'four events');
    expect(events.map((e) => (e.type === 'alarm' ? `${e.alarm.id}:${e.change}:${e.alarm.signal ?? '-'}` : e.type))).to.deep.equal([
      '257:coming:-',
      '257:going:-',
      '258:coming:-',
      '512:coming:3',
    ]);
    const listed = await client.alarms();
    expect(listed.map((a) => `${a.id}:${a.state}:${a.kind}:${a.needsAck}`).sort()).to.deep.equal([
      '257:going:ALARM_SQ:true',
      '258:coming:ALARM_S:false',
      '512:coming:ALARM_8:true',
    ]);
    const noAck = await client.acknowledge(0x102).catch((e: unknown) => e);
    expect(noAck).to.be.instanceOf(PlcError).with.property('code', 'ACCESS_DENIED');
    const unknown = await client.acknowledge(0x999).catch((e: unknown) => e);
    expect(unknown).to.be.instanceOf(PlcError).with.property('code', 'OBJECT_DOES_NOT_EXIST');
    await client.acknowledge(0x101);
    await until(() => sub.active.every((a) => a.id !== 0x101), 3000, 'the acknowledged alarm leaving the list');
  });

  it('mode changes and diagnostic messages reach a subscription that asked for them', async () => {
    const { server, client } = await start();
    const events: AlarmEvent[] = [];
    const sub = await client.subscribeAlarms({ mode: true, diagnostics: true }, (e) => events.push(e));
    open.unshift(sub);
    server.stop();
    await until(() => events.some((e) => e.type === 'mode'), 3000, 'the mode event');
    expect(events.find((e) => e.type === 'mode')).to.include({ to: 'STOP' });
    const diag = events.find((e) => e.type === 'diagnostic');
    expect(diag).to.include({ type: 'diagnostic', id: 0x4304 });
    server.start();
    await until(() => events.filter((e) => e.type === 'mode').length === 2, 3000, 'RUN');
    expect(events.filter((e) => e.type === 'mode').map((e) => (e.type === 'mode' ? e.to : ''))).to.deep.equal(['STOP', 'RUN']);
  });

  it('closing one of two subscriptions of a client leaves the other registered', async () => {
    const { server, client } = await start();
    const first = await client.subscribeAlarms({}, () => undefined);
    const events: AlarmEvent[] = [];
    const second = await client.subscribeAlarms({}, (e) => events.push(e));
    open.unshift(second);
    await first.close();
    server.memory.writeBit('M', 0, 10, 0, true);
    await until(() => events.length === 1, 3000, 'the coming event after the other subscription closed');
  });

  it('a read-only connection and one outside its allow-list refuse acknowledge before a byte goes out', async () => {
    const { client, server } = await start('s7-300', '&readOnly=true');
    let requests = 0;
    server.on('request', () => requests++);
    const err = await client.acknowledge(0x101).catch((e: unknown) => e);
    expect(err).to.be.instanceOf(PlcError).with.property('code', 'WRITE_NOT_ALLOWED');
    expect(requests).to.equal(0);
  });

  it('an allow-list naming ALARM257 (and an address) connects, acknowledges alarm 257 only, and still guards writes by its address', async () => {
    // Before the fix, the write guard read ALARM257 as an address and the connect itself failed.
    const { client, server } = await start('s7-300', '&allow=ALARM257,DB1.DBW2');
    server.memory.writeBit('M', 0, 10, 0, true);
    let requests = 0;
    server.on('request', () => requests++);
    const other = await client.acknowledge(0x200).catch((e: unknown) => e);
    expect(other).to.be.instanceOf(PlcError).with.property('code', 'WRITE_NOT_ALLOWED');
    expect(requests).to.equal(0);
    await client.acknowledge(0x101);
    expect((await client.alarms()).find((a) => a.id === 0x101)).to.include({ acknowledged: true });
    await client.write({ 'DB1.DBW2:INT': 5 });
    const write = await client.write({ 'DB1.DBW4:INT': 5 }).catch((e: unknown) => e);
    expect((write as Error).message).to.match(/DB1\.DBW4.*not in the connection's write allow-list \(ALARM257, DB1\.DBW2\)/);
    expect(server.memory.read('DB', 1, 4, 2).readInt16BE(0)).to.equal(0);
  });

  for (const profile of ['s7-1500', 's7-1200', 's7-200', 'logo'] as const) {
    it(`an ${profile} refuses the classic alarm services as its CPU does, the error pointing at s7plus://`, async () => {
      const { client } = await start(profile);
      const err = await client.alarms().catch((e: unknown) => e);
      expect(err).to.be.instanceOf(PlcError).with.property('code', 'NOT_SUPPORTED');
      expect((err as Error).message).to.match(/refuses the classic alarm services.*s7plus:\/\/127\.0\.0\.1/);
      const sub = await client.subscribeAlarms({}, () => undefined).catch((e: unknown) => e);
      expect(sub).to.be.instanceOf(PlcError).with.property('code', 'NOT_SUPPORTED');
    });
  }

  it('after a link loss the subscription registers again and reports what came and went meanwhile (during: outage)', async () => {
    const { server, client } = await start();
    const events: AlarmEvent[] = [];
    const sub = await client.subscribeAlarms({}, (e) => events.push(e));
    open.unshift(sub);
    server.memory.writeBit('M', 0, 10, 0, true);
    await until(() => events.length === 1, 3000, 'coming');
    const lost = waitFor(sub as never, 'lost', 5000);
    server.faults.dropConnections();
    await lost;
    // While the link is down: 0x101 goes (unacknowledged: still listed, as going), 0x102 comes.
    server.memory.writeBit('M', 0, 10, 0, false);
    server.memory.writeBit('DB', 1, 0, 1, true);
    await waitFor(sub as never, 'active', 10000);
    const outage = events.slice(1).map((e) => (e.type === 'alarm' && 'during' in e ? `${e.alarm.id}:${e.change}:${e.during}` : 'other'));
    expect(outage.sort()).to.deep.equal(['257:going:outage', '258:coming:outage']);
    // And pushes flow again on the new connection.
    server.memory.writeBit('DB', 1, 0, 1, false);
    await until(
      () => events.some((e) => e.type === 'alarm' && e.alarm.id === 0x102 && e.change === 'going'),
      3000,
      'going after reconnect',
    );
  });
});
