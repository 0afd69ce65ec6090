/**
 * The simulated CPU's system services: the RUN/STOP state machine with its
 * diagnostic buffer, the clock, identity (SZL), blocks (one per DB of the
 * memory, a few OBs/FCs so lists look real), block info and upload, and
 * protection levels with a password. S7Server dispatches userdata PDUs and
 * the control jobs (PLC stop, PI service, upload) here; everything is
 * answered the way a CPU of the profile answers, refusals included.
 * Malformed requests throw ProtocolError (the server drops that connection);
 * well-formed requests for something the CPU does not offer get the CPU's
 * error answer and the connection stays up. The SZL lists are built in
 * szl-lists.ts, the blocks and block functions in blocks.ts.
 */
import { EventEmitter } from 'node:events';
import { ProtocolError } from '../../errors';
import type { PlcMemory } from '../../sim/memory';
import { decodeDateAndTime, encodeDateAndTime } from '../../values/time';
import { encodeLoadBlock, loadSizeOf } from '../codec/blocks';
import { decodeControl, encodeControlAck, encodeStartUploadAck, encodeUploadAck } from '../codec/control';
import { type DiagnosticEntry, type DiagnosticEvent, describeEvent } from '../codec/diagnostics';
import { encodeHeaderErrorAck } from '../codec/pdu';
import { encodeSzl, type SzlList } from '../codec/szl';
import { decodePassword, decodeUserdata, encodeUserdataResponse, USERDATA_OVERHEAD, type UserdataPdu } from '../codec/userdata';
import {
  ControlFunction,
  CpuSubfunction,
  S7Function,
  SecuritySubfunction,
  TimeSubfunction,
  UserdataGroup,
  UserdataMethod,
  UserdataType,
  blockTypeName,
  type BlockType,
} from '../constants';
import { FRAME_OVERHEAD } from '../../iso/constants';
import { blockNumbers, blockSpec, serveBlockFunction, type SimulatedBlock } from './blocks';
import type { CpuIdentity } from './profiles';
import { SERVICE_CODE as E } from './service-codes';
import { SZL_IDS, szlList } from './szl-lists';
import { AlarmEngine, type AlarmOptions, type AlarmPeer } from './alarms';

/** RUN or STOP (the simulator passes STARTUP at once). */
export type SimulatorMode = 'RUN' | 'STOP';

/** Why the simulated CPU stops: the event ID its diagnostic buffer logs. */
export const STOP_CAUSES = Object.freeze({
  /** PLC stop from a programming device or a client (0x4304). */
  command: 0x4304,
  /** The mode selector turned to STOP (0x4303). */
  switch: 0x4303,
  /** A programming error without its error OB (0x4562). */
  'programming-error': 0x4562,
  /** An I/O access error without its error OB (0x4563). */
  'io-error': 0x4563,
  /** A time error without OB 80 (0x4568). */
  'time-error': 0x4568,
} as const);
export type StopCause = keyof typeof STOP_CAUSES;

/** Per-connection state of the services. */
export interface ServiceSession {
  /** The rest of a multi-part answer, asked for part by part with its sequence number. */
  pending: { sequence: number; group: number; subfunction: number; rest: Buffer } | undefined;
  uploads: Map<number, { bytes: Buffer; offset: number }>;
  nextRef: number;
  /** The connection gave the right password. */
  authorized: boolean;
  peer?: AlarmPeer;
}

export function newServiceSession(peer?: AlarmPeer): ServiceSession {
  return { pending: undefined, uploads: new Map(), nextRef: 0, authorized: false, peer };
}

const DIAGNOSTIC_CAPACITY = 100;
/** The range of a DATE_AND_TIME, with a day's margin at the end so the running clock stays inside. */
const CLOCK_MIN = Date.UTC(1990, 0, 1);
const CLOCK_MAX = Date.UTC(2089, 11, 30);

/**
 * The system side of a simulated CPU, shared by all its connections.
 * Emits `mode` (SimulatorMode) on every transition and `diagnostic`
 * (DiagnosticEntry) for every entry logged.
 */
export class CpuServices extends EventEmitter {
  private modeNow: SimulatorMode = 'RUN';
  private readonly log: DiagnosticEvent[] = [];
  private offset = 0;
  private level = 1;
  private password: string | undefined;
  private lastTransition: { eventId: number; time: Date };
  private readonly created: Date;
  readonly alarms: AlarmEngine;

  constructor(
    private readonly memory: PlcMemory,
    readonly identity: Readonly<CpuIdentity>,
    private readonly limits: { maxConnections: number } & AlarmOptions,
  ) {
    super();
    this.alarms = new AlarmEngine(memory, this, limits);
    this.created = new Date(Math.floor(Date.now() / 1000) * 1000);
    // A CPU that was powered on and went to RUN.
    this.record(0x1382, 0xfe, 100);
    this.record(0x4301);
    this.record(0x4302);
    this.lastTransition = { eventId: 0x4302, time: this.now() };
  }

