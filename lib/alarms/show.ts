/**
 * Alarms as people and flows see them, the same in the CLI (`plcwire alarms`,
 * `plcwire ack`), the Node-RED alarms node and the dashboard: an alarm id as
 * a user types it, an alarm's text in one language, one line per alarm or
 * event, and plain data (ISO strings for the PLC's time stamps: messages are
 * cloned and shown in debug sidebars, JSON has no dates).
 */
import { PlcError } from '../errors';
import type { AlarmEvent, PlcAlarm } from './model';

/**
 * An alarm id as typed: decimal (`1001`), or hex as STEP 7 (`16#3E9`) or C
 * (`0x3E9`) write it; a 32-bit unsigned number (a classic EV_ID, a
 * Program_Alarm's CPU alarm id). Anything else is INVALID_VALUE naming it.
 */
export function parseAlarmId(text: string): number {
  const t = text.trim();
  const m = /^(?:(?:16#|0x)([0-9a-f]+)|(\d+))$/i.exec(t);
  const id = m === null ? NaN : m[1] !== undefined ? parseInt(m[1], 16) : Number(m[2]);
  if (!Number.isSafeInteger(id) || id > 0xffffffff) {
    throw new PlcError('INVALID_VALUE', `alarm id "${text}" is not a number from 0 to 4294967295 (decimal, 16#hex or 0x hex)`, {
      tag: text,
    });
  }
  return id;
}

/**
 * The alarm's text in `language` (`en-US`, or its language part `en`), else
 * in the first language the PLC sent; undefined when it sent none (classic
 * CPUs keep their texts in the engineering project, not in the CPU).
 */
export function alarmText(alarm: PlcAlarm, language?: string): string | undefined {
  const texts = alarm.texts;
  if (!texts) return undefined;
  const langs = Object.keys(texts);
  const wanted = language?.toLowerCase();
  const chosen =
    (wanted && langs.find((l) => l.toLowerCase() === wanted)) ??
    (wanted && langs.find((l) => l.toLowerCase().split('-')[0] === wanted.split('-')[0])) ??
    langs[0];
  return chosen === undefined ? undefined : texts[chosen]?.text;
}

/** `ALARM_8 signal 3`, `Program_Alarm`: the kind, and the signal of an 8-signal block. */
function alarmSource(alarm: PlcAlarm): string {
  return alarm.signal === undefined ? alarm.kind : `${alarm.kind} signal ${alarm.signal}`;
}

/** Whether an active alarm still waits for an operator. */
function waitsForAck(alarm: PlcAlarm): boolean {
  return alarm.needsAck && !alarm.acknowledged;
}

const iso = (d: Date | undefined): string | undefined => (d instanceof Date && !Number.isNaN(d.getTime()) ? d.toISOString() : undefined);

/** An associated value as text: `REAL 95.5`, `STRING "low"`. */
function valueText(v: { type: string; value: unknown }): string {
  const shown =
    typeof v.value === 'string' ? JSON.stringify(v.value) : Array.isArray(v.value) ? `[${v.value.join(', ')}]` : String(v.value);
  return `${v.type} ${shown}`;
}

/**
 * One line for an alarm: id, source, state, acknowledgement, priority or
 * class, when it came, its text and its associated values.
 * `1001 ALARM_S coming unacknowledged priority 3 came 2026-… "Tank high level 95.5" (REAL 95.5)`
 */
export function alarmLine(alarm: PlcAlarm, language?: string): string {
  const parts = [String(alarm.id), alarmSource(alarm), alarm.state];
  parts.push(!alarm.needsAck ? 'no acknowledgement needed' : alarm.acknowledged ? 'acknowledged' : 'unacknowledged');
  if (alarm.priority !== undefined) parts.push(`priority ${alarm.priority}`);
  if (alarm.alarmClass !== undefined) parts.push(`class ${alarm.alarmClass}`);
  const came = iso(alarm.coming);
  if (came) parts.push(`came ${came}`);
  const went = iso(alarm.going);
  if (alarm.state === 'going' && went) parts.push(`went ${went}`);
  const text = alarmText(alarm, language);
  if (text !== undefined) parts.push(JSON.stringify(text));
  if (alarm.values.length > 0) parts.push(`(${alarm.values.map(valueText).join(', ')})`);
  return parts.join(' ');
}

/**
 * One line for an event, its time first:
 * `2026-… coming 1001 ALARM_S … "Tank high level"`, `2026-… mode STOP -> RUN`,
 * `2026-… diagnostic 16#4302 coming Mode transition from STARTUP to RUN`.
 */
export function eventLine(event: AlarmEvent, language?: string): string {
  const at = iso(event.at) ?? '-';
  switch (event.type) {
    case 'alarm': {
      const outage = 'during' in event ? ' (while the link was down)' : '';
      return `${at} ${event.change}${outage} ${alarmLine(event.alarm, language)}`;
    }
    case 'mode':
      return `${at} mode ${event.from ?? '?'} -> ${event.to}`;
    case 'diagnostic':
      return `${at} diagnostic 16#${event.id.toString(16).toUpperCase().padStart(4, '0')}${event.state ? ` ${event.state}` : ''} ${event.text}`;
  }
}

/** A PlcAlarm as a message or JSON carries it: its time stamps as ISO strings, absent ones left out. */
export type PlainAlarm = Omit<PlcAlarm, 'coming' | 'going' | 'acked'> & { coming?: string; going?: string; acked?: string };

export function plainAlarm(alarm: PlcAlarm): PlainAlarm {
  const { coming, going, acked, ...rest } = alarm;
  const out: PlainAlarm = { ...rest, values: alarm.values.map((v) => ({ ...v })) };
  const c = iso(coming);
  const g = iso(going);
  const a = iso(acked);
  if (c) out.coming = c;
  if (g) out.going = g;
  if (a) out.acked = a;
  return out;
}

/** An AlarmEvent as a message or JSON carries it (its alarm plain, `at` an ISO string). */
export type PlainAlarmEvent =
  | { type: 'alarm'; change: 'coming' | 'going' | 'acknowledged'; alarm: PlainAlarm; at: string; during?: 'outage' }
  | { type: 'mode'; from?: string; to: string; at: string }
  | { type: 'diagnostic'; id: number; text: string; state?: 'coming' | 'going'; at: string; raw: string };

export function plainEvent(event: AlarmEvent): PlainAlarmEvent {
  const at = iso(event.at) ?? new Date().toISOString();
  if (event.type === 'alarm') return { ...event, alarm: plainAlarm(event.alarm), at };
  return { ...event, at };
}

/** The topic of an event's message: `alarm/1001/coming`, `mode`, `diagnostic/17154`. */
export function eventTopic(event: AlarmEvent | PlainAlarmEvent): string {
  if (event.type === 'alarm') return `alarm/${event.alarm.id}/${event.change}`;
  return event.type === 'mode' ? 'mode' : `diagnostic/${event.id}`;
}

/** How many alarms are active, and how many of them wait for an acknowledgement. */
export function alarmCounts(active: readonly PlcAlarm[]): { active: number; unacknowledged: number } {
  return { active: active.length, unacknowledged: active.filter(waitsForAck).length };
}
