/**
 * The simulated S7-300/400 CPU's message services (userdata group 4): the
 * registration of a connection for MODE / SYS / ALM (ALARM_S and ALARM
 * families), the alarm blocks of a program modelled by AlarmDefinitions
 * (a trigger tag's TRUE brings the alarm, FALSE makes it go; the `values`
 * tags go with it), their indications pushed to every registered
 * connection, the alarm query (a multi-part answer when long), and the
 * acknowledgement with its ack indication. Mode changes and diagnostic
 * buffer entries are pushed to connections registered for MODE / SYS.
 * A CPU without the classic services (S7-1200/1500 over PUT/GET, S7-200,
 * LOGO!) answers every one of them 0x8104, as those CPUs do.
 *
 * The simulator's own choices where no public source says what a CPU does:
 * an acknowledge of an unknown event id answers 0x0A (object does not
 * exist), of an alarm that needs none 0x03 (access denied); only the coming
 * of an alarm is acknowledged (its ack-going bits stay set), and an alarm stays
 * in the query's answer while it is coming or its coming is not acknowledged.
 */
import type { EventEmitter } from 'node:events';
import type { AlarmDefinition, AlarmKind } from '../../alarms/model';
import { parseAddress } from '../../address/parse';
import { PlcError } from '../../errors';
import type { PlcMemory, MemoryAccess } from '../../sim/memory';
import type { SymbolTable } from '../../symbols/model';
import { addressOrSymbol } from '../../symbols/resolve';
import type { Tag } from '../../types';
import {
  AlarmRegistration,
  AlarmSubfunction,
  AlarmSyntax,
  AlarmType,
  MODE_TRANSITION_GROUP,
  MessageEvents,
  decodeAckRequest,
  decodeMessageServiceRequest,
  encodeAckAnswer,
  encodeAckIndication,
  encodeAlarmIndication,
  encodeMessageServiceAnswer,
  type AckObject,
  type AssociatedValue,
} from '../codec/alarms';
import { decodeQueryRequest, encodeQueryAnswer, type QueryEntry } from '../codec/alarm-query';
import type { DiagnosticEntry } from '../codec/diagnostics';
import { encodeUserdata, encodeUserdataResponse, type UserdataAnswer, type UserdataPdu } from '../codec/userdata';
import { DataTransportSize, UserdataGroup, UserdataMethod, UserdataType } from '../constants';
import { encodeDateAndTime } from '../../values/time';
import { SERVICE_CODE as E } from './service-codes';

/** The push subfunction of each classic alarm kind, and its family (the registration and query type). */
const KINDS: Partial<Record<AlarmKind, { subfunction: number; family: number; notify?: true }>> = {
  ALARM_S: { subfunction: AlarmSubfunction.AlarmS, family: AlarmType.ALARM_S },
  ALARM_D: { subfunction: AlarmSubfunction.AlarmS, family: AlarmType.ALARM_S },
  ALARM_SQ: { subfunction: AlarmSubfunction.AlarmSq, family: AlarmType.ALARM_S },
  ALARM_DQ: { subfunction: AlarmSubfunction.AlarmSq, family: AlarmType.ALARM_S },
  ALARM: { subfunction: AlarmSubfunction.Alarm8, family: AlarmType.ALARM_8 },
  ALARM_8: { subfunction: AlarmSubfunction.Alarm8, family: AlarmType.ALARM_8 },
  ALARM_8P: { subfunction: AlarmSubfunction.Alarm8, family: AlarmType.ALARM_8 },
  NOTIFY: { subfunction: AlarmSubfunction.Notify, family: AlarmType.ALARM_8, notify: true },
  NOTIFY_8P: { subfunction: AlarmSubfunction.Notify8, family: AlarmType.ALARM_8, notify: true },
};

/** The options of the simulator the engine takes: the alarm definitions and the symbols their tags may name. */
export interface AlarmOptions {
  alarms?: readonly AlarmDefinition[] | undefined;
  symbols?: SymbolTable | undefined;
}

/** What the engine needs of the CPU: its clock, whether it has the classic services, its `mode` and `diagnostic` events. */
interface AlarmCpu extends Pick<EventEmitter, 'on'> {
  now(): Date;
  readonly identity: { readonly blockFunctions: boolean };
}

