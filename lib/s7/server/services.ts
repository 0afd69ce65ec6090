/**
 * The simulated CPU's system services: the RUN/STOP state machine with its
 * diagnostic buffer, the clock, identity (SZL), blocks (one per DB of the
 * memory, a few OBs/FCs so lists look real), block info and upload, and
 * protection levels with a password. S7Server dispatches userdata PDUs and
 * the control jobs (PLC stop, PI service, upload) here; everything is
 * answered the way a CPU of the profile answers, refusals included.
 * Malformed requests throw ProtocolError (the server drops that connection);
 * well-formed requests for something the CPU does not offer get the CPU's
 * error answer and the connection stays up.
 */
import { EventEmitter } from 'node:events';
import { ProtocolError } from '../../errors';
import type { PlcMemory } from '../../sim/memory';
import { decodeDateAndTime, encodeDateAndTime } from '../../values/time';
import {
  encodeBlockCounts,
  encodeBlockInfo,
  encodeBlockListEntries,
  encodeLoadBlock,
  decodeBlockInfoRequest,
  loadSizeOf,
  type BlockSpec,
} from '../codec/blocks';
import { decodeControl, encodeControlAck, encodeStartUploadAck, encodeUploadAck } from '../codec/control';
import { encodeErrorAck } from '../codec/pdu';
import { decodePassword, decodeUserdata, encodeUserdataResponse, USERDATA_OVERHEAD, type UserdataPdu } from '../codec/userdata';
import {
  BLOCK_TYPES,
  BlockSubfunction,
  ControlFunction,
  CpuSubfunction,
  FRAME_OVERHEAD,
  S7Function,
  SecuritySubfunction,
  TimeSubfunction,
  UserdataGroup,
  UserdataMethod,
  UserdataType,
  blockTypeName,
  type BlockType,
} from '../constants';
import { encodeDiagnosticBuffer, type DiagnosticEntry, type DiagnosticEvent, describeEvent } from '../codec/diagnostics';
import type { CpuIdentity } from './profiles';
import {
  SZL,
  encodeCommunication,
  encodeComponentIdentification,
  encodeCpuState,
  encodeLeds,
  encodeModuleIdentification,
  encodeProtection,
  encodeSzl,
  encodeSzlIds,
  type SzlList,
} from '../codec/szl';

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
}

export function newServiceSession(): ServiceSession {
  return { pending: undefined, uploads: new Map(), nextRef: 0, authorized: false };
}

/** Service error codes the simulator answers with (SERVICE_ERRORS). */
const E = Object.freeze({
  NOT_IMPLEMENTED: 0x8104,
  STATE: 0x8402,
  NEED_PASSWORD: 0xd241,
  BLOCK_NOT_FOUND: 0xd209,
  NO_BLOCKS: 0xd20e,
  SZL_ID: 0xd401,
  SZL_INDEX: 0xd402,
  SYNTAX: 0xd405,
  WRONG_PASSWORD: 0xd602,
  NO_PASSWORD: 0xd605,
  BAD_TIME: 0xdc01,
});

