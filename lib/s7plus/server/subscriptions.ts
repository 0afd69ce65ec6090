/**
 * Subscriptions of one session, as a CPU keeps them: the client's
 * CreateObject of a Subscription object under the session's container
 * (its reference list names the items, its cycle time the sampling), a
 * notification at each cycle in which a value changed (the first with every
 * value), while the client's credits last; SetVariable of the credit limit
 * gives more; DeleteObject of the container ends them all. Layouts:
 * s7commplus (MIT) subscription.py (build_subscription_request,
 * parse_subscription_notification) and connection.py send_subscription_credit.
 */
import { ProtocolError } from '../../errors';
import { Reader } from '../codec/bytes';
import { skipPValue } from '../codec/pvalue';
import { encodeUVlq32 } from '../codec/vlq';
import { ElementId, Ids, NotificationRecord, Opcode, S7P_PROTOCOL_ID } from '../constants';
import { itemValue, type CpuSide } from './services';

/** The shortest cycle the simulator samples at (a CPU's own minimum is not public; this keeps a hostile request from spinning it). */
const MIN_CYCLE_MS = 10;
/** Subscriptions one session may hold. */
const MAX_SUBSCRIPTIONS = 20;
/** Items one subscription may hold. */
const MAX_ITEMS = 1000;

interface Item {
  readonly reference: number;
  readonly area: number;
  readonly subArea: number;
  readonly lids: readonly number[];
}

interface Subscription {
  readonly id: number;
  readonly changeCounter: number;
  readonly items: readonly Item[];
  readonly timer: NodeJS.Timeout;
  /** Credit limit: notifications stop when the tick reaches it; -1 unlimited. */
  limit: number;
  tick: number;
  sequence: number;
  last: (Buffer | undefined)[] | undefined;
}

export class Subscriptions {
  private readonly active = new Map<number, Subscription>();
  private nextId = 0x70000001;

  constructor(
    private readonly cpu: CpuSide,
    /** Sends a notification frame to the client. */
    private readonly push: (frame: Buffer) => void,
    private readonly version: number,
  ) {}

  /** CreateObject of a Subscription (the body after the integrity id): its object id. */
  create(object: Buffer): number {
    if (this.active.size >= MAX_SUBSCRIPTIONS) throw new ProtocolError(`more than ${MAX_SUBSCRIPTIONS} subscriptions in one session`);
    const r = new Reader(object);
    if (r.u8('the subscription object') !== ElementId.StartOfObject) throw new ProtocolError('S7CommPlus CreateObject without an object');
    r.u32('the relation id');
    if (r.uvlq32() !== Ids.ClassSubscription) throw new ProtocolError('S7CommPlus CreateObject of a class the simulator does not create');
    r.uvlq32();
    r.uvlq32();
    let items: Item[] | undefined;
    let changeCounter = 0;
    let cycle = 100;
    let limit = -1;
    while (r.peek() === ElementId.Attribute) {
      r.u8();
      const id = r.uvlq32();
      if (id === Ids.SubscriptionReferenceList) ({ items, changeCounter } = referenceList(r));
      else if (id === Ids.SubscriptionCycleTime) cycle = scalarUDInt(r);
      else if (id === Ids.SubscriptionCreditLimit) limit = scalarInt(r);
      else r.offset = skipPValue(r.buf, r.offset);
    }
    if (!items || items.length === 0) throw new ProtocolError('S7CommPlus subscription without a reference list');
    const id = this.nextId++;
    const sub: Subscription = {
      id,
      changeCounter,
      items,
      limit,
      tick: 0,
      sequence: 0,
      last: undefined,
      timer: setInterval(() => this.sample(sub), Math.max(MIN_CYCLE_MS, cycle)),
    };
    this.active.set(id, sub);
    setImmediate(() => this.sample(sub));
    return id;
  }

