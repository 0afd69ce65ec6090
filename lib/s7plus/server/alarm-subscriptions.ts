/**
 * The alarm subscriptions of one session: the client's CreateObject of a
 * Subscription with an AlarmSubscriptionRef child (codec/alarms.ts), then a
 * notification for each alarm that comes or goes, its texts in the languages
 * asked for, while the client's credits last (SetVariable of the credit
 * limit gives more, as for data subscriptions); what comes meanwhile waits,
 * in order. DeleteObject of the container ends them with the data ones.
 * Changes that wait go out together, several alarm objects in one
 * notification. Layouts: s7commplus (MIT) alarm.py; credits: connection.py
 * send_subscription_credit.
 */
import { ProtocolError } from '../../errors';
import { daiObject, encodeAlarmNotification, type Dai } from '../codec/alarms';
import { encodeObject, type PObject } from '../codec/object';
import { S7P_PROTOCOL_ID } from '../constants';
import type { AlarmSubsystem } from './alarms';

/** Alarm subscriptions one session may hold. */
const MAX_ALARM_SUBSCRIPTIONS = 4;
/** Changes kept for a subscription out of credits; older ones are dropped (the client's re-read of the active list shows the state). */
const MAX_WAITING = 10_000;
/** The largest frame the simulator sends (its length field has 16 bits). */
const MAX_FRAME_DATA = 0xffff;
/** A notification's bytes besides its alarm objects (head, sequence, value list end, alarm subscription id, fill). */
const NOTIFICATION_HEAD = 32;
/** Changes one notification carries at most (a notification holds a list of alarm objects: alarm.py parse_alarm_notification). */
const MAX_PER_NOTIFICATION = 100;

interface AlarmSub {
  readonly id: number;
  readonly languages: readonly number[];
  readonly sendTexts: boolean;
  limit: number;
  tick: number;
  sequence: number;
  readonly waiting: Dai[];
  readonly stop: () => void;
}

export class AlarmSubscriptions {
  private readonly active = new Map<number, AlarmSub>();
  /** Alarm subscription ids start so: their first byte is not 0, which a notification's reader takes for "no alarms" (alarm.py). */
  private nextId = 0x7a000001;

  constructor(
    private readonly alarms: AlarmSubsystem,
    private readonly push: (frame: Buffer) => void,
    private readonly version: number,
  ) {}

  create(spec: { languages: number[]; sendTexts: boolean; creditLimit: number }): number {
    if (this.active.size >= MAX_ALARM_SUBSCRIPTIONS)
      throw new ProtocolError(`more than ${MAX_ALARM_SUBSCRIPTIONS} alarm subscriptions in one session`);
    const id = this.nextId++;
    const sub: AlarmSub = {
      id,
      languages: spec.languages,
      sendTexts: spec.sendTexts,
      limit: spec.creditLimit,
      tick: 0,
      sequence: 0,
      waiting: [],
      stop: this.alarms.subscribe((dai) => this.changed(sub, dai)),
    };
    this.active.set(id, sub);
    return id;
  }

  has(id: number): boolean {
    return this.active.has(id);
  }

  /** SetVariable of an alarm subscription's credit limit: what waited goes out. */
  setCredit(id: number, limit: number): void {
    const sub = this.active.get(id);
    if (!sub) return;
    sub.limit = limit;
    this.flush(sub);
  }

  clear(): void {
    for (const s of this.active.values()) s.stop();
    this.active.clear();
  }

  private changed(sub: AlarmSub, dai: Dai): void {
    if (sub.waiting.push(dai) > MAX_WAITING) sub.waiting.shift();
    this.flush(sub);
  }

  /** What waits goes out while credits last: as many changes per notification as fit one frame (its alarm list). */
  private flush(sub: AlarmSub): void {
    while (sub.waiting.length > 0 && this.active.has(sub.id)) {
      if (sub.limit >= 0 && sub.tick === sub.limit) return;
      const objects: PObject[] = [];
      let bytes = NOTIFICATION_HEAD;
      while (sub.waiting.length > 0 && objects.length < MAX_PER_NOTIFICATION) {
        const object = daiObject(this.inLanguages(sub, sub.waiting[0]!));
        const size = encodeObject(object).length;
        if (objects.length > 0 && bytes + size > MAX_FRAME_DATA) break;
        objects.push(object);
        bytes += size;
        sub.waiting.shift();
      }
      sub.tick = (sub.tick + 1) % 255;
      sub.sequence = (sub.sequence + 1) >>> 0;
      const data = encodeAlarmNotification({
        subscriptionId: sub.id,
        creditTick: sub.tick,
        sequence: sub.sequence,
        changeCounter: 1,
        alarmSubscriptionId: sub.id,
        unexplained: 0,
        alarms: objects,
      });
      if (data.length > MAX_FRAME_DATA) throw new ProtocolError(`an alarm notification of ${data.length} bytes`);
      const head = Buffer.from([S7P_PROTOCOL_ID, this.version, data.length >> 8, data.length & 0xff]);
      this.push(Buffer.concat([head, data, Buffer.from([S7P_PROTOCOL_ID, this.version, 0, 0])]));
    }
  }

  /** The DAI with the texts the subscription asked for: none without send texts, the languages named (all when none). */
  private inLanguages(sub: AlarmSub, dai: Dai): Dai {
    if (!sub.sendTexts) return { ...dai, texts: new Map() };
    if (sub.languages.length === 0) return dai;
    return { ...dai, texts: new Map([...dai.texts].filter(([key]) => sub.languages.includes(key >>> 16))) };
  }
}
