/**
 * A PLC's alarms as Sparkplug metrics (lib/sparkplug/alarms.ts, issue #34): the five fixed `Alarms/…`
 * metrics in the DBIRTH, an alarm coming, acknowledged and going as DDATA (the event with the PLC's own
 * time stamp, the active table, the counts), acknowledgement by DCMD through the connection's guard, an
 * alarm that came while the PLC's link was down, a CPU that refuses alarms, both generations: an S7-400
 * (ALARM_SQ over s7://) and an S7-1500 (Program_Alarm over s7plus://), through a real mosquitto.
 */
import { expect } from 'chai';
import type { EventEmitter } from 'node:events';
import type { AlarmDefinition } from '../lib/alarms/model';
import { createClient } from '../lib/connect';
import { PlcError } from '../lib/errors';
import type { S7Client } from '../lib/s7/client';
import { S7Server } from '../lib/s7/server';
import { ALARM_COLUMNS, ALARM_METRICS, SparkplugEdgeNode, type SparkplugDeviceOptions } from '../lib/sparkplug';
import { DataType } from '../lib/sparkplug/datatypes';
import type { DataSet, SparkplugMetric } from '../lib/sparkplug/model';
import { encodePayload } from '../lib/sparkplug/payload';
import type { PlcClient } from '../lib/types';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { Mosquitto } from './support/mosquitto';
import { requirePeers } from './support/sparkplug-peers';
import { startPlusSimulator, type PlusSimulator } from './support/s7plus-sim';
import { TestHost, type Received } from './support/sparkplug-host';
import { until, waitFor } from './support/wait';

const FAST = { backoff: { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 } };

/** An ALARM_SQ that needs acknowledging (DB1.DBX0.0) with the level as its value, and a NOTIFY (DB1.DBX0.1). */
const HIGH: AlarmDefinition = {
  id: 0x101,
  kind: 'ALARM_SQ',
  texts: { 'en-US': 'Tank level high' },
  needsAck: true,
  trigger: 'DB1.DBX0.0',
  values: ['DB1.DBW2:INT'],
};
const DOOR: AlarmDefinition = { id: 0x102, kind: 'NOTIFY', texts: { 'en-US': 'Door open' }, needsAck: false, trigger: 'DB1.DBX0.1' };

const byName = (m: Received, name: string): SparkplugMetric | undefined => m.payload!.metrics.find((x) => x.name === name);
/** The values of one metric in a data message, by its alias. */
const valuesOf = (m: Received, alias: number): SparkplugMetric[] => m.payload!.metrics.filter((x) => Number(x.alias) === alias);

