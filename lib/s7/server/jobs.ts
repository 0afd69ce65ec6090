/**
 * The simulator's Read Var / Write Var service, straight from the request
 * frame into one response Buffer: no per-item objects on the hot path (the
 * benchmark measures the simulator in requests per second). Malformed jobs
 * throw ProtocolError; the server then drops the connection like a CPU does.
 */
import { ProtocolError } from '../../errors';
import type { PlcMemory } from '../../sim/memory';
import type { AreaName } from '../../types';
import { dataLengthBytes, dataLengthField, encodeHeaderErrorAck, s7Frame } from '../codec/pdu';
import { s7PduRef, s7Rosctr } from '../codec/pdu-decode';
import {
  DataTransportSize,
  HeaderError,
  READ_ITEM,
  ReturnCode,
  Rosctr,
  S7Area,
  S7Function,
  S7_ACK_HEADER,
  S7_JOB_HEADER,
  S7_PROTOCOL_ID,
  TransportSize,
  VAR_PARAMETER_HEAD,
} from '../constants';
import { COTP_DT_HEADER, CotpType, FRAME_OVERHEAD, TPKT_HEADER } from '../../iso/constants';

export interface JobContext {
  memory: PlcMemory;
  /** Negotiated PDU size: requests and answers larger than this are refused with 0x8500. */
  pduSize: number;
  /** DBs that answer "object does not exist" (fault injection); undefined when none. */
  missingDb?: ((dbNumber: number) => boolean) | undefined;
  /** Optimized DBs (served by S7CommPlus only): a CPU answers PUT/GET on them "address out of range" (python-snap7#191). */
  optimizedDb?: ReadonlySet<number> | undefined;
  /** false: the S5 counter and timer areas answer 0x03 (an S7-200 or LOGO!); default true. */
  s5CountersTimers?: boolean;
}

/** Where the S7 parameters of a job start in a frame with the usual 3-byte COTP DT header. */
const PARAMS = FRAME_OVERHEAD + S7_JOB_HEADER;
const ACK_PARAMS = FRAME_OVERHEAD + S7_ACK_HEADER;
/** The COTP DT header after TPKT: its length indicator (2), its code (DT) and EOT (0x80, the last data unit). */
const COTP_LI = TPKT_HEADER;
const COTP_CODE = TPKT_HEADER + 1;
const COTP_EOT_AT = TPKT_HEADER + 2;
const EOT = 0x80;

/**
 * COUNTERS_AND_TIMERS: how an S7-300/400 CPU serves the S5 counter (0x1C) and
 * timer (0x1D) areas, and so the simulator.
 * - An item whose transport size is the area's own code (COUNTER 0x1C for C,
 *   TIMER 0x1D for T) counts counters/timers of 2 bytes, and its address field
 *   is the counter/timer number, not a bit address. That is how snap7's client
 *   asks (s7_micro_client.cpp: WordLen S7WLCounter/S7WLTimer, Address = Start
 *   with no ×8) and how S7NetPlus reads (S7NetPlus/s7netplus#561: the start
 *   address is the counter number).
 * - The answer's data transport size is 0x09 OCTET STRING, its length in bytes
 *   (2 per element): nodes7 checks exactly that (nodeS7.js, readTransportCode
 *   0x09 for C and T), and snap7's server answers so (TS_ResOctet).
 * - Any other transport size on C or T is refused with 0x05 "address out of
 *   range". A real CPU did so to python-snap7 before its fix #121, which asked
 *   for a timer with BYTE (0x02) at a bit address (gijzelaerr/python-snap7#62,
 *   "CPU : Address out of range"); snap7's server applies the same rule to every
 *   mismatch ("timers/counters coherence", RA_OutOfRange). No capture of a CPU
 *   answering transport size 0x09 (which @st-one-io/nodes7 sends for C and T;
 *   the item table names 0x09 DATE) was found: the simulator follows snap7's
 *   rule and answers 0x05 there too.
 * - S7-200 SMART CPUs refuse the 0x1C/0x1D areas with 0x03 "access denied"
 *   (S7NetPlus/s7netplus#531, st-one-io/node-red-contrib-s7#144); their counters
 *   and timers are the IEC areas 0x1E/0x1F (gijzelaerr/python-snap7#471), which
 *   the simulator does not serve. JobContext.s5CountersTimers false models that.
 * Where the sources disagree: snap7's server turns the number into a byte
 * offset with `Start >> 1` (s7_server.cpp), so its CTRead(5) answers the word
 * of C1 (checked against node-snap7 1.0.9), where the clients above get
 * counter n for the number n. The simulator keeps counter n at bytes
 * 2n..2n+1 and answers it for number n. Not known: what an S7-1200 (no S5
 * counters or timers) answers; the simulator serves C and T on every
 * S7-300/400/1200/1500 profile.
 */
