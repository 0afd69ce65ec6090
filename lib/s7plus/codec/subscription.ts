/**
 * Subscriptions: the PLC sends changes of the variables it was given.
 *
 * Created with a CreateObject on the session's subscription container
 * (RequestId = its id, transport flags 0x34, the integrity id between request
 * set and object) of a Subscription object (ClassId 1001) whose attributes
 * give its name (233), cycle (1049, ms), credit limit (1053), … and the
 * reference list (1048): an address array of UDInt
 *
 *     0x80000000 | changeCounter << 16, 0, item count,
 *     per item: 0x80040000 | (1 + LID count), reference id, 0, AccessArea, SymbolCrc, AccessSubArea, LID…
 *
 * A notification (opcode 0x33, no request header):
 *
 *     33 <subscription id:4> <reserved:2 ×3> <credit tick:1> <sequence:UVLQ>
 *        [<timestamp:8, µs since 1970, its first byte 0>] <change counter:1>
 *        records: 92 <ref:4> <PValue> | 9B <ref:UVLQ> <PValue> | 03/13 <ref:4> (error) … 00, then <fill:4>
 *
 * Source: s7commplus (MIT), subscription.py build_subscription_request,
 * _reference_list and parse_subscription_notification; golden frames (TIA's
 * subscription create, two notifications).
 */
import { ProtocolError } from '../../errors';
import { DataType, FunctionCode, Ids, NotificationRecord, Opcode, PValueFlag, TransportFlags } from '../constants';
import { Reader, Writer } from './bytes';
import { NO_QUALIFIER, writeObjectQualifier, writeRequestHeader, type Request } from './header';
import { attributeOf, newObject, type PObject } from './object';
import { readPValue, scalar, writePValue, type PValue } from './pvalue';
import type { CreateObjectRequest } from './session';

export interface SubscriptionItem {
  referenceId: number;
  accessArea: number;
  symbolCrc: number;
  accessSubArea: number;
  lids: number[];
}

const LIST_HEAD = 0x80000000;
const ITEM_HEAD = 0x80040000;

/** The reference list (attribute 1048) as its UDInt values. */
export function referenceList(changeCounter: number, items: SubscriptionItem[]): number[] {
  const out = [(LIST_HEAD | ((changeCounter & 0xff) << 16)) >>> 0, 0, items.length];
  for (const it of items)
    out.push((ITEM_HEAD | (1 + it.lids.length)) >>> 0, it.referenceId, 0, it.accessArea, it.symbolCrc, it.accessSubArea, ...it.lids);
  return out;
}

/** The items of a reference list; ProtocolError when it does not follow the layout. */
export function parseReferenceList(values: number[]): { changeCounter: number; items: SubscriptionItem[] } {
  const bad = (why: string) => new ProtocolError(`S7CommPlus: subscription reference list: ${why}`);
  const [head, , count] = values;
  if (head === undefined || count === undefined || (head & 0xff00ffff) >>> 0 !== LIST_HEAD) throw bad('no list head');
  const items: SubscriptionItem[] = [];
  let at = 3;
  for (let i = 0; i < count; i++) {
    const itemHead = values[at];
    if (itemHead === undefined || (itemHead & 0xffff0000) >>> 0 !== ITEM_HEAD) throw bad(`item ${i + 1} has no head`);
    const lidCount = (itemHead & 0xffff) - 1;
    const fields = values.slice(at + 1, at + 6 + lidCount);
    if (lidCount < 0 || fields.length !== 5 + lidCount) throw bad(`item ${i + 1} is cut short`);
    const [referenceId, , accessArea, symbolCrc, accessSubArea] = fields as [number, number, number, number, number];
    items.push({ referenceId, accessArea, symbolCrc, accessSubArea, lids: fields.slice(5) });
    at += 6 + lidCount;
  }
  if (at !== values.length) throw bad(`${values.length - at} values after the last item`);
  return { changeCounter: (head >>> 16) & 0xff, items };
}

export interface SubscriptionSpec {
  /** The new object's RelationId; s7commplus uses 0x7FFFC001, TIA 0x7FFFC000 + a counter. Its name is Subscription_<relationId>. */
  relationId: number;
  cycleMs: number;
  /** -1: no limit. */
  creditLimit: number;
  changeCounter: number;
  items: SubscriptionItem[];
  /** s7commplus sends 0x14, TIA 1. */
  routeMode?: number;
  /** s7commplus sends 0, TIA 3. */
  functionClassId?: number;
}

