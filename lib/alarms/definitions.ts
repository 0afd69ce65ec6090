/**
 * The alarm definitions file of the simulators (`plcwire serve s7 --alarms
 * FILE`, ServerOptions.alarms): JSON, an array of alarms or an object with
 * one (`{ "alarms": [ … ] }`), each a PLC program's alarm block modelled:
 *
 *   { "id": 257, "kind": "ALARM_SQ", "texts": { "en-US": "Tank high: @1%d@ mm" },
 *     "trigger": "M10.0", "values": ["MW20:INT"], "needsAck": true }
 *
 * `id` a whole number 0..0xFFFFFFFF (or "16#…"), `kind` an AlarmKind,
 * `signal` 1..8 for the 8-signal blocks (ALARM_8, ALARM_8P, NOTIFY_8P),
 * `needsAck` defaulting to the kind's (ALARM_SQ/DQ, ALARM, ALARM_8/8P and
 * Program_Alarm yes; ALARM_S/D and the NOTIFYs, which cannot be acknowledged,
 * no), `priority` 0..16, `alarmClass` text or number. Every error is a
 * SourceError naming the file, the line and column, and the field.
 */
import { SourceError } from '../errors';
import type { AlarmDefinition, AlarmKind } from './model';

const KINDS: readonly AlarmKind[] = [
  'ALARM_S',
  'ALARM_SQ',
  'ALARM_D',
  'ALARM_DQ',
  'ALARM',
  'ALARM_8',
  'ALARM_8P',
  'NOTIFY',
  'NOTIFY_8P',
  'SCAN',
  'Program_Alarm',
  'system',
];
const ACK_BY_DEFAULT: ReadonlySet<AlarmKind> = new Set(['ALARM_SQ', 'ALARM_DQ', 'ALARM', 'ALARM_8', 'ALARM_8P', 'Program_Alarm']);
const NEVER_ACK: ReadonlySet<AlarmKind> = new Set(['NOTIFY', 'NOTIFY_8P', 'ALARM_S', 'ALARM_D']);
const EIGHT_SIGNALS: ReadonlySet<AlarmKind> = new Set(['ALARM_8', 'ALARM_8P', 'NOTIFY_8P']);
const FIELDS = new Set(['id', 'kind', 'signal', 'texts', 'priority', 'alarmClass', 'needsAck', 'trigger', 'values']);

interface Pos {
  line: number;
  column: number;
}

/** A JSON reader that remembers where each value and each object's keys stand. */
class Reader {
  private i = 0;
  readonly at = new WeakMap<object, Pos>();
  readonly keys = new WeakMap<object, Map<string, Pos>>();

  constructor(
    private readonly text: string,
    private readonly file: string,
  ) {}

  pos(i = this.i): Pos {
    let line = 1;
    let start = 0;
    for (let k = 0; k < i; k++) {
      if (this.text.charCodeAt(k) === 10) {
        line++;
        start = k + 1;
      }
    }
    return { line, column: i - start + 1 };
  }

  fail(problem: string, at: Pos = this.pos()): never {
    throw new SourceError({ file: this.file, ...at }, problem);
  }

  private skip(): void {
    while (/\s/.test(this.text[this.i] ?? '')) this.i++;
  }

  document(): unknown {
    const v = this.value();
    this.skip();
    if (this.i < this.text.length) this.fail('unexpected text after the JSON value');
    return v;
  }

  private value(): unknown {
    this.skip();
    const c = this.text[this.i];
    const start = this.pos();
    if (c === '{') {
      this.i++;
      const obj: Record<string, unknown> = {};
      const keys = new Map<string, Pos>();
      this.at.set(obj, start);
      this.keys.set(obj, keys);
      this.skip();
      if (this.text[this.i] === '}') return (this.i++, obj);
      for (;;) {
        this.skip();
        const keyAt = this.pos();
        if (this.text[this.i] !== '"') this.fail('expected a "quoted" field name');
        const key = this.string();
        if (keys.has(key)) this.fail(`field "${key}" given twice`, keyAt);
        this.skip();
        if (this.text[this.i] !== ':') this.fail(`expected ":" after "${key}"`);
        this.i++;
        obj[key] = this.value();
        keys.set(key, keyAt);
        this.skip();
        if (this.text[this.i] === ',') this.i++;
        else if (this.text[this.i] === '}') return (this.i++, obj);
        else this.fail('expected "," or "}"');
      }
    }
    if (c === '[') {
      this.i++;
      const arr: unknown[] = [];
      this.at.set(arr, start);
      this.skip();
      if (this.text[this.i] === ']') return (this.i++, arr);
      for (;;) {
        arr.push(this.value());
        this.skip();
        if (this.text[this.i] === ',') this.i++;
        else if (this.text[this.i] === ']') return (this.i++, arr);
        else this.fail('expected "," or "]"');
      }
    }
    if (c === '"') return this.string();
    const m = /^(?:-?\d+(?:\.\d+)?(?:[eE][+-]?\d+)?|true|false|null)/.exec(this.text.slice(this.i, this.i + 40));
    if (!m) this.fail(c === undefined ? 'the file ends where a value should be' : `unexpected ${JSON.stringify(c)}`);
    this.i += m[0].length;
    return JSON.parse(m[0]) as unknown;
  }

