/**
 * What both halves of the classic alarm client (alarms.ts, alarm-subscription.ts)
 * share: the client they need, which kinds need acknowledging, how an
 * associated value reads, and an alarm's key in an active list.
 */
import type { AlarmKind, AlarmValue, PlcAlarm } from '../../alarms/model';
import type { TypedEvents } from '../../client/events';
import type { ClientEvents } from '../../types';
import type { AssociatedValue } from '../codec/alarms';
import { DataTransportSize } from '../constants';
import type { PushHub } from './pushes';

/** Kinds whose blocks need acknowledging (SFC 17/107 and SFB 33–35; ALARM_S/D and the NOTIFYs do not). */
export const ACK_KINDS: ReadonlySet<AlarmKind> = new Set(['ALARM_SQ', 'ALARM_DQ', 'ALARM', 'ALARM_8', 'ALARM_8P']);

/** What the alarm service needs of S7Client besides the service host: its pushes and its link events. */
export type AlarmClient = Pick<TypedEvents<ClientEvents>, 'on' | 'off'> & { readonly pushes: PushHub };

/** An associated value by its transport size and length. */
export function alarmValue(v: AssociatedValue): AlarmValue {
  const d = v.data;
  switch (v.transportSize) {
    case DataTransportSize.BIT:
      return { type: 'BOOL', value: (d[0]! & 1) === 1 };
    case DataTransportSize.BYTE:
      if (d.length === 1) return { type: 'BYTE', value: d[0]! };
      if (d.length === 2) return { type: 'WORD', value: d.readUInt16BE(0) };
      if (d.length === 4) return { type: 'DWORD', value: d.readUInt32BE(0) };
      break;
    case DataTransportSize.INTEGER:
      if (d.length === 2) return { type: 'INT', value: d.readInt16BE(0) };
      if (d.length === 4) return { type: 'DINT', value: d.readInt32BE(0) };
      break;
    case DataTransportSize.REAL:
      if (d.length === 4) return { type: 'REAL', value: d.readFloatBE(0) };
      if (d.length === 8) return { type: 'LREAL', value: d.readDoubleBE(0) };
      break;
    default:
      break;
  }
  return { type: 'BYTES', value: [...d] };
}

/** An alarm's key in an active list: its id and signal. */
export function alarmKey(a: PlcAlarm): string {
  return `${a.id}:${a.signal ?? 0}`;
}
