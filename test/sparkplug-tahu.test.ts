/**
 * Sparkplug B against a host nobody here wrote: Eclipse Tahu 1.0.21's decoder
 * and a primary host built on it (test/support/tahu.ts), through a real
 * mosquitto (test/support/mosquitto.ts). Without java, the built Tahu host or
 * mosquitto the suite skips and says why; .ci/run (PLCWIRE_REQUIRE_SPARKPLUG=1)
 * makes a missing peer a failure instead.
 */
import { expect } from 'chai';
import type { AlarmDefinition } from '../lib/alarms/model';
import { createClient, type AnyClient } from '../lib/connect';
import type { S7Client } from '../lib/s7/client';
import { S7Server } from '../lib/s7/server';
import { SparkplugEdgeNode } from '../lib/sparkplug/edge-node';
import { Mosquitto } from './support/mosquitto';
import { missingMosquitto, requirePeers } from './support/sparkplug-peers';
import { TahuHost, missingTahu, type TahuLine, type TahuMetric } from './support/tahu';
import { waitFor } from './support/wait';

const mqtt = require('mqtt');

/** Subscribes a plain MQTT.js client to `topic` and resolves with the first message (retained ones too). */
function firstMessage(url: string, topic: string, ms = 20_000): Promise<{ payload: string; retain: boolean; qos: number }> {
  return new Promise((resolve, reject) => {
    const client = mqtt.connect(url, { reconnectPeriod: 0 });
    const timer = setTimeout(() => (client.end(true), reject(new Error(`nothing on ${topic} within ${ms} ms`))), ms);
    client.on('error', (e: Error) => (clearTimeout(timer), client.end(true), reject(e)));
    client.on('connect', () => client.subscribe(topic, { qos: 1 }));
    client.on('message', (_t: string, payload: Buffer, packet: { retain: boolean; qos: number }) => {
      clearTimeout(timer);
      client.end(true);
      resolve({ payload: payload.toString('utf8'), retain: packet.retain, qos: packet.qos });
    });
  });
}

describe('Sparkplug B: the Eclipse Tahu host (test/interop/tahu) and mosquitto', function () {
  this.timeout(120_000);
  const broker = new Mosquitto();

  before(async function () {
    requirePeers(this, missingMosquitto() ?? missingTahu());
    await broker.start();
  });
  after(() => broker.dispose());

  it('publishes its STATE online as Sparkplug 3.0 asks: retained, QoS 1, JSON with a timestamp', async () => {
    const host = new TahuHost(broker.url, 'HarnessHost');
    try {
      await host.ready();
      const state = await firstMessage(broker.url, 'spBv1.0/STATE/HarnessHost');
      expect(state.retain).to.equal(true);
      expect(state.qos).to.equal(1);
      const json = JSON.parse(state.payload);
      expect(json.online).to.equal(true);
      expect(json.timestamp)
        .to.be.a('number')
        .within(Date.now() - 120_000, Date.now());
    } finally {
      await host.close();
    }
    // A clean quit leaves STATE offline retained, with the same birth timestamp.
    const after = JSON.parse((await firstMessage(broker.url, 'spBv1.0/STATE/HarnessHost')).payload);
    expect(after.online).to.equal(false);
  });

  it("leaves STATE offline through its Will when it is killed (the broker's Will delivery)", async () => {
    const host = new TahuHost(broker.url, 'KilledHost');
    await host.ready();
    const online = JSON.parse((await firstMessage(broker.url, 'spBv1.0/STATE/KilledHost')).payload);
    expect(online.online).to.equal(true);
    await host.close(true);
    const deadline = Date.now() + 30_000;
    let state = online;
    while (state.online && Date.now() < deadline) state = JSON.parse((await firstMessage(broker.url, 'spBv1.0/STATE/KilledHost')).payload);
    expect(state).to.deep.equal({ online: false, timestamp: online.timestamp });
  });

  it('encodes NCMD rebirth and DCMD with Tahu and decodes them back with Tahu (the harness itself)', async () => {
    const host = new TahuHost(broker.url, 'EchoHost');
    try {
      await host.ready();
      await host.command('rebirth G1 E1');
      const ncmd = await host.waitFor((l) => l.type === 'NCMD');
      expect(ncmd.topic).to.equal('spBv1.0/G1/NCMD/E1');
      expect(ncmd.metrics![0]).to.include({ name: 'Node Control/Rebirth', datatype: 'Boolean', value: true });
      await host.command('dcmd G1 E1 D1 Counter Int64 9007199254740993');
      const dcmd = await host.waitFor((l) => l.type === 'DCMD');
      expect(dcmd.topic).to.equal('spBv1.0/G1/DCMD/E1/D1');
      expect(dcmd.metrics![0]).to.include({ name: 'Counter', datatype: 'Int64', value: '9007199254740993' });
    } finally {
      await host.close();
    }
  });
});

