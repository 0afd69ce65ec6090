/**
 * Program_Alarm over S7CommPlus (S7-1200/1500), on the wire:
 *
 * - the alarm subscription: a CreateObject, in the session's subscription
 *   container, of a Subscription object (class 1001, relation 0x7FFFC001,
 *   function class 2, route mode 2, reference list `0x80010000, 0, 0`: no
 *   variables) with one child, the AlarmSubscriptionRef (class 2662,
 *   relation 0x51010001, name `S7pDriver_Alarming`, trigger mode 3, alarm
 *   domains, the domain filter, the text languages as Windows LCIDs, send
 *   texts) related to the alarm subsystem (relation 2660 → RID 8);
 * - the active-alarm list: an Explore of the alarm subsystem (RID 8, request
 *   id 2667, its relation to the alarms that are "update relevant"), which
 *   answers one DAI object (class 2681) per alarm;
 * - the alarm notification: the notification head of a data subscription
 *   (opcode 0x33, subscription id, 6 reserved bytes, credit tick, sequence,
 *   change counter or timestamp), an empty value list (0x00), then the alarm
 *   subscription's id, 2 bytes not explained in public sources, a return
 *   value byte 0x81, the DAI objects;
 * - the DAI object: name (233), CPU alarm id (2670, LWord), all-states info
 *   (2671, USInt), alarm domain (2672, UInt), message type (4079, DInt),
 *   HMI info (7813, Blob), sequence counter (7917, UDInt), the coming (2673)
 *   or going (2677) struct (AS_CGS: all-states info 3474, time stamp 3475,
 *   associated values 3476, acknowledgement time 3646) and the texts (2715: a
 *   sparse array of Blobs keyed `LCID << 16 | text id`).
 *
 * Sources: s7commplus (MIT) alarm.py (build_alarm_subscription_request,
 * build_alarm_explore_request, parse_alarm_notification, _alarm_from_object,
 * _alarm_texts), S7CommPlusDriver (LGPL; facts only): the attribute types of
 * AlarmsDai.cs, the HMI info layout of AlarmsHmiInfo.cs, the AS_CGS members
 * of AlarmsAsCgs.cs and Ids.cs, the associated values' array of
 * AlarmsAssociatedValues.cs (element 0 a type information, 1–10 SD_1–SD_10),
 * the time stamps in nanoseconds since 1970 (Utils.DtFromValueTimestamp).
 */
import { ProtocolError } from '../../errors';
import { DataType, Ids, NotificationRecord, Opcode, PValueFlag } from '../constants';
import { Reader, Writer } from './bytes';
import { attributeOf, childrenOf, newObject, readObjects, writeObject, type PObject } from './object';
import { scalar, type BlobValue, type PValue, type SparseEntry, type StructValue } from './pvalue';
import type { ExploreRequest } from './explore';

/** s7commplus names its alarm subscription object's relation so (alarm.py _ALARM_SUBSCRIPTION_RELATION_ID). */
const ALARM_SUBSCRIPTION_RELATION_ID = 0x7fffc001;
/** The relation of the AlarmSubscriptionRef child (alarm.py _ALARM_REFERENCE_RELATION_ID). */
const ALARM_REFERENCE_RELATION_ID = 0x51010001;
/** The return value byte before an alarm notification's objects (alarm.py parse_alarm_notification). */
const ALARM_NOTIFICATION_RETURN = 0x81;
/** The text ids of a DAI's texts (alarm.py _alarm_texts): 1 the info text, 2 the alarm text, 3–11 the additional texts 1–9. */
export const TextId = { Info: 1, Alarm: 2, FirstAdditional: 3, LastAdditional: 11 } as const;
/** The associated values' array: element 0 a type information (root id 3476, 4 bytes), 1–10 SD_1 to SD_10, 17 elements in all (AlarmsAssociatedValues.cs). */
export const ASSOCIATED_VALUES = { count: 17, maxValues: 10, typeInfoBytes: 4 } as const;
/** The struct id a CPU gives its AS_CGS struct is not public; the simulator sends 0 and the decoder ignores it. */
const AS_CGS_STRUCT_ID = 0;

export interface AlarmSubscriptionSpec {
  /** Windows LCIDs of the texts wanted; none: every language the CPU has. */
  languages: readonly number[];
  /** Alarm domains to include; default every one (0xFFFF). */
  domains?: readonly number[];
  /** -1 (no limit) or 0–255; s7commplus sends 10, what the S7-1500 of its reference trace took. */
  creditLimit: number;
  relationId?: number;
}

