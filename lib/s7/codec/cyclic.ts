/**
 * Cyclic data of S7-300/400 CPUs (userdata function group 2): a client
 * registers a job of variables the CPU then sends unasked every n × time
 * base (or, change-driven, when they change), until it unsubscribes or the
 * connection closes. Pure, in userdata.ts's style.
 *
 * Sources (facts only): Wireshark's s7comm dissector (packet-s7comm.c,
 * s7comm_decode_ud_cyclic_subfunc; tshark 4.0's value tables): subfunctions
 * 0x01 cyclic transfer, 0x04 unsubscribe, 0x05 change driven transfer; time
 * base 0 = 100 ms, 1 = 1 s, 2 = 10 s; "response and push use the same format
 * as in the read response"; error codes 0xD801–0xD807. Apache PLC4X's
 * s7.mspec (Apache-2.0): S7PayloadUserDataItemCyclicServicesSubscribeRequest
 * (uint16 item count, time base, time factor, items), ...UnsubscribeRequest
 * (function, job id), and its S7 driver: the CPU's answer carries the job id
 * in the parameters' sequence number, unsubscribe function 0x05.
 *
 * Data of a request (after the userdata item header FF 09 len):
 *
 *   nn nn      item count
 *   tb         time base (CYCLIC_TIME_BASE_MS: 0 = 100 ms, 1 = 1 s, 2 = 10 s)
 *   ff         time factor: the period is ff × time base
 *   items      each an S7ANY request item (12 10 0A …, 12 bytes) as in a Read Var job
 *
 * Unsubscribe data: 05 (unsubscribe one job), job id.
 * Answer and push data: nn nn item count, then the items as in a Read Var
 * ack (return code, transport size, length, data, a fill byte after odd-length
 * data except the last). The job id is the parameters' sequence number.
 */
import { ProtocolError, ValueError } from '../../errors';
import { READ_ITEM, Rosctr, S7_JOB_HEADER, S7_PROTOCOL_ID, UserdataGroup, UserdataMethod, UserdataType } from '../constants';
import { FRAME_OVERHEAD } from '../../iso/constants';
import { dataLengthBytes, dataLengthField, type ReadResponseItem, type S7Item } from './pdu';
import { encodeUserdata, encodeUserdataRequest, encodeUserdataResponse } from './userdata';

/** Subfunctions of function group 2 (Wireshark: userdata_cyclic_subfunc_names). */
export const enum CyclicSubfunction {
  /** Cyclic transfer: every n × time base. */
  Memory = 0x01,
  Unsubscribe = 0x04,
  /** Change driven transfer: when a value changed (checked every n × time base). */
  ChangeDriven = 0x05,
}

/** Milliseconds of each time base, by its code (Wireshark: s7comm.cyclic.interval_timebase 0 = 100 ms, 1 = 1 s, 2 = 10 s). */
export const CYCLIC_TIME_BASE_MS: readonly number[] = Object.freeze([100, 1000, 10000]);

/** The unsubscribe request's function byte: end one job (PLC4X's S7 driver). */
export const UNSUBSCRIBE_ONE_JOB = 0x05;

/** Error codes of the cyclic services (Wireshark: param_errcode_names). */
export const CYCLIC_ERRORS = Object.freeze({
  /** At least one tag address is invalid. */
  BAD_ADDRESS: 0xd801,
  /** Specified job does not exist. */
  NO_SUCH_JOB: 0xd802,
  /** Illegal cycle time (illegal time base or multiple). */
  BAD_CYCLE: 0xd804,
  /** No more cyclic read jobs can be set up. */
  NO_MORE_JOBS: 0xd805,
});

/** The words of CYCLIC_ERRORS and the rest of the group's codes (Wireshark: param_errcode_names). */
export const CYCLIC_ERROR_TEXT: Readonly<Record<number, string>> = Object.freeze({
  0xd801: 'at least one tag address is invalid',
  0xd802: 'the specified job does not exist',
  0xd803: 'illegal job status',
  0xd804: 'illegal cycle time (illegal time base or multiple)',
  0xd805: 'no more cyclic read jobs can be set up',
  0xd806: 'the referenced job is in a state in which the requested function cannot be performed',
  0xd807: 'function aborted due to overload: the read cycle takes longer than the set cycle time',
});

