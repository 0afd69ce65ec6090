/**
 * Program_Alarms over S7CommPlus (issue #33): the alarm subscription's
 * CreateObject and the active-alarm Explore byte for byte as s7commplus
 * 0.3.0 (MIT) builds them, the DAI object and the alarm notification both
 * ways, associated values and texts with their placeholders; then our
 * client against our S7-1500 simulator: the active list, events as the
 * trigger tags change, texts per language, acknowledgement refused as it
 * must be, a burst of 1000 alarms complete and in order, a link lost in the
 * middle of a burst losing nothing.
 */
import { expect } from 'chai';
import * as net from 'node:net';
import type { AlarmEvent, PlcAlarm } from '../lib/alarms/model';
import { createClient } from '../lib/connect';
import { DRIVERS } from '../lib/drivers';
import { PlcError, ProtocolError } from '../lib/errors';
import type { S7PlusClient } from '../lib';
import {
  alarmExploreBody,
  alarmSubscriptionObject,
  daiObject,
  decodeAlarmNotification,
  decodeHmiInfo,
  encodeAlarmNotification,
  isAlarmNotification,
  readDai,
  type Dai,
  type HmiInfo,
} from '../lib/s7plus/codec/alarms';
import {
  associatedValueBlob,
  associatedValuesArray,
  decodeAssociatedValue,
  fillPlaceholders,
  formatValue,
  lcidOf,
  toPlcAlarm,
} from '../lib/s7plus/codec/alarm-texts';
import { encodeExploreRequest } from '../lib/s7plus/codec/explore';
import { decodeObject, encodeObject } from '../lib/s7plus/codec/object';
import { decodePValue, encodePValue } from '../lib/s7plus/codec/pvalue';
import { encodeCreateObjectRequest } from '../lib/s7plus/codec/session';
import { subscriptionCreateBody } from '../lib/s7plus/codec/subscription';
import { DataType, FunctionCode, TransportFlags } from '../lib/s7plus/constants';
import type { AlarmDefinition } from '../lib/alarms/model';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { startPlusSimulator, type PlusSimulator } from './support/s7plus-sim';
import { until, waitFor } from './support/wait';

const head = { sequence: 1, sessionId: 0x10, transportFlags: TransportFlags.Normal };

