/**
 * Program_Alarms of an S7-1200/1500 (issue #33): the active-alarm list (an
 * Explore of the alarm subsystem) and the alarm subscription, which lives on
 * a session of its own as the data subscriptions do (push.ts: nothing is
 * written on it), kept by its own supervisor. On each new session the alarm
 * subscription is created again and the active list read again: what came
 * or went while the link was down is reported as events `during: 'outage'`;
 * notifications that the list already shows (by the alarm's sequence
 * counter) are not reported twice. Credits are renewed as for data
 * subscriptions. Layouts: codec/alarms.ts; the credit rule: s7commplus (MIT)
 * subscription.py SubscriptionRegistry.route.
 */
import { EventEmitter } from 'node:events';
import type { AlarmEvent, AlarmSubscribeOptions, AlarmSubscription, PlcAlarm } from '../../alarms/model';
import { PlcError, toPlcError } from '../../errors';
import type { LinkSupervisor } from '../../link/supervisor';
import { lcidOf, toPlcAlarm } from '../codec/alarm-texts';
import { alarmExploreBody, alarmSubscriptionObject, decodeAlarmNotification, readDai, type AlarmNotification } from '../codec/alarms';
import { decodeExploreResponse, encodeExploreRequest, type ExploreRequest, type ExploreResponse } from '../codec/explore';
import { FunctionCode, Ids, ProtocolVersion, serviceResultCode } from '../constants';
import { subscriptionCreateAsk, subscriptionDeleteAsk } from './asks';
import {
  CREDIT_LIMIT,
  GOODBYE_MS,
  creditRunningOut,
  grantCredit,
  pushedSessionSupervisor,
  type PushedSessionWiring,
} from './pushed-session';
import type { Ask, S7PlusSession } from './session';

/** Notifications kept while the subscription's CreateObject answer is awaited. */
const MAX_EARLY = 10_000;

/** The Explore of the active alarms (alarm.py build_alarm_explore_request). */
function alarmExploreAsk(): Ask<ExploreRequest, ExploreResponse> {
  return { functionCode: FunctionCode.Explore, body: alarmExploreBody(), encode: encodeExploreRequest, decode: decodeExploreResponse };
}

/** The LCIDs of `languages` (`en-US`, `de`, or LCIDs as text); a language TIA does not have is a clear error. */
export function languageIds(languages: readonly string[] | undefined): number[] {
  return (languages ?? []).map((l) => {
    const id = lcidOf(l);
    if (id === undefined)
      throw new PlcError(
        'INVALID_VALUE',
        `alarm text language ${JSON.stringify(l)}: not one of TIA's (en-US, de-DE, fr-FR, … or a Windows LCID)`,
      );
    return id;
  });
}

/** The alarms active now on `session`, each with the sequence counter of its last change. */
async function activeDais(
  session: S7PlusSession,
  languages: readonly number[],
  signal?: AbortSignal,
): Promise<{ alarm: PlcAlarm; sequence: number }[]> {
  const body = await session.request(alarmExploreAsk(), signal ? { signal } : {});
  if (body.returnValue !== 0n)
    throw new PlcError('PLC_ERROR', `the PLC refused to tell its active alarms (0x${body.returnValue.toString(16)})`, {
      plcCode: serviceResultCode(body.returnValue),
    });
  return body.objects
    .filter((o) => o.classId === Ids.AlarmDaiClassRid)
    .map((o) => {
      const dai = readDai(o);
      return { alarm: toPlcAlarm(dai, languages), sequence: dai.sequenceCounter };
    });
}

/** The alarms active now on `session`, as PlcAlarms with the texts of `languages` (LCIDs; none: every language). */
export async function activeAlarms(session: S7PlusSession, languages: readonly number[], signal?: AbortSignal): Promise<PlcAlarm[]> {
  return (await activeDais(session, languages, signal)).map((k) => k.alarm);
}

