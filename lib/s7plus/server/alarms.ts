/**
 * The simulated CPU's alarm subsystem (Program_Alarm, S7-1200/1500): each
 * AlarmDefinition (lib/alarms/model.ts, `S7PlusOptions.alarms`) is a
 * Program_Alarm whose trigger tag (a bit address or a by-name member of the
 * program) brings it when it goes TRUE and makes it go when it goes FALSE,
 * with its associated values read from their tags at that moment. Every
 * change goes to the alarm subscriptions of every session (subscriptions
 * below) as a DAI (codec/alarms.ts); the Explore of the alarm subsystem
 * answers the alarms active now. Acknowledgement over S7CommPlus has no
 * public layout (docs/alarms.md): the simulator offers none, so an alarm
 * that needs acknowledging stays unacknowledged.
 */
import { parseAddress } from '../../address/parse';
import type { AlarmDefinition } from '../../alarms/model';
import { ValueError } from '../../errors';
import type { MemoryAccess, PlcMemory } from '../../sim/memory';
import type { PlcValue, Tag } from '../../types';
import { tagDecoder } from '../../values';
import { associatedValueBlob, associatedValuesArray, lcidOf, nsOfDate, ACK_CLASS } from '../codec/alarm-texts';
import { TextId, type Dai } from '../codec/alarms';
import type { BlobValue } from '../codec/pvalue';
import type { PlusModel } from './model';

/** The alarm class of an alarm that needs no acknowledgement (TIA's "No acknowledgement"; an assumption, docs/alarms.md). */
const NO_ACK_CLASS = 2;
/** The HMI info's syntax id that carries the alarm class (AlarmsHmiInfo.cs). */
const HMI_SYNTAX = 258;
/** The relation ids the simulator gives its DAI objects: this plus the alarm's index. */
const DAI_RELATION_BASE = 0x8c000000;

interface Watched {
  readonly def: AlarmDefinition;
  readonly index: number;
  trigger: Tag | undefined;
  values: (Tag | undefined)[];
  on: boolean;
  sequence: number;
  dai: Dai | undefined;
}

/** What a session's alarm subscription is told. */
export type AlarmListener = (dai: Dai) => void;

export class AlarmSubsystem {
  private readonly alarms: Watched[];
  private readonly listeners = new Set<AlarmListener>();
  private memory: PlcMemory | undefined;
  /** The program the tags were resolved in: a download (reload) resolves them again. */
  private resolvedIn: PlusModel | undefined;
  private readonly onWrite = (access: MemoryAccess): void => this.evaluate(access);

  constructor(
    definitions: readonly AlarmDefinition[],
    private readonly model: () => PlusModel,
    private readonly now: () => Date = () => new Date(),
  ) {
    const ids = new Set<number>();
    this.alarms = definitions.map((def, index) => {
      if (!Number.isInteger(def.id) || def.id < 1) throw new ValueError(`ALARM${String(def.id)}`, 'an alarm id is a whole number from 1');
      if (ids.has(def.id)) throw new ValueError(`ALARM${def.id}`, 'the alarm is defined twice');
      ids.add(def.id);
      if ((def.values?.length ?? 0) > 10)
        throw new ValueError(`ALARM${def.id}`, 'a Program_Alarm has at most 10 associated values (SD_1 to SD_10)');
      for (const lang of Object.keys(def.texts))
        if (lcidOf(lang) === undefined) throw new ValueError(`ALARM${def.id}`, `text language ${lang} is none of TIA's (en-US, de-DE, …)`);
      return { def, index, trigger: undefined, values: [], on: false, sequence: 0, dai: undefined };
    });
  }

  /** Watches `memory` (the CPU's): from now on a trigger's change raises or clears its alarm. */
  attach(memory: PlcMemory): void {
    if (this.memory === memory) return;
    this.detach();
    this.memory = memory;
    memory.on('write', this.onWrite);
    this.evaluate();
  }

  detach(): void {
    this.memory?.off('write', this.onWrite);
    this.memory = undefined;
  }

  /** The alarms active now (coming), in their id order. */
  active(): Dai[] {
    this.evaluate();
    return this.alarms.filter((a) => a.on && a.dai).map((a) => a.dai!);
  }