describe('S7CommPlus alarms (codec)', () => {
  it("the alarm subscription's CreateObject, byte for byte as s7commplus builds it (alarm.py build_alarm_subscription_request)", () => {
    // Printed by s7commplus 0.3.0 in our venv: build_alarm_subscription_request(0x12345, [1033]).hex()
    const theirs =
      '0001234500040000000000a17fffc00187690000a38169001517537562736372697074696f6e5f32313437343637323635a3883a000202a3876a00030000a3876b000900a38810000202a38811000101a3881820040388808480000000a38819000400a3881a000400a3881b000200a3881c000200a3881d0007000aa3881e0003ffffa15101000194660000a381690015125337704472697665725f416c61726d696e67a3876d000203a3946310030a0000000000000000000000000000000000000000a3bc33200301ffffa3bf752004018809a3bf6d000101a4946400000008a2a200000000';
    const object = alarmSubscriptionObject({ languages: [1033], creditLimit: 10 });
    const frame = encodeCreateObjectRequest({
      header: { ...head, functionCode: FunctionCode.CreateObject },
      body: subscriptionCreateBody(0x12345, object),
    });
    expect(frame.subarray(14).toString('hex')).to.equal(theirs);
  });

  it('the active-alarm Explore, byte for byte as s7commplus builds it (alarm.py build_alarm_explore_request)', () => {
    const frame = encodeExploreRequest({ header: { ...head, functionCode: FunctionCode.Explore }, body: alarmExploreBody() });
    expect(frame.subarray(14).toString('hex')).to.equal('00000008946b010100000a946e946f9470947194759f6fbd058169bd6d951b0000000000');
  });

  it('a typed Blob (root id above 1) carries 8 bytes and its blob type before its count, both ways (alarm.py _decode_blob)', () => {
    const wire = Buffer.from('0014' + '90808001' + '0000000000000000' + '02' + '02' + '0007', 'hex');
    const { value, length } = decodePValue(wire);
    expect(length).to.equal(wire.length);
    expect(value.value).to.deep.include({ rootId: 0x02000001, blobType: 2 });
    expect(encodePValue(value)).to.deep.equal(wire);
    expect(() => decodePValue(Buffer.from('0014' + '90808001' + '0000000000000000' + '07' + '00', 'hex'))).to.throw(/typed Blob of type 7/);
  });

  const dai: Dai = {
    relationId: 0x8c000001,
    name: 'Program_Alarm_7',
    cpuAlarmId: 7n,
    allStatesInfo: 1,
    domain: 1,
    messageType: 1,
    sequenceCounter: 3,
    hmi: { syntaxId: 258, version: 1, clientAlarmId: 7, priority: 5, alarmClass: 1 },
    state: 'coming',
    timestamp: 1_700_000_000_123_000_000n,
    ackTimestamp: 0n,
    values: associatedValuesArray([
      associatedValueBlob('REAL', 12.5),
      associatedValueBlob('INT', -7),
      associatedValueBlob('STRING', 'abc', 10),
    ]),
    texts: new Map([
      [(1033 << 16) | 2, 'Level @1%5.1f@ m, count @2%d@, @3%s@, @4%d@'],
      [(1031 << 16) | 2, 'Pegel @1%.2f@'],
      [(1031 << 16) | 1, 'Info'],
    ]),
  };

  it('a DAI object encodes and decodes to the same alarm; its PlcAlarm has the values by type and the texts filled', () => {
    const obj = decodeObject(encodeObject(daiObject(dai))).value;
    const back = readDai(obj);
    expect(back).to.deep.include({ cpuAlarmId: 7n, state: 'coming', sequenceCounter: 3, timestamp: dai.timestamp });
    expect(back.hmi).to.deep.include({ priority: 5, alarmClass: 1 });
    const alarm = toPlcAlarm(back);
    expect(alarm).to.deep.include({
      id: 7,
      kind: 'Program_Alarm',
      state: 'coming',
      needsAck: true,
      acknowledged: false,
      priority: 5,
      alarmClass: 1,
    });
    expect(alarm.values).to.deep.equal([
      { type: 'REAL', value: 12.5 },
      { type: 'INT', value: -7 },
      { type: 'STRING', value: 'abc' },
    ]);
    expect(alarm.coming?.toISOString()).to.equal('2023-11-14T22:13:20.123Z');
    // A placeholder whose value is absent (@4%d@) stays as written.
    expect(alarm.texts).to.deep.equal({
      'en-US': { text: 'Level  12.5 m, count -7, abc, @4%d@' },
      'de-DE': { text: 'Pegel 12.50', info: 'Info' },
    });
    expect(Object.keys(toPlcAlarm(back, [1031]).texts ?? {})).to.deep.equal(['de-DE']);
  });

  it('a DAI whose CPU alarm id is no whole number is a ProtocolError (found by the fuzzer: a REAL id made BigInt() throw a RangeError)', () => {
    const obj = daiObject(dai);
    const m = obj.members.find((x) => x.kind === 'attribute' && x.id === 2670)!;
    if (m.kind === 'attribute') m.value = { flags: 0, type: DataType.LReal, value: 2.5 };
    expect(() => readDai(decodeObject(encodeObject(obj)).value)).to.throw(ProtocolError, /CPU alarm id/);
  });

  it('an alarm notification encodes and decodes both ways; a data notification is not one', () => {
    const data = encodeAlarmNotification({
      subscriptionId: 0x7a000001,
      creditTick: 1,
      sequence: 1,
      changeCounter: 1,
      alarmSubscriptionId: 0x7a000001,
      unexplained: 0,
      alarms: [daiObject(dai)],
    });
    expect(isAlarmNotification(data)).to.equal(true);
    const n = decodeAlarmNotification(data);
    expect(n).to.deep.include({ subscriptionId: 0x7a000001, creditTick: 1, sequence: 1, alarmSubscriptionId: 0x7a000001 });
    expect(readDai(n.alarms[0]!).cpuAlarmId).to.equal(7n);
    // A data notification with no values: its fill follows the value list's end.
    const empty = Buffer.from('33' + '70000001' + '040000000000' + '01' + '01' + '01' + '00' + '00000000', 'hex');
    expect(isAlarmNotification(empty)).to.equal(false);
    expect(() => decodeAlarmNotification(Buffer.from('32', 'hex'))).to.throw(/expected a notification/);
  });

  it('the HMI info blob of syntax 258 (AlarmsHmiInfo.cs): client alarm id, priority, then 3 reserved bytes, alarm class, producer, group, flags', () => {
    const h: HmiInfo = decodeHmiInfo(Buffer.from('0102' + '0001' + '00000007' + '05' + '000000' + '0001' + '02' + '03' + '04', 'hex'));
    expect(h).to.deep.equal({ syntaxId: 258, version: 1, clientAlarmId: 7, priority: 5, alarmClass: 1, producer: 2, groupId: 3, flags: 4 });
    expect(decodeHmiInfo(Buffer.from('0100000100000007' + '09', 'hex'))).to.deep.equal({
      syntaxId: 256,
      version: 1,
      clientAlarmId: 7,
      priority: 9,
    });
    expect(() => decodeHmiInfo(Buffer.from('0102', 'hex'))).to.throw(/HMI info version/);
  });

  it('associated values by root id (alarm.py _decode_associated_value): WSTRING, DINT, an unknown type, a cut value', () => {
    expect(decodeAssociatedValue(associatedValueBlob('WSTRING', 'Öl', 10))).to.deep.equal({ type: 'WSTRING', value: 'Öl' });
    expect(decodeAssociatedValue(associatedValueBlob('DINT', -70000))).to.deep.equal({ type: 'DINT', value: -70000 });
    expect(decodeAssociatedValue(associatedValueBlob('BOOL', true))).to.deep.equal({ type: 'BOOL', value: true });
    expect(decodeAssociatedValue({ rootId: 0x02000099, data: Buffer.of(1) })).to.equal(undefined);
    expect(decodeAssociatedValue({ rootId: 0x02000008, data: Buffer.of(1, 2) })).to.equal(undefined);
  });

  it('placeholders: C printf conversions as TIA writes them', () => {
    expect(formatValue('%d', 42)).to.equal('42');
    expect(formatValue('%5d', 42)).to.equal('   42');
    expect(formatValue('%05d', 42)).to.equal('00042');
    expect(formatValue('%-4d', 7)).to.equal('7   ');
    expect(formatValue('%X', 255)).to.equal('FF');
    expect(formatValue('%.1f', 2.25)).to.equal('2.3');
    expect(formatValue('%s', 'abc')).to.equal('abc');
    expect(formatValue('%d', 'abc')).to.equal(undefined);
    expect(formatValue('%q', 1)).to.equal(undefined);
    expect(
      fillPlaceholders('@1%d@ of @2%s@ @9%d@', [
        { type: 'INT', value: 1 },
        { type: 'STRING', value: 'x' },
      ]),
    ).to.equal('1 of x @9%d@');
    expect(lcidOf('en-US')).to.equal(1033);
    expect(lcidOf('de')).to.equal(1031);
    expect(lcidOf('1040')).to.equal(1040);
    expect(lcidOf('xx-YY')).to.equal(undefined);
  });

  it('a value type TIA does not allow as an associated value is a TypeError naming the types it allows', () => {
    expect(() => associatedValueBlob('TIME', 5)).to.throw(TypeError, /TIA allows BOOL/);
    expect(() => associatedValuesArray(new Array(11).fill(associatedValueBlob('INT', 1)))).to.throw(RangeError);
    expect(DataType.Blob).to.equal(0x14);
  });
});

