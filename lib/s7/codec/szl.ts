/**
 * SZL (system status list, "SSL" in English manuals): the list format and
 * decoders for the common lists, with the encoders the simulator builds its
 * answers with, so both sides read one layout.
 *
 * A list as the CPU sends it: SZL ID (2), index (2), record length in bytes
 * (LENTHDR, 2), record count (N_DR, 2), then N_DR records. An answer larger
 * than the PDU comes in several userdata parts; the header is in the first
 * part only, the records continue in the next parts byte for byte.
 * The ID's high byte selects the extract: 0x00xx all records, 0x01xx one
 * record or group given by the index, 0x0Fxx the header only.
 */
import { ProtocolError, ValueError } from '../../errors';
import { decodeDateAndTime, encodeDateAndTime } from '../../values/time';
import { hex4 } from '../../values/text';

/** One SZL list as read (`readSzl`). Records are copies (they do not keep the frames alive). */
export interface SzlList {
  id: number;
  index: number;
  /** Bytes per record (LENTHDR). */
  recordLength: number;
  records: Buffer[];
}

/** SZL IDs this library decodes. */
export const SZL = Object.freeze({
  /** The SZL IDs the CPU offers. */
  IDS: 0x0000,
  /** Module identification: order code, hardware and firmware version. */
  MODULE_ID: 0x0011,
  /** Component identification: names, serial number, copyright. */
  COMPONENT_ID: 0x001c,
  /** Communication capabilities (index 1: max PDU, connections, rates). */
  COMMUNICATION: 0x0131,
  /** Protection level and key switch (index 4). */
  PROTECTION: 0x0232,
  /** Current mode and the last mode transition. */
  CPU_STATE: 0x0424,
  /** LEDs. */
  LEDS: 0x0074,
  /** Diagnostic buffer (0x01A0: the n most recent entries, n = index). */
  DIAGNOSTICS: 0x00a0,
} as const);

const HEADER = 8;

/** The list from the bytes of a whole answer (first part's data and every next part's, concatenated). Throws ProtocolError. */
export function parseSzl(bytes: Buffer): SzlList {
  if (bytes.length < HEADER) throw new ProtocolError(`SZL answer of ${bytes.length} bytes is shorter than its 8-byte header`);
  const id = bytes.readUInt16BE(0);
  const index = bytes.readUInt16BE(2);
  const recordLength = bytes.readUInt16BE(4);
  const count = bytes.readUInt16BE(6);
  const body = bytes.length - HEADER;
  const name = `SZL 0x${hex4(id)} index 0x${hex4(index)}`;
  // A header-only extract (0x0Fxx) announces N_DR records and sends none.
  const headerOnly = (id & 0x0f00) === 0x0f00;
  if (headerOnly ? body !== 0 : recordLength * count !== body) {
    throw new ProtocolError(`${name} announces ${count} records of ${recordLength} bytes, ${body} bytes arrived`);
  }
  if (!headerOnly && count > 0 && recordLength === 0) throw new ProtocolError(`${name} announces ${count} records of 0 bytes`);
  const records: Buffer[] = [];
  if (!headerOnly)
    for (let i = 0; i < count; i++) records.push(Buffer.from(bytes.subarray(HEADER + i * recordLength, HEADER + (i + 1) * recordLength)));
  return { id, index, recordLength, records };
}

/** The bytes of a list (header and records), as the simulator sends them before splitting into parts. */
export function encodeSzl(list: SzlList, headerOnly = false): Buffer {
  const out = Buffer.alloc(HEADER + (headerOnly ? 0 : list.recordLength * list.records.length));
  out.writeUInt16BE(list.id, 0);
  out.writeUInt16BE(list.index, 2);
  out.writeUInt16BE(list.recordLength, 4);
  out.writeUInt16BE(list.records.length, 6);
  if (!headerOnly) {
    list.records.forEach((r, i) => {
      if (r.length !== list.recordLength)
        throw new ValueError(`SZL record ${i}`, `it has ${r.length} bytes, the list's records ${list.recordLength}`);
      r.copy(out, HEADER + i * list.recordLength);
    });
  }
  return out;
}

