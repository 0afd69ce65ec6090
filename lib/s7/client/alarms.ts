/**
 * The classic alarms of an S7-300/400 CPU for S7Client (issue #33): the
 * active alarms (the alarm query, ALARM_S and ALARM_8 families, every part
 * of a multi-part answer), a subscription (the message service registering
 * ALM and, when asked, MODE and SYS; the CPU's pushes decoded in the order
 * it sent them; registered again after every reconnect, with the active
 * list read again and the difference reported `during: 'outage'`), and the
 * acknowledgement (an operator's write: ack-guard.ts decides before the
 * first byte; done when the CPU answers it). The frames: codec/alarms.ts.
 *
 * What the wire does not tell, said here once: an ALARM_D arrives as an
 * ALARM_S, an ALARM_DQ as an ALARM_SQ, an ALARM / ALARM_8P as an ALARM_8
 * (one push subfunction each); an alarm's kind read from the query alone is
 * its family's (ALARM_S, ALARM_8) until a push names it.
 */
import { ackRefusal } from '../../alarms/ack-guard';
import type { AlarmEvent, AlarmKind, AlarmSubscribeOptions, AlarmSubscription, PlcAlarm } from '../../alarms/model';
import { PlcError, ProtocolError } from '../../errors';
import type { RequestOptions } from '../../types';
import {
  AlarmRegistration,
  AlarmSubfunction,
  AlarmType,
  MessageEvents,
  decodeAckAnswer,
  decodeMessageServiceAnswer,
  encodeAckRequest,
  encodeMessageServiceRequest,
} from '../codec/alarms';
import { decodeQueryAnswer, encodeQueryRequest } from '../codec/alarm-query';
import type { UserdataPdu } from '../codec/userdata';
import { UserdataGroup } from '../constants';
import { S7AlarmSubscription } from './alarm-subscription';
import { ACK_KINDS, alarmValue, type AlarmClient } from './alarm-values';
import { ServiceTransport, type Service, type ServiceHost } from './service-transport';

const MESSAGE_SERVICE: Service = { group: UserdataGroup.Cpu, subfunction: AlarmSubfunction.MessageService };
const QUERY: Service = { group: UserdataGroup.Cpu, subfunction: AlarmSubfunction.Query };
const ACK: Service = { group: UserdataGroup.Cpu, subfunction: AlarmSubfunction.Ack };

/** The name the client registers with (8 characters on the wire). */
const USERNAME = 'plcwire';

export class S7Alarms extends ServiceTransport {
  /** Kinds learnt from pushes, by event id (the query tells only the family). */
  readonly kinds = new Map<number, AlarmKind>();

  constructor(
    host: ServiceHost,
    private readonly client: AlarmClient,
  ) {
    super(host);
  }

  /** Whether the client has a live session (to deregister on close). */
  get connected(): boolean {
    return this.host.current() !== undefined;
  }

  /** The refusal of a CPU without the classic alarm services, worded for the user. */
  private refused(err: unknown): unknown {
    if (!(err instanceof PlcError) || err.code !== 'NOT_SUPPORTED') return err;
    return new PlcError(
      'NOT_SUPPORTED',
      `${this.host.name} refuses the classic alarm services (S7-300/400 message service, alarm query): ${err.message}. ` +
        `S7-300/400 CPUs offer them, S7-200 and LOGO! have none, and an S7-1200/1500 reports its alarms over S7CommPlus: ` +
        `connect with s7plus://${this.host.endpoint.host}`,
      { cause: err, ...(err.plcCode !== undefined ? { plcCode: err.plcCode } : {}) },
    );
  }

  /** The alarms active now: coming, or gone but not yet acknowledged (the alarm query of both families). */
  async list(options: RequestOptions = {}): Promise<PlcAlarm[]> {
    const out: PlcAlarm[] = [];
    for (const type of [AlarmType.ALARM_S, AlarmType.ALARM_8]) {
      const what = `alarm query (${type === AlarmType.ALARM_S ? 'ALARM_S' : 'ALARM_8'})`;
      let first: UserdataPdu;
      try {
        first = await this.request(QUERY, what, options.signal, encodeQueryRequest(type));
      } catch (err) {
        // An S7-300 without the ALARM_8 family: its ALARM_S answer is the whole list.
        if (type === AlarmType.ALARM_8 && err instanceof PlcError && err.code === 'NOT_SUPPORTED') continue;
        throw this.refused(err);
      }
      const bytes = await this.allParts(first, QUERY, what, options.signal);
      let entries;
      try {
        entries = decodeQueryAnswer(bytes);
      } catch (err) {
        throw this.malformed(err);
      }
      for (const e of entries) {
        const kind = this.kinds.get(e.eventId) ?? (type === AlarmType.ALARM_S ? 'ALARM_S' : 'ALARM_8');
        const eight = type === AlarmType.ALARM_8;
        for (let i = 0; i < (eight ? 8 : 1); i++) {
          const bit = 1 << i;
          const acked = (e.ackComing & bit) !== 0 && (e.ackGoing & bit) !== 0;
          const coming = (e.eventState & bit) !== 0;
          if (!coming && acked) continue;
          const alarm: PlcAlarm = {
            id: e.eventId,
            kind,
            state: coming ? 'coming' : 'going',
            needsAck: !acked || ACK_KINDS.has(kind),
            acknowledged: acked,
            values: e.coming && e.coming.value.returnCode === 0xff ? [alarmValue(e.coming.value)] : [],
          };
          if (eight) alarm.signal = i + 1;
          if (e.coming) alarm.coming = e.coming.time;
          if (e.going && !coming) alarm.going = e.going.time;
          out.push(alarm);
        }
      }
    }
    return out;
  }