  private string(): string {
    const m = /^"(?:[^"\\\n]|\\(?:["\\/bfnrt]|u[0-9a-fA-F]{4}))*"/.exec(this.text.slice(this.i));
    if (!m) this.fail('a string that does not end on its line, or has a bad escape');
    this.i += m[0].length;
    return JSON.parse(m[0]) as string;
  }
}

/** Parses the alarm definitions in `text` (the contents of `file`, named in every error). */
export function parseAlarmDefinitions(text: string, file: string): AlarmDefinition[] {
  const r = new Reader(text.replace(/^\uFEFF/, ''), file);
  const doc = r.document();
  let list: unknown = doc;
  if (isObject(doc) && !Array.isArray(doc)) {
    list = doc.alarms;
    if (!Array.isArray(list)) r.fail('expected an array of alarms, or an object with one in "alarms"', r.at.get(doc));
  }
  if (!Array.isArray(list)) return r.fail('expected an array of alarms, or an object with one in "alarms"', { line: 1, column: 1 });
  const seen = new Map<string, number>();
  return list.map((item, n) => {
    const where = `alarm ${n + 1}`;
    if (!isObject(item) || Array.isArray(item)) return r.fail(`${where} is not an object`, isObject(item) ? r.at.get(item) : undefined);
    const keys = r.keys.get(item)!;
    const at = (field: string) => keys.get(field) ?? r.at.get(item)!;
    const bad = (field: string, problem: string): never => r.fail(`${where}, field "${field}": ${problem}`, at(field));
    for (const k of Object.keys(item)) if (!FIELDS.has(k)) bad(k, `unknown field (${[...FIELDS].join(', ')})`);
    for (const k of ['id', 'kind', 'texts', 'trigger']) if (!(k in item)) r.fail(`${where}: the field "${k}" is missing`, r.at.get(item));
    const id = alarmId(item.id);
    if (id === undefined) bad('id', `expected a whole number 0..4294967295 or "16#…", got ${JSON.stringify(item.id)}`);
    const kind = item.kind as AlarmKind;
    if (!KINDS.includes(kind)) bad('kind', `${JSON.stringify(item.kind)} is not one of ${KINDS.join(', ')}`);
    const def: AlarmDefinition = { id: id!, kind, texts: {}, needsAck: ACK_BY_DEFAULT.has(kind), trigger: '' };
    if (item.signal !== undefined) {
      if (!EIGHT_SIGNALS.has(kind)) bad('signal', `only the 8-signal blocks (${[...EIGHT_SIGNALS].join(', ')}) have signals`);
      if (!isInt(item.signal, 1, 8)) bad('signal', `expected 1..8, got ${JSON.stringify(item.signal)}`);
      def.signal = item.signal as number;
    }
    if (!isObject(item.texts) || Array.isArray(item.texts) || Object.keys(item.texts).length === 0) {
      bad('texts', 'expected an object of texts by language, e.g. { "en-US": "Tank high" }');
    }
    for (const [lang, t] of Object.entries(item.texts as Record<string, unknown>)) {
      if (typeof t !== 'string') bad('texts', `the ${lang} text is not a string`);
      def.texts[lang] = t as string;
    }
    if (item.needsAck !== undefined) {
      if (typeof item.needsAck !== 'boolean') bad('needsAck', 'expected true or false');
      if (item.needsAck && NEVER_ACK.has(kind))
        bad('needsAck', `a ${kind} cannot be acknowledged (its acknowledgeable twin: ALARM_SQ, ALARM_DQ, ALARM_8P)`);
      def.needsAck = item.needsAck as boolean;
    }
    if (item.priority !== undefined) {
      if (!isInt(item.priority, 0, 16)) bad('priority', `expected 0..16, got ${JSON.stringify(item.priority)}`);
      def.priority = item.priority as number;
    }
    if (item.alarmClass !== undefined) {
      if (typeof item.alarmClass !== 'string' && !isInt(item.alarmClass, 0, 0xffff)) bad('alarmClass', 'expected a name or a number');
      def.alarmClass = item.alarmClass as string | number;
    }
    if (typeof item.trigger !== 'string' || item.trigger.trim() === '')
      bad('trigger', 'expected a bit address (M10.0, DB1.DBX0.1) or a name (Tank.High)');
    def.trigger = (item.trigger as string).trim();
    if (item.values !== undefined) {
      const v = item.values;
      if (!Array.isArray(v) || v.some((x) => typeof x !== 'string' || x.trim() === ''))
        bad('values', 'expected an array of tag addresses or names');
      if ((v as unknown[]).length > 10) bad('values', 'an alarm block carries at most 10 associated values (SD_1…SD_10)');
      def.values = (v as string[]).map((x) => x.trim());
    }
    const key = `${def.id}:${def.signal ?? 1}`;
    const twice = seen.get(key);
    if (twice !== undefined)
      bad('id', `alarm ${def.id}${def.signal ? ` signal ${def.signal}` : ''} is defined twice (also alarm ${twice + 1})`);
    seen.set(key, n);
    return def;
  });
}

function isObject(v: unknown): v is Record<string, unknown> {
  return typeof v === 'object' && v !== null;
}

function isInt(v: unknown, min: number, max: number): boolean {
  return typeof v === 'number' && Number.isInteger(v) && v >= min && v <= max;
}

function alarmId(v: unknown): number | undefined {
  if (isInt(v, 0, 0xffffffff)) return v as number;
  if (typeof v !== 'string') return undefined;
  const m = /^(?:16#|0x)([0-9a-f]{1,8})$/i.exec(v.trim());
  return m ? parseInt(m[1]!, 16) : undefined;
}