export type AlarmWiring = PushedSessionWiring;

/** The alarms known active, by id, with the sequence counter of their last change. */
type Known = Map<number, { alarm: PlcAlarm; sequence: number }>;

export class S7PlusAlarmSubscription extends EventEmitter implements AlarmSubscription {
  private readonly supervisor: LinkSupervisor<S7PlusSession>;
  private readonly languages: number[];
  private known: Known = new Map();
  private live: { session: S7PlusSession; id: number; credit: number } | undefined;
  /** Notifications that came before the subscription's id (and the active list) was known, in order. */
  private early: AlarmNotification[] = [];
  private synced = false;
  private everSynced = false;
  private closed = false;
  private ending: Promise<void> = Promise.resolve();

  constructor(
    private readonly wiring: AlarmWiring,
    options: AlarmSubscribeOptions,
  ) {
    super();
    this.languages = languageIds(options.languages);
    this.supervisor = pushedSessionSupervisor(wiring, 'alarms', this, (data) => this.route(data));
    this.on('connected', () => void this.sync());
    this.on('disconnected', (err: PlcError) => this.gone(err));
    // The supervisor emits 'error' for what it cannot recover from; an application without a listener must not crash.
    this.on('error', () => {});
  }

  override off(event: string | symbol, listener: (...args: never[]) => void): this {
    return super.off(event, listener as (...args: unknown[]) => void);
  }

  get active(): readonly PlcAlarm[] {
    return [...this.known.values()].map((k) => k.alarm);
  }

  /** Opens the session and creates the subscription; rejects (and ends) when the first attempt fails. */
  async start(): Promise<void> {
    const first = new Promise<void>((resolve, reject) => {
      const ok = () => {
        this.off('failed', ko);
        resolve();
      };
      const ko = (err: PlcError) => {
        this.off('active', ok);
        reject(err);
      };
      this.once('active', ok);
      this.once('failed', ko);
    });
    this.supervisor.connectOnce().catch((err: unknown) => this.emit('failed', toPlcError(err, 'CONNECT_FAILED')));
    try {
      await first;
    } catch (err) {
      await this.close();
      throw err;
    }
  }

  /** On a new session: the subscription created, the active list read, the difference reported, what came meanwhile after it. */
  private async sync(): Promise<void> {
    const session = this.supervisor.session;
    if (!session || this.closed) return;
    try {
      if (session.subscriptionContainerId === 0)
        throw new PlcError('NOT_SUPPORTED', `${this.wiring.name} offers no subscription container: it cannot report alarms`);
      const object = alarmSubscriptionObject({ languages: this.languages, creditLimit: CREDIT_LIMIT });
      const created = await session.request(subscriptionCreateAsk(session.subscriptionContainerId, object));
      const id = created.objectIds[0];
      if (created.returnValue !== 0n || id === undefined)
        throw new PlcError('PLC_ERROR', `${this.wiring.name} refused the alarm subscription (0x${created.returnValue.toString(16)})`, {
          plcCode: Number(created.returnValue & 0xffffn),
        });
      this.live = { session, id, credit: CREDIT_LIMIT };
      const list = await activeDais(session, this.languages);
      if (session !== this.supervisor.session || this.closed) return;
      this.difference(list);
      this.synced = true;
      const early = this.early;
      this.early = [];
      for (const n of early) this.deliver(n);
      this.everSynced = true;
      this.emit('active');
    } catch (err) {
      const e = toPlcError(err, 'PROTOCOL_ERROR');
      if (!session.alive) return; // a lost link: the supervisor reconnects and this runs again
      if (!this.everSynced) this.emit('failed', e);
      else this.emit('error', e);
    }
  }

