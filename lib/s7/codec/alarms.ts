/**
 * The classic alarm services of S7-300/400 CPUs: userdata function group 4
 * (CPU functions) and the mode-transition push of group 0. Only the data
 * part of each userdata PDU is built and read here; userdata.ts frames it.
 * Public sources of the layout: Apache PLC4X's s7.mspec (Apache-2.0: the
 * message service, AlarmMessagePushType, AlarmMessageAckType, the alarm
 * query request, the SyntaxIdType / AlarmType / AlarmStateType / EventType
 * enums) and the field names of Wireshark's s7comm dissector
 * (packet-s7comm.c, facts only), which reads every frame built here without
 * a malformed field (test/s7-alarms-tshark.test.ts).
 *
 *   message service (0x02) request:  events(MODE 01 | SYS 02 | USR 04 | ALM 80) 00 username[8] [alarm type 00]
 *   message service answer:          result 00 [alarm type 00 00]
 *   indications (05 06 11 12 16):    time[8 BCD] function 00 objects{n}
 *       object: 12 length syntax(16 | 1C) values{n} event-id[4] event-state local-state ack-going ack-coming
 *               [NOTIFY_IND 1C only: event-going event-coming event-last-changed 00] value*
 *       value:  return-code transport-size length[2] data (length in bits for 03 04 05, else bytes)
 *   ack (0x0b) request:              function 09 objects{n}: 12 08 syntax 19 values 01 event-id[4] ack-going ack-coming
 *   ack answer:                      function 09 n result*(FF ok)
 *   ack indication (0x0c):           time[8 BCD] function 00 n objects as in the ack request
 *   query (0x13):                    alarm-query.ts
 *   diagnostic message (0x03):       the 20-byte diagnostic buffer entry (codec/diagnostics.ts)
 *
 * Decoders take the data part (a subarray of the frame) and throw only ProtocolError.
 */
import { ProtocolError } from '../../errors';
import { decodeDateAndTime, encodeDateAndTime } from '../../values/time';
import { dataLengthBytes, dataLengthField } from './pdu';

/** Group 4 subfunctions of the alarm services. */
export const AlarmSubfunction = Object.freeze({
  MessageService: 0x02,
  DiagnosticMessage: 0x03,
  Alarm8: 0x05,
  Notify: 0x06,
  Ack: 0x0b,
  AckIndication: 0x0c,
  AlarmSq: 0x11,
  AlarmS: 0x12,
  Query: 0x13,
  Notify8: 0x16,
});

/** The function group of the mode-transition push (its subfunction is the new mode). */
export const MODE_TRANSITION_GROUP = 0x0;

/** The message service's event bits: what a connection registers for. */
export const MessageEvents = Object.freeze({ MODE: 0x01, SYS: 0x02, USR: 0x04, ALM: 0x80 });

/** The alarm registration byte of the message service (PLC4X AlarmStateType). */
export const AlarmRegistration = Object.freeze({
  ALARM_ABORT: 0x04,
  ALARM_INITIATE: 0x05,
  ALARM_S_ABORT: 0x08,
  ALARM_S_INITIATE: 0x09,
});

/** The alarm types of the query and the registration answer (PLC4X AlarmType). */
export const AlarmType = Object.freeze({ SCAN: 0x01, ALARM_8: 0x02, ALARM_S: 0x04 });

/** Syntax ids of the alarm objects. */
export const AlarmSyntax = Object.freeze({ ALARM_IND: 0x16, ALARM_ACK: 0x19, ALARM_QUERYREQ: 0x1a, NOTIFY_IND: 0x1c });

/** The CPU modes a mode-transition push names (PLC4X ModeTransitionType). */
export const MODE_NAMES: Readonly<Record<number, string>> = Object.freeze({
  0x00: 'STOP',
  0x01: 'WARM_RESTART',
  0x02: 'RUN',
  0x03: 'HOT_RESTART',
  0x04: 'HOLD',
  0x06: 'COLD_RESTART',
  0x09: 'RUN_R',
  0x11: 'LINK_UP',
  0x12: 'UPDATE',
});