/** Bytes per element of a request item's transport size; 0 = not supported. */
const ELEMENT = new Uint8Array(256);
ELEMENT[TransportSize.BIT] = 1;
ELEMENT[TransportSize.BYTE] = 1;
ELEMENT[TransportSize.CHAR] = 1;
ELEMENT[TransportSize.WORD] = 2;
ELEMENT[TransportSize.INT] = 2;
ELEMENT[TransportSize.DWORD] = 4;
ELEMENT[TransportSize.DINT] = 4;
ELEMENT[TransportSize.REAL] = 4;
// The other ANY-pointer data type codes a CPU accepts in a Read/Write Var item, with their sizes.
ELEMENT[TransportSize.DATE] = 2;
ELEMENT[TransportSize.TIME_OF_DAY] = 4;
ELEMENT[TransportSize.TIME] = 4;
ELEMENT[TransportSize.S5TIME] = 2;
ELEMENT[TransportSize.DATE_AND_TIME] = 8;
// Counted in 2-byte elements: Apache PLC4X 0.13.1 reads and writes one WCHAR as code 0x13, count 1, 2 bytes.
ELEMENT[TransportSize.STRING] = 2;
ELEMENT[TransportSize.COUNTER] = 2;
ELEMENT[TransportSize.TIMER] = 2;

/**
 * Data transport size a CPU answers with: BIT for bits, INTEGER for INT/DINT,
 * REAL for REAL, OCTET STRING for counters/timers, BYTE otherwise.
 */
function answerSize(transportSize: number, area: number): number {
  if (transportSize === TransportSize.BIT) return DataTransportSize.BIT;
  if (area === S7Area.C || area === S7Area.T) return DataTransportSize.OCTET_STRING;
  if (transportSize === TransportSize.INT || transportSize === TransportSize.DINT) return DataTransportSize.INTEGER;
  if (transportSize === TransportSize.REAL) return DataTransportSize.REAL;
  return DataTransportSize.BYTE;
}

function areaName(code: number, forWrite: boolean): AreaName | undefined {
  switch (code) {
    case S7Area.DB:
      return 'DB';
    case S7Area.M:
      return 'M';
    case S7Area.I:
      return 'I';
    case S7Area.Q:
      return 'Q';
    // The peripheral area is one code: reads see PE (inputs), writes go to PA (outputs).
    case S7Area.PE_PA:
      return forWrite ? 'PA' : 'PE';
    case S7Area.C:
      return 'C';
    case S7Area.T:
      return 'T';
    default:
      return undefined;
  }
}

/** What a job frame is, without allocating: its function when it is a well-formed Read/Write Var job, else 0. */
export function jobFunction(frame: Buffer): number {
  if (frame.length < PARAMS + 2 || frame[COTP_LI] !== COTP_DT_HEADER - 1 || frame[COTP_CODE] !== CotpType.DT || frame[COTP_EOT_AT] !== EOT)
    return 0;
  if (frame[FRAME_OVERHEAD] !== S7_PROTOCOL_ID || s7Rosctr(frame) !== Rosctr.Job) return 0;
  const func = frame[PARAMS]!;
  return func === S7Function.ReadVar || func === S7Function.WriteVar ? func : 0;
}

export function jobPduRef(frame: Buffer): number {
  return s7PduRef(frame);
}

/** Scratch per item, reused by every job (jobs are served synchronously, one at a time). */
const itemBuffer: (Buffer | undefined)[] = new Array<Buffer | undefined>(256);
const itemOffset = new Int32Array(256);
const itemLength = new Int32Array(256);
const itemCode = new Uint8Array(256);
const itemSize = new Uint8Array(256);
const itemBit = new Int8Array(256);
const itemData = new Int32Array(256);

function checkLengths(frame: Buffer): { count: number; paramLength: number; dataLength: number } {
  const paramLength = frame.readUInt16BE(13);
  const dataLength = frame.readUInt16BE(15);
  if (FRAME_OVERHEAD + S7_JOB_HEADER + paramLength + dataLength !== frame.length) {
    throw new ProtocolError(`S7 lengths (parameters ${paramLength} + data ${dataLength}) do not match the frame (${frame.length} bytes)`);
  }
  const count = frame[PARAMS + 1]!;
  if (paramLength !== 2 + READ_ITEM * count)
    throw new ProtocolError(`${count} items need ${2 + READ_ITEM * count} parameter bytes, got ${paramLength}`);
  return { count, paramLength, dataLength };
}