/**
 * Every PLC type the edge node maps, its Sparkplug datatype (as Tahu names it),
 * the value written into the PLC, and that value as Tahu prints it: 64-bit
 * integers as exact decimal strings, DateTime as ms since the epoch.
 */
const WHEN = Date.UTC(2026, 11, 3, 13, 30, 15, 250);
const TYPES: { tag: string; datatype: string; plc: unknown; tahu: unknown }[] = [
  { tag: 'DB1.DBB0:SINT', datatype: 'Int8', plc: -100, tahu: -100 },
  { tag: 'DB1.DBW2:INT', datatype: 'Int16', plc: -30000, tahu: -30000 },
  { tag: 'DB1.DBD4:DINT', datatype: 'Int32', plc: -2_000_000_000, tahu: -2_000_000_000 },
  { tag: 'DB1.DBB8:LINT', datatype: 'Int64', plc: -9007199254740993n, tahu: '-9007199254740993' },
  { tag: 'DB1.DBB16:ULINT', datatype: 'UInt64', plc: 18446744073709551615n, tahu: '18446744073709551615' },
  { tag: 'DB1.DBB24:USINT', datatype: 'UInt8', plc: 200, tahu: 200 },
  { tag: 'DB1.DBW26:UINT', datatype: 'UInt16', plc: 65000, tahu: 65000 },
  { tag: 'DB1.DBD28:UDINT', datatype: 'UInt32', plc: 4_000_000_000, tahu: '4000000000' },
  { tag: 'DB1.DBD32:REAL', datatype: 'Float', plc: -2.5, tahu: -2.5 },
  { tag: 'DB1.DBB36:LREAL', datatype: 'Double', plc: -1.25e300, tahu: -1.25e300 },
  { tag: 'DB1.DBX44.0', datatype: 'Boolean', plc: true, tahu: true },
  { tag: 'DB1.DBB46:STRING[10]', datatype: 'String', plc: 'Filling', tahu: 'Filling' },
  { tag: 'DB1.DBB58:DTL', datatype: 'DateTime', plc: new Date(WHEN), tahu: WHEN },
  { tag: 'DB1.DBB70:DATE_AND_TIME', datatype: 'DateTime', plc: new Date(WHEN), tahu: WHEN },
  { tag: 'DB1.DBB78:INT[4]', datatype: 'Int16Array', plc: [-1, 2, -32768, 32767], tahu: [-1, 2, -32768, 32767] },
  { tag: 'DB1.DBB86:SINT[2]', datatype: 'Int8Array', plc: [-128, 127], tahu: [-128, 127] },
  { tag: 'DB1.DBB88:DINT[2]', datatype: 'Int32Array', plc: [-2147483648, 7], tahu: [-2147483648, 7] },
  {
    tag: 'DB1.DBB96:LINT[2]',
    datatype: 'Int64Array',
    plc: [-9007199254740993n, 9007199254740993n],
    tahu: ['-9007199254740993', '9007199254740993'],
  },
  { tag: 'DB1.DBB112:REAL[2]', datatype: 'FloatArray', plc: [1.5, -0.25], tahu: [1.5, -0.25] },
  { tag: 'DB1.DBB120:LREAL[2]', datatype: 'DoubleArray', plc: [Math.PI, -1e-300], tahu: [Math.PI, -1e-300] },
];

