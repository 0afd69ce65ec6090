/**
 * Fuzz targets of the S7CommPlus alarm decoders (issue #33): the alarm
 * notification, the DAI object and its PlcAlarm (values, texts and their
 * placeholders), the HMI info, an associated value by its root id, the
 * simulator's reading of an alarm subscription. Seeded with our encoders'
 * output, which s7commplus 0.3.0 reads (test/s7plus-alarms-python.test.ts),
 * and the package's own alarm subscription request (test/s7plus-alarms.test.ts).
 */
import {
  associatedValueBlob,
  associatedValuesArray,
  decodeAssociatedValue,
  fillPlaceholders,
  toPlcAlarm,
} from '../../lib/s7plus/codec/alarm-texts';
import {
  alarmSubscriptionObject,
  daiObject,
  decodeAlarmNotification,
  decodeHmiInfo,
  encodeAlarmNotification,
  readAlarmSubscription,
  readDai,
  type Dai,
} from '../../lib/s7plus/codec/alarms';
import { decodeObject, encodeObject } from '../../lib/s7plus/codec/object';
import type { FuzzTarget } from './engine';

const DAI: Dai = {
  relationId: 0x8c000001,
  name: 'Program_Alarm_7',
  cpuAlarmId: 7n,
  allStatesInfo: 1,
  domain: 1,
  messageType: 1,
  sequenceCounter: 3,
  hmi: { syntaxId: 258, version: 1, clientAlarmId: 7, priority: 5, alarmClass: 1 },
  state: 'coming',
  timestamp: 1_700_000_000_000_000_000n,
  ackTimestamp: 0n,
  values: associatedValuesArray([
    associatedValueBlob('REAL', 12.5),
    associatedValueBlob('DINT', -7),
    associatedValueBlob('STRING', 'abc', 10),
    associatedValueBlob('WSTRING', 'Öl', 4),
  ]),
  texts: new Map([
    [(1033 << 16) | 2, 'Level @1%5.1f@ m, @2%d@, @3%s@, @4%s@'],
    [(1031 << 16) | 1, 'Info @1%X@'],
  ]),
};

export function s7plusAlarmTargets(): FuzzTarget[] {
  const object = encodeObject(daiObject(DAI));
  const going = encodeObject(daiObject({ ...DAI, state: 'going', sequenceCounter: 4 }));
  const notification = (o: Dai[]) =>
    encodeAlarmNotification({
      subscriptionId: 0x7a000001,
      creditTick: 1,
      sequence: 1,
      changeCounter: 1,
      alarmSubscriptionId: 0x7a000001,
      unexplained: 0,
      alarms: o.map(daiObject),
    });
  const subscription = encodeObject(alarmSubscriptionObject({ languages: [1033, 1031], creditLimit: 10 }));
  return [
    {
      name: 'S7+ alarm notification → PlcAlarms',
      seeds: [notification([DAI]), notification([DAI, { ...DAI, state: 'going' }]), notification([])],
      run: (b) => {
        for (const o of decodeAlarmNotification(b).alarms) toPlcAlarm(readDai(o), [1033]);
      },
    },
    {
      name: 'S7+ DAI object → PlcAlarm',
      seeds: [object, going],
      run: (b) => void toPlcAlarm(readDai(decodeObject(b).value)),
    },
    {
      name: 'S7+ alarm HMI info',
      seeds: [Buffer.from('0102000100000007050000000001020304', 'hex'), Buffer.from('010000010000000709', 'hex')],
      run: (b) => void decodeHmiInfo(b),
    },
    {
      name: 'S7+ associated value, placeholders',
      seeds: DAI.values
        .filter((v) => v.data.length > 0)
        .map((v) => Buffer.concat([Buffer.from(v.rootId.toString(16).padStart(8, '0'), 'hex'), v.data])),
      run: (b) => {
        if (b.length < 4) return;
        const value = decodeAssociatedValue({ rootId: b.readUInt32BE(0), data: b.subarray(4) });
        fillPlaceholders(b.toString('latin1'), [value, value]);
      },
    },
    {
      name: 'S7+ alarm subscription (simulator side)',
      seeds: [subscription],
      run: (b) => void readAlarmSubscription(decodeObject(b).value),
    },
  ];
}