describe('Sparkplug: a PLC’s alarms as metrics of its device (issue #34)', function () {
  this.timeout(60000);
  const broker = new Mosquitto();
  const open: { close(): Promise<void> }[] = [];
  let host: TestHost;
  let node: SparkplugEdgeNode | undefined;

  before(async function () {
    requirePeers(this);
    await broker.start();
  });
  after(() => broker.dispose());

  beforeEach(async () => {
    host = new TestHost(broker.url);
    await host.connect();
  });

  afterEach(async () => {
    await node?.stop();
    node = undefined;
    await host.close();
    for (const x of open.splice(0).reverse()) await x.close();
  });

  async function s7400(query = '') {
    const server = new S7Server({ port: 0, profile: 's7-400', alarms: [HIGH, DOOR], layout: { dbs: { 1: 16 } } });
    await server.listen();
    open.push(server);
    const client = createClient(`s7://127.0.0.1:${server.port}?slot=2&timeout=2000${query}`, FAST) as S7Client;
    open.push(client);
    await client.connect();
    return { server, client };
  }

  function edge(device: SparkplugDeviceOptions, errors: [PlcError, string | undefined][] = []): SparkplugEdgeNode {
    node = new SparkplugEdgeNode({ brokers: [broker.url], group: 'Plant', node: 'Alarms', interval: 100, devices: [device] });
    node.on('error', (e, d) => errors.push([e, d]));
    node.start();
    return node;
  }

  /** The next DDATA of `device` that carries metric `alias`. */
  const dataWith = (device: string, alias: number, ms = 10000): Promise<Received> =>
    host.next(
      (m) => m.parsed.type === 'DDATA' && m.parsed.device === device && valuesOf(m, alias).length > 0,
      ms,
      `DDATA with alias ${alias}`,
    );

  it('the DBIRTH names the five alarm metrics with their datatypes after the tags: an empty table, counts 0, no event yet', async () => {
    const { client } = await s7400();
    edge({ name: 'Tank', client, tags: { Level: 'DB1.DBW2:INT' }, alarms: true });
    const birth = await host.nextOf('DBIRTH', 'Tank', 10000);
    const metrics = birth.payload!.metrics;
    expect(metrics.map((m) => [m.name, m.datatype])).to.deep.equal([
      ['Level', DataType.Int16],
      [ALARM_METRICS.active, DataType.DataSet],
      [ALARM_METRICS.activeCount, DataType.Int32],
      [ALARM_METRICS.unacknowledged, DataType.Int32],
      [ALARM_METRICS.event, DataType.String],
      [ALARM_METRICS.acknowledge, DataType.UInt32],
    ]);
    expect(new Set(metrics.map((m) => Number(m.alias))).size).to.equal(6);
    const table = byName(birth, ALARM_METRICS.active)!.value as DataSet;
    expect(table.columns).to.deep.equal(ALARM_COLUMNS.map(([c]) => c));
    expect(table.types).to.deep.equal(ALARM_COLUMNS.map(([, t]) => t));
    expect(table.rows).to.deep.equal([]);
    expect(byName(birth, ALARM_METRICS.activeCount)!.value).to.equal(0);
    expect(byName(birth, ALARM_METRICS.unacknowledged)!.value).to.equal(0);
    expect(byName(birth, ALARM_METRICS.event)).to.include({ isNull: true });
    expect(byName(birth, ALARM_METRICS.acknowledge)!.value).to.equal(0);
    expect(metrics.every((m) => typeof m.timestamp === 'number')).to.equal(true);
  });

  it('S7-400: an ALARM_SQ comes, is acknowledged by a host’s DCMD and goes, each as DDATA with the PLC’s event and the table', async () => {
    const { server, client } = await s7400('&allow=ALARMS');
    const errors: [PlcError, string | undefined][] = [];
    edge({ name: 'Tank', client, tags: { Level: 'DB1.DBW2:INT' }, alarms: true, writable: [ALARM_METRICS.acknowledge] }, errors);
    const birth = await host.nextOf('DBIRTH', 'Tank', 10000);
    const alias = (name: string): number => Number(byName(birth, name)!.alias);

    server.memory.write('DB', 1, 2, Buffer.from([0x03, 0xe8])); // level 1000, the alarm's value
    server.memory.writeBit('DB', 1, 0, 0, true);
    const came = await dataWith('Tank', alias(ALARM_METRICS.event));
    const [event] = valuesOf(came, alias(ALARM_METRICS.event));
    const json = JSON.parse(event!.value as string);
    expect(json).to.deep.include({ type: 'alarm', change: 'coming' });
    expect(json.alarm).to.deep.include({ id: 0x101, kind: 'ALARM_SQ', state: 'coming', acknowledged: false, needsAck: true });
    expect(json.alarm.values).to.deep.equal([{ type: 'INT', value: 1000 }]);
    expect(event!.timestamp).to.equal(Date.parse(json.at)); // the PLC's own time of the event
    expect(event!.isHistorical ?? false).to.equal(false);
    // The event and the table it changed go in one DDATA.
    const table = valuesOf(came, alias(ALARM_METRICS.active))[0]!.value as DataSet;
    expect(table.rows).to.have.length(1);
    expect(table.rows[0]!.slice(0, 6)).to.deep.equal([0x101, 'ALARM_SQ', 0, 'coming', false, 0]);
    expect(table.rows[0]![6]).to.be.instanceOf(Date);

    // The host acknowledges: the CPU's own alarm query says so, and the next DDATA shows it.
    const done = waitFor(node as unknown as EventEmitter, 'command', 10000);
    await host.client.publishAsync(
      'spBv1.0/Plant/DCMD/Alarms/Tank',
      encodePayload({ timestamp: Date.now(), metrics: [{ name: ALARM_METRICS.acknowledge, datatype: DataType.UInt32, value: 0x101 }] }),
    );
    expect(await done).to.deep.equal({ device: 'Tank', metric: ALARM_METRICS.acknowledge, value: 0x101 });
    expect((await client.alarms()).find((a) => a.id === 0x101)).to.include({ acknowledged: true });
    const acked = await host.next(
      (m) =>
        m.parsed.type === 'DDATA' &&
        valuesOf(m, alias(ALARM_METRICS.event)).some((e) => JSON.parse(e.value as string).change === 'acknowledged'),
      10000,
      'the acknowledgement as an event',
    );
    expect(acked).to.not.equal(undefined);
    await until(
      () =>
        host.messages.some((m) => m.parsed.type === 'DDATA' && valuesOf(m, alias(ALARM_METRICS.unacknowledged)).some((u) => u.value === 0)),
      10000,
      'Unacknowledged Count 0',
    );

    // It goes: acknowledged and gone, it leaves the table.
    server.memory.writeBit('DB', 1, 0, 0, false);
    await host.next(
      (m) => m.parsed.type === 'DDATA' && valuesOf(m, alias(ALARM_METRICS.activeCount)).some((c) => c.value === 0),
      10000,
      'Active Count 0',
    );
    const events = host.messages
      .filter((m) => m.parsed.type === 'DDATA')
      .flatMap((m) => valuesOf(m, alias(ALARM_METRICS.event)))
      .map((e) => JSON.parse(e.value as string).change);
    expect(events).to.deep.equal(['coming', 'acknowledged', 'going']);
    expect(errors).to.deep.equal([]);
  });

  it('a DCMD acknowledge on a read-only connection is an error event naming the device, and the alarm stays unacknowledged in the CPU', async () => {
    const { server, client } = await s7400('&readOnly=true');
    const errors: [PlcError, string | undefined][] = [];
    edge({ name: 'Tank', client, tags: { Level: 'DB1.DBW2:INT' }, alarms: true, writable: [ALARM_METRICS.acknowledge] }, errors);
    await host.nextOf('DBIRTH', 'Tank', 10000);
    server.memory.writeBit('DB', 1, 0, 0, true);
    await eventually(async () => (await client.alarms()).length === 1, 'the alarm active');
    await host.client.publishAsync(
      'spBv1.0/Plant/DCMD/Alarms/Tank',
      encodePayload({ timestamp: Date.now(), metrics: [{ name: ALARM_METRICS.acknowledge, datatype: DataType.UInt32, value: 0x101 }] }),
    );
    await until(() => errors.length > 0, 10000, 'the refusal');
    const [err, device] = errors[0]!;
    expect(device).to.equal('Tank');
    expect(err.code).to.equal('WRITE_NOT_ALLOWED');
    expect(err.message).to.match(/Tank.*Alarms\/Acknowledge 257.*read-only/);
    expect((await client.alarms())[0]).to.include({ id: 0x101, acknowledged: false });
  });

  it('without Alarms/Acknowledge in writable, a DCMD acknowledge is refused before the PLC', async () => {
    const { server, client } = await s7400('&allow=ALARMS');
    const errors: [PlcError, string | undefined][] = [];
    edge({ name: 'Tank', client, tags: { Level: 'DB1.DBW2:INT' }, alarms: true, writable: ['Level'] }, errors);
    await host.nextOf('DBIRTH', 'Tank', 10000);
    server.memory.writeBit('DB', 1, 0, 0, true);
    await eventually(async () => (await client.alarms()).length === 1, 'the alarm active');
    node!.on('command', () => expect.fail('no acknowledgement may be done'));
    await host.client.publishAsync(
      'spBv1.0/Plant/DCMD/Alarms/Tank',
      encodePayload({ timestamp: Date.now(), metrics: [{ name: ALARM_METRICS.acknowledge, datatype: DataType.UInt32, value: 0x101 }] }),
    );
    await until(() => errors.length > 0, 10000, 'the refusal');
    expect(errors[0]![0].code).to.equal('WRITE_NOT_ALLOWED');
    expect(errors[0]![0].message).to.match(/"Alarms\/Acknowledge" is not writable/);
    expect(errors[0]![1]).to.equal('Tank');
    expect((await client.alarms())[0]).to.include({ acknowledged: false });
  });

  it('an alarm that came while the PLC link was down: DDEATH, then a DBIRTH whose table holds it, and its event reported as during the outage', async () => {
    const { server, client } = await s7400();
    edge({ name: 'Tank', client, tags: { Level: 'DB1.DBW2:INT' }, alarms: true });
    const birth = await host.nextOf('DBIRTH', 'Tank', 10000);
    const eventAlias = Number(byName(birth, ALARM_METRICS.event)!.alias);
    const down = waitFor(client as unknown as EventEmitter, 'disconnected', 10000);
    server.faults.dropConnections();
    server.memory.writeBit('DB', 1, 0, 0, true);
    await down;
    await host.nextOf('DDEATH', 'Tank', 10000);
    const reborn = await host.nextOf('DBIRTH', 'Tank', 20000);
    await until(
      () =>
        host.messages
          .filter((m) => m.parsed.type === 'DDATA')
          .some((m) => valuesOf(m, eventAlias).some((e) => JSON.parse(e.value as string).during === 'outage')),
      20000,
      'the outage event',
    );
    // The table as the CPU has it: in the DBIRTH, or in the DDATA after it if the subscription came back later.
    const tables = [reborn, ...host.messages.filter((m) => m.parsed.type === 'DDATA')]
      .flatMap((m) => m.payload!.metrics.filter((x) => x.name === ALARM_METRICS.active || Number(x.alias) === eventAlias - 3))
      .filter((x) => x.value !== null);
    expect((tables.at(-1)!.value as DataSet).rows.map((r) => r[0])).to.deep.equal([0x101]);
    const outage = host.messages
      .filter((m) => m.parsed.type === 'DDATA')
      .flatMap((m) => valuesOf(m, eventAlias))
      .map((e) => JSON.parse(e.value as string));
    expect(outage.filter((e) => e.during === 'outage').map((e) => [e.change, e.alarm.id])).to.deep.equal([['coming', 0x101]]);
  });

  it('a CPU that refuses alarms (an S7-1500 over PUT/GET): one error naming the device, the device born with its tags and the alarm metrics null and BAD', async () => {
    const server = new S7Server({ port: 0, profile: 's7-1500', layout: { dbs: { 1: 16 } } });
    await server.listen();
    open.push(server);
    const client = createClient(`s7://127.0.0.1:${server.port}?timeout=2000`, FAST) as S7Client;
    open.push(client);
    await client.connect();
    const errors: [PlcError, string | undefined][] = [];
    edge({ name: 'Press', client, tags: { Level: 'DB1.DBW2:INT' }, alarms: true }, errors);
    const birth = await host.nextOf('DBIRTH', 'Press', 10000);
    expect(byName(birth, 'Level')!.value).to.equal(0);
    for (const name of [ALARM_METRICS.active, ALARM_METRICS.activeCount, ALARM_METRICS.unacknowledged]) {
      expect(byName(birth, name), name).to.deep.include({ isNull: true, properties: { Quality: { type: DataType.Int32, value: 0 } } });
    }
    expect(errors).to.have.length(1);
    expect(errors[0]![1]).to.equal('Press');
    expect(errors[0]![0].code).to.equal('NOT_SUPPORTED');
    expect(errors[0]![0].message).to.match(/^device Press: alarms: /);
    // Polled on: a change of the tag is DDATA, and the refusal is not asked again and again.
    server.memory.write('DB', 1, 2, Buffer.from([0, 9]));
    const data = await host.nextOf('DDATA', 'Press', 10000);
    expect(data.payload!.metrics.map((m) => m.value)).to.deep.equal([9]);
    expect(errors).to.have.length(1);
  });

  it('a device whose protocol reports no alarms (FETCH/WRITE) is refused when the edge node is made, naming the device', async () => {
    const client = createClient('fetchwrite://127.0.0.1?port=2000') as PlcClient; // never connected: refused before
    open.push(client);
    expect(
      () =>
        new SparkplugEdgeNode({
          brokers: [broker.url],
          group: 'Plant',
          node: 'X',
          devices: [{ name: 'Old', client, tags: { W: 'DB1.DBW0:INT' }, alarms: true }],
        }),
    )
      .to.throw(PlcError, /device Old: a fetchwrite connection reports no alarms \(s7:\/\/.*s7plus:\/\/ do\)/)
      .with.property('code', 'NOT_SUPPORTED');
  });

  it('a burst of 1,000 alarms within a second: every event reaches the host once, in the CPU’s order, and the table ends with all 1,000', async () => {
    const N = 1000;
    const burst: AlarmDefinition[] = Array.from({ length: N }, (_, i) => ({
      id: 0x10000 + i,
      kind: 'ALARM_S' as const,
      texts: {},
      needsAck: false,
      trigger: `DB2.DBX${i >> 3}.${i & 7}`,
    }));
    const server = new S7Server({ port: 0, profile: 's7-400', alarms: burst, layout: { dbs: { 1: 16, 2: N / 8 } } });
    await server.listen();
    open.push(server);
    const client = createClient(`s7://127.0.0.1:${server.port}?slot=2&timeout=5000`, FAST) as S7Client;
    open.push(client);
    await client.connect();
    edge({ name: 'Burst', client, tags: { Level: 'DB1.DBW2:INT' }, alarms: true });
    const birth = await host.nextOf('DBIRTH', 'Burst', 10000);
    const eventAlias = Number(byName(birth, ALARM_METRICS.event)!.alias);
    const countAlias = Number(byName(birth, ALARM_METRICS.activeCount)!.alias);
    const t0 = Date.now();
    for (let i = 0; i < N; i++) server.memory.writeBit('DB', 2, i >> 3, i & 7, true);
    const events = (): SparkplugMetric[] =>
      host.messages.filter((m) => m.parsed.type === 'DDATA' && m.parsed.device === 'Burst').flatMap((m) => valuesOf(m, eventAlias));
    await until(() => events().length >= N, 30000, `${N} events at the host`);
    const ms = Date.now() - t0;
    const messages = host.messages.filter((m) => m.parsed.type === 'DDATA' && m.parsed.device === 'Burst').length;
    console.log(`      ${N} alarms raised, all ${N} events at the host after ${ms} ms, in ${messages} DDATA`);
    expect(events().map((e) => JSON.parse(e.value as string).alarm.id - 0x10000)).to.deep.equal(Array.from({ length: N }, (_, i) => i));
    await until(
      () => host.messages.some((m) => m.parsed.type === 'DDATA' && valuesOf(m, countAlias).some((c) => c.value === N)),
      10000,
      `Active Count ${N}`,
    );
  });

  it('store-and-forward: an alarm that came and went while the broker was down is sent after the new births as historical events, in order', async () => {
    const own = new Mosquitto();
    await own.start();
    try {
      const { server, client } = await s7400();
      node = new SparkplugEdgeNode({
        brokers: [own.url],
        group: 'Plant',
        node: 'Buffered',
        interval: 100,
        reconnectDelay: 100,
        devices: [{ name: 'Tank', client, tags: { Level: 'DB1.DBW2:INT' }, alarms: true }],
      });
      node.on('error', () => undefined);
      let h = new TestHost(own.url);
      await h.connect();
      node.start();
      const birth = await h.nextOf('DBIRTH', 'Tank', 10000);
      const eventAlias = Number(byName(birth, ALARM_METRICS.event)!.alias);
      await h.close();
      await own.stop();
      await until(() => node!.stats.state === 'connecting', 10000, 'the session lost');
      server.memory.writeBit('DB', 1, 0, 1, true); // the NOTIFY comes
      server.memory.writeBit('DB', 1, 0, 1, false); // and goes
      await until(() => node!.stats.buffered >= 2, 10000, 'both events kept');
      await own.start();
      h = new TestHost(own.url);
      await h.connect();
      try {
        await h.nextOf('NBIRTH', undefined, 20000);
        await h.nextOf('DBIRTH', 'Tank', 10000);
        const history = await h.next((m) => m.parsed.type === 'DDATA' && valuesOf(m, eventAlias).length > 0, 10000, 'the kept events');
        const events = valuesOf(history, eventAlias);
        expect(
          events.map((e) => [JSON.parse(e.value as string).change, JSON.parse(e.value as string).alarm.id, e.isHistorical]),
        ).to.deep.equal([
          ['coming', 0x102, true],
          ['going', 0x102, true],
        ]);
        expect(events[0]!.timestamp!).to.be.at.most(events[1]!.timestamp!);
      } finally {
        await h.close();
      }
    } finally {
      await node?.stop();
      node = undefined;
      await own.dispose();
    }
  });

  describe('S7-1500 over s7plus://: Program_Alarm with its texts', () => {
    let sim: PlusSimulator;
    const TANK: AlarmDefinition = {
      id: 7,
      kind: 'Program_Alarm',
      texts: { 'en-US': 'Tank level @1%d@ high', 'de-DE': 'Tankpegel @1%d@ hoch' },
      needsAck: true,
      priority: 5,
      trigger: '"Tank".Alarm',
      values: ['"Tank".Count'],
    };

    before(async () => {
      sim = await startPlusSimulator({ sources: SOURCES, db: DB_NUMBERS, alarms: [TANK] });
    });
    after(() => sim?.server.close());

    it('the Program_Alarm comes as an event and a row with its priority and its text in the language asked', async () => {
      const client = createClient(sim.url, FAST);
      open.push(client);
      await client.connect();
      const errors: [PlcError, string | undefined][] = [];
      edge(
        { name: 'Line', client, tags: { Count: '"Tank".Count' }, alarms: { languages: ['de-DE'] }, writable: [ALARM_METRICS.acknowledge] },
        errors,
      );
      const birth = await host.nextOf('DBIRTH', 'Line', 20000);
      const tableAlias = Number(byName(birth, ALARM_METRICS.active)!.alias);
      await client.write({ '"Tank".Count': 42, '"Tank".Alarm': true });
      const data = await host.next(
        (m) => m.parsed.type === 'DDATA' && valuesOf(m, tableAlias).some((t) => (t.value as DataSet).rows.length === 1),
        20000,
        'the table with the alarm',
      );
      const row = (valuesOf(data, tableAlias)[0]!.value as DataSet).rows[0]!;
      expect([row[0], row[1], row[3], row[4], row[5], row[7]]).to.deep.equal([7, 'Program_Alarm', 'coming', false, 5, 'Tankpegel 42 hoch']);
      const event = JSON.parse(valuesOf(data, tableAlias + 3)[0]!.value as string);
      expect(event.alarm.texts['de-DE'].text).to.equal('Tankpegel 42 hoch');
      // A Program_Alarm cannot be acknowledged over S7CommPlus (no public layout): the DCMD is an error saying so.
      await host.client.publishAsync(
        'spBv1.0/Plant/DCMD/Alarms/Line',
        encodePayload({ timestamp: Date.now(), metrics: [{ name: ALARM_METRICS.acknowledge, datatype: DataType.UInt32, value: 7 }] }),
      );
      await until(() => errors.length > 0, 10000, 'the refusal');
      expect(errors[0]![1]).to.equal('Line');
      expect(errors[0]![0].code).to.equal('NOT_SUPPORTED');
      expect(errors[0]![0].message).to.match(/docs\/alarms\.md/);
      await client.write({ '"Tank".Alarm': false });
    });
  });
});