  /** Acknowledges alarm `id` (all its signals, or `signal8` of an 8-signal block); resolves when the CPU confirmed it. */
  async acknowledge(id: number, options: RequestOptions & { signal8?: number } = {}): Promise<void> {
    if (!Number.isInteger(id) || id < 0 || id > 0xffffffff)
      throw new PlcError('INVALID_VALUE', `an alarm id is 0..0xFFFFFFFF, got ${String(id)}`);
    const s8 = options.signal8;
    if (s8 !== undefined && !(Number.isInteger(s8) && s8 >= 1 && s8 <= 8)) {
      throw new PlcError('INVALID_VALUE', `signal8 is the signal 1..8 of an 8-signal block, got ${String(s8)}`);
    }
    const refusal = ackRefusal(id, this.host.endpoint.readOnly, this.host.endpoint.allow);
    if (refusal) throw refusal;
    const bits = s8 === undefined ? 0xff : 1 << (s8 - 1);
    const what = `acknowledge of alarm ${id}`;
    let u: UserdataPdu;
    try {
      u = await this.request(ACK, what, options.signal, encodeAckRequest([{ eventId: id, ackGoing: bits, ackComing: bits }]));
    } catch (err) {
      throw this.refused(err);
    }
    let results: number[];
    try {
      results = decodeAckAnswer(u.data);
      if (results.length !== 1) throw new ProtocolError(`the answer to ${what} has ${results.length} results, expected 1`);
    } catch (err) {
      throw this.malformed(err);
    }
    const r = results[0]!;
    if (r === 0xff) return;
    if (r === 0x0a)
      throw new PlcError('OBJECT_DOES_NOT_EXIST', `${this.host.name} ${what}: the CPU has no such alarm (0x0A)`, { plcCode: r });
    if (r === 0x03)
      throw new PlcError('ACCESS_DENIED', `${this.host.name} ${what}: the alarm needs no acknowledgement (0x03)`, { plcCode: r });
    throw new PlcError('PLC_ERROR', `${this.host.name} ${what}: the CPU answered 0x${r.toString(16).padStart(2, '0')}`, { plcCode: r });
  }

  /** What each live subscription registered for: the CPU is registered for all of it, and off when none is left. */
  private readonly wanted = new Map<object, number>();

  async registerFor(sub: object, events: number | undefined, signal?: AbortSignal): Promise<void> {
    if (events === undefined) this.wanted.delete(sub);
    else this.wanted.set(sub, events);
    let all = 0;
    for (const e of this.wanted.values()) all |= e;
    await this.register(all, signal);
  }

  /** Registers for (or, with 0 and the aborts, off) the CPU's pushes: ALM with both families, MODE and SYS as asked. */
  private async register(events: number, signal?: AbortSignal): Promise<void> {
    const on = events !== 0;
    const families = on
      ? [AlarmRegistration.ALARM_S_INITIATE, AlarmRegistration.ALARM_INITIATE]
      : [AlarmRegistration.ALARM_S_ABORT, AlarmRegistration.ALARM_ABORT];
    for (const alarms of families) {
      const data = encodeMessageServiceRequest({ events: events | MessageEvents.ALM, username: USERNAME, alarms });
      let u: UserdataPdu;
      try {
        u = await this.request(MESSAGE_SERVICE, 'alarm registration (message service)', signal, data);
      } catch (err) {
        throw this.refused(err);
      }
      try {
        decodeMessageServiceAnswer(u.data);
      } catch (err) {
        throw this.malformed(err);
      }
    }
  }

  /** Events in the order the CPU sent them (alarm-subscription.ts). */
  async subscribe(options: AlarmSubscribeOptions, listener: (e: AlarmEvent) => void): Promise<AlarmSubscription> {
    const sub = new S7AlarmSubscription(this, this.client, options);
    sub.on('event', listener);
    try {
      await sub.start();
    } catch (err) {
      await sub.close();
      throw err;
    }
    return sub;
  }
}