/** The Subscription object, attribute for attribute in the order TIA and s7commplus send them. */
export function subscriptionObject(s: SubscriptionSpec): PObject {
  return newObject({ relationId: s.relationId, classId: Ids.ClassSubscription }, [
    [Ids.ObjectVariableTypeName, scalar(DataType.WString, `Subscription_${s.relationId}`)],
    [Ids.SubscriptionFunctionClassId, scalar(DataType.USInt, s.functionClassId ?? 0)],
    [Ids.SubscriptionMissedSendings, scalar(DataType.UInt, 0)],
    [Ids.SubscriptionSubsystemError, scalar(DataType.LInt, 0n)],
    [Ids.SubscriptionRouteMode, scalar(DataType.USInt, s.routeMode ?? 0x14)],
    [Ids.SubscriptionActive, scalar(DataType.Bool, true)],
    [
      Ids.SubscriptionReferenceList,
      { flags: PValueFlag.AddressArray, type: DataType.UDInt, value: referenceList(s.changeCounter, s.items) },
    ],
    [Ids.SubscriptionCycleTime, scalar(DataType.UDInt, s.cycleMs)],
    [Ids.SubscriptionDisabled, scalar(DataType.USInt, 0)],
    [Ids.SubscriptionCount, scalar(DataType.USInt, 0)],
    [Ids.SubscriptionCreditLimit, scalar(DataType.Int, s.creditLimit)],
    [Ids.SubscriptionTicks, scalar(DataType.UInt, 0xffff)],
    [Ids.Subscription1055, scalar(DataType.USInt, 0)],
  ]);
}

/** The CreateObject of a subscription in the container `containerId` (the second ObjectId of the session's CreateObject answer). */
export function subscriptionCreateRequest(
  sequence: number,
  sessionId: number,
  containerId: number,
  object: PObject,
): Request<CreateObjectRequest> {
  return {
    header: { functionCode: FunctionCode.CreateObject, sequence, sessionId, transportFlags: TransportFlags.Normal },
    body: subscriptionCreateBody(containerId, object),
  };
}

/** The body of a subscription's CreateObject (see subscriptionCreateRequest). */
export function subscriptionCreateBody(containerId: number, object: PObject): CreateObjectRequest {
  return { requestId: containerId, requestValue: scalar(DataType.UDInt, 0), object };
}

export interface CreditRequest {
  subscriptionId: number;
  /** The new credit limit (1 to 255 as s7commplus sends it). */
  creditLimit: number;
  /** A session of frame version 1: the ObjectQualifier's V1 form. */
  v1?: boolean;
}

/**
 * More notifications for a subscription: SetVariable of its credit limit
 * (attribute 1053, an Int) with transport flags 0x74, which the PLC does not
 * answer. Layout: s7commplus (MIT), connection.py send_subscription_credit and
 * _build_set_variable_payload (object id, 1 item, its address, the PValue, the
 * ObjectQualifier, a 0 byte, [IntegrityId], fill).
 */
export function subscriptionCreditRequest(sequence: number, sessionId: number, credit: CreditRequest): Request<CreditRequest> {
  return {
    header: { functionCode: FunctionCode.SetVariable, sequence, sessionId, transportFlags: TransportFlags.NoAnswer },
    body: credit,
  };
}

export function encodeCreditRequest(req: Request<CreditRequest>): Buffer {
  const { subscriptionId, creditLimit, v1 } = req.body;
  if (!Number.isInteger(creditLimit) || creditLimit < 1 || creditLimit > 255)
    throw new RangeError(`S7CommPlus: a credit limit of ${creditLimit} (1 to 255)`);
  const w = new Writer();
  writeRequestHeader(w, { ...req.header, functionCode: FunctionCode.SetVariable });
  w.u32(subscriptionId).uvlq32(1).uvlq32(Ids.SubscriptionCreditLimit);
  writePValue(w, scalar(DataType.Int, creditLimit));
  writeObjectQualifier(w, { ...NO_QUALIFIER, ...(v1 ? { v1: true } : {}) });
  w.u8(0);
  if (req.integrityId !== undefined) w.uvlq32(req.integrityId);
  return w.u32(0).toBuffer();
}

/**
 * DeleteObject of a session's subscription container (every subscription in
 * it goes): the object id, a 0 byte, the ObjectQualifier, [IntegrityId], fill.
 * Layout: s7commplus (MIT), subscription.py build_delete_subscription_request,
 * as client.py delete_subscription sends it.
 */