/** What the engine needs of a connection (its socket): where its pushes go, and whether it is still open. */
export interface AlarmPeer {
  write(frame: Buffer): unknown;
  readonly destroyed: boolean;
}

interface Registration {
  events: number;
  /** AlarmType families registered (ALARM_S, ALARM_8). */
  families: Set<number>;
}

/** One signal of an alarm block, with its tags resolved. */
interface Signal {
  def: AlarmDefinition;
  bit: number;
  trigger: Tag;
  values: Tag[];
}

/** An alarm block's state (all its signals), by event id. */
interface Block {
  id: number;
  kind: AlarmKind;
  signals: Signal[];
  eventState: number;
  ackComing: number;
  ackGoing: number;
  /** Signals that need acknowledging. */
  ackMask: number;
  coming?: { time: Date; value: AssociatedValue };
  going?: { time: Date; value: AssociatedValue };
}

export class AlarmEngine {
  private readonly registered = new Map<AlarmPeer, Registration>();
  private readonly blocks = new Map<number, Block>();
  /** The signals by the byte of their trigger bit (`area:db:byte`), so a write looks at its own bytes only. */
  private readonly byByte = new Map<string, { block: Block; signal: Signal }[]>();

  /** False on a CPU without the classic message services (those without block functions: S7-1200/1500, S7-200, LOGO!). */
  readonly served: boolean;

  constructor(
    private readonly memory: PlcMemory,
    private readonly cpu: AlarmCpu,
    options: AlarmOptions,
  ) {
    this.served = cpu.identity.blockFunctions;
    cpu.on('mode', (mode: 'RUN' | 'STOP') => this.mode(mode));
    cpu.on('diagnostic', (e: DiagnosticEntry) => this.diagnostic(e));
    const symbols = options.symbols;
    for (const def of options.alarms ?? []) {
      const kind = KINDS[def.kind];
      if (!kind) continue;
      const tag = (text: string, what: string): Tag => {
        try {
          return addressOrSymbol(text, parseAddress, symbols).tag;
        } catch (err) {
          const message = err instanceof Error ? err.message : String(err);
          throw new PlcError('INVALID_VALUE', `alarm ${def.id}: its ${what} "${text}": ${message}`);
        }
      };
      const trigger = tag(def.trigger, 'trigger');
      if (trigger.type !== 'BOOL')
        throw new PlcError('INVALID_VALUE', `alarm ${def.id}: its trigger "${def.trigger}" is a ${trigger.type}, not a bit`);
      const block = this.blocks.get(def.id) ?? {
        id: def.id,
        kind: def.kind,
        signals: [],
        eventState: 0,
        ackComing: 0xff,
        ackGoing: 0xff,
        ackMask: 0,
      };
      if (block.kind !== def.kind) throw new PlcError('INVALID_VALUE', `alarm ${def.id} is defined as both ${block.kind} and ${def.kind}`);
      const bit = 1 << ((def.signal ?? 1) - 1);
      if (block.signals.some((s) => s.bit === bit))
        throw new PlcError('INVALID_VALUE', `alarm ${def.id} signal ${def.signal ?? 1} is defined twice`);
      block.signals.push({ def, bit, trigger, values: (def.values ?? []).map((v, i) => tag(v, `value ${i + 1}`)) });
      if (def.needsAck) block.ackMask |= bit;
      this.blocks.set(def.id, block);
      const k = `${trigger.area}:${trigger.dbNumber}:${trigger.byteOffset}`;
      this.byByte.set(k, [...(this.byByte.get(k) ?? []), { block, signal: block.signals.at(-1)! }]);
    }
    for (const block of this.blocks.values()) for (const s of block.signals) if (this.bitOf(s.trigger)) block.eventState |= s.bit;
    if (this.blocks.size > 0) memory.on('write', this.onWrite);
  }

  /** Stops watching the memory. */
  dispose(): void {
    this.memory.off('write', this.onWrite);
    this.registered.clear();
  }

  /** The number of alarm blocks (by event id) the program has. */
  get size(): number {
    return this.blocks.size;
  }

  private bitOf(tag: Tag): boolean {
    const area = this.memory.area(tag.area, tag.dbNumber);
    return area !== undefined && tag.byteOffset < area.length && (area[tag.byteOffset]! & (1 << tag.bitOffset)) !== 0;
  }