  get mode(): SimulatorMode {
    return this.modeNow;
  }

  /** The CPU clock: the host clock plus the offset (ms). */
  now(): Date {
    return new Date(Date.now() + this.offset);
  }

  get clockOffset(): number {
    return this.offset;
  }

  /** The offset is checked: the CPU clock (a DATE_AND_TIME) stays within 1990..2089. */
  set clockOffset(ms: number) {
    if (!Number.isFinite(ms)) throw new TypeError(`clock offset must be a number of milliseconds, got ${String(ms)}`);
    const at = Date.now() + Math.round(ms);
    if (at < CLOCK_MIN || at > CLOCK_MAX)
      throw new RangeError(`the CPU clock runs from 1990 to 2089; ${new Date(at).toISOString()} is outside`);
    this.offset = Math.round(ms);
  }

  /** Sets the CPU clock to `date` (it runs on from there). */
  setClock(date: Date): void {
    this.clockOffset = date.getTime() - Date.now();
  }

  /** The diagnostic buffer, newest first, with descriptions. */
  get diagnostics(): DiagnosticEntry[] {
    return this.log.map((e) => ({ ...e, description: describeEvent(e.eventId) }));
  }

  /** Logs an event in the diagnostic buffer (newest first, the oldest dropped beyond 100). */
  record(
    eventId: number,
    priority = 0xff,
    ob = 0xff,
    info: Partial<Pick<DiagnosticEvent, 'dataId' | 'info1' | 'info2' | 'info3'>> = {},
  ): void {
    const e: DiagnosticEvent = {
      time: this.now(),
      eventId,
      priority,
      ob,
      dataId: info.dataId ?? 0,
      info1: info.info1 ?? 0,
      info2: info.info2 ?? 0,
      info3: info.info3 ?? 0,
    };
    this.log.unshift(e);
    if (this.log.length > DIAGNOSTIC_CAPACITY) this.log.length = DIAGNOSTIC_CAPACITY;
    if (this.listenerCount('diagnostic') > 0) this.emit('diagnostic', { ...e, description: describeEvent(eventId) });
  }

  /** RUN → STOP, logging the cause; false when already in STOP. */
  stop(cause: StopCause | number = 'command'): boolean {
    const eventId = typeof cause === 'number' ? cause : STOP_CAUSES[cause];
    if (eventId === undefined || !Number.isInteger(eventId) || eventId < 0 || eventId > 0xffff) {
      throw new TypeError(`unknown stop cause "${String(cause)}" (${Object.keys(STOP_CAUSES).join(', ')}, or an event ID)`);
    }
    if (this.modeNow === 'STOP') return false;
    this.modeNow = 'STOP';
    this.record(eventId);
    this.lastTransition = { eventId, time: this.now() };
    this.emit('mode', this.modeNow);
    return true;
  }

  /** STOP → STARTUP → RUN (warm restart, OB 100, or cold restart, OB 102); false when already in RUN. */
  start(kind: 'warm' | 'cold' = 'warm'): boolean {
    if (this.modeNow === 'RUN') return false;
    this.record(kind === 'cold' ? 0x1385 : 0x1381, 0xfe, kind === 'cold' ? 102 : 100);
    this.record(0x4301);
    this.record(0x4302);
    this.modeNow = 'RUN';
    this.lastTransition = { eventId: 0x4302, time: this.now() };
    this.emit('mode', this.modeNow);
    return true;
  }

  /** Protection level 1 (none), 2 (writes and control need the password) or 3 (reads and upload too). */
  setProtection(level: 1 | 2 | 3, password?: string): void {
    if (level !== 1 && level !== 2 && level !== 3) throw new TypeError(`protection level must be 1, 2 or 3, got ${String(level)}`);
    if (level > 1 && (typeof password !== 'string' || password.length === 0 || password.length > 8)) {
      throw new TypeError('protection levels 2 and 3 need a password of 1 to 8 characters');
    }
    this.level = level;
    this.password = level > 1 ? password : undefined;
  }

  get protectionLevel(): number {
    return this.level;
  }

  /** The level in force for a connection: 1 once it gave the password. */
  private levelFor(s: ServiceSession): number {
    return s.authorized ? 1 : this.level;
  }

  /** True when the protection level refuses a Read Var (level 3) or Write Var (level 2) job of this connection. */
  refusesData(s: ServiceSession, func: number): boolean {
    const level = this.levelFor(s);
    return func === S7Function.WriteVar ? level >= 2 : level >= 3;
  }

