/**
 * The SZL lists of a CPU's capabilities and state (szl-list.ts has the list
 * format): 0x0131 communication capabilities, 0x0232 protection, 0x0424
 * the CPU state, 0x0074 the LEDs.
 */
import { ProtocolError } from '../../errors';
import { decodeDateAndTime, encodeDateAndTime } from '../../values/time';
import { SZL, need, type SzlList } from './szl-list';

// ---------------------------------------------------------------- 0x0131 index 1: communication capabilities

export interface CommunicationCapabilities {
  /** Largest PDU the CPU can negotiate. */
  maxPdu: number;
  /** Connections the CPU serves at once. */
  maxConnections: number;
  /** MPI and backplane bus rates, bit/s. */
  mpiRate: number;
  busRate: number;
}

const COMM_RECORD = 40;

export function decodeCommunication(list: SzlList): CommunicationCapabilities {
  need(list, 18, 'communication capabilities');
  // The record that says it is index 1: another index has a layout of its own (szl-capabilities.ts).
  const r = list.records.find((x) => x.readUInt16BE(0) === 1);
  if (!r) {
    const sent = list.records.map((x) => x.readUInt16BE(0)).join(', ');
    throw new ProtocolError(`SZL 0x0131 has no index 1 record (general communication data)${sent ? `: it sent index ${sent}` : ''}`);
  }
  return { maxPdu: r.readUInt16BE(2), maxConnections: r.readUInt16BE(4), mpiRate: r.readUInt32BE(6), busRate: r.readUInt32BE(10) };
}

export function encodeCommunication(c: CommunicationCapabilities): SzlList {
  const r = Buffer.alloc(COMM_RECORD);
  r.writeUInt16BE(1, 0);
  r.writeUInt16BE(c.maxPdu, 2);
  r.writeUInt16BE(c.maxConnections, 4);
  r.writeUInt32BE(c.mpiRate, 6);
  r.writeUInt32BE(c.busRate, 10);
  return { id: SZL.COMMUNICATION, index: 1, recordLength: COMM_RECORD, records: [r] };
}

// ---------------------------------------------------------------- 0x0232 index 4: protection

export type KeySwitch = 'RUN' | 'RUN-P' | 'STOP' | 'MRES';
const KEY_SWITCH: readonly (KeySwitch | undefined)[] = [undefined, 'RUN', 'RUN-P', 'STOP', 'MRES'];

export interface Protection {
  /** The protection level in force: 1 none, 2 write protection, 3 read/write protection. */
  level: number;
  /** The level set with the mode selector (key switch). */
  switchLevel: number;
  /** The level set in the configuration (0 = none set). */
  configuredLevel: number;
  /** Position of the mode selector, when the CPU has one. */
  keySwitch: KeySwitch | undefined;
  /** Position of the startup switch: complete restart (CRST) or warm restart (WRST), when the CPU has one. */
  startupSwitch: 'CRST' | 'WRST' | undefined;
}

const PROTECTION_RECORD = 40;

export function decodeProtection(list: SzlList): Protection {
  need(list, 12, 'protection');
  const r = list.records.find((x) => x.readUInt16BE(0) === 4) ?? list.records[0];
  if (!r) throw new ProtocolError('SZL 0x0232 index 4 has no record');
  const startup = r.readUInt16BE(10);
  return {
    switchLevel: r.readUInt16BE(2),
    configuredLevel: r.readUInt16BE(4),
    level: r.readUInt16BE(6),
    keySwitch: KEY_SWITCH[r.readUInt16BE(8)],
    startupSwitch: startup === 1 ? 'CRST' : startup === 2 ? 'WRST' : undefined,
  };
}

export function encodeProtection(p: Omit<Protection, 'startupSwitch'> & { startupSwitch?: Protection['startupSwitch'] }): SzlList {
  const r = Buffer.alloc(PROTECTION_RECORD);
  r.writeUInt16BE(4, 0);
  r.writeUInt16BE(p.switchLevel, 2);
  r.writeUInt16BE(p.configuredLevel, 4);
  r.writeUInt16BE(p.level, 6);
  r.writeUInt16BE(p.keySwitch ? KEY_SWITCH.indexOf(p.keySwitch) : 0, 8);
  r.writeUInt16BE(p.startupSwitch === 'CRST' ? 1 : p.startupSwitch === 'WRST' ? 2 : 0, 10);
  return { id: SZL.PROTECTION, index: 4, recordLength: PROTECTION_RECORD, records: [r] };
}