const udintArray = (values: readonly number[]): PValue => ({ flags: PValueFlag.AddressArray, type: DataType.UDInt, value: [...values] });

/** The Subscription object of an alarm subscription, with its AlarmSubscriptionRef child, in s7commplus's order. */
export function alarmSubscriptionObject(spec: AlarmSubscriptionSpec): PObject {
  if (!Number.isInteger(spec.creditLimit) || spec.creditLimit < -1 || spec.creditLimit > 255)
    throw new RangeError(`S7CommPlus: an alarm subscription's credit limit of ${spec.creditLimit} (-1 or 0 to 255)`);
  const domains = spec.domains ?? [0xffff];
  if (domains.some((d) => !Number.isInteger(d) || d < 0 || d > 0xffff)) throw new RangeError('S7CommPlus: alarm domains are UInt values');
  if (spec.languages.some((l) => !Number.isInteger(l) || l < 0 || l > 0xffffffff))
    throw new RangeError('S7CommPlus: language ids are UDInt values');
  const relationId = spec.relationId ?? ALARM_SUBSCRIPTION_RELATION_ID;
  const ref = newObject({ relationId: ALARM_REFERENCE_RELATION_ID, classId: Ids.AlarmSubscriptionRefClassRid }, [
    [Ids.ObjectVariableTypeName, scalar(DataType.WString, 'S7pDriver_Alarming')],
    [Ids.SubscriptionReferenceTriggerMode, scalar(DataType.USInt, 3)],
    [Ids.AlarmSubscriptionRefAlarmDomain, { flags: PValueFlag.Array, type: DataType.UInt, value: new Array<number>(10).fill(0) }],
    [Ids.AlarmSubscriptionRefAlarmDomainFilter, { flags: PValueFlag.AddressArray, type: DataType.UInt, value: [...domains] }],
    [Ids.AlarmSubscriptionRefTextLanguages, udintArray(spec.languages)],
    [Ids.AlarmSubscriptionRefSendTexts, scalar(DataType.Bool, true)],
  ]);
  ref.members.push({ kind: 'relation', id: Ids.AlarmSubscriptionRefItsAlarmSubsystem, target: Ids.NativeTheAlarmSubsystemRID });
  return newObject(
    { relationId, classId: Ids.ClassSubscription },
    [
      [Ids.ObjectVariableTypeName, scalar(DataType.WString, `Subscription_${relationId}`)],
      [Ids.SubscriptionFunctionClassId, scalar(DataType.USInt, 2)],
      [Ids.SubscriptionMissedSendings, scalar(DataType.UInt, 0)],
      [Ids.SubscriptionSubsystemError, scalar(DataType.LInt, 0n)],
      [Ids.SubscriptionRouteMode, scalar(DataType.USInt, 2)],
      [Ids.SubscriptionActive, scalar(DataType.Bool, true)],
      [Ids.SubscriptionReferenceList, udintArray([0x80010000, 0, 0])],
      [Ids.SubscriptionCycleTime, scalar(DataType.UDInt, 0)],
      [Ids.SubscriptionDelayTime, scalar(DataType.UDInt, 0)],
      [Ids.SubscriptionDisabled, scalar(DataType.USInt, 0)],
      [Ids.SubscriptionCount, scalar(DataType.USInt, 0)],
      [Ids.SubscriptionCreditLimit, scalar(DataType.Int, spec.creditLimit)],
      [Ids.SubscriptionTicks, scalar(DataType.UInt, 0xffff)],
    ],
    [ref],
  );
}

/** What the simulator needs of an alarm subscription; undefined when `obj` is a Subscription without an AlarmSubscriptionRef (a data subscription). */
export function readAlarmSubscription(obj: PObject): { languages: number[]; sendTexts: boolean; creditLimit: number } | undefined {
  if (obj.classId !== Ids.ClassSubscription) return undefined;
  const ref = childrenOf(obj).find((c) => c.classId === Ids.AlarmSubscriptionRefClassRid);
  if (!ref) return undefined;
  const langs = attributeOf(ref, Ids.AlarmSubscriptionRefTextLanguages)?.value;
  const languages = Array.isArray(langs) ? langs.filter((l): l is number => typeof l === 'number') : [];
  const credit = attributeOf(obj, Ids.SubscriptionCreditLimit)?.value;
  return {
    languages,
    sendTexts: attributeOf(ref, Ids.AlarmSubscriptionRefSendTexts)?.value !== false,
    creditLimit: typeof credit === 'number' ? credit : -1,
  };
}