  // ---------------------------------------------------------------- userdata

  serveUserdata(frame: Buffer, s: ServiceSession, pduSize: number): Buffer {
    const u = decodeUserdata(frame);
    const { params } = u;
    if (params.type !== UserdataType.Request) throw new ProtocolError(`userdata of type ${params.type} sent to a CPU (expected a request)`);
    const answer = (a: Parameters<typeof encodeUserdataResponse>[3]) =>
      encodeUserdataResponse(u.pduRef, params.group, params.subfunction, a);
    // A request for the next part of a multi-part answer.
    if (params.method === UserdataMethod.Response) {
      const p = s.pending;
      if (!p || p.sequence !== params.sequence || p.group !== params.group || p.subfunction !== params.subfunction) {
        return answer({ sequence: params.sequence, errorCode: E.SYNTAX });
      }
      return this.part(s, u, pduSize, p.rest, p.sequence);
    }
    if (params.method !== UserdataMethod.Request)
      throw new ProtocolError(`userdata method 0x${params.method.toString(16)}, expected 0x11 or 0x12`);
    // A new request abandons an unfinished multi-part answer, as a CPU does.
    s.pending = undefined;
    switch (params.group) {
      case UserdataGroup.Cpu:
        if (params.subfunction === CpuSubfunction.ReadSzl) return this.readSzl(u, s, pduSize);
        return this.alarms.serve(u, s.peer, (bytes) => this.part(s, u, pduSize, bytes, this.nextSequence(s)));
      case UserdataGroup.Time:
        if (params.subfunction === TimeSubfunction.ReadClock) return answer({ data: this.clockData() });
        if (params.subfunction === TimeSubfunction.SetClock) {
          if (this.levelFor(s) >= 2) return answer({ errorCode: E.NEED_PASSWORD });
          const d = u.data.length === 10 ? decodeDateAndTime(u.data, 2) : new Date(Number.NaN);
          if (Number.isNaN(d.getTime()) || d.getTime() > CLOCK_MAX) return answer({ errorCode: E.BAD_TIME });
          this.setClock(d);
          return answer({});
        }
        break;
      case UserdataGroup.Block:
        if (!this.identity.blockFunctions) break;
        return this.blockFunction(u, s, pduSize);
      case UserdataGroup.Security:
        if (!this.identity.passwordFunctions) break;
        if (params.subfunction === SecuritySubfunction.SetPassword) {
          if (u.data.length !== 8) return answer({ errorCode: E.SYNTAX });
          if (this.password === undefined) return answer({ errorCode: E.NO_PASSWORD });
          if (decodePassword(u.data) !== this.password.padEnd(8, ' ')) return answer({ errorCode: E.WRONG_PASSWORD });
          s.authorized = true;
          return answer({});
        }
        if (params.subfunction === SecuritySubfunction.ClearPassword) {
          s.authorized = false;
          return answer({});
        }
        break;
      default:
        break;
    }
    return answer({ errorCode: E.NOT_IMPLEMENTED });
  }

  /** Sends `bytes` (part of an answer) in the space one PDU has; the rest waits for the next request. */
  private part(s: ServiceSession, u: UserdataPdu, pduSize: number, bytes: Buffer, sequence: number): Buffer {
    const room = pduSize - (USERDATA_OVERHEAD - FRAME_OVERHEAD);
    const { group, subfunction } = u.params;
    if (bytes.length <= room) {
      s.pending = undefined;
      return encodeUserdataResponse(u.pduRef, group, subfunction, { sequence, dataUnitRef: sequence, data: bytes });
    }
    // Block lists are cut at whole entries.
    const cut = group === UserdataGroup.Block ? room - (room % 4) : room;
    s.pending = { sequence, group, subfunction, rest: bytes.subarray(cut) };
    return encodeUserdataResponse(u.pduRef, group, subfunction, {
      sequence,
      dataUnitRef: sequence,
      last: false,
      data: bytes.subarray(0, cut),
    });
  }

  private nextSequence(s: ServiceSession): number {
    s.nextRef = (s.nextRef % 255) + 1;
    return s.nextRef;
  }

  private clockData(): Buffer {
    const now = this.now();
    const d = Buffer.alloc(10);
    const year = now.getUTCFullYear();
    d[1] = year >= 2000 ? 0x20 : 0x19;
    encodeDateAndTime(now, d, 2);
    return d;
  }

  // ---------------------------------------------------------------- SZL