const USERNAME_BYTES = 8;

// ---------------------------------------------------------------- message service

export interface MessageServiceRequest {
  /** MessageEvents bits. */
  events: number;
  /** The 8-byte name the registering station gives (padded with spaces). */
  username: string;
  /** The alarm registration (AlarmRegistration), present when ALM is set. */
  alarms?: number;
}

export function encodeMessageServiceRequest(r: MessageServiceRequest): Buffer {
  const alm = (r.events & MessageEvents.ALM) !== 0;
  const b = Buffer.alloc(2 + USERNAME_BYTES + (alm ? 2 : 0));
  b[0] = r.events & 0xff;
  b.write(r.username.padEnd(USERNAME_BYTES, ' ').slice(0, USERNAME_BYTES), 2, 'latin1');
  if (alm) b[2 + USERNAME_BYTES] = r.alarms ?? AlarmRegistration.ALARM_S_INITIATE;
  return b;
}

export function decodeMessageServiceRequest(d: Buffer): MessageServiceRequest {
  if (d.length < 2 + USERNAME_BYTES) throw new ProtocolError(`message service request of ${d.length} bytes, expected at least 10`);
  const events = d[0]!;
  const r: MessageServiceRequest = { events, username: d.toString('latin1', 2, 2 + USERNAME_BYTES) };
  if (events & MessageEvents.ALM) {
    if (d.length < 2 + USERNAME_BYTES + 1) throw new ProtocolError('message service request registers alarms without an alarm type');
    r.alarms = d[2 + USERNAME_BYTES]!;
  }
  return r;
}

export interface MessageServiceAnswer {
  /** The CPU's result byte. */
  result: number;
  /** The alarm type registered (AlarmType), when the request registered alarms. */
  alarmType?: number;
}

export function encodeMessageServiceAnswer(a: MessageServiceAnswer): Buffer {
  return a.alarmType === undefined ? Buffer.of(a.result, 0) : Buffer.of(a.result, 0, a.alarmType, 0, 0);
}

export function decodeMessageServiceAnswer(d: Buffer): MessageServiceAnswer {
  if (d.length === 2) return { result: d[0]! };
  if (d.length === 5) return { result: d[0]!, alarmType: d[2]! };
  throw new ProtocolError(`message service answer of ${d.length} bytes, expected 2 or 5`);
}

// ---------------------------------------------------------------- associated values

/** One associated value as sent: return code, transport size, the raw bytes. */
export interface AssociatedValue {
  returnCode: number;
  transportSize: number;
  data: Buffer;
}

function valueBytes(values: readonly AssociatedValue[]): number {
  return values.reduce((n, v) => n + 4 + v.data.length, 0);
}

export function writeValue(b: Buffer, o: number, v: AssociatedValue, lengthInBytes: boolean): number {
  b[o] = v.returnCode;
  b[o + 1] = v.transportSize;
  b.writeUInt16BE(lengthInBytes ? v.data.length : dataLengthField(v.transportSize, v.data.length), o + 2);
  v.data.copy(b, o + 4);
  return o + 4 + v.data.length;
}

export function readValue(d: Buffer, o: number, lengthInBytes: boolean, what: string): [AssociatedValue, number] {
  if (o + 4 > d.length) throw new ProtocolError(`${what}: associated value header cut off at byte ${o}`);
  const transportSize = d[o + 1]!;
  const field = d.readUInt16BE(o + 2);
  const len = lengthInBytes ? field : dataLengthBytes(transportSize, field);
  if (o + 4 + len > d.length) throw new ProtocolError(`${what}: associated value of ${len} bytes at byte ${o} runs past the end`);
  return [{ returnCode: d[o]!, transportSize, data: d.subarray(o + 4, o + 4 + len) }, o + 4 + len];
}

// ---------------------------------------------------------------- indications

