/**
 * A live classic alarm subscription (S7Alarms.subscribe, alarms.ts): the
 * CPU's pushes decoded in the order it sent them and turned into events;
 * registered again after every reconnect, the active list read again and
 * what came or went meanwhile reported `during: 'outage'`.
 */
import { EventEmitter } from 'node:events';
import type { AlarmEvent, AlarmKind, AlarmSubscribeOptions, AlarmSubscription, AlarmValue, PlcAlarm } from '../../alarms/model';
import { ProtocolError, type PlcError } from '../../errors';
import type { RequestOptions } from '../../types';
import {
  AlarmSubfunction,
  MODE_NAMES,
  MODE_TRANSITION_GROUP,
  MessageEvents,
  decodeAckIndication,
  decodeAlarmIndication,
} from '../codec/alarms';
import { describeEvent } from '../codec/event-texts';
import { decodeUserdata } from '../codec/userdata';
import { UserdataGroup, UserdataType } from '../constants';
import { decodeDateAndTime } from '../../values/time';
import { ACK_KINDS, alarmKey, alarmValue, type AlarmClient } from './alarm-values';

/** What a subscription needs of the alarm service (S7Alarms): registration, the active list, the kinds pushes named. */
export interface AlarmService {
  readonly kinds: Map<number, AlarmKind>;
  readonly connected: boolean;
  /** Registers with the CPU for what every live subscription wants (`events` this one's; undefined: it closed). */
  registerFor(sub: object, events: number | undefined, signal?: AbortSignal): Promise<void>;
  list(options?: RequestOptions): Promise<PlcAlarm[]>;
}

/** The kind each push subfunction reports, and whether its block has 8 signals. */
const PUSH_KINDS: Readonly<Record<number, { kind: AlarmKind; eight: boolean }>> = {
  [AlarmSubfunction.AlarmS]: { kind: 'ALARM_S', eight: false },
  [AlarmSubfunction.AlarmSq]: { kind: 'ALARM_SQ', eight: false },
  [AlarmSubfunction.Alarm8]: { kind: 'ALARM_8', eight: true },
  [AlarmSubfunction.Notify]: { kind: 'NOTIFY', eight: false },
  [AlarmSubfunction.Notify8]: { kind: 'NOTIFY_8P', eight: true },
};

/** One alarm block as last reported: its signals' states. */
interface BlockState {
  kind: AlarmKind;
  eight: boolean;
  eventState: number;
  ackComing: number;
  ackGoing: number;
  /** Signals seen unacknowledged at least once: they need acknowledging. */
  needsAck: number;
  coming: Date[];
  going: Date[];
  acked: Date[];
  values: AlarmValue[];
}

export class S7AlarmSubscription extends EventEmitter implements AlarmSubscription {
  private readonly blocks = new Map<number, BlockState>();
  private current = new Map<string, PlcAlarm>();
  private unlisten: (() => void) | undefined;
  private closed = false;
  private readonly events: number;

  constructor(
    private readonly service: AlarmService,
    private readonly client: AlarmClient,
    private readonly options: AlarmSubscribeOptions,
  ) {
    super();
    this.events = MessageEvents.ALM | (options.mode ? MessageEvents.MODE : 0) | (options.diagnostics ? MessageEvents.SYS : 0);
  }

  /** EventEmitter's off, typed as AlarmSubscription declares it. */
  override off(event: string, listener: (...args: never[]) => void): this {
    return super.off(event, listener as (...args: unknown[]) => void);
  }

  get active(): readonly PlcAlarm[] {
    return [...this.current.values()];
  }

  async start(): Promise<void> {
    this.unlisten = this.client.pushes.listen(this.onPush);
    this.client.on('connected', this.onConnected);
    this.client.on('disconnected', this.onLost);
    await this.service.registerFor(this, this.events, this.options.signal);
    this.setActive(await this.service.list(this.options));
    this.emit('active');
  }

  private readonly onLost = (err: PlcError): void => {
    if (!this.closed && this.listenerCount('lost') > 0) this.emit('lost', err);
  };

  /** After a reconnect: registered again, the active list read again, what came or went meanwhile reported. */
  private readonly onConnected = (): void => {
    if (this.closed) return;
    void (async () => {
      await this.service.registerFor(this, this.events, this.options.signal);
      const now = await this.service.list(this.options);
      if (this.closed) return;
      const at = new Date();
      const before = this.current;
      this.setActive(now);
      for (const [key, alarm] of this.current) {
        const was = before.get(key);
        if (!was || was.state !== alarm.state || (alarm.coming?.getTime() ?? 0) !== (was.coming?.getTime() ?? 0)) {
          this.emit('event', { type: 'alarm', change: alarm.state, alarm, at, during: 'outage' } satisfies AlarmEvent);
        }
      }
      for (const [key, was] of before) {
        if (this.current.has(key) || was.state === 'going') continue;
        this.emit('event', {
          type: 'alarm',
          change: 'going',
          alarm: { ...was, state: 'going' },
          at,
          during: 'outage',
        } satisfies AlarmEvent);
      }
      this.emit('active');
    })().catch((err: unknown) => {
      if (!this.closed && this.listenerCount('error') > 0) this.emit('error', err);
    });
  };

  private setActive(list: readonly PlcAlarm[]): void {
    this.current = new Map(list.map((a) => [alarmKey(a), a]));
    for (const a of list) {
      const b = this.block(a.id, a.kind, a.signal !== undefined);
      const bit = 1 << ((a.signal ?? 1) - 1);
      b.eventState = a.state === 'coming' ? b.eventState | bit : b.eventState & ~bit;
      if (!a.acknowledged) {
        b.ackComing &= ~bit;
        b.needsAck |= bit;
      }
    }
  }

