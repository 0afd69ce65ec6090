/**
 * The SZL lists a CPU says who it is with (szl-list.ts has the list format):
 * 0x0011 module identification (order code, hardware and firmware version)
 * and 0x001C component identification (names, serial number, copyright).
 */
import { SZL, need, putText, text, type SzlList } from './szl-list';

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