interface AlarmObject {
  /** AlarmSyntax.ALARM_IND, or NOTIFY_IND for NOTIFY/NOTIFY_8P. */
  syntaxId: number;
  eventId: number;
  /** One bit per signal (SIG_1 = bit 0): set while the signal is coming. */
  eventState: number;
  localState: number;
  /** One bit per signal: acknowledged going / coming. */
  ackGoing: number;
  ackComing: number;
  /** NOTIFY_IND objects only: the signals going, coming, and the one(s) that changed last. */
  notify?: { going: number; coming: number; lastChanged: number };
  values: AssociatedValue[];
}

export interface AlarmIndication {
  /** The CPU's time stamp (its clock fields as UTC). */
  time: Date;
  objects: AlarmObject[];
}

const OBJECT_HEAD = 12;
/** A NOTIFY_IND object's head: 4 more bytes (event going, event coming, event last changed, reserved; Wireshark's field names). */
const NOTIFY_HEAD = 16;

function headOf(syntaxId: number): number {
  return syntaxId === AlarmSyntax.NOTIFY_IND ? NOTIFY_HEAD : OBJECT_HEAD;
}

/** The data of an ALARM_S / ALARM_SQ / ALARM_8 / NOTIFY / NOTIFY_8 indication. */
export function encodeAlarmIndication(ind: AlarmIndication): Buffer {
  const size = 10 + ind.objects.reduce((n, ob) => n + headOf(ob.syntaxId) + valueBytes(ob.values), 0);
  const b = Buffer.alloc(size);
  encodeDateAndTime(ind.time, b, 0);
  b[9] = ind.objects.length;
  let o = 10;
  for (const ob of ind.objects) {
    b[o] = 0x12;
    const head = headOf(ob.syntaxId);
    b[o + 1] = head - 2 + valueBytes(ob.values);
    b[o + 2] = ob.syntaxId;
    b[o + 3] = ob.values.length;
    b.writeUInt32BE(ob.eventId >>> 0, o + 4);
    b[o + 8] = ob.eventState;
    b[o + 9] = ob.localState;
    b[o + 10] = ob.ackGoing;
    b[o + 11] = ob.ackComing;
    if (head === NOTIFY_HEAD) {
      b[o + 12] = ob.notify?.going ?? 0;
      b[o + 13] = ob.notify?.coming ?? 0;
      b[o + 14] = ob.notify?.lastChanged ?? 0;
    }
    o += head;
    for (const v of ob.values) o = writeValue(b, o, v, false);
  }
  return b;
}

export function decodeAlarmIndication(d: Buffer): AlarmIndication {
  const what = 'alarm indication';
  if (d.length < 10) throw new ProtocolError(`${what} of ${d.length} bytes, expected at least 10`);
  const time = decodeDateAndTime(d, 0);
  const n = d[9]!;
  const objects: AlarmObject[] = [];
  let o = 10;
  for (let i = 0; i < n; i++) {
    if (o + OBJECT_HEAD > d.length) throw new ProtocolError(`${what}: object ${i + 1} of ${n} cut off at byte ${o}`);
    if (d[o] !== 0x12) throw new ProtocolError(`${what}: object ${i + 1} starts with 0x${d[o]!.toString(16)}, expected 0x12`);
    const end = o + 2 + d[o + 1]!;
    if (end > d.length) throw new ProtocolError(`${what}: object ${i + 1} announces ${d[o + 1]} bytes past the end`);
    const count = d[o + 3]!;
    const head = headOf(d[o + 2]!);
    if (o + head > end) throw new ProtocolError(`${what}: object ${i + 1} of ${d[o + 1]} bytes is shorter than its head`);
    const ob: AlarmObject = {
      syntaxId: d[o + 2]!,
      eventId: d.readUInt32BE(o + 4),
      eventState: d[o + 8]!,
      localState: d[o + 9]!,
      ackGoing: d[o + 10]!,
      ackComing: d[o + 11]!,
      values: [],
    };
    if (head === NOTIFY_HEAD) ob.notify = { going: d[o + 12]!, coming: d[o + 13]!, lastChanged: d[o + 14]! };
    o += head;
    for (let k = 0; k < count; k++) {
      const [v, next] = readValue(d.subarray(0, end), o, false, what);
      ob.values.push(v);
      o = next;
    }
    if (o !== end) throw new ProtocolError(`${what}: object ${i + 1} announces ${end - o} bytes more than its values`);
    objects.push(ob);
  }
  if (o !== d.length) throw new ProtocolError(`${what}: ${d.length - o} bytes after its ${n} objects`);
  return { time, objects };
}