export function encodeSubscriptionDeleteRequest(req: Request<{ objectId: number; v1?: boolean }>): Buffer {
  const w = new Writer();
  writeRequestHeader(w, { ...req.header, functionCode: FunctionCode.DeleteObject });
  w.u32(req.body.objectId).u8(0);
  writeObjectQualifier(w, { ...NO_QUALIFIER, ...(req.body.v1 ? { v1: true } : {}) });
  if (req.integrityId !== undefined) w.uvlq32(req.integrityId);
  return w.u32(0).toBuffer();
}

/** What the simulator needs of a Subscription object; ProtocolError when it is not one. */
export function readSubscription(obj: PObject): {
  relationId: number;
  cycleMs: number;
  creditLimit: number;
  changeCounter: number;
  items: SubscriptionItem[];
} {
  if (obj.classId !== Ids.ClassSubscription)
    throw new ProtocolError(`S7CommPlus: CreateObject of class ${obj.classId}, not a subscription (1001)`);
  const list = attributeOf(obj, Ids.SubscriptionReferenceList);
  if (!list || !Array.isArray(list.value) || list.type !== DataType.UDInt)
    throw new ProtocolError('S7CommPlus: a subscription without a reference list');
  const cycle = attributeOf(obj, Ids.SubscriptionCycleTime)?.value;
  const credit = attributeOf(obj, Ids.SubscriptionCreditLimit)?.value;
  return {
    relationId: obj.relationId,
    cycleMs: typeof cycle === 'number' ? cycle : 0,
    creditLimit: typeof credit === 'number' ? credit : -1,
    ...parseReferenceList(list.value as number[]),
  };
}

export type NotificationItem =
  { kind: 'value'; ref: number; value: PValue; vlqRef?: boolean } | { kind: 'error'; ref: number; status: number };

export interface Notification {
  subscriptionId: number;
  reserved: [number, number, number];
  creditTick: number;
  sequence: number;
  /** µs since 1970; absent when the PLC sent none. */
  timestamp?: bigint;
  changeCounter: number;
  items: NotificationItem[];
}

/** The data of a notification frame (opcode 0x33 first). */
export function decodeNotification(data: Buffer): Notification {
  const r = new Reader(data);
  const opcode = r.u8('opcode');
  if (opcode !== Opcode.Notification)
    throw new ProtocolError(`S7CommPlus: expected a notification (0x33), found opcode 0x${opcode.toString(16)}`);
  const subscriptionId = r.u32('subscription id');
  const reserved: [number, number, number] = [r.u16(), r.u16(), r.u16()];
  const creditTick = r.u8('credit tick');
  const sequence = r.uvlq32();
  const n: Notification = { subscriptionId, reserved, creditTick, sequence, changeCounter: 0, items: [] };
  if (r.peek() === 0) n.timestamp = r.u64('timestamp');
  n.changeCounter = r.u8('change counter');
  for (;;) {
    const at = r.offset;
    const tag = r.u8('notification record');
    if (tag === NotificationRecord.End) break;
    if (tag === NotificationRecord.Value) n.items.push({ kind: 'value', ref: r.u32('reference'), value: readPValue(r) });
    else if (tag === NotificationRecord.ValueVlq) n.items.push({ kind: 'value', ref: r.uvlq32(), value: readPValue(r), vlqRef: true });
    else if (tag === NotificationRecord.Error || tag === NotificationRecord.Error2)
      n.items.push({ kind: 'error', ref: r.u32('reference'), status: tag });
    else throw new ProtocolError(`S7CommPlus: notification record 0x${tag.toString(16).padStart(2, '0')} at offset ${at} is not known`);
  }
  // The fill (4 zero bytes) that follows is not needed.
  return n;
}

export function encodeNotification(n: Notification): Buffer {
  const w = new Writer();
  w.u8(Opcode.Notification)
    .u32(n.subscriptionId)
    .u16(n.reserved[0])
    .u16(n.reserved[1])
    .u16(n.reserved[2])
    .u8(n.creditTick)
    .uvlq32(n.sequence);
  if (n.timestamp !== undefined) {
    if (n.timestamp < 0n || n.timestamp >= 1n << 56n)
      throw new RangeError('S7CommPlus: a notification timestamp must have its first byte 0');
    w.u64(n.timestamp);
  } else if (n.changeCounter === 0) throw new RangeError('S7CommPlus: change counter 0 without a timestamp would read as one');
  w.u8(n.changeCounter);
  for (const it of n.items) {
    if (it.kind === 'error') w.u8(it.status).u32(it.ref);
    else {
      if (it.vlqRef) w.u8(NotificationRecord.ValueVlq).uvlq32(it.ref);
      else w.u8(NotificationRecord.Value).u32(it.ref);
      writePValue(w, it.value);
    }
  }
  return w.u8(NotificationRecord.End).u32(0).toBuffer();
}