  /** SetVariable of a subscription's credit limit. */
  setCredit(id: number, limit: number): void {
    const sub = this.active.get(id);
    if (!sub) return;
    sub.limit = limit;
    this.sample(sub);
  }

  /** Ends every subscription (DeleteObject of the container, the session's end). */
  clear(): void {
    for (const s of this.active.values()) clearInterval(s.timer);
    this.active.clear();
  }

  /** A cycle: the values now; a notification when one changed since the last, while credits last. */
  private sample(sub: Subscription): void {
    if (!this.active.has(sub.id)) return;
    if (sub.limit >= 0 && sub.tick === sub.limit) return;
    const values = sub.items.map((it) => itemValue(this.cpu, it));
    const last = sub.last;
    if (last && values.every((v, i) => (v === undefined ? last[i] === undefined : last[i] !== undefined && v.equals(last[i])))) return;
    sub.last = values;
    sub.tick = (sub.tick + 1) % 255;
    sub.sequence++;
    const records: Buffer[] = [];
    values.forEach((v, i) => {
      const ref = Buffer.alloc(4);
      ref.writeUInt32BE(sub.items[i]!.reference);
      records.push(
        v
          ? Buffer.concat([Buffer.from([NotificationRecord.Value]), ref, v])
          : Buffer.concat([Buffer.from([NotificationRecord.Error]), ref]),
      );
    });
    const head = Buffer.alloc(12);
    head[0] = Opcode.Notification;
    head.writeUInt32BE(sub.id, 1);
    head[11] = sub.tick;
    const data = Buffer.concat([
      head,
      encodeUVlq32(sub.sequence),
      Buffer.from([sub.changeCounter]),
      ...records,
      Buffer.from([NotificationRecord.End]),
    ]);
    const frame = Buffer.alloc(4);
    frame[0] = S7P_PROTOCOL_ID;
    frame[1] = this.version;
    frame.writeUInt16BE(data.length, 2);
    this.push(Buffer.concat([frame, data, Buffer.from([S7P_PROTOCOL_ID, this.version, 0, 0])]));
  }
}

/** The reference list: an address array of UDInt whose head gives the change counter and the item count, then each item. */
function referenceList(r: Reader): { items: Item[]; changeCounter: number } {
  if (r.u8('the reference list flags') !== 0x20 || r.u8('the reference list type') !== 0x04)
    throw new ProtocolError('S7CommPlus reference list is not an address array of UDInt');
  const count = r.uvlq32();
  if (count < 3) throw new ProtocolError('S7CommPlus reference list too short');
  const values: number[] = [];
  for (let i = 0; i < count; i++) values.push(r.uvlq32());
  const changeCounter = (values[0]! >>> 16) & 0xff;
  const n = values[2]!;
  if (n > MAX_ITEMS) throw new ProtocolError(`S7CommPlus subscription of ${n} items`);
  const items: Item[] = [];
  let at = 3;
  for (let k = 0; k < n; k++) {
    const head = values[at];
    if (head === undefined) throw new ProtocolError('S7CommPlus reference list ends inside an item');
    const lidCount = (head & 0xffff) - 1;
    const fields = values.slice(at + 1, at + 6 + lidCount);
    if (lidCount < 0 || fields.length !== 5 + lidCount) throw new ProtocolError('S7CommPlus reference list ends inside an item');
    const [reference, , area, , subArea, ...lids] = fields as [number, number, number, number, number, ...number[]];
    items.push({ reference, area, subArea, lids });
    at += 6 + lidCount;
  }
  return { items, changeCounter };
}

function scalarUDInt(r: Reader): number {
  r.u8('flags');
  if (r.u8('type') !== 0x04) throw new ProtocolError('S7CommPlus cycle time is not a UDInt');
  return r.uvlq32();
}

function scalarInt(r: Reader): number {
  r.u8('flags');
  if (r.u8('type') !== 0x07) throw new ProtocolError('S7CommPlus credit limit is not an Int');
  return r.bytes(2, 'an Int').readInt16BE(0);
}