  private readonly onWrite = (w: MemoryAccess): void => {
    for (let byte = w.offset; byte < w.offset + w.length; byte++) {
      for (const { block, signal } of this.byByte.get(`${w.area}:${w.dbNumber}:${byte}`) ?? []) {
        const on = this.bitOf(signal.trigger);
        if (on !== ((block.eventState & signal.bit) !== 0)) this.change(block, signal, on);
      }
    }
  };

  /** A signal came or went: the block's state, and its indication to every registered connection. */
  private change(block: Block, s: Signal, on: boolean): void {
    const time = this.cpu.now();
    const values = s.values.map((tag) => this.value(tag));
    const first = values[0] ?? { returnCode: 0x0a, transportSize: 0, data: Buffer.alloc(0) };
    if (on) {
      block.eventState |= s.bit;
      if (block.ackMask & s.bit) block.ackComing &= ~s.bit;
      block.coming = { time, value: first };
    } else {
      block.eventState &= ~s.bit;
      block.going = { time, value: first };
    }
    const kind = KINDS[block.kind]!;
    const data = encodeAlarmIndication({
      time: clockSafe(time),
      objects: [
        {
          syntaxId: kind.notify ? AlarmSyntax.NOTIFY_IND : AlarmSyntax.ALARM_IND,
          eventId: block.id,
          eventState: block.eventState,
          localState: 0,
          ackGoing: block.ackGoing,
          ackComing: block.ackComing,
          ...(kind.notify ? { notify: { going: on ? 0 : s.bit, coming: block.eventState, lastChanged: s.bit } } : {}),
          values,
        },
      ],
    });
    this.pushTo((r) => (r.events & MessageEvents.ALM) !== 0 && r.families.has(kind.family), UserdataGroup.Cpu, kind.subfunction, data);
  }

  /** A value tag's bytes as an associated value, with the transport size of its type. */
  private value(tag: Tag): AssociatedValue {
    const area = this.memory.area(tag.area, tag.dbNumber);
    if (!area || tag.byteOffset + tag.byteLength > area.length) return { returnCode: 0x0a, transportSize: 0, data: Buffer.alloc(0) };
    if (tag.type === 'BOOL') return { returnCode: 0xff, transportSize: DataTransportSize.BIT, data: Buffer.of(this.bitOf(tag) ? 1 : 0) };
    const data = Buffer.from(area.subarray(tag.byteOffset, tag.byteOffset + tag.byteLength));
    const size =
      tag.type === 'REAL'
        ? DataTransportSize.REAL
        : tag.type === 'INT' || tag.type === 'DINT'
          ? DataTransportSize.INTEGER
          : data.length <= 4 && tag.count === 1 && !tag.type.includes('STRING')
            ? DataTransportSize.BYTE
            : DataTransportSize.OCTET_STRING;
    return { returnCode: 0xff, transportSize: size, data };
  }

  private pushTo(to: (r: Registration) => boolean, group: number, subfunction: number, data: Buffer | undefined): void {
    let frame: Buffer | undefined;
    for (const [peer, r] of this.registered) {
      if (peer.destroyed) {
        this.registered.delete(peer);
        continue;
      }
      if (!to(r)) continue;
      frame ??= encodeUserdata(0, { method: UserdataMethod.Request, type: UserdataType.Push, group, subfunction, sequence: 0 }, data);
      peer.write(frame);
    }
  }

  /** A mode transition, pushed to connections registered for MODE (its subfunction is the new mode: 0 STOP, 2 RUN). */
  mode(mode: 'RUN' | 'STOP'): void {
    this.pushTo((r) => (r.events & MessageEvents.MODE) !== 0, MODE_TRANSITION_GROUP, mode === 'RUN' ? 0x02 : 0x00, undefined);
  }

  /** A diagnostic buffer entry, pushed to connections registered for SYS as a diagnostic message. */
  diagnostic(e: DiagnosticEntry): void {
    const d = Buffer.alloc(20);
    d.writeUInt16BE(e.eventId, 0);
    d[2] = e.priority;
    d[3] = e.ob;
    d.writeUInt16BE(e.dataId, 4);
    d.writeUInt16BE(e.info1, 6);
    d.writeUInt16BE(e.info2, 8);
    d.writeUInt16BE(e.info3, 10);
    encodeDateAndTime(clockSafe(e.time), d, 12);
    this.pushTo((r) => (r.events & MessageEvents.SYS) !== 0, UserdataGroup.Cpu, AlarmSubfunction.DiagnosticMessage, d);
  }

