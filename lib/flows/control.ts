/**
 * The control node's plain logic: which action a message asks for, results
 * as plain data (ISO strings instead of Dates: messages are cloned and
 * shown in debug sidebars), and which diagnostic entries are new since the
 * last call. No Node-RED and no sockets.
 */
import { PlcError } from '../errors';
import type { DiagnosticEntry } from '../s7/codec/diagnostics';
import type { CpuMode, CpuState } from '../s7/codec/szl';

export const ACTIONS = Object.freeze(['info', 'state', 'diagnostics', 'clock', 'clock-sync', 'blocks', 'stop', 'start'] as const);
export type ControlAction = (typeof ACTIONS)[number];

const isAction = (v: unknown): v is ControlAction => (ACTIONS as readonly unknown[]).includes(v);

/** What actionOf() reads of a message. */
export interface ActionMessage {
  action?: unknown;
  topic?: unknown;
}

/** A message's value as String() shows it (flow data can be anything). */
const shown = (value: unknown): string => String(value);

/**
 * The action of a message: `msg.action` if it is set (an unknown one is an
 * INVALID_VALUE error: it was meant as an action), else `msg.topic` if it
 * names an action (topics often carry other things), else `configured`.
 */
export function actionOf(msg: ActionMessage, configured: ControlAction): ControlAction {
  const asked = msg.action;
  if (asked !== undefined && asked !== null && asked !== '') {
    if (isAction(asked)) return asked;
    throw new PlcError('INVALID_VALUE', `msg.action "${shown(asked)}" is not one of ${ACTIONS.join(', ')}`);
  }
  if (typeof msg.topic === 'string' && isAction(msg.topic)) return msg.topic;
  return configured;
}

/** The configured action of a node: one of ACTIONS, else 'info'. */
export function configuredAction(value: unknown): ControlAction {
  return isAction(value) ? value : 'info';
}

/** A Date as an ISO string; null for a time stamp that is no date (a CPU clock never set). */
export function isoOrNull(date: unknown): string | null {
  return date instanceof Date && !Number.isNaN(date.getTime()) ? date.toISOString() : null;
}

/** A diagnostic entry as a message carries it: its time as an ISO string. */
export type PlainDiagnosticEntry = Omit<DiagnosticEntry, 'time'> & { time: string | null };

/** A diagnostic entry with its time as an ISO string. */
export function plainEntry(e: DiagnosticEntry): PlainDiagnosticEntry {
  return { ...e, time: isoOrNull(e.time) };
}

/** cpuState() as the control node sends it. */
export interface PlainCpuState {
  /** The mode in lower case: 'run', 'stop' … */
  state: string;
  mode: CpuMode;
  modeCode: number;
  previousCode: number;
  eventId: number;
  time: string | null;
}

/** cpuState() as the node sends it: `state` in lower case ('run', 'stop' …), the CPU's mode as read, the transition's time as ISO. */
export function plainState(s: CpuState): PlainCpuState {
  return {
    state: String(s.mode).toLowerCase(),
    mode: s.mode,
    modeCode: s.modeCode,
    previousCode: s.previousCode,
    eventId: s.eventId,
    time: isoOrNull(s.time),
  };
}

/** The fields that tell one diagnostic entry from another (the description is derived from the event ID). */
type EntryKey = Pick<DiagnosticEntry, 'time' | 'eventId' | 'priority' | 'ob' | 'dataId' | 'info1' | 'info2' | 'info3'>;

const timeOf = (e: EntryKey): number => (e.time instanceof Date ? e.time.getTime() : NaN);

function keyOf(e: EntryKey): string {
  return [timeOf(e), e.eventId, e.priority, e.ob, e.dataId, e.info1, e.info2, e.info3].join('/');
}

/**
 * Remembers the newest diagnostic entry reported; `take(entries)` (newest
 * first, as the CPU gives them) returns the ones logged since. The first
 * call returns every entry (none was reported yet). When the remembered
 * entry has left the buffer (more new entries than it holds, or a memory
 * reset), the entries later than its time stamp are the new ones.
 */
export class DiagnosticsCursor {
  private last: { key: string; time: number } | undefined;

  take<E extends EntryKey>(entries: readonly E[]): readonly E[] {
    let fresh = entries;
    const last = this.last;
    if (last) {
      const i = entries.findIndex((e) => keyOf(e) === last.key);
      fresh = i >= 0 ? entries.slice(0, i) : entries.filter((e) => e.time instanceof Date && e.time.getTime() > last.time);
    }
    if (entries.length > 0) this.last = { key: keyOf(entries[0]!), time: timeOf(entries[0]!) };
    return fresh;
  }
}