/** Waits for an async condition, with a deadline. */
async function eventually(condition: () => Promise<boolean>, what: string, ms = 10000): Promise<void> {
  const deadline = Date.now() + ms;
  while (!(await condition())) {
    if (Date.now() > deadline) throw new Error(`no ${what} within ${ms} ms`);
    await new Promise((r) => setTimeout(r, 50));
  }
}

describe('Sparkplug alarms: a subscription that fails on a link that stays up (lib/sparkplug/alarms.ts)', () => {
  it('is tried again at most every 10 s from the poll, at once on a reconnect, and its error is told once, not at every try', async () => {
    const { DeviceAlarms } = await import('../lib/sparkplug/alarms');
    let attempts = 0;
    // The S7 driver's alarms port calls client.subscribeAlarms: a client whose CPU does not answer the registration in time.
    const client = {
      protocol: 's7',
      state: 'connected',
      subscribeAlarms: () => {
        attempts++;
        return Promise.reject(new PlcError('TIMEOUT', 'no answer to the alarm registration within 2000 ms'));
      },
    } as unknown as PlcClient;
    const errors: PlcError[] = [];
    let changes = 0;
    const alarms = new DeviceAlarms(
      'Tank',
      client,
      {},
      10,
      () => changes++,
      (e) => errors.push(e),
    );
    alarms.open();
    await until(() => alarms.settled, 2000, 'the first attempt ended');
    for (let i = 0; i < 5; i++) alarms.open(true); // the poll, within RETRY_MS: no new attempt
    await new Promise((r) => setImmediate(r));
    expect(attempts).to.equal(1);
    alarms.open(); // the link came back: at once
    await until(() => attempts === 2 && changes >= 2, 2000, 'the second attempt');
    expect(errors.map((e) => [e.code, e.message])).to.deep.equal([
      ['TIMEOUT', 'device Tank: alarms: no answer to the alarm registration within 2000 ms'],
    ]);
    // Born meanwhile with the alarm metrics BAD.
    expect(
      alarms
        .birth()
        .slice(0, 3)
        .every((m) => m.isNull && m.properties?.['Quality']?.value === 0),
    ).to.equal(true);
    await alarms.close();
  });
});