  /** Answers a group 4 request other than Read SZL from `peer`; `part` cuts a long answer (the query's) into parts. */
  serve(u: UserdataPdu, peer: AlarmPeer | undefined, part: (whole: Buffer) => Buffer): Buffer {
    const a = this.answer(u, peer);
    return 'whole' in a ? part(a.whole) : encodeUserdataResponse(u.pduRef, u.params.group, u.params.subfunction, a);
  }

  private answer(u: UserdataPdu, peer: AlarmPeer | undefined): UserdataAnswer | { whole: Buffer } {
    if (!this.served || !peer) return { errorCode: E.NOT_IMPLEMENTED };
    switch (u.params.subfunction) {
      case AlarmSubfunction.MessageService: {
        const req = decodeMessageServiceRequest(u.data);
        const r = this.registered.get(peer) ?? { events: 0, families: new Set<number>() };
        r.events = req.events;
        const family = registrationFamily(req.alarms);
        if (req.alarms !== undefined && family === undefined) return { errorCode: E.SYNTAX };
        if (family !== undefined) {
          if (req.alarms === AlarmRegistration.ALARM_S_INITIATE || req.alarms === AlarmRegistration.ALARM_INITIATE) r.families.add(family);
          else r.families.delete(family);
        }
        if ((r.events & ~MessageEvents.ALM) === 0 && r.families.size === 0) this.registered.delete(peer);
        else this.registered.set(peer, r);
        return { data: encodeMessageServiceAnswer({ result: 0x02, alarmType: req.alarms }) };
      }
      case AlarmSubfunction.Query: {
        const q = decodeQueryRequest(u.data);
        const entries: QueryEntry[] = [];
        for (const b of this.blocks.values()) {
          if (KINDS[b.kind]!.family !== q.alarmType) continue;
          if (b.eventState === 0 && (b.ackComing & b.ackGoing & b.ackMask) === b.ackMask) continue;
          entries.push({
            alarmType: q.alarmType,
            eventId: b.id,
            eventState: b.eventState,
            ackGoing: b.ackGoing,
            ackComing: b.ackComing,
            coming: b.coming,
            going: b.going,
          });
        }
        return { whole: encodeQueryAnswer(entries) };
      }
      case AlarmSubfunction.Ack: {
        const objects = decodeAckRequest(u.data);
        const done: AckObject[] = [];
        const results = objects.map((o) => {
          const b = this.blocks.get(o.eventId);
          if (!b) return 0x0a;
          if (b.ackMask === 0) return 0x03;
          const bits = (o.ackComing | o.ackGoing || b.ackMask) & b.ackMask;
          if ((b.ackComing & bits) === bits && (b.ackGoing & bits) === bits) return 0xff;
          b.ackComing |= bits;
          b.ackGoing |= bits;
          done.push({ eventId: b.id, ackGoing: b.ackGoing, ackComing: b.ackComing });
          return 0xff;
        });
        if (done.length > 0) {
          const data = encodeAckIndication({ time: clockSafe(this.cpu.now()), objects: done });
          this.pushTo((r) => (r.events & MessageEvents.ALM) !== 0, UserdataGroup.Cpu, AlarmSubfunction.AckIndication, data);
        }
        return { data: encodeAckAnswer(results) };
      }
      default:
        return { errorCode: E.NOT_IMPLEMENTED };
    }
  }
}

function registrationFamily(alarms: number | undefined): number | undefined {
  if (alarms === AlarmRegistration.ALARM_S_INITIATE || alarms === AlarmRegistration.ALARM_S_ABORT) return AlarmType.ALARM_S;
  if (alarms === AlarmRegistration.ALARM_INITIATE || alarms === AlarmRegistration.ALARM_ABORT) return AlarmType.ALARM_8;
  return undefined;
}

/** A time stamp a DATE_AND_TIME holds (the CPU clock stays within 1990..2089). */
function clockSafe(d: Date): Date {
  return Number.isNaN(d.getTime()) ? new Date(Date.UTC(1990, 0, 1)) : d;
}