/** The attributes the active-alarm Explore asks for, in s7commplus's order (alarm.py build_alarm_explore_request). */
const ALARM_EXPLORE_ATTRIBUTES: readonly number[] = [
  Ids.AlarmDaiCpuAlarmId,
  Ids.AlarmDaiAllStatesInfo,
  Ids.AlarmDaiDomain,
  Ids.AlarmDaiComing,
  Ids.AlarmDaiGoing,
  Ids.AlarmDaiMessageType,
  Ids.AlarmDaiHmiInfo,
  Ids.ObjectVariableTypeName,
  Ids.AlarmDaiSequenceCounter,
  Ids.AlarmDaiTexts,
];

/** The Explore of the active alarms: the alarm subsystem, request id 2667, recursive, flag 1 (alarm.py). */
export function alarmExploreBody(): ExploreRequest {
  return {
    exploreId: Ids.NativeTheAlarmSubsystemRID,
    requestId: Ids.AlarmSubsystemUpdateRelevantDai,
    childsRecursive: 1,
    flag: 1,
    parents: 0,
    attributes: [...ALARM_EXPLORE_ATTRIBUTES],
  };
}

/** The HMI info blob (AlarmsHmiInfo.cs): syntax id 258 carries priority, alarm class, producer, group and flags. */
export interface HmiInfo {
  syntaxId: number;
  version: number;
  clientAlarmId: number;
  priority: number;
  alarmClass?: number;
  producer?: number;
  groupId?: number;
  flags?: number;
}

function encodeHmiInfo(h: HmiInfo): Buffer {
  const w = new Writer().u16(h.syntaxId).u16(h.version).u32(h.clientAlarmId).u8(h.priority);
  if (h.syntaxId >= 257) w.u8(0).u8(0).u8(0);
  if (h.syntaxId >= 258)
    w.u16(h.alarmClass ?? 0)
      .u8(h.producer ?? 0)
      .u8(h.groupId ?? 0)
      .u8(h.flags ?? 0);
  return w.toBuffer();
}

export function decodeHmiInfo(b: Buffer): HmiInfo {
  const r = new Reader(b);
  const h: HmiInfo = {
    syntaxId: r.u16('HMI info syntax id'),
    version: r.u16('HMI info version'),
    clientAlarmId: r.u32('client alarm id'),
    priority: r.u8('priority'),
  };
  if (h.syntaxId >= 257) r.bytes(3, 'HMI info reserved');
  if (h.syntaxId >= 258) {
    h.alarmClass = r.u16('alarm class');
    h.producer = r.u8('producer');
    h.groupId = r.u8('group id');
    h.flags = r.u8('HMI info flags');
  }
  return h;
}

/** One DAI (an alarm as the CPU reports it). */
export interface Dai {
  relationId: number;
  name: string;
  /** The CPU alarm id (LWord). */
  cpuAlarmId: bigint;
  allStatesInfo: number;
  domain: number;
  messageType: number;
  sequenceCounter: number;
  hmi?: HmiInfo;
  state: 'coming' | 'going';
  /** The AS_CGS struct's all-states info. */
  cgsAllStatesInfo?: number;
  /** Nanoseconds since 1970. */
  timestamp?: bigint;
  /** Nanoseconds since 1970; 0 or absent: not acknowledged. */
  ackTimestamp?: bigint;
  /** The associated values' blobs as they came (element 0 the type information). */
  values: BlobValue[];
  /** Texts by `LCID << 16 | text id`, as the CPU sent them (placeholders not filled). */
  texts: Map<number, string>;
}

function blobOf(v: unknown): BlobValue | undefined {
  return v !== null && typeof v === 'object' && 'rootId' in v && 'data' in v ? (v as BlobValue) : undefined;
}