  private block(id: number, kind: AlarmKind, eight: boolean): BlockState {
    let b = this.blocks.get(id);
    if (!b) {
      b = { kind, eight, eventState: 0, ackComing: 0xff, ackGoing: 0xff, needsAck: 0, coming: [], going: [], acked: [], values: [] };
      this.blocks.set(id, b);
    }
    return b;
  }

  /** A pushed PDU: decoded, turned into events in the order the CPU sent them. */
  private readonly onPush = (frame: Buffer): void => {
    if (this.closed) return;
    const u = decodeUserdata(frame);
    const { group, subfunction, type } = u.params;
    if (type !== UserdataType.Push) return;
    if (group === MODE_TRANSITION_GROUP) {
      if (this.options.mode)
        this.emit('event', { type: 'mode', to: MODE_NAMES[subfunction] ?? `mode 0x${subfunction.toString(16)}`, at: new Date() });
      return;
    }
    if (group !== UserdataGroup.Cpu) return;
    if (subfunction === AlarmSubfunction.DiagnosticMessage) return this.diagnostic(u.data);
    if (subfunction === AlarmSubfunction.AckIndication) return this.acked(u.data);
    const kind = PUSH_KINDS[subfunction];
    if (kind) this.indication(kind.kind, kind.eight, u.data);
  };

  private diagnostic(d: Buffer): void {
    if (!this.options.diagnostics) return;
    if (d.length !== 20) throw new ProtocolError(`diagnostic message of ${d.length} bytes, expected 20`);
    const id = d.readUInt16BE(0);
    const time = decodeDateAndTime(d, 12);
    const text = describeEvent(id);
    this.emit('event', { type: 'diagnostic', id, text, at: Number.isNaN(time.getTime()) ? new Date() : time, raw: d.toString('hex') });
  }

  private indication(kind: AlarmKind, eight: boolean, data: Buffer): void {
    const ind = decodeAlarmIndication(data);
    for (const ob of ind.objects) {
      this.service.kinds.set(ob.eventId, kind);
      const b = this.block(ob.eventId, kind, eight);
      b.kind = kind;
      const changed = b.eventState ^ ob.eventState;
      b.eventState = ob.eventState;
      b.ackComing = ob.ackComing;
      b.ackGoing = ob.ackGoing;
      b.values = ob.values.map(alarmValue);
      // Unknown before and nothing changed (a going of an alarm never seen): its first signal went.
      const bits = changed !== 0 ? changed : ob.eventState === 0 ? 1 : 0;
      for (let i = 0; i < (eight ? 8 : 1); i++) {
        const bit = 1 << i;
        if (!(bits & bit)) continue;
        const coming = (ob.eventState & bit) !== 0;
        if (coming) {
          b.coming[i] = ind.time;
          if (!(ob.ackComing & bit)) b.needsAck |= bit;
        } else {
          b.going[i] = ind.time;
          if (!(ob.ackGoing & bit)) b.needsAck |= bit;
        }
        const alarm = this.alarm(ob.eventId, b, i);
        this.track(alarm);
        this.emit('event', { type: 'alarm', change: coming ? 'coming' : 'going', alarm, at: ind.time });
      }
    }
  }

  private acked(data: Buffer): void {
    const ind = decodeAckIndication(data);
    for (const ob of ind.objects) {
      const b = this.blocks.get(ob.eventId);
      if (!b) continue;
      const newly = (ob.ackComing & ~b.ackComing) | (ob.ackGoing & ~b.ackGoing);
      b.ackComing = ob.ackComing;
      b.ackGoing = ob.ackGoing;
      for (let i = 0; i < (b.eight ? 8 : 1); i++) {
        if (!(newly & (1 << i))) continue;
        b.acked[i] = ind.time;
        const alarm = this.alarm(ob.eventId, b, i);
        this.track(alarm);
        this.emit('event', { type: 'alarm', change: 'acknowledged', alarm, at: ind.time });
      }
    }
  }

  /** Signal `i` of a block as a PlcAlarm. */
  private alarm(id: number, b: BlockState, i: number): PlcAlarm {
    const bit = 1 << i;
    const acknowledged = (b.ackComing & bit) !== 0 && (b.ackGoing & bit) !== 0;
    const coming = (b.eventState & bit) !== 0;
    const alarm: PlcAlarm = {
      id,
      kind: b.kind,
      state: coming ? 'coming' : 'going',
      needsAck: (b.needsAck & bit) !== 0 || ACK_KINDS.has(b.kind),
      acknowledged,
      values: b.values,
    };
    if (b.eight) alarm.signal = i + 1;
    if (b.coming[i]) alarm.coming = b.coming[i];
    if (b.going[i] && !coming) alarm.going = b.going[i];
    if (b.acked[i] && acknowledged) alarm.acked = b.acked[i];
    return alarm;
  }

  /** Keeps `active` as the CPU's query would answer it: coming, or not yet acknowledged. */
  private track(alarm: PlcAlarm): void {
    if (alarm.state === 'coming' || !alarm.acknowledged) this.current.set(alarmKey(alarm), alarm);
    else this.current.delete(alarmKey(alarm));
  }

  async close(): Promise<void> {
    if (this.closed) return;
    this.closed = true;
    this.unlisten?.();
    this.client.off('connected', this.onConnected);
    this.client.off('disconnected', this.onLost);
    // Best effort: the CPU forgets a closed connection's registrations anyway.
    if (this.service.connected) await this.service.registerFor(this, undefined).catch(() => undefined);
  }
}