/** Bytes of a request's data before its items: count, time base, factor. */
export const CYCLIC_REQUEST_HEAD = 4;
/** Bytes of an answer's or push's data before its items: the count. */
export const CYCLIC_ANSWER_HEAD = 2;

/** Whether a whole frame is a userdata request of function group 2 (bytes only; the service decodes). */
export function isCyclicRequest(frame: Buffer): boolean {
  const at = FRAME_OVERHEAD;
  const params = at + S7_JOB_HEADER;
  return (
    frame.length > params + 8 &&
    frame[at] === S7_PROTOCOL_ID &&
    frame[at + 1] === Rosctr.UserData &&
    frame[params + 2] === 0x12 &&
    frame[params + 5] === ((UserdataType.Request << 4) | UserdataGroup.Cyclic)
  );
}

/** A cyclic job as a client registers it. */
export interface CyclicJob {
  subfunction: CyclicSubfunction.Memory | CyclicSubfunction.ChangeDriven;
  timeBase: number;
  /** 1..255: the period is factor × time base. */
  factor: number;
  items: readonly S7Item[];
}

/** The registration request (the data of a userdata request of group 2). */
export function encodeCyclicSubscribe(job: CyclicJob): Buffer {
  const n = job.items.length;
  if (n < 1 || n > 0xffff) throw new ValueError('cyclic job', `${n} items (1 or more)`);
  if (!(job.timeBase in CYCLIC_TIME_BASE_MS)) throw new ValueError('cyclic job', `time base ${job.timeBase} (0, 1 or 2)`);
  if (!Number.isInteger(job.factor) || job.factor < 1 || job.factor > 255)
    throw new ValueError('cyclic job', `time factor ${job.factor} (1..255)`);
  const data = Buffer.alloc(CYCLIC_REQUEST_HEAD + READ_ITEM * n);
  data.writeUInt16BE(n, 0);
  data[2] = job.timeBase;
  data[3] = job.factor;
  for (let i = 0; i < n; i++) {
    const it = job.items[i]!;
    const o = CYCLIC_REQUEST_HEAD + READ_ITEM * i;
    data[o] = 0x12; // variable specification
    data[o + 1] = 0x0a; // length of the rest of the item
    data[o + 2] = 0x10; // syntax id S7ANY
    data[o + 3] = it.transportSize;
    data.writeUInt16BE(it.count & 0xffff, o + 4);
    data.writeUInt16BE(it.dbNumber & 0xffff, o + 6);
    data[o + 8] = it.area;
    data.writeUIntBE(it.address & 0xffffff, o + 9, 3);
  }
  return encodeUserdataRequest(UserdataGroup.Cyclic, job.subfunction, data);
}

/** A registration's data back to the job (the simulator's side); throws ProtocolError. */
export function decodeCyclicSubscribe(subfunction: number, data: Buffer): CyclicJob {
  if (subfunction !== CyclicSubfunction.Memory && subfunction !== CyclicSubfunction.ChangeDriven) {
    throw new ProtocolError(`cyclic subfunction 0x${subfunction.toString(16)} is not a registration`);
  }
  if (data.length < CYCLIC_REQUEST_HEAD) throw new ProtocolError(`cyclic registration of ${data.length} bytes, expected at least 4`);
  const n = data.readUInt16BE(0);
  if (data.length !== CYCLIC_REQUEST_HEAD + READ_ITEM * n) {
    throw new ProtocolError(`cyclic registration of ${n} items needs ${CYCLIC_REQUEST_HEAD + READ_ITEM * n} bytes, got ${data.length}`);
  }
  const items: S7Item[] = [];
  for (let i = 0; i < n; i++) {
    const o = CYCLIC_REQUEST_HEAD + READ_ITEM * i;
    if (data[o] !== 0x12 || data[o + 1] !== 0x0a || data[o + 2] !== 0x10) {
      throw new ProtocolError(`cyclic item ${i + 1}: not an S7ANY address (12 0A 10)`);
    }
    items.push({
      transportSize: data[o + 3]!,
      count: data.readUInt16BE(o + 4),
      dbNumber: data.readUInt16BE(o + 6),
      area: data[o + 8]!,
      address: data.readUIntBE(o + 9, 3),
    });
  }
  return { subfunction, timeBase: data[2]!, factor: data[3]!, items };
}