/** A DAI object's attributes; ProtocolError for an object that is not a DAI or whose attributes have the wrong types. */
export function readDai(obj: PObject): Dai {
  if (obj.classId !== Ids.AlarmDaiClassRid)
    throw new ProtocolError(`S7CommPlus: object of class ${obj.classId} where an alarm (DAI, 2681) was expected`);
  const num = (id: number, what: string): number => {
    const v = attributeOf(obj, id)?.value;
    if (v === undefined) return 0;
    if (typeof v === 'number') return v;
    if (typeof v === 'bigint' && v <= 0xffffffffn) return Number(v);
    throw new ProtocolError(`S7CommPlus: alarm attribute ${what} (${id}) is not a number`);
  };
  const idValue = attributeOf(obj, Ids.AlarmDaiCpuAlarmId)?.value;
  // An LWord (AlarmsDai.cs); any whole number of another integer type is taken too.
  if (!(typeof idValue === 'bigint' || (typeof idValue === 'number' && Number.isInteger(idValue))) || idValue < 0)
    throw new ProtocolError('S7CommPlus: an alarm (DAI) without a CPU alarm id (2670) that is a whole number');
  const name = attributeOf(obj, Ids.ObjectVariableTypeName)?.value;
  const coming = attributeOf(obj, Ids.AlarmDaiComing);
  const going = attributeOf(obj, Ids.AlarmDaiGoing);
  const cgs = coming ?? going;
  if (!cgs) throw new ProtocolError(`S7CommPlus: alarm ${String(idValue)} has neither its coming (2673) nor its going (2677) state`);
  const dai: Dai = {
    relationId: obj.relationId,
    name: typeof name === 'string' ? name : '',
    cpuAlarmId: BigInt(idValue),
    allStatesInfo: num(Ids.AlarmDaiAllStatesInfo, 'AllStatesInfo'),
    domain: num(Ids.AlarmDaiDomain, 'AlarmDomain'),
    messageType: num(Ids.AlarmDaiMessageType, 'MessageType'),
    sequenceCounter: num(Ids.AlarmDaiSequenceCounter, 'SequenceCounter'),
    state: coming ? 'coming' : 'going',
    values: [],
    texts: new Map(),
  };
  const hmi = blobOf(attributeOf(obj, Ids.AlarmDaiHmiInfo)?.value);
  if (hmi && hmi.data.length > 0) dai.hmi = decodeHmiInfo(hmi.data);
  const s = cgs.value as StructValue;
  if (cgs.type !== DataType.Struct || s === null || typeof s !== 'object' || !('members' in s))
    throw new ProtocolError(`S7CommPlus: alarm ${String(idValue)}'s ${dai.state} state is not a struct`);
  for (const m of s.members) {
    const v = m.value.value;
    if (m.key === Ids.AsCgsAllStatesInfo && typeof v === 'number') dai.cgsAllStatesInfo = v;
    else if (m.key === Ids.AsCgsTimestamp && typeof v === 'bigint') dai.timestamp = v;
    else if (m.key === Ids.AsCgsAckTimestamp && typeof v === 'bigint') dai.ackTimestamp = v;
    else if (m.key === Ids.AsCgsAssociatedValues && Array.isArray(v))
      dai.values = v.map(blobOf).filter((b): b is BlobValue => b !== undefined);
  }
  const texts = attributeOf(obj, Ids.AlarmDaiTexts);
  if (texts && texts.flags & PValueFlag.SparseArray && Array.isArray(texts.value)) {
    for (const e of texts.value as SparseEntry[]) {
      const b = blobOf(e.value);
      if (b) dai.texts.set(e.key, b.data.toString('utf8'));
    }
  }
  return dai;
}

/** The DAI object of `dai`, attribute for attribute as the decoder reads it. */
export function daiObject(dai: Dai): PObject {
  const cgs: StructValue = {
    id: AS_CGS_STRUCT_ID,
    members: [
      { key: Ids.AsCgsAllStatesInfo, value: scalar(DataType.USInt, dai.cgsAllStatesInfo ?? dai.allStatesInfo) },
      { key: Ids.AsCgsTimestamp, value: scalar(DataType.Timestamp, dai.timestamp ?? 0n) },
      { key: Ids.AsCgsAssociatedValues, value: { flags: PValueFlag.Array, type: DataType.Blob, value: dai.values } },
      { key: Ids.AsCgsAckTimestamp, value: scalar(DataType.Timestamp, dai.ackTimestamp ?? 0n) },
    ],
  };
  const texts: SparseEntry[] = [...dai.texts].map(([key, text]) => ({ key, value: { rootId: 0, data: Buffer.from(text, 'utf8') } }));
  return newObject({ relationId: dai.relationId, classId: Ids.AlarmDaiClassRid }, [
    [Ids.ObjectVariableTypeName, scalar(DataType.WString, dai.name)],
    [Ids.AlarmDaiCpuAlarmId, scalar(DataType.LWord, dai.cpuAlarmId)],
    [Ids.AlarmDaiAllStatesInfo, scalar(DataType.USInt, dai.allStatesInfo)],
    [Ids.AlarmDaiDomain, scalar(DataType.UInt, dai.domain)],
    [Ids.AlarmDaiMessageType, scalar(DataType.DInt, dai.messageType)],
    [Ids.AlarmDaiHmiInfo, scalar(DataType.Blob, { rootId: 0, data: dai.hmi ? encodeHmiInfo(dai.hmi) : Buffer.alloc(0) })],
    [Ids.AlarmDaiSequenceCounter, scalar(DataType.UDInt, dai.sequenceCounter)],
    [dai.state === 'coming' ? Ids.AlarmDaiComing : Ids.AlarmDaiGoing, { flags: 0, type: DataType.Struct, value: cgs }],
    [Ids.AlarmDaiTexts, { flags: PValueFlag.SparseArray, type: DataType.Blob, value: texts }],
  ]);
}