  /** The active list read on a new session against what was known: after an outage, what came and went meanwhile. */
  private difference(list: { alarm: PlcAlarm; sequence: number }[]): void {
    const now = new Map(list.map((k) => [k.alarm.id, k]));
    const report = this.everSynced;
    const at = new Date();
    if (report) {
      for (const [id, k] of this.known)
        if (!now.has(id)) this.send({ type: 'alarm', change: 'going', alarm: { ...k.alarm, state: 'going' }, at, during: 'outage' });
    }
    const next: Known = new Map();
    for (const k of list) {
      const before = this.known.get(k.alarm.id);
      next.set(k.alarm.id, k);
      if (report && (!before || before.sequence !== k.sequence))
        this.send({ type: 'alarm', change: 'coming', alarm: k.alarm, at, during: 'outage' });
    }
    this.known = next;
  }

  private route(data: Buffer): void {
    let n: AlarmNotification;
    try {
      n = decodeAlarmNotification(data);
    } catch (err) {
      const session = this.supervisor.session;
      if (session) this.supervisor.lost(session, toPlcError(err, 'PROTOCOL_ERROR'));
      return;
    }
    if (!this.synced) {
      if (this.early.push(n) > MAX_EARLY) this.early.shift();
      return;
    }
    this.deliver(n);
  }

  private deliver(n: AlarmNotification): void {
    const live = this.live;
    if (!live || n.subscriptionId !== live.id) return;
    for (const o of n.alarms) {
      if (o.classId !== Ids.AlarmDaiClassRid) continue;
      const dai = readDai(o);
      this.apply(toPlcAlarm(dai, this.languages), dai.sequenceCounter);
    }
    if (creditRunningOut(live.credit, n.creditTick)) this.grant(live);
  }

  /** One alarm change: the known list updated, the event sent (once: a change the active list already showed is not sent again). */
  private apply(alarm: PlcAlarm, sequence: number): void {
    const before = this.known.get(alarm.id);
    if (before && before.sequence === sequence && before.alarm.state === alarm.state && before.alarm.acknowledged === alarm.acknowledged)
      return;
    const at = alarm[alarm.state] ?? new Date();
    if (alarm.state === 'coming') {
      this.known.set(alarm.id, { alarm, sequence });
      const change = before && before.sequence === sequence && !before.alarm.acknowledged && alarm.acknowledged ? 'acknowledged' : 'coming';
      this.send({ type: 'alarm', change, alarm, at: change === 'acknowledged' ? (alarm.acked ?? at) : at });
    } else {
      this.known.delete(alarm.id);
      this.send({ type: 'alarm', change: 'going', alarm, at });
    }
  }

  private send(e: AlarmEvent): void {
    try {
      this.emit('event', e);
    } catch (err) {
      // A listener's own error is the application's, not the PLC's.
      process.nextTick(() => {
        throw err;
      });
    }
  }

  private grant(live: { session: S7PlusSession; id: number; credit: number }): void {
    if (!live.session.alive) return;
    live.credit = grantCredit(live.session, live.id, live.credit);
  }

  private gone(err: PlcError): void {
    this.live = undefined;
    this.synced = false;
    this.early = [];
    if (this.everSynced && !this.closed) this.emit('lost', err);
  }

  /** Ends the subscription and its session. Always resolves. */
  close(): Promise<void> {
    if (this.closed) return this.ending;
    this.closed = true;
    this.ending = this.goodbye();
    return this.ending;
  }

  private async goodbye(): Promise<void> {
    const session = this.supervisor.session;
    if (session?.alive) {
      const ac = new AbortController();
      const timer = setTimeout(() => ac.abort(), Math.min(this.wiring.timeout, GOODBYE_MS));
      try {
        await session.request(subscriptionDeleteAsk(session.subscriptionContainerId, session.version === ProtocolVersion.V1), {
          signal: ac.signal,
        });
      } catch {
        // The link went meanwhile: nothing to end on the PLC.
      } finally {
        clearTimeout(timer);
      }
      await session.goodbye(Math.min(this.wiring.timeout, GOODBYE_MS));
    }
    await this.supervisor.close();
    this.live = undefined;
  }
}