  private readSzl(u: UserdataPdu, s: ServiceSession, pduSize: number): Buffer {
    if (u.data.length !== 4) return encodeUserdataResponse(u.pduRef, u.params.group, u.params.subfunction, { errorCode: E.SYNTAX });
    const id = u.data.readUInt16BE(0);
    const index = u.data.readUInt16BE(2);
    const headerOnly = (id & 0x0f00) === 0x0f00;
    const list = this.szl(headerOnly ? id & 0xf0ff : id, index, s, pduSize);
    if (typeof list === 'number') return encodeUserdataResponse(u.pduRef, u.params.group, u.params.subfunction, { errorCode: list });
    if (headerOnly) list.id = id;
    return this.part(s, u, pduSize, encodeSzl(list, headerOnly), this.nextSequence(s));
  }

  /** The SZL IDs served (0x0Fxx header-only extracts of the 0x00xx lists included). */
  static readonly SZL_IDS: readonly number[] = SZL_IDS;

  private szl(id: number, index: number, s: ServiceSession, pduSize: number): SzlList | number {
    return szlList(id, index, {
      identity: this.identity,
      maxConnections: this.limits.maxConnections,
      pduSize,
      level: this.levelFor(s),
      configuredLevel: this.level,
      mode: this.modeNow,
      lastTransition: this.lastTransition,
      log: this.log,
    });
  }

  // ---------------------------------------------------------------- blocks

  /** Every block of the simulated CPU: a DB per data block of the memory, and the fixed OBs, FCs … */
  blockNumbers(type: BlockType): number[] {
    return blockNumbers(this.memory, type);
  }

  private blockSpec(type: BlockType, number: number): SimulatedBlock | undefined {
    return blockSpec(this.memory, this.created, type, number);
  }

  private blockFunction(u: UserdataPdu, s: ServiceSession, pduSize: number): Buffer {
    return serveBlockFunction(u, this.memory, this.created, (bytes) => this.part(s, u, pduSize, bytes, this.nextSequence(s)));
  }

  // ---------------------------------------------------------------- control jobs

  /** PLC stop, PI service (start) and upload jobs. */
  serveControl(frame: Buffer, s: ServiceSession, pduSize: number): Buffer {
    const m = decodeControl(frame);
    const ref = m.pduRef;
    switch (m.kind) {
      case 'stop':
        if (this.levelFor(s) >= 2) return encodeControlAck(ref, ControlFunction.PlcStop, 0, E.NEED_PASSWORD);
        // Already in STOP: refused with the state error, parameter 0x07 (as CPUs answer).
        if (!this.stop('command')) return encodeControlAck(ref, ControlFunction.PlcStop, 0x07, E.STATE);
        return encodeControlAck(ref, ControlFunction.PlcStop);
      case 'start':
        if (m.service !== 'P_PROGRAM') return encodeControlAck(ref, ControlFunction.PiService, 0, E.NOT_IMPLEMENTED);
        if (this.levelFor(s) >= 2) return encodeControlAck(ref, ControlFunction.PiService, 0, E.NEED_PASSWORD);
        if (!this.start(m.cold ? 'cold' : 'warm')) return encodeControlAck(ref, ControlFunction.PiService, 0x03, E.STATE);
        return encodeControlAck(ref, ControlFunction.PiService);
      case 'start-upload': {
        // Upload refusals: an ack without parameters carrying the error (an ack-data would need the whole answer).
        if (!this.identity.blockFunctions) return refusal(ref, E.NOT_IMPLEMENTED);
        if (this.levelFor(s) >= 3) return refusal(ref, E.NEED_PASSWORD);
        const type = blockTypeName(m.blockType);
        const block = type ? this.blockSpec(type, m.number) : undefined;
        if (!block) return refusal(ref, E.BLOCK_NOT_FOUND);
        if (s.uploads.size >= 4) return refusal(ref, 0x8304);
        const id = this.nextSequence(s);
        // The block as it is now: later writes to the DB do not change an upload under way.
        s.uploads.set(id, { bytes: encodeLoadBlock(block.spec, Buffer.from(block.code)), offset: 0 });
        return encodeStartUploadAck(ref, id, loadSizeOf(block.spec));
      }
      case 'upload': {
        const up = s.uploads.get(m.uploadId);
        if (!up) return refusal(ref, E.STATE);
        // TPKT/COTP aside: header 12, parameters 2, data header 4.
        const room = pduSize - 18;
        const chunk = up.bytes.subarray(up.offset, up.offset + room);
        up.offset += chunk.length;
        return encodeUploadAck(ref, chunk, up.offset < up.bytes.length);
      }
      case 'end-upload':
        s.uploads.delete(m.uploadId);
        return encodeControlAck(ref, ControlFunction.EndUpload);
      default:
        throw new ProtocolError(`a control answer (${m.kind}) sent to a CPU`);
    }
  }
}

/** An ack (ROSCTR 2) without parameters carrying a service error as its header error. */
function refusal(pduRef: number, code: number): Buffer {
  return encodeHeaderErrorAck(pduRef, code);
}