export interface AlarmNotification {
  subscriptionId: number;
  creditTick: number;
  sequence: number;
  changeCounter: number;
  /** µs since 1970, when the change counter is 0. */
  timestamp?: bigint;
  /** The alarm subscription's id after the value list; 0 when the notification carries no alarms. */
  alarmSubscriptionId: number;
  /** The 2 bytes after it, not explained in public sources, kept as they came. */
  unexplained: number;
  alarms: PObject[];
}

/** Whether a notification's data (opcode first) carries alarms: an empty value list followed by a non-zero byte (alarm.py). */
export function isAlarmNotification(data: Buffer): boolean {
  try {
    const r = new Reader(data);
    readHead(r);
    return r.u8('value list') === NotificationRecord.End && (r.peek() ?? 0) !== 0;
  } catch {
    return false;
  }
}

function readHead(r: Reader): Pick<AlarmNotification, 'subscriptionId' | 'creditTick' | 'sequence' | 'changeCounter' | 'timestamp'> {
  const opcode = r.u8('opcode');
  if (opcode !== Opcode.Notification)
    throw new ProtocolError(`S7CommPlus: expected a notification (0x33), found opcode 0x${opcode.toString(16)}`);
  const subscriptionId = r.u32('subscription id');
  r.bytes(6, 'notification reserved');
  const creditTick = r.u8('credit tick');
  const sequence = r.uvlq32();
  const head: ReturnType<typeof readHead> = { subscriptionId, creditTick, sequence, changeCounter: 0 };
  if (r.peek() === 0) head.timestamp = r.u64('timestamp');
  head.changeCounter = r.u8('change counter');
  return head;
}

/** An alarm notification's data (opcode 0x33 first); ProtocolError for anything else. */
export function decodeAlarmNotification(data: Buffer): AlarmNotification {
  const r = new Reader(data);
  const head = readHead(r);
  const at = r.offset;
  if (r.u8('value list') !== NotificationRecord.End)
    throw new ProtocolError(
      `S7CommPlus: alarm notification with values at offset ${at} (mixed data and alarm notifications are not known)`,
    );
  const n: AlarmNotification = { ...head, alarmSubscriptionId: 0, unexplained: 0, alarms: [] };
  if ((r.peek() ?? 0) === 0) return n;
  n.alarmSubscriptionId = r.u32('alarm subscription id');
  n.unexplained = r.u16('alarm notification bytes');
  const rv = r.u8('alarm notification return value');
  if (rv !== ALARM_NOTIFICATION_RETURN)
    throw new ProtocolError(`S7CommPlus: alarm notification return value 0x${rv.toString(16)} (0x81 is known)`);
  n.alarms = readObjects(r);
  return n;
}

export function encodeAlarmNotification(n: AlarmNotification): Buffer {
  const w = new Writer();
  // The 6 reserved bytes as TIA's captures show them: 04 00 00 00 00 00 (s7commplus docs/subscriptions-alarms.rst).
  w.u8(Opcode.Notification).u32(n.subscriptionId).u16(0x0400).u16(0).u16(0).u8(n.creditTick).uvlq32(n.sequence);
  if (n.timestamp !== undefined) {
    if (n.timestamp < 0n || n.timestamp >= 1n << 56n)
      throw new RangeError('S7CommPlus: a notification timestamp must have its first byte 0');
    w.u64(n.timestamp);
  } else if (n.changeCounter === 0) throw new RangeError('S7CommPlus: change counter 0 without a timestamp would read as one');
  w.u8(n.changeCounter).u8(NotificationRecord.End);
  if (n.alarmSubscriptionId >>> 24 === 0)
    throw new RangeError('S7CommPlus: an alarm subscription id whose first byte is 0 reads as no alarms');
  w.u32(n.alarmSubscriptionId).u16(n.unexplained).u8(ALARM_NOTIFICATION_RETURN);
  for (const o of n.alarms) writeObject(w, o);
  // The fill of a notification.
  return w.u32(0).toBuffer();
}
