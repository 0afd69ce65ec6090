/**
 * The alarm query (userdata group 4, subfunction 0x13) of S7-300/400 CPUs:
 * the active alarms of one family, as datasets in an answer that may come
 * in several parts (the SZL's data unit reference and next-part requests).
 * Layout (alarms.ts has the other alarm services and the sources: PLC4X's
 * s7.mspec for the request, Wireshark's s7comm field names for the answer):
 *
 *   request:  00 01 12 08 1A 00 query-type(01 by alarm type) 34 alarm-type[4]
 *   answer:   00 n FF 09 length[2] dataset*, or 00 00 0A 00 00 00 when no alarm is active
 *   dataset:  length 00 00 alarm-type event-id[4] 00 event-state ack-going ack-coming
 *             coming-time[8] coming-value going-time[8] going-value (each value as an indication's)
 */
import { ProtocolError } from '../../errors';
import { decodeDateAndTime, encodeDateAndTime } from '../../values/time';
import { AlarmSyntax, readValue, writeValue, type AssociatedValue } from './alarms';

/** Query type 1: by alarm type. */
const QUERY_BY_TYPE = 0x01;

export function encodeQueryRequest(alarmType: number): Buffer {
  return Buffer.of(0x00, 0x01, 0x12, 0x08, AlarmSyntax.ALARM_QUERYREQ, 0x00, QUERY_BY_TYPE, 0x34, 0, 0, 0, alarmType);
}

/** The alarm type asked for: a 32-bit field (Wireshark); PLC4X 0.13.1 sends it as one byte, read too. */
export function decodeQueryRequest(d: Buffer): { queryType: number; alarmType: number } {
  if (d.length < 9 || d[2] !== 0x12 || d[4] !== AlarmSyntax.ALARM_QUERYREQ) {
    throw new ProtocolError(`alarm query request ${d.subarray(0, 12).toString('hex')} is not 00 01 12 08 1A …`);
  }
  return { queryType: d[6]!, alarmType: d.length >= 12 ? d.readUInt32BE(8) : d[8]! };
}

export interface QueryEntry {
  alarmType: number;
  eventId: number;
  eventState: number;
  ackGoing: number;
  ackComing: number;
  /** Time and associated value (the SD_i bytes) of the last coming / going; absent as all-zero. */
  coming?: { time: Date; value: AssociatedValue };
  going?: { time: Date; value: AssociatedValue };
}

/** A dataset's head: length, 2 reserved, alarm type, event id, 1 reserved, event state, ack going, ack coming. */
const DATASET_HEAD = 12;
const NO_VALUE: AssociatedValue = { returnCode: 0x0a, transportSize: 0, data: Buffer.alloc(0) };

/** The whole answer's data (the server cuts it into parts). */
export function encodeQueryAnswer(entries: readonly QueryEntry[]): Buffer {
  const sets = entries.map((e) => {
    const cv = e.coming?.value ?? NO_VALUE;
    const gv = e.going?.value ?? NO_VALUE;
    const b = Buffer.alloc(DATASET_HEAD + 8 + 4 + cv.data.length + 8 + 4 + gv.data.length);
    b[0] = b.length - 1;
    b[3] = e.alarmType;
    b.writeUInt32BE(e.eventId >>> 0, 4);
    b[9] = e.eventState;
    b[10] = e.ackGoing;
    b[11] = e.ackComing;
    let o = DATASET_HEAD;
    if (e.coming) encodeDateAndTime(e.coming.time, b, o);
    o = writeValue(b, o + 8, cv, false);
    if (e.going) encodeDateAndTime(e.going.time, b, o);
    writeValue(b, o + 8, gv, false);
    return b;
  });
  // No alarm: return code 0x0A (no data), as Wireshark's dissector reads an answer without datasets.
  if (entries.length === 0) return Buffer.of(0x00, 0x00, 0x0a, 0x00, 0x00, 0x00);
  const body = Buffer.concat(sets);
  const head = Buffer.of(0x00, Math.min(entries.length, 0xff), 0xff, 0x09, 0, 0);
  head.writeUInt16BE(Math.min(body.length, 0xffff), 4);
  return Buffer.concat([head, body]);
}

function stamp(d: Buffer, o: number): Date | undefined {
  return d.subarray(o, o + 8).every((x) => x === 0) ? undefined : decodeDateAndTime(d, o);
}

/** The whole answer (every part joined). */
export function decodeQueryAnswer(d: Buffer): QueryEntry[] {
  const what = 'alarm query answer';
  if (d.length < 6) throw new ProtocolError(`${what} of ${d.length} bytes, expected at least 6`);
  if (d[2] !== 0xff) return [];
  const out: QueryEntry[] = [];
  let o = 6;
  while (o < d.length) {
    const end = o + 1 + d[o]!;
    if (end > d.length || end - o < DATASET_HEAD + 24)
      throw new ProtocolError(`${what}: dataset at byte ${o} of ${d[o]} bytes does not fit`);
    const set = d.subarray(0, end);
    const e: QueryEntry = {
      alarmType: d[o + 3]!,
      eventId: d.readUInt32BE(o + 4),
      eventState: d[o + 9]!,
      ackGoing: d[o + 10]!,
      ackComing: d[o + 11]!,
    };
    let p = o + DATASET_HEAD;
    const ct = stamp(set, p);
    const [cv, afterComing] = readValue(set, p + 8, false, what);
    if (ct) e.coming = { time: ct, value: cv };
    p = afterComing;
    if (p + 8 > end) throw new ProtocolError(`${what}: dataset at byte ${o} has no going time`);
    const gt = stamp(set, p);
    const [gv, afterGoing] = readValue(set, p + 8, false, what);
    if (gt) e.going = { time: gt, value: gv };
    if (afterGoing !== end) throw new ProtocolError(`${what}: dataset at byte ${o} announces ${end - afterGoing} bytes more than it holds`);
    out.push(e);
    o = end;
  }
  return out;
}