function need(list: SzlList, min: number, what: string): void {
  if (list.recordLength < min)
    throw new ProtocolError(`SZL 0x${hex4(list.id)} (${what}): records of ${list.recordLength} bytes, expected at least ${min}`);
}

/** Text of a fixed-width field: up to the first NUL, trailing spaces removed. */
function text(b: Buffer, start: number, end: number): string {
  const field = b.subarray(start, Math.min(end, b.length));
  const nul = field.indexOf(0);
  return (nul < 0 ? field : field.subarray(0, nul)).toString('latin1').replace(/\s+$/, '');
}

/** Text into a fixed-width field, padded with `pad` (module identification pads with spaces, component identification with NULs, as CPUs send them). */
function putText(b: Buffer, start: number, width: number, value: string, pad = 0x20): void {
  b.fill(pad, start, start + width);
  b.write(value.slice(0, width), start, 'latin1');
}

// ---------------------------------------------------------------- 0x0000: SZL IDs

/** SZL 0x0000: the IDs the CPU offers (2-byte records). */
export function decodeSzlIds(list: SzlList): number[] {
  need(list, 2, 'available SZL IDs');
  return list.records.map((r) => r.readUInt16BE(0));
}

export function encodeSzlIds(ids: readonly number[]): SzlList {
  return { id: SZL.IDS, index: 0, recordLength: 2, records: ids.map((id) => Buffer.of(id >> 8, id & 0xff)) };
}

// ---------------------------------------------------------------- 0x0011: module identification

/** One record of SZL 0x0011 (28 bytes): index, order code (20 chars), module type ID, two version words. */
export interface ModuleIdRecord {
  /** 1 module, 6 basic hardware, 7 basic firmware (0x81… boot loader and other parts). */
  index: number;
  orderCode: string;
  moduleTypeId: number;
  /** The two version words (Ausbg, Ausbe). */
  version: [number, number];
}

/** Module identification as `info()` shows it. */
export interface ModuleIdentification {
  /** Order code (MLFB) of the module, e.g. "6ES7 315-2EH14-0AB0". */
  orderCode: string;
  /** Hardware version (product version of the module), when the CPU gives it. */
  hardwareVersion: number | undefined;
  /** Firmware version, e.g. "V3.2.6", when the CPU gives it. */
  firmware: string | undefined;
  records: ModuleIdRecord[];
}

const MODULE_RECORD = 28;

/** A version word pair of the firmware record: 'V' and the major version in the first word, minor and patch in the second. */
function firmwareText(v: readonly [number, number]): string {
  const letter = v[0] >> 8;
  const prefix = letter >= 0x41 && letter <= 0x5a ? String.fromCharCode(letter) : '';
  return `${prefix}${v[0] & 0xff}.${v[1] >> 8}.${v[1] & 0xff}`;
}

export function decodeModuleIdentification(list: SzlList): ModuleIdentification {
  need(list, MODULE_RECORD, 'module identification');
  const records = list.records.map((r) => ({
    index: r.readUInt16BE(0),
    orderCode: text(r, 2, 22),
    moduleTypeId: r.readUInt16BE(22),
    version: [r.readUInt16BE(24), r.readUInt16BE(26)] as [number, number],
  }));
  const module = records.find((r) => r.index === 1) ?? records.find((r) => r.index === 6);
  const hw = records.find((r) => r.index === 6) ?? records.find((r) => r.index === 1);
  const fw = records.find((r) => r.index === 7);
  return {
    orderCode: module?.orderCode ?? '',
    hardwareVersion: hw ? hw.version[0] : undefined,
    firmware: fw ? firmwareText(fw.version) : undefined,
    records,
  };
}

/** "V2.9.2" → the two version words of a firmware record. */
function firmwareWords(firmware: string): [number, number] {
  const m = /^([A-Z]?)(\d+)\.(\d+)\.(\d+)$/.exec(firmware);
  if (!m) throw new TypeError(`firmware "${firmware}" is not of the form V1.2.3`);
  const letter = m[1] ? m[1].charCodeAt(0) : 0x56;
  return [(letter << 8) | Number(m[2]), (Number(m[3]) << 8) | Number(m[4])];
}