/** Our sockets to `port` still open. */
function socketsTo(port: number): net.Socket[] {
  const handles = (process as unknown as { _getActiveHandles(): unknown[] })._getActiveHandles();
  return handles.filter((h): h is net.Socket => h instanceof net.Socket && !h.destroyed && h.remotePort === port);
}

const TANK: AlarmDefinition = {
  id: 7,
  kind: 'Program_Alarm',
  texts: { 'en-US': 'Tank level @1%5.1f@ m, count @2%d@, @3%s@', 'de-DE': 'Tankpegel @1%5.1f@ m' },
  needsAck: true,
  priority: 5,
  trigger: '"Tank".Alarm',
  values: ['"Tank".Level', '"Tank".Count', '"Tank".Name'],
};
/** 1000 alarms on the bits of DB1 bytes 100–224 (the Recipe DB's spare bytes are not used: DB3 is a plain standard DB). */
const BURST: AlarmDefinition[] = Array.from({ length: 1000 }, (_, i) => ({
  id: 1000 + i,
  kind: 'Program_Alarm',
  texts: { 'en-US': `Burst ${i}` },
  needsAck: false,
  trigger: `M${100 + (i >> 3)}.${i & 7}`,
}));

describe('S7CommPlus alarms (our client, our S7-1500 simulator)', function () {
  this.timeout(60000);
  let sim: PlusSimulator;
  let client: S7PlusClient;
  let writer: S7PlusClient;

  before(async () => {
    sim = await startPlusSimulator({ sources: SOURCES, db: DB_NUMBERS, alarms: [TANK, ...BURST] });
  });
  beforeEach(async () => {
    client = createClient(sim.url, { backoff: { initialDelay: 50, maxDelay: 200 } }) as S7PlusClient;
    writer = createClient(sim.url) as S7PlusClient;
    await client.connect();
    await writer.connect();
  });
  afterEach(async () => {
    // "Tank".Alarm is DB1.DBX6.1 (test/fixtures/s7plus/Tank.db).
    sim.server.memory.writeBit('DB', 1, 6, 1, false);
    for (let b = 100; b < 225; b++) sim.server.memory.write('M', 0, b, Buffer.of(0));
    await client?.close();
    await writer?.close();
  });
  after(async () => {
    await sim?.server.close();
  });

  it('the active list is empty, then holds the alarm with its values and texts once its trigger is TRUE', async () => {
    expect(await client.alarms()).to.deep.equal([]);
    await writer.write({ '"Tank".Alarm': true });
    const [alarm, ...rest] = await client.alarms({ languages: ['en-US'] });
    expect(rest).to.deep.equal([]);
    expect(alarm).to.deep.include({ id: 7, kind: 'Program_Alarm', state: 'coming', needsAck: true, acknowledged: false, priority: 5 });
    expect(alarm!.values).to.deep.equal([
      { type: 'REAL', value: 12.5 },
      { type: 'INT', value: 7 },
      { type: 'STRING', value: 'abc' },
    ]);
    expect(alarm!.texts).to.deep.equal({ 'en-US': { text: 'Tank level  12.5 m, count 7, abc' } });
    expect(Object.keys((await client.alarms()).at(0)?.texts ?? {}).sort()).to.deep.equal(['de-DE', 'en-US']);
  });

  it('subscribeAlarms: coming and going as the trigger changes, values as they were then, texts in the language asked', async () => {
    const events: AlarmEvent[] = [];
    const sub = await client.subscribeAlarms({ languages: ['de-DE'] }, (e) => events.push(e));
    expect(sub.active).to.deep.equal([]);
    await writer.write({ '"Tank".Count': 9 });
    await writer.write({ '"Tank".Alarm': true });
    await until(() => events.length === 1, 5000, 'the coming event');
    await writer.write({ '"Tank".Level': 3.5 });
    await writer.write({ '"Tank".Alarm': false });
    await until(() => events.length === 2, 5000, 'the going event');
    const [coming, going] = events as [Extract<AlarmEvent, { type: 'alarm' }>, Extract<AlarmEvent, { type: 'alarm' }>];
    expect([coming.change, going.change]).to.deep.equal(['coming', 'going']);
    expect(coming.alarm.values[1]).to.deep.equal({ type: 'INT', value: 9 });
    expect(coming.alarm.texts).to.deep.equal({ 'de-DE': { text: 'Tankpegel  12.5 m' } });
    expect(going.alarm.texts).to.deep.equal({ 'de-DE': { text: 'Tankpegel   3.5 m' } });
    expect(sub.active).to.deep.equal([]);
    await writer.write({ '"Tank".Level': 12.5, '"Tank".Count': 7 });
    await sub.close();
  });

  it('acknowledge: refused read-only and outside the allow-list (WRITE_NOT_ALLOWED), else NOT_SUPPORTED; the registry port says the same', async () => {
    const ro = createClient(`${sim.url}&readOnly=true`) as S7PlusClient;
    await ro.connect();
    try {
      const e1 = await ro.acknowledge(7).catch((e: PlcError) => e);
      expect(e1).to.be.instanceOf(PlcError).with.property('code', 'WRITE_NOT_ALLOWED');
    } finally {
      await ro.close();
    }
    const listed = createClient(sim.url, { allow: ['DB1.DBW0'] }) as S7PlusClient;
    await listed.connect();
    try {
      expect(await listed.acknowledge(7).catch((e: PlcError) => e.code)).to.equal('WRITE_NOT_ALLOWED');
    } finally {
      await listed.close();
    }
    const e3 = await DRIVERS.s7plus.alarms!.acknowledge(client, 7).catch((e: PlcError) => e);
    expect(e3).to.have.property('code', 'NOT_SUPPORTED');
    expect((e3 as PlcError).message).to.match(/docs\/alarms\.md/);
    expect(await DRIVERS.s7plus.alarms!.list(client)).to.deep.equal([]);
  });

  it('an unknown text language is refused naming it', async () => {
    const e = await client.alarms({ languages: ['xx-YY'] }).catch((err: PlcError) => err);
    expect(e).to.be.instanceOf(PlcError).with.property('code', 'INVALID_VALUE');
    expect((e as PlcError).message).to.match(/xx-YY/);
  });

  it('1000 alarms coming within a second reach the subscriber complete and in order', async () => {
    const got: number[] = [];
    const sub = await client.subscribeAlarms({}, (e) => {
      if (e.type === 'alarm' && e.change === 'coming') got.push(e.alarm.id);
    });
    const started = Date.now();
    for (let b = 100; b < 225; b++) sim.server.memory.write('M', 0, b, Buffer.of(0xff));
    await until(() => got.length === 1000, 20000, '1000 coming events');
    const ms = Date.now() - started;
    expect(got).to.deep.equal(BURST.map((d) => d.id));
    expect(sub.active).to.have.length(1000);
    if (process.env.PLCWIRE_FIGURES) console.log(`      1000 Program_Alarms delivered in ${ms} ms`);
    await sub.close();
  });

  it('a link lost in the middle of a burst loses nothing: the active list read again reports what came and went meanwhile', async () => {
    const events: AlarmEvent[] = [];
    const sub = await client.subscribeAlarms({}, (e) => events.push(e));
    // Half of them come first.
    for (let b = 100; b < 162; b++) sim.server.memory.write('M', 0, b, Buffer.of(0xff));
    const lost = waitFor(sub, 'lost', 10000);
    // Every link to the simulator is cut (the subscription's own session among them).
    for (const s of socketsTo(sim.server.port)) s.destroy();
    await lost;
    // During the outage: the rest come, and the first 80 go.
    for (let b = 162; b < 225; b++) sim.server.memory.write('M', 0, b, Buffer.of(0xff));
    for (let b = 100; b < 110; b++) sim.server.memory.write('M', 0, b, Buffer.of(0));
    await waitFor(sub, 'active', 15000);
    const now = new Set(sub.active.map((a) => a.id));
    const expected = BURST.filter((_, i) => i >= 80).map((d) => d.id);
    expect([...now].filter((id) => id >= 1000).sort()).to.deep.equal(expected);
    // Every change is accounted for: the events replayed give the same list.
    const state = new Set<number>();
    for (const e of events) if (e.type === 'alarm') e.change === 'going' ? state.delete(e.alarm.id) : state.add(e.alarm.id);
    expect([...state].sort()).to.deep.equal(expected);
    expect(events.some((e) => e.type === 'alarm' && 'during' in e && e.during === 'outage')).to.equal(true);
    await sub.close();
  });

  it('closing the client closes its alarm subscriptions and leaves no socket to the PLC', async () => {
    await client.subscribeAlarms({});
    expect(socketsTo(sim.server.port).length).to.be.at.least(2);
    await client.close();
    await writer.close();
    await until(() => socketsTo(sim.server.port).length === 0, 5000, 'no socket left');
  });
});

export type { PlcAlarm };