/** The request ending a job. */
export function encodeCyclicUnsubscribe(jobId: number): Buffer {
  return encodeUserdataRequest(UserdataGroup.Cyclic, CyclicSubfunction.Unsubscribe, Buffer.from([UNSUBSCRIBE_ONE_JOB, jobId & 0xff]));
}

/** An unsubscribe request's data: its function and job id; throws ProtocolError. */
export function decodeCyclicUnsubscribe(data: Buffer): { func: number; jobId: number } {
  if (data.length !== 2) throw new ProtocolError(`cyclic unsubscribe of ${data.length} bytes, expected 2`);
  return { func: data[0]!, jobId: data[1]! };
}

/** Answer and push data: the count, then the items as a Read Var ack carries them. */
export function encodeCyclicValues(items: readonly ReadResponseItem[]): Buffer {
  let size = CYCLIC_ANSWER_HEAD;
  const last = items.length - 1;
  items.forEach((it, i) => (size += 4 + it.data.length + (it.data.length & 1 && i < last ? 1 : 0)));
  const data = Buffer.alloc(size);
  data.writeUInt16BE(items.length, 0);
  let p = CYCLIC_ANSWER_HEAD;
  items.forEach((it, i) => {
    const ok = it.returnCode === 0xff;
    data[p] = it.returnCode;
    data[p + 1] = ok ? it.transportSize : 0;
    data.writeUInt16BE(ok ? dataLengthField(it.transportSize, it.data.length) : 0, p + 2);
    if (ok) it.data.copy(data, p + 4);
    p += 4 + (ok ? it.data.length : 0);
    if (ok && it.data.length & 1 && i < last) p++;
  });
  return p === size ? data : data.subarray(0, p);
}

/** Answer and push data back to the items (data subarrays of `data`); throws ProtocolError. A failed item carries no data. */
export function decodeCyclicValues(data: Buffer): ReadResponseItem[] {
  if (data.length < CYCLIC_ANSWER_HEAD) throw new ProtocolError(`cyclic data of ${data.length} bytes, expected at least 2`);
  const n = data.readUInt16BE(0);
  const items: ReadResponseItem[] = [];
  let p = CYCLIC_ANSWER_HEAD;
  for (let i = 0; i < n; i++) {
    if (p + 4 > data.length) throw new ProtocolError(`cyclic data: item ${i + 1} of ${n} is missing`);
    const returnCode = data[p]!;
    const transportSize = data[p + 1]!;
    const len = returnCode === 0xff ? dataLengthBytes(transportSize, data.readUInt16BE(p + 2)) : 0;
    if (p + 4 + len > data.length)
      throw new ProtocolError(`cyclic data: item ${i + 1} announces ${len} bytes, ${data.length - p - 4} present`);
    items.push({ returnCode, transportSize, data: data.subarray(p + 4, p + 4 + len) });
    p += 4 + len;
    if (len & 1 && i < n - 1) p++;
  }
  if (data.length - p > 1) throw new ProtocolError(`cyclic data: ${data.length - p} bytes after ${n} items`);
  return items;
}

/** The CPU's answer to a registration: the job id (sequence number) and the first values, or a service error. */
export function encodeCyclicAnswer(pduRef: number, subfunction: number, jobId: number, values?: Buffer, errorCode = 0): Buffer {
  return encodeUserdataResponse(pduRef, UserdataGroup.Cyclic, subfunction, {
    sequence: jobId,
    errorCode,
    ...(values ? { data: values } : {}),
  });
}

/** The CPU's push of a job's values (userdata type push, the job id as sequence number). */
export function encodeCyclicPush(subfunction: number, jobId: number, values: Buffer): Buffer {
  return encodeUserdata(
    0,
    {
      method: UserdataMethod.Response,
      type: UserdataType.Push,
      group: UserdataGroup.Cyclic,
      subfunction,
      sequence: jobId & 0xff,
      dataUnitRef: 0,
      lastDataUnit: true,
      errorCode: 0,
    },
    values,
  );
}