// ---------------------------------------------------------------- 0x0424: CPU state

export type CpuMode = 'RUN' | 'STOP' | 'STARTUP' | 'HOLD' | 'DEFECT' | 'UNKNOWN';

/** The mode code of SZL 0x0424 (low nibble of "bzu-id"): 1–4 STOP variants, 5–7 STARTUP variants, 8 RUN, 0xA HOLD, 0xD DEFECT. */
export function cpuModeOf(code: number): CpuMode {
  if (code >= 1 && code <= 4) return 'STOP';
  if (code >= 5 && code <= 7) return 'STARTUP';
  if (code === 8 || code === 9) return 'RUN';
  if (code === 0x0a) return 'HOLD';
  if (code === 0x0d) return 'DEFECT';
  return 'UNKNOWN';
}

export interface CpuState {
  mode: CpuMode;
  /** The raw mode code (8 RUN, 4 STOP (internal) …). */
  modeCode: number;
  /** The previous mode's code when the CPU gives it (high nibble), else 0. */
  previousCode: number;
  /** Event ID of the last mode transition. */
  eventId: number;
  /** When the last mode transition happened (PLC clock fields as UTC, see readClock). */
  time: Date;
}

const STATE_RECORD = 20;

export function decodeCpuState(list: SzlList): CpuState {
  need(list, STATE_RECORD, 'CPU state');
  const r = list.records[0];
  if (!r) throw new ProtocolError('SZL 0x0424 has no record');
  const bzu = r[3]!;
  return {
    mode: cpuModeOf(bzu & 0x0f),
    modeCode: bzu & 0x0f,
    previousCode: bzu >> 4,
    eventId: r.readUInt16BE(0),
    time: decodeDateAndTime(r, 12),
  };
}

/** `previous` 0 leaves the high nibble clear, as the CPUs do that answer RUN with 0x08. */
export function encodeCpuState(modeCode: number, eventId: number, time: Date, previous = 0): SzlList {
  const r = Buffer.alloc(STATE_RECORD);
  r.writeUInt16BE(eventId, 0);
  r[2] = 0xff;
  r[3] = ((previous & 0x0f) << 4) | (modeCode & 0x0f);
  encodeDateAndTime(time, r, 12);
  return { id: SZL.CPU_STATE, index: 0, recordLength: STATE_RECORD, records: [r] };
}

// ---------------------------------------------------------------- 0x0074: LEDs

const LED_NAMES: Readonly<Record<number, string>> = Object.freeze({
  0x01: 'SF',
  0x02: 'INTF',
  0x03: 'EXTF',
  0x04: 'RUN',
  0x05: 'STOP',
  0x06: 'FRCE',
  0x07: 'CRST',
  0x08: 'BAF',
  0x09: 'USR',
  0x0a: 'USR1',
  0x0b: 'BUS1F',
  0x0c: 'BUS2F',
  0x0d: 'REDF',
  0x0e: 'MSTR',
  0x0f: 'RACK0',
  0x10: 'RACK1',
  0x11: 'RACK2',
  0x12: 'IFM1F',
  0x13: 'IFM2F',
  0x15: 'MAINT',
});

export interface Led {
  /** LED ID (low byte of the record's first word): 1 SF, 4 RUN, 5 STOP … */
  id: number;
  /** Its label, or "LED 0x.." for an ID this library does not know. */
  name: string;
  on: boolean;
  /** Not flashing, flashing at 2 Hz, or slowly at 0.5 Hz. */
  flashing: 'no' | '2Hz' | '0.5Hz';
}

export function decodeLeds(list: SzlList): Led[] {
  need(list, 4, 'LEDs');
  return list.records.map((r) => {
    const id = r[1]!;
    const blink = r[3]!;
    return {
      id,
      name: LED_NAMES[id] ?? `LED 0x${id.toString(16).padStart(2, '0')}`,
      on: r[2] === 1,
      flashing: blink === 1 ? '2Hz' : blink === 2 ? '0.5Hz' : 'no',
    };
  });
}

export function encodeLeds(leds: readonly { id: number; on: boolean; flashing?: Led['flashing'] }[]): SzlList {
  return {
    id: SZL.LEDS,
    index: 0,
    recordLength: 4,
    records: leds.map((l) => Buffer.of(0, l.id, l.on ? 1 : 0, l.flashing === '2Hz' ? 1 : l.flashing === '0.5Hz' ? 2 : 0)),
  };
}