// ---------------------------------------------------------------- acknowledgement

export interface AckObject {
  eventId: number;
  /** Signals whose going / coming is acknowledged (one bit each). */
  ackGoing: number;
  ackComing: number;
}

const ACK_FUNCTION = 0x09;
const ACK_OBJECT = 10;

function encodeAckObjects(b: Buffer, o: number, objects: readonly AckObject[]): void {
  for (const ob of objects) {
    b[o] = 0x12;
    b[o + 1] = ACK_OBJECT - 2;
    b[o + 2] = AlarmSyntax.ALARM_ACK;
    b[o + 3] = 1;
    b.writeUInt32BE(ob.eventId >>> 0, o + 4);
    b[o + 8] = ob.ackGoing;
    b[o + 9] = ob.ackComing;
    o += ACK_OBJECT;
  }
}

function decodeAckObjects(d: Buffer, o: number, n: number, what: string): AckObject[] {
  if (d.length !== o + n * ACK_OBJECT) throw new ProtocolError(`${what} of ${d.length} bytes does not hold ${n} objects of 10`);
  const out: AckObject[] = [];
  for (let i = 0; i < n; i++, o += ACK_OBJECT) {
    if (d[o] !== 0x12 || d[o + 1] !== ACK_OBJECT - 2) throw new ProtocolError(`${what}: object ${i + 1} does not start 12 08`);
    out.push({ eventId: d.readUInt32BE(o + 4), ackGoing: d[o + 8]!, ackComing: d[o + 9]! });
  }
  return out;
}

export function encodeAckRequest(objects: readonly AckObject[]): Buffer {
  const b = Buffer.alloc(2 + objects.length * ACK_OBJECT);
  b[0] = ACK_FUNCTION;
  b[1] = objects.length;
  encodeAckObjects(b, 2, objects);
  return b;
}

export function decodeAckRequest(d: Buffer): AckObject[] {
  if (d.length < 2) throw new ProtocolError(`alarm ack request of ${d.length} bytes`);
  return decodeAckObjects(d, 2, d[1]!, 'alarm ack request');
}

/** The ack answer: one result per object (0xFF done, else the CPU's item error: 0x0A no such alarm, 0x05 not to be acknowledged). */
export function encodeAckAnswer(results: readonly number[]): Buffer {
  return Buffer.from([ACK_FUNCTION, results.length, ...results]);
}

export function decodeAckAnswer(d: Buffer): number[] {
  if (d.length < 2 || d.length !== 2 + d[1]!)
    throw new ProtocolError(`alarm ack answer of ${d.length} bytes is not function, count, results`);
  return [...d.subarray(2)];
}

export interface AckIndication {
  time: Date;
  objects: AckObject[];
}

export function encodeAckIndication(ind: AckIndication): Buffer {
  const b = Buffer.alloc(10 + ind.objects.length * ACK_OBJECT);
  encodeDateAndTime(ind.time, b, 0);
  b[9] = ind.objects.length;
  encodeAckObjects(b, 10, ind.objects);
  return b;
}

export function decodeAckIndication(d: Buffer): AckIndication {
  if (d.length < 10) throw new ProtocolError(`alarm ack indication of ${d.length} bytes, expected at least 10`);
  return { time: decodeDateAndTime(d, 0), objects: decodeAckObjects(d, 10, d[9]!, 'alarm ack indication') };
}
