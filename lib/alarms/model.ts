/**
 * What a PLC tells without being asked, in one model for both generations:
 * its alarms (S7-300/400: ALARM_S/SQ/D, ALARM_8/8P, NOTIFY/NOTIFY_8P, SCAN
 * over S7comm userdata group 4; S7-1200/1500: Program_Alarm and system
 * diagnostics over the S7CommPlus alarm subscription), its operating-mode
 * changes and its diagnostic messages. Each driver that offers alarms maps
 * its own frames to these types (its `alarms` port in lib/drivers.ts); the
 * CLI (`plcwire alarms`, `plcwire ack`), the Node-RED alarms node and the
 * dashboard read only these types.
 */
import type { PlcError } from '../errors';
import type { PlcValue, RequestOptions } from '../types';

/** Where an alarm comes from: the block or service that raised it. */
export type AlarmKind =
  | 'ALARM_S'
  | 'ALARM_SQ'
  | 'ALARM_D'
  | 'ALARM_DQ'
  | 'ALARM'
  | 'ALARM_8'
  | 'ALARM_8P'
  | 'NOTIFY'
  | 'NOTIFY_8P'
  | 'SCAN'
  | 'Program_Alarm'
  | 'system';

/** One associated value of an alarm, decoded by its type (the PLC sends the type with it). */
export interface AlarmValue {
  /** The type as the PLC names it (S7comm transport size or S7CommPlus datatype): 'INT', 'REAL', 'BYTE', 'STRING', … */
  type: string;
  value: PlcValue;
}

/** An alarm as the PLC reports it: active now, or as it was when an event changed it. */
export interface PlcAlarm {
  /**
   * The CPU's id of the alarm: the event id of a classic alarm (ALARM_S's
   * EV_ID, the 32-bit message number), the alarm id of a Program_Alarm (CPU
   * alarm id). What `client.acknowledge(id)` takes.
   */
  id: number;
  kind: AlarmKind;
  /** For the 8-signal blocks (ALARM_8, ALARM_8P, NOTIFY_8P): the signal 1–8; absent for single-signal alarms. */
  signal?: number;
  state: 'coming' | 'going';
  /** Whether this alarm must be acknowledged at all (a NOTIFY never needs it). */
  needsAck: boolean;
  /** Acknowledged (of its latest coming; a `needsAck: false` alarm counts as acknowledged). */
  acknowledged: boolean;
  /** When it came, went, was acknowledged: the PLC's time stamps, as the PLC sends them. */
  coming?: Date;
  going?: Date;
  acked?: Date;
  /** The alarm's priority (Program_Alarm 0–16; classic ALARM_S: none sent, absent). */
  priority?: number;
  /** The alarm class (S7-1500: 'Acknowledgement', 'No acknowledgement', or its number; classic: absent). */
  alarmClass?: string | number;
  /** The associated values in their order (SD_1, SD_2, … of the block), decoded by the types the PLC sent. */
  values: AlarmValue[];
  /**
   * The texts where the PLC sends them, per language (`en-US`, `de-DE`, …):
   * the alarm text with the associated values put in their placeholders,
   * and the info text and additional texts when present.
   */
  texts?: Record<string, AlarmTexts>;
}

/** The texts of one alarm in one language. */
export interface AlarmTexts {
  text: string;
  info?: string;
  additional?: string[];
}

/** One change the PLC reported. */
export type AlarmEvent =
  | { type: 'alarm'; change: 'coming' | 'going' | 'acknowledged'; alarm: PlcAlarm; at: Date }
  /** After a reconnect, the active list read again: what came or went during the outage (`during: 'outage'`). */
  | { type: 'alarm'; change: 'coming' | 'going'; alarm: PlcAlarm; at: Date; during: 'outage' }
  | { type: 'mode'; from?: string; to: string; at: Date }
  | { type: 'diagnostic'; id: number; text: string; state?: 'coming' | 'going'; at: Date; raw: string };

/** What to receive: alarms always; mode changes and diagnostic messages when asked for. */
export interface AlarmSubscribeOptions extends RequestOptions {
  /** Also report operating-mode changes (classic: the message service's MODE). Default false. */
  mode?: boolean;
  /** Also report diagnostic messages (classic: SYS; S7-1500: system diagnostics). Default false. */
  diagnostics?: boolean;
  /** Languages of the texts (S7CommPlus; default the PLC's first). */
  languages?: readonly string[];
}

/** A live alarm subscription: re-subscribed by the client after every reconnect. */
export interface AlarmSubscription {
  on(event: 'event', listener: (e: AlarmEvent) => void): unknown;
  on(event: 'lost' | 'error', listener: (err: PlcError) => void): unknown;
  on(event: 'active', listener: () => void): unknown;
  off(event: string, listener: (...args: never[]) => void): unknown;
  /** The alarms active now, as this subscription knows them. */
  readonly active: readonly PlcAlarm[];
  close(): Promise<void>;
}

/**
 * One alarm a simulator raises (the `--alarms` file of `plcwire serve s7`,
 * and ServerOptions.alarms): a PLC program's alarm block, modelled.
 */
export interface AlarmDefinition {
  id: number;
  kind: AlarmKind;
  /** For 8-signal blocks: which signal (1–8). */
  signal?: number;
  /** Texts per language; placeholders `@1%d@` (classic) or `@1%d@`-style as TIA writes them. */
  texts: Record<string, string>;
  priority?: number;
  alarmClass?: string | number;
  needsAck: boolean;
  /** The tag whose TRUE brings the alarm and FALSE makes it go: a bit address (`DB1.DBX0.0`, `M10.1`) or a by-name member (`Tank.High`). */
  trigger: string;
  /** The tags whose values go with the alarm (SD_1…), read when it comes or goes. */
  values?: readonly string[];
}

/**
 * A driver's alarms port (lib/drivers.ts): every caller (the CLI, the
 * Node-RED alarms node, the dashboard) reaches alarms through it, never
 * through a scheme.
 */
export interface AlarmPort<C> {
  /** The alarms active now (classic: the alarm query, every telegram of it; S7CommPlus: the active-alarm list). */
  list(client: C, options?: RequestOptions): Promise<PlcAlarm[]>;
  /** Events in the order the PLC sent them; see AlarmSubscription. */
  subscribe(client: C, options: AlarmSubscribeOptions, listener: (e: AlarmEvent) => void): Promise<AlarmSubscription>;
  /** Acknowledges one alarm (an operator's write: lib/alarms/ack-guard.ts decides); resolves when the PLC confirmed it. */
  acknowledge(client: C, id: number, options?: RequestOptions & { signal8?: number }): Promise<void>;
}