const DIAGNOSTIC_CAPACITY = 100;
/** The range of a DATE_AND_TIME, with a day's margin at the end so the running clock stays inside. */
const CLOCK_MIN = Date.UTC(1990, 0, 1);
const CLOCK_MAX = Date.UTC(2089, 11, 30);
const FIXED_BLOCKS: Readonly<Partial<Record<BlockType, readonly number[]>>> = Object.freeze({
  OB: [1, 35, 80, 82, 86, 100, 121, 122],
  FB: [1],
  FC: [1, 2],
  SDB: [0, 1, 2, 7],
  SFC: [0, 1, 14, 15, 20, 46, 51, 52],
  SFB: [0, 1, 2, 3, 4, 5],
});
/** MC7 of a block that does nothing: BE (block end). */
const EMPTY_CODE = Buffer.of(0x65, 0x00);

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

  constructor(
    private readonly memory: PlcMemory,
    readonly identity: Readonly<CpuIdentity>,
    private readonly limits: { maxConnections: number },
  ) {
    super();
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
        if (params.subfunction !== CpuSubfunction.ReadSzl) break;
        return this.readSzl(u, s, pduSize);
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
  static readonly SZL_IDS: readonly number[] = Object.freeze([
    0x0000, 0x0011, 0x0111, 0x001c, 0x011c, 0x0131, 0x0232, 0x0424, 0x0074, 0x00a0, 0x01a0, 0x0f00, 0x0f11, 0x0f1c, 0x0f74, 0x0fa0,
  ]);

  private szl(id: number, index: number, s: ServiceSession, pduSize: number): SzlList | number {
    const i = this.identity;
    switch (id) {
      case SZL.IDS:
        return encodeSzlIds(CpuServices.SZL_IDS);
      case SZL.MODULE_ID:
      case 0x0111: {
        if (id === 0x0111 && ![1, 6, 7].includes(index)) return E.SZL_INDEX;
        return encodeModuleIdentification(i.orderCode, i.hardwareVersion, i.firmware, id === 0x0111 ? index : 0);
      }
      case SZL.COMPONENT_ID:
      case 0x011c: {
        const fields = {
          asName: i.asName,
          moduleName: i.moduleName,
          plantId: i.plantId,
          copyright: i.copyright,
          serialNumber: i.serialNumber,
          moduleTypeName: i.moduleTypeName,
        };
        const list = encodeComponentIdentification(fields, id === 0x011c ? index : 0);
        return list.records.length === 0 ? E.SZL_INDEX : list;
      }
      case SZL.COMMUNICATION:
        if (index !== 1) return E.SZL_INDEX;
        return encodeCommunication({ maxPdu: pduSize, maxConnections: this.limits.maxConnections, mpiRate: 187_500, busRate: 10_000_000 });
      case SZL.PROTECTION:
        if (index !== 4) return E.SZL_INDEX;
        return encodeProtection({
          level: this.levelFor(s),
          switchLevel: 1,
          configuredLevel: this.level > 1 ? this.level : 0,
          keySwitch: this.identity.blockFunctions ? 'RUN-P' : 'RUN',
        });
      case SZL.CPU_STATE:
        return encodeCpuState(this.modeNow === 'RUN' ? 8 : 4, this.lastTransition.eventId, this.lastTransition.time);
      case SZL.LEDS: {
        const run = this.modeNow === 'RUN';
        return encodeLeds([
          { id: 0x01, on: false },
          { id: 0x04, on: run },
          { id: 0x05, on: !run },
          { id: 0x06, on: false },
        ]);
      }
      case SZL.DIAGNOSTICS:
        return encodeDiagnosticBuffer(this.log);
      case 0x01a0:
        if (index === 0) return E.SZL_INDEX;
        return encodeDiagnosticBuffer(this.log, index);
      default:
        return E.SZL_ID;
    }
  }

  // ---------------------------------------------------------------- blocks

  /** Every block of the simulated CPU: a DB per data block of the memory, and the fixed OBs, FCs … */
  blockNumbers(type: BlockType): number[] {
    if (type === 'DB') return this.memory.dataBlockNumbers();
    return [...(FIXED_BLOCKS[type] ?? [])];
  }

  private blockSpec(type: BlockType, number: number): { spec: BlockSpec; code: Buffer } | undefined {
    let code: Buffer;
    if (type === 'DB') {
      const db = this.memory.area('DB', number);
      if (!db) return undefined;
      code = db;
    } else {
      if (!this.blockNumbers(type).includes(number)) return undefined;
      code = EMPTY_CODE;
    }
    let checksum = 0;
    for (let k = 0; k < code.length; k++) checksum = (checksum + code[k]! * ((k % 7) + 1)) & 0xffff;
    return {
      code,
      spec: {
        type,
        number,
        languageCode: type === 'DB' ? 0x05 : type === 'SDB' ? 0x07 : 0x01,
        mc7Size: code.length,
        author: 'PLCWIRE',
        family: 'SIM',
        name: `${type}${number}`,
        version: 0x10,
        checksum,
        codeTime: this.created,
        interfaceTime: this.created,
      },
    };
  }

  private blockFunction(u: UserdataPdu, s: ServiceSession, pduSize: number): Buffer {
    const { group, subfunction } = u.params;
    const error = (errorCode: number) => encodeUserdataResponse(u.pduRef, group, subfunction, { errorCode });
    if (subfunction === BlockSubfunction.ListAll) {
      const counts = Object.fromEntries((Object.keys(BLOCK_TYPES) as BlockType[]).map((t) => [t, this.blockNumbers(t).length]));
      return encodeUserdataResponse(u.pduRef, group, subfunction, { data: encodeBlockCounts(counts) });
    }
    if (subfunction === BlockSubfunction.ListType) {
      if (u.data.length !== 2 || u.data[0] !== 0x30) return error(E.SYNTAX);
      const type = blockTypeName(u.data[1]!);
      if (!type) return error(E.SYNTAX);
      const numbers = this.blockNumbers(type);
      if (numbers.length === 0) return error(E.NO_BLOCKS);
      const language = type === 'DB' ? 0x05 : type === 'SDB' ? 0x07 : 0x01;
      const bytes = encodeBlockListEntries(numbers.map((number) => ({ number, flags: 0x22, language })));
      return this.part(s, u, pduSize, bytes, this.nextSequence(s));
    }
    if (subfunction === BlockSubfunction.BlockInfo) {
      const { typeCode, number } = decodeBlockInfoRequest(u.data);
      const type = blockTypeName(typeCode);
      const block = type ? this.blockSpec(type, number) : undefined;
      if (!block) return error(E.BLOCK_NOT_FOUND);
      return encodeUserdataResponse(u.pduRef, group, subfunction, { data: encodeBlockInfo(block.spec) });
    }
    return error(E.NOT_IMPLEMENTED);
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
  return encodeErrorAck(pduRef, code >> 8, code & 0xff);
}