describe('Sparkplug B: our edge node as Eclipse Tahu 1.0.21 decodes it (test/interop/tahu)', function () {
  this.timeout(180_000);
  const broker = new Mosquitto();
  const plc = new S7Server({ port: 0, profile: 's7-1500' });
  let host: TahuHost;
  let client: AnyClient;
  let edge: SparkplugEdgeNode;

  const metricsOf = (l: TahuLine): Record<string, TahuMetric> => Object.fromEntries(l.metrics!.map((m) => [m.name!, m]));

  before(async function () {
    requirePeers(this, missingMosquitto() ?? missingTahu());
    await broker.start();
    const port = await plc.listen();
    client = createClient(`s7://127.0.0.1:${port}?rack=0&slot=1`);
    client.on('error', () => undefined);
    await client.connect();
    await client.write(Object.fromEntries(TYPES.map((t) => [t.tag, t.plc])));
    client.start();
    host = new TahuHost(broker.url, 'TahuPrimary');
    await host.ready();
    edge = new SparkplugEdgeNode({
      brokers: [broker.url],
      group: 'Plant',
      node: 'Edge1',
      primaryHost: 'TahuPrimary',
      interval: 50,
      reconnectDelay: 200,
      devices: [{ name: 'Line1', client, tags: Object.fromEntries(TYPES.map((t) => [t.tag, t.tag])), writable: TYPES.map((t) => t.tag) }],
    });
    edge.on('error', () => undefined);
    edge.start();
  });
  after(async () => {
    await edge?.stop();
    await client?.close();
    await host?.close();
    await plc.close();
    await broker.dispose();
  });

  it('Tahu decodes NBIRTH (bdSeq, Node Control/Rebirth) and a DBIRTH whose every metric has its name, alias, datatype, value and timestamp', async () => {
    const nbirth = await host.waitFor((l) => l.type === 'NBIRTH', 60_000);
    expect(nbirth.error, nbirth.error).to.equal(undefined);
    expect(nbirth.seq).to.equal(0);
    expect(nbirth.qos).to.equal(0);
    const n = metricsOf(nbirth);
    expect(n.bdSeq).to.include({ datatype: 'Int64' });
    expect(n['Node Control/Rebirth']).to.include({ datatype: 'Boolean', value: false });
    const dbirth = await host.waitFor((l) => l.type === 'DBIRTH' && l.device === 'Line1');
    expect(dbirth.error, dbirth.error).to.equal(undefined);
    expect(dbirth.seq).to.equal(1);
    const d = metricsOf(dbirth);
    for (const t of TYPES) {
      const m = d[t.tag];
      expect(m, t.tag).to.not.equal(undefined);
      expect(m, t.tag).to.include({ datatype: t.datatype, is_historical: false, is_null: false });
      expect(m!.value, `${t.tag} as Tahu decodes it`).to.deep.equal(t.tahu);
      expect(m!.alias, t.tag).to.be.a('number');
      expect(m!.timestamp, t.tag)
        .to.be.a('number')
        .within(Date.now() - 120_000, Date.now() + 1000);
    }
    expect(new Set(dbirth.metrics!.map((m) => m.alias)).size, 'aliases unique').to.equal(TYPES.length);
  });

  it('Tahu decodes DDATA by alias alone (the names from the DBIRTH) and a seq one more than the message before', async () => {
    const from = host.lines.length;
    await client.write({ 'DB1.DBW2:INT': -12345, 'DB1.DBB8:LINT': 9007199254740995n });
    const ddata = await host.waitFor((l) => l.type === 'DDATA' && (l.metrics ?? []).length >= 2, 20_000, from);
    expect(ddata.error, ddata.error).to.equal(undefined);
    const d = metricsOf(ddata);
    expect(d['DB1.DBW2:INT']).to.include({ named: false, datatype: 'Int16', value: -12345 });
    expect(d['DB1.DBB8:LINT']).to.include({ named: false, datatype: 'Int64', value: '9007199254740995' });
    const before = host.messages().filter((l) => l.seq !== undefined && host.lines.indexOf(l) < host.lines.indexOf(ddata));
    expect(ddata.seq).to.equal((before[before.length - 1]!.seq! + 1) % 256);
  });

  it('writes each datatype Tahu sends in a DCMD into the PLC, and the next DDATA shows it', async () => {
    const writes: [string, string, string, unknown][] = [
      ['DB1.DBB0:SINT', 'Int8', '-7', -7],
      ['DB1.DBW2:INT', 'Int16', '-32768', -32768],
      ['DB1.DBD4:DINT', 'Int32', '-123456789', -123456789],
      ['DB1.DBB8:LINT', 'Int64', '-9007199254740999', -9007199254740999n],
      ['DB1.DBB16:ULINT', 'UInt64', '18446744073709551000', 18446744073709551000n],
      // Tahu puts a UInt32 in long_value, not int_value (lib/sparkplug/scalars.ts takes both).
      ['DB1.DBD28:UDINT', 'UInt32', '4000000001', 4_000_000_001],
      ['DB1.DBD32:REAL', 'Float', '0.5', 0.5],
      ['DB1.DBB36:LREAL', 'Double', '-2.75', -2.75],
      ['DB1.DBX44.0', 'Boolean', 'false', false],
      ['DB1.DBB46:STRING[10]', 'String', 'Draining', 'Draining'],
      ['DB1.DBB58:DTL', 'DateTime', String(WHEN + 1000), new Date(WHEN + 1000)],
    ];
    for (const [tag, type, text, value] of writes) {
      const from = host.lines.length;
      await host.command(`dcmd Plant Edge1 Line1 ${tag} ${type} ${text}`);
      const ddata = await host.waitFor(
        (l) => l.type === 'DDATA' && (l.metrics ?? []).some((m) => m.name === tag),
        20_000,
        from,
        `DDATA of ${tag}`,
      );
      const read = (await client.read([tag]))[tag];
      expect(read, tag).to.deep.equal(value);
      const shown = metricsOf(ddata)[tag]!.value;
      expect(shown, `${tag} in DDATA`).to.deep.equal(
        // Tahu holds Int64, UInt32 and UInt64 as Long/BigInteger: the harness prints them as decimal strings.
        typeof value === 'bigint' || type === 'UInt32' ? String(value) : value instanceof Date ? value.getTime() : value,
      );
    }
  });

  it('answers a rebirth from Tahu with NBIRTH (the same bdSeq, seq 0) and DBIRTH with the current values', async () => {
    const first = host.messages('NBIRTH')[0]!;
    const from = host.lines.length;
    await host.command('rebirth Plant Edge1');
    const nbirth = await host.waitFor((l) => l.type === 'NBIRTH', 20_000, from);
    expect(nbirth.seq).to.equal(0);
    expect(nbirth.bdSeq).to.equal(first.bdSeq);
    const dbirth = await host.waitFor((l) => l.type === 'DBIRTH', 20_000, from);
    expect(dbirth.seq).to.equal(1);
    expect(metricsOf(dbirth)['DB1.DBB46:STRING[10]']!.value).to.equal('Draining');
    expect(host.messages('NDEATH').length, 'no NDEATH on a rebirth').to.equal(0);
  });

  it('sends DDEATH when the PLC is lost and a DBIRTH once it is back, Tahu decoding both', async () => {
    const from = host.lines.length;
    plc.dropConnections();
    const ddeath = await host.waitFor((l) => l.type === 'DDEATH', 20_000, from);
    expect(ddeath.error, ddeath.error).to.equal(undefined);
    expect(ddeath.seq).to.be.a('number');
    await waitFor(client, 'connected', 20_000);
    const dbirth = await host.waitFor((l) => l.type === 'DBIRTH', 20_000, host.lines.indexOf(ddeath));
    expect(dbirth.seq).to.equal((ddeath.seq! + 1) % 256);
    expect(metricsOf(dbirth)['DB1.DBB0:SINT']!.value).to.equal(-7);
  });

  it("leaves when Tahu's STATE goes offline (NDEATH) and births again when it is back online", async () => {
    const bdSeq = host.messages('NBIRTH')[0]!.bdSeq;
    const from = host.lines.length;
    await host.command('state offline');
    const ndeath = await host.waitFor((l) => l.type === 'NDEATH', 20_000, from);
    expect(ndeath.bdSeq).to.equal(bdSeq);
    expect(ndeath.seq, 'NDEATH has no seq').to.equal(undefined);
    await host.command('state online');
    const nbirth = await host.waitFor((l) => l.type === 'NBIRTH', 30_000, host.lines.indexOf(ndeath));
    expect(Number(nbirth.bdSeq)).to.equal((Number(bdSeq) + 1) % 256);
  });

  it('sends NDEATH with the session bdSeq on stop(), which Tahu decodes', async () => {
    const births = host.messages('NBIRTH');
    const bdSeq = births[births.length - 1]!.bdSeq;
    const from = host.lines.length;
    await edge.stop();
    const ndeath = await host.waitFor((l) => l.type === 'NDEATH', 20_000, from);
    expect(ndeath.error, ndeath.error).to.equal(undefined);
    expect(ndeath.qos).to.equal(1);
    expect(ndeath.bdSeq).to.equal(bdSeq);
    const errors = host.lines.filter((l) => l.error);
    expect(errors, 'nothing Tahu could not decode').to.deep.equal([]);
  });
});