export function encodeModuleIdentification(orderCode: string, hardwareVersion: number, firmware: string, index = 0): SzlList {
  const record = (i: number, code: string, v: [number, number]) => {
    const r = Buffer.alloc(MODULE_RECORD);
    r.writeUInt16BE(i, 0);
    putText(r, 2, 20, code);
    r.writeUInt16BE(0x00c0, 22);
    r.writeUInt16BE(v[0], 24);
    r.writeUInt16BE(v[1], 26);
    return r;
  };
  const all = [
    record(1, orderCode, [hardwareVersion, 1]),
    record(6, orderCode, [hardwareVersion, 1]),
    record(7, '', firmwareWords(firmware)),
  ];
  const wanted = index === 0 ? all : all.filter((r) => r.readUInt16BE(0) === index);
  return { id: index === 0 ? SZL.MODULE_ID : 0x0111, index, recordLength: MODULE_RECORD, records: wanted };
}

// ---------------------------------------------------------------- 0x001C: component identification

/** Component identification as `info()` shows it; a field the CPU does not send is undefined. */
export interface ComponentIdentification {
  /** Index 1: name of the automation system (AS name). */
  asName: string | undefined;
  /** Index 2: name of the module. */
  moduleName: string | undefined;
  /** Index 3: plant designation (plant ID). */
  plantId: string | undefined;
  /** Index 4: copyright. */
  copyright: string | undefined;
  /** Index 5: serial number of the module. */
  serialNumber: string | undefined;
  /** Index 7: module type name, e.g. "CPU 315-2 PN/DP". */
  moduleTypeName: string | undefined;
  /** Index 8: serial number of the memory card. */
  memoryCardSerial: string | undefined;
  /** Index 11 (0x0B): location designation. */
  location: string | undefined;
}

const COMPONENT_RECORD = 34;
const COMPONENT_FIELDS: ReadonlyArray<[number, keyof ComponentIdentification]> = [
  [1, 'asName'],
  [2, 'moduleName'],
  [3, 'plantId'],
  [4, 'copyright'],
  [5, 'serialNumber'],
  [7, 'moduleTypeName'],
  [8, 'memoryCardSerial'],
  [11, 'location'],
];

export function decodeComponentIdentification(list: SzlList): ComponentIdentification {
  need(list, COMPONENT_RECORD, 'component identification');
  const out = {} as ComponentIdentification;
  for (const [, key] of COMPONENT_FIELDS) out[key] = undefined;
  for (const r of list.records) {
    const field = COMPONENT_FIELDS.find(([i]) => i === r.readUInt16BE(0));
    if (field) out[field[1]] = text(r, 2, COMPONENT_RECORD);
  }
  return out;
}

/** Records in index order (1, 2, 3, 4, 5, 7, 8, 11): clients that read fixed offsets of the list expect that order. */
export function encodeComponentIdentification(c: Partial<ComponentIdentification>, index = 0): SzlList {
  const records: Buffer[] = [];
  for (const [i, key] of COMPONENT_FIELDS) {
    const value = c[key];
    if (value === undefined || (index !== 0 && index !== i)) continue;
    const r = Buffer.alloc(COMPONENT_RECORD);
    r.writeUInt16BE(i, 0);
    // Names are 24 characters followed by reserved bytes; the module type name and plant ID use all 32.
    const width = key === 'moduleTypeName' || key === 'plantId' ? 32 : key === 'copyright' ? 26 : 24;
    putText(r, 2, width, value, 0x00);
    records.push(r);
  }
  return { id: index === 0 ? SZL.COMPONENT_ID : 0x011c, index, recordLength: COMPONENT_RECORD, records };
}

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
  const r = list.records.find((x) => x.readUInt16BE(0) === 1) ?? list.records[0];
  if (!r) throw new ProtocolError('SZL 0x0131 index 1 has no record');
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
