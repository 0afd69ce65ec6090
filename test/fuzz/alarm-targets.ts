/** Fuzz targets of the classic alarm decoders (lib/s7/codec/alarms.ts, alarm-query.ts) and the simulator's alarm services (issue #33). */
import type { AlarmDefinition } from '../../lib/alarms/model';
import { decodeQueryAnswer, decodeQueryRequest, encodeQueryAnswer, encodeQueryRequest } from '../../lib/s7/codec/alarm-query';
import {
  decodeAckAnswer,
  decodeAckIndication,
  decodeAckRequest,
  decodeAlarmIndication,
  decodeMessageServiceAnswer,
  decodeMessageServiceRequest,
  encodeAckAnswer,
  encodeAckIndication,
  encodeAckRequest,
  encodeAlarmIndication,
  encodeMessageServiceAnswer,
  encodeMessageServiceRequest,
} from '../../lib/s7/codec/alarms';
import { encodeUserdataRequest } from '../../lib/s7/codec/userdata';
import { IDENTITIES } from '../../lib/s7/server/profiles';
import { CpuServices, newServiceSession } from '../../lib/s7/server/services';
import { PlcMemory } from '../../lib/sim/memory';
import type { FuzzTarget } from './engine';

const T = new Date(Date.UTC(2024, 4, 3, 10, 11, 12, 345));
const value = (ts: number, hex: string) => ({ returnCode: 0xff, transportSize: ts, data: Buffer.from(hex, 'hex') });

function indicationSeeds(): Buffer[] {
  const base = { eventId: 0x60000001, eventState: 1, localState: 0, ackGoing: 0xff, ackComing: 0xfe };
  return [
    encodeAlarmIndication({
      time: T,
      objects: [{ ...base, syntaxId: 0x16, values: [value(5, '0102'), value(7, '41200000'), value(4, '07')] }],
    }),
    encodeAlarmIndication({
      time: T,
      objects: [{ ...base, syntaxId: 0x1c, notify: { going: 0, coming: 1, lastChanged: 1 }, values: [value(3, '01')] }],
    }),
    encodeAlarmIndication({
      time: T,
      objects: [
        { ...base, syntaxId: 0x16, values: [] },
        { ...base, syntaxId: 0x16, values: [value(9, 'aabbcc')] },
      ],
    }),
  ];
}

export function alarmTargets(): FuzzTarget[] {
  const defs: AlarmDefinition[] = [
    { id: 1, kind: 'ALARM_SQ', texts: { en: 'a' }, needsAck: true, trigger: 'M0.0', values: ['MW2:INT'] },
    { id: 2, kind: 'ALARM_8', signal: 2, texts: { en: 'b' }, needsAck: true, trigger: 'M0.1' },
  ];
  const memory = new PlcMemory();
  const cpu = new CpuServices(memory, IDENTITIES['s7-300'], { maxConnections: 8, alarms: defs });
  const peer = { write: () => true, destroyed: false };
  memory.writeBit('M', 0, 0, 0, true);
  return [
    {
      name: 'S7 alarm indication',
      seeds: indicationSeeds(),
      run: (b) => void decodeAlarmIndication(b),
    },
    {
      name: 'S7 message service',
      seeds: [
        encodeMessageServiceRequest({ events: 0x83, username: 'plcwire', alarms: 9 }),
        encodeMessageServiceAnswer({ result: 2, alarmType: 9 }),
        encodeMessageServiceAnswer({ result: 2 }),
      ],
      run: (b) => {
        decodeMessageServiceRequest(b);
        decodeMessageServiceAnswer(b);
      },
    },
    {
      name: 'S7 alarm ack / ack indication',
      seeds: [
        encodeAckRequest([{ eventId: 1, ackGoing: 0, ackComing: 1 }]),
        encodeAckAnswer([0xff, 0x0a]),
        encodeAckIndication({ time: T, objects: [{ eventId: 1, ackGoing: 0xff, ackComing: 0xff }] }),
      ],
      run: (b) => {
        decodeAckRequest(b);
        decodeAckAnswer(b);
        decodeAckIndication(b);
      },
    },
    {
      name: 'S7 alarm query',
      seeds: [
        encodeQueryRequest(4),
        encodeQueryAnswer([
          { alarmType: 4, eventId: 1, eventState: 1, ackGoing: 0xff, ackComing: 0xfe, coming: { time: T, value: value(5, '0102') } },
          { alarmType: 4, eventId: 2, eventState: 0, ackGoing: 0xff, ackComing: 0xff, going: { time: T, value: value(9, 'aa') } },
        ]),
      ],
      run: (b) => {
        decodeQueryRequest(b);
        decodeQueryAnswer(b);
      },
    },
    {
      name: 'S7 simulator alarm services',
      seeds: [
        encodeUserdataRequest(4, 2, encodeMessageServiceRequest({ events: 0x83, username: 'plcwire', alarms: 9 })),
        encodeUserdataRequest(4, 0x13, encodeQueryRequest(4)),
        encodeUserdataRequest(4, 0x0b, encodeAckRequest([{ eventId: 1, ackGoing: 0, ackComing: 1 }])),
      ],
      run: (b) => void cpu.serveUserdata(b, newServiceSession(peer), 240),
    },
  ];
}