/**
 * Locates item i (request item at `o`) in memory: sets the scratch entries
 * and returns the item's return code (0xFF when it can be served).
 */
function locate(frame: Buffer, i: number, o: number, ctx: JobContext, forWrite: boolean): number {
  if (frame[o] !== 0x12 || frame[o + 1] !== 0x0a || frame[o + 2] !== 0x10)
    throw new ProtocolError(`item ${i + 1}: not an S7ANY address (12 0A 10)`);
  const ts = frame[o + 3]!;
  const count = (frame[o + 4]! << 8) | frame[o + 5]!;
  const db = (frame[o + 6]! << 8) | frame[o + 7]!;
  const areaCode = frame[o + 8]!;
  const address = (frame[o + 9]! << 16) | (frame[o + 10]! << 8) | frame[o + 11]!;
  itemSize[i] = answerSize(ts, areaCode);
  itemLength[i] = 0;
  itemBit[i] = -1;
  const area = areaName(areaCode, forWrite);
  if (!area) return ReturnCode.AddressOutOfRange;
  let offset: number;
  let length: number;
  if (area === 'C' || area === 'T') {
    if (ctx.s5CountersTimers === false) return ReturnCode.AccessDenied;
    // Only the area's own transport size is served (see COUNTERS_AND_TIMERS); the address is the number.
    if (ts !== (area === 'C' ? TransportSize.COUNTER : TransportSize.TIMER)) return ReturnCode.AddressOutOfRange;
    offset = address * 2;
    length = count * 2;
  } else {
    const element = ELEMENT[ts]!;
    if (element === 0) return ReturnCode.DataTypeNotSupported;
    if (ts === TransportSize.COUNTER || ts === TransportSize.TIMER) return ReturnCode.DataTypeNotSupported;
    if (ts === TransportSize.BIT) {
      if (count !== 1) return ReturnCode.DataTypeInconsistent;
      itemBit[i] = address & 7;
      length = 1;
    } else {
      // The bit part of a byte-sized item's address is ignored (docs/protocols.md, corrections: unaligned BYTE items).
      length = count * element;
    }
    offset = address >>> 3;
  }
  if (length === 0) return ReturnCode.AddressOutOfRange;
  if (area === 'DB' && ctx.missingDb?.(db)) return ReturnCode.ObjectDoesNotExist;
  if (area === 'DB' && ctx.optimizedDb?.has(db)) return ReturnCode.AddressOutOfRange;
  const buf = ctx.memory.area(area, db);
  if (!buf) return ReturnCode.ObjectDoesNotExist;
  if (offset + length > buf.length) return ReturnCode.AddressOutOfRange;
  itemBuffer[i] = buf;
  itemOffset[i] = offset;
  itemLength[i] = length;
  return ReturnCode.Success;
}

/** An ack with a header error (class << 8 | code) and no parameters: how a CPU refuses a whole job. */
export function refuseJob(pduRef: number, error: HeaderError): Buffer {
  return encodeHeaderErrorAck(pduRef, error);
}

/** An ack-data frame for Read/Write Var with `count` items and `dataLength` data bytes, header and parameters written. */
function ackData(pduRef: number, func: number, count: number, dataLength: number): Buffer {
  const frame = s7Frame(Rosctr.AckData, pduRef, VAR_PARAMETER_HEAD, dataLength);
  frame[ACK_PARAMS] = func;
  frame[ACK_PARAMS + 1] = count;
  return frame;
}