/** The PLC's alarms as Tahu decodes them (lib/sparkplug/alarms.ts): the DataSet table, the event, an acknowledgement by DCMD. */
describe('Sparkplug B: a PLC’s alarms as Eclipse Tahu 1.0.21 decodes them', function () {
  this.timeout(180_000);
  const broker = new Mosquitto();
  const HIGH: AlarmDefinition = {
    id: 0x101,
    kind: 'ALARM_SQ',
    texts: { 'en-US': 'Tank level high' },
    needsAck: true,
    trigger: 'DB1.DBX0.0',
    values: ['DB1.DBW2:INT'],
  };
  const plc = new S7Server({ port: 0, profile: 's7-400', alarms: [HIGH], layout: { dbs: { 1: 16 } } });
  let host: TahuHost;
  let client: AnyClient;
  let edge: SparkplugEdgeNode;

  before(async function () {
    requirePeers(this, missingMosquitto() ?? missingTahu());
    await broker.start();
    const port = await plc.listen();
    client = createClient(`s7://127.0.0.1:${port}?slot=2&allow=ALARMS`);
    client.on('error', () => undefined);
    await client.connect();
    host = new TahuHost(broker.url, 'TahuAlarms');
    await host.ready();
    edge = new SparkplugEdgeNode({
      brokers: [broker.url],
      group: 'Plant',
      node: 'Edge2',
      primaryHost: 'TahuAlarms',
      interval: 100,
      devices: [{ name: 'Tank', client, tags: { Level: 'DB1.DBW2:INT' }, alarms: true, writable: ['Alarms/Acknowledge'] }],
    });
    edge.on('error', (e) => errors.push(e.message));
    edge.start();
  });
  after(async () => {
    await edge?.stop();
    await client?.close();
    await host?.close();
    await plc.close();
    await broker.dispose();
  });

  const errors: string[] = [];
  const metricsOf = (l: TahuLine): Record<string, TahuMetric> => Object.fromEntries(l.metrics!.map((m) => [m.name!, m]));

  it('Tahu decodes the alarm metrics of the DBIRTH, an alarm’s DDATA (event and table), and its DCMD acknowledges the alarm in the CPU', async () => {
    const dbirth = await host.waitFor((l) => l.type === 'DBIRTH' && l.device === 'Tank', 60_000);
    expect(dbirth.error, dbirth.error).to.equal(undefined);
    const birth = metricsOf(dbirth);
    expect(birth['Alarms/Active']).to.deep.include({
      datatype: 'DataSet',
      value: {
        columns: ['Id', 'Kind', 'Signal', 'State', 'Acknowledged', 'Priority', 'Time', 'Text'],
        types: ['UInt32', 'String', 'UInt8', 'String', 'Boolean', 'Int32', 'DateTime', 'String'],
        rows: [],
      },
    });
    expect(birth['Alarms/Active Count']).to.include({ datatype: 'Int32', value: 0 });
    expect(birth['Alarms/Event']).to.include({ datatype: 'String', is_null: true });
    expect(birth['Alarms/Acknowledge']).to.include({ datatype: 'UInt32', value: '0' });

    const from = host.lines.length;
    plc.memory.writeBit('DB', 1, 0, 0, true);
    const came = await host.waitFor((l) => l.type === 'DDATA' && l.metrics!.some((m) => m.name === 'Alarms/Event'), 20_000, from);
    expect(came.error, came.error).to.equal(undefined);
    const data = metricsOf(came);
    expect(JSON.parse(data['Alarms/Event']!.value as string)).to.deep.include({ type: 'alarm', change: 'coming' });
    const table = data['Alarms/Active']!.value as { rows: unknown[][] };
    expect(table.rows).to.have.length(1);
    expect(table.rows[0]!.slice(0, 6)).to.deep.equal(['257', 'ALARM_SQ', 0, 'coming', false, 0]);
    expect(data['Alarms/Unacknowledged Count']).to.include({ value: 1 });

    const before = host.lines.length;
    await host.command('dcmd Plant Edge2 Tank Alarms/Acknowledge UInt32 257');
    const acked = await host
      .waitFor(
        (l) => l.type === 'DDATA' && l.metrics!.some((m) => m.name === 'Alarms/Unacknowledged Count' && m.value === 0),
        20_000,
        before,
      )
      .catch((e: Error) => {
        throw new Error(`${e.message}; the edge node's errors: ${errors.join('; ')}`);
      });
    expect(acked.error, acked.error).to.equal(undefined);
    expect((await (client as S7Client).alarms()).find((a) => a.id === 0x101)).to.include({ acknowledged: true });
    expect(host.lines.filter((l) => l.error)).to.deep.equal([]);
  });
});