  subscribe(listener: AlarmListener): () => void {
    this.listeners.add(listener);
    return () => this.listeners.delete(listener);
  }

  /** Each trigger read now (only those in the bytes of `written`, when given): an edge raises or clears its alarm (in definition order). */
  evaluate(written?: MemoryAccess): void {
    const memory = this.memory;
    if (!memory) return;
    const model = this.model();
    if (model !== this.resolvedIn) {
      this.resolvedIn = model;
      for (const a of this.alarms) {
        a.trigger = undefined;
        a.values = [];
      }
    }
    for (const a of this.alarms) {
      const t = a.trigger;
      if (written && t && !overlaps(t, written)) continue;
      const on = this.read(memory, a, 'trigger') === true;
      if (on === a.on) continue;
      a.on = on;
      a.sequence = (a.sequence + 1) >>> 0;
      a.dai = this.daiOf(memory, a, on ? 'coming' : 'going');
      for (const l of [...this.listeners]) {
        try {
          l(a.dai);
        } catch {
          // One session's failure to send (a notification too long for a frame) is not the writer's: the change stands.
        }
      }
    }
  }

  private daiOf(memory: PlcMemory, a: Watched, state: 'coming' | 'going'): Dai {
    const def = a.def;
    const values: BlobValue[] = [];
    (def.values ?? []).forEach((_, i) => {
      const v = this.read(memory, a, i);
      const tag = a.values[i];
      let b: BlobValue = { rootId: 0, data: Buffer.alloc(0) };
      try {
        if (tag && v !== undefined && v !== null && !Array.isArray(v))
          b = associatedValueBlob(tag.type, v as PlcValue, tag.stringLength || 254);
      } catch {
        // A type TIA does not allow as an associated value (checked when the definitions are read): sent empty.
      }
      values.push(b);
    });
    const texts = new Map<number, string>();
    for (const [lang, text] of Object.entries(def.texts)) texts.set(((lcidOf(lang)! << 16) | TextId.Alarm) >>> 0, text);
    const alarmClass = typeof def.alarmClass === 'number' ? def.alarmClass : def.needsAck ? ACK_CLASS : NO_ACK_CLASS;
    return {
      relationId: DAI_RELATION_BASE + a.index,
      name: `Program_Alarm_${def.id}`,
      cpuAlarmId: BigInt(def.id),
      allStatesInfo: state === 'coming' ? 1 : 0,
      domain: 1,
      messageType: 1,
      sequenceCounter: a.sequence,
      hmi: { syntaxId: HMI_SYNTAX, version: 1, clientAlarmId: def.id, priority: def.priority ?? 0, alarmClass },
      state,
      timestamp: nsOfDate(this.now()),
      ackTimestamp: 0n,
      values: associatedValuesArray(values),
      texts,
    };
  }

  /** The trigger's (or value `i`'s) value now; undefined when its tag names nothing the memory holds. */
  private read(memory: PlcMemory, a: Watched, which: 'trigger' | number): unknown {
    const address = which === 'trigger' ? a.def.trigger : a.def.values?.[which];
    if (address === undefined) return undefined;
    let tag = which === 'trigger' ? a.trigger : a.values[which];
    if (!tag) {
      tag = this.resolve(address);
      if (!tag) return undefined;
      if (which === 'trigger') a.trigger = tag;
      else a.values[which] = tag;
    }
    const area = memory.area(tag.area, tag.dbNumber);
    if (!area || tag.byteOffset + tag.byteLength > area.length) return undefined;
    return tagDecoder(tag)(area, tag.byteOffset);
  }

  /** A bit or typed address as written, else a name of the program (its entry's address in the simulator's layout). */
  private resolve(address: string): Tag | undefined {
    try {
      return parseAddress(address);
    } catch {
      const entry = this.model().table.lookup(address);
      if (!entry?.address) return undefined;
      try {
        return parseAddress(entry.address);
      } catch {
        return undefined;
      }
    }
  }
}

/** Whether a write touched the bytes of `tag`. */
function overlaps(tag: Tag, w: MemoryAccess): boolean {
  return (
    tag.area === w.area &&
    tag.dbNumber === (w.area === 'DB' ? w.dbNumber : tag.dbNumber) &&
    tag.byteOffset < w.offset + w.length &&
    w.offset < tag.byteOffset + tag.byteLength
  );
}