/** Serves a Read Var job frame (jobFunction(frame) === ReadVar); returns the whole answer frame. */
export function serveRead(frame: Buffer, ctx: JobContext): Buffer {
  const pduRef = jobPduRef(frame);
  const { count, dataLength } = checkLengths(frame);
  if (dataLength !== 0) throw new ProtocolError(`read request with ${dataLength} data bytes`);
  if (frame.length - FRAME_OVERHEAD > ctx.pduSize) return refuseJob(pduRef, HeaderError.PduTooLarge);
  let data = 0;
  for (let i = 0; i < count; i++) {
    const code = locate(frame, i, PARAMS + 2 + READ_ITEM * i, ctx, false);
    itemCode[i] = code;
    if (code !== ReturnCode.Success) itemLength[i] = 0;
    const len = itemLength[i]!;
    data += 4 + len + (len & 1 && i < count - 1 ? 1 : 0);
  }
  if (S7_ACK_HEADER + 2 + data > ctx.pduSize) return refuseJob(pduRef, HeaderError.PduTooLarge);
  const reply = ackData(pduRef, S7Function.ReadVar, count, data);
  const notify = ctx.memory.listenerCount('read') > 0;
  let p = ACK_PARAMS + 2;
  for (let i = 0; i < count; i++) {
    const code = itemCode[i]!;
    const len = itemLength[i]!;
    reply[p] = code;
    if (code !== ReturnCode.Success) {
      reply[p + 1] = 0;
      reply[p + 2] = 0;
      reply[p + 3] = 0;
      p += 4;
      continue;
    }
    const size = itemSize[i]!;
    const field = dataLengthField(size, len);
    reply[p + 1] = size;
    reply[p + 2] = field >> 8;
    reply[p + 3] = field & 0xff;
    const buf = itemBuffer[i]!;
    const offset = itemOffset[i]!;
    const bit = itemBit[i]!;
    if (bit >= 0) reply[p + 4] = (buf[offset]! >> bit) & 1;
    else if (len <= 16) for (let k = 0; k < len; k++) reply[p + 4 + k] = buf[offset + k]!;
    else buf.copy(reply, p + 4, offset, offset + len);
    p += 4 + len;
    if (len & 1 && i < count - 1) reply[p++] = 0;
    if (notify) emitAccess(ctx, 'read', frame, i, offset, len);
  }
  for (let i = 0; i < count; i++) itemBuffer[i] = undefined;
  return reply;
}

/** Serves a Write Var job frame (jobFunction(frame) === WriteVar); returns the whole answer frame. */
export function serveWrite(frame: Buffer, ctx: JobContext): Buffer {
  const pduRef = jobPduRef(frame);
  const { count, paramLength } = checkLengths(frame);
  // Parse the whole data part first: a malformed job must not change memory at all.
  let p = PARAMS + paramLength;
  for (let i = 0; i < count; i++) {
    if (p + 4 > frame.length) throw new ProtocolError(`data item ${i + 1} of ${count} is missing`);
    const size = frame[p + 1]!;
    const len = dataLengthBytes(size, (frame[p + 2]! << 8) | frame[p + 3]!);
    if (p + 4 + len > frame.length) throw new ProtocolError(`data item ${i + 1}: ${len} bytes announced, ${frame.length - p - 4} present`);
    itemData[i] = p;
    p += 4 + len;
    if (len & 1 && i < count - 1) p++;
  }
  if (frame.length - p > 1) throw new ProtocolError(`${frame.length - p} stray bytes after the data items`);
  if (frame.length - FRAME_OVERHEAD > ctx.pduSize) return refuseJob(pduRef, HeaderError.PduTooLarge);
  const reply = ackData(pduRef, S7Function.WriteVar, count, count);
  const notify = ctx.memory.listenerCount('write') > 0;
  for (let i = 0; i < count; i++) {
    let code = locate(frame, i, PARAMS + 2 + READ_ITEM * i, ctx, true);
    if (code === ReturnCode.Success) {
      const d = itemData[i]!;
      const size = frame[d + 1]!;
      const len = dataLengthBytes(size, (frame[d + 2]! << 8) | frame[d + 3]!);
      const buf = itemBuffer[i]!;
      const offset = itemOffset[i]!;
      const bit = itemBit[i]!;
      if (bit >= 0) {
        if (size !== DataTransportSize.BIT || len !== 1) code = ReturnCode.DataTypeInconsistent;
        else buf[offset] = frame[d + 4]! & 1 ? buf[offset]! | (1 << bit) : buf[offset]! & ~(1 << bit);
      } else if (size === DataTransportSize.BIT || len !== itemLength[i]) {
        code = ReturnCode.DataTypeInconsistent;
      } else {
        frame.copy(buf, offset, d + 4, d + 4 + len);
      }
      if (code === ReturnCode.Success && notify) emitAccess(ctx, 'write', frame, i, offset, bit >= 0 ? 1 : len, buf);
    }
    reply[ACK_PARAMS + 2 + i] = code;
    itemBuffer[i] = undefined;
  }
  return reply;
}

/** Memory's 'read'/'write' events (only built when someone listens). */
function emitAccess(
  ctx: JobContext,
  kind: 'read' | 'write',
  frame: Buffer,
  i: number,
  offset: number,
  length: number,
  written?: Buffer,
): void {
  const o = PARAMS + 2 + READ_ITEM * i;
  const area = areaName(frame[o + 8]!, kind === 'write')!;
  const dbNumber = area === 'DB' ? frame.readUInt16BE(o + 6) : 0;
  const event =
    written === undefined
      ? { area, dbNumber, offset, length }
      : { area, dbNumber, offset, length, data: Buffer.from(written.subarray(offset, offset + length)) };
  ctx.memory.emit(kind, event);
}
