/**
 * The S7 address parser: one pure function shared by the S7 and FETCH/WRITE
 * drivers, the CLI and the Node-RED editor. It accepts the nodes7 style
 * (`DB1,INT2`, `MW4`), the IEC / TIA Portal style (`DB1.DBW2`, `%MW4`) with a
 * `:TYPE[n]` override, the S7-200 V area (`VW10` = DB1) and timers/counters.
 */
import { AddressError } from '../errors';
import type { AreaName, DataTypeName, Tag } from '../types';

const MAX_DB = 65535;
const MAX_OFFSET = 0xffff;
const MAX_STRING = 254;
const MAX_WSTRING = 16382;
const MAX_COUNT = 65535;

/** Bytes of one element; STRING/WSTRING include their headers. BOOL: see tagBytes. */
const SIZES: Readonly<Record<DataTypeName, number>> = Object.freeze({
  BOOL: 1, BYTE: 1, CHAR: 1, SINT: 1, USINT: 1,
  WORD: 2, INT: 2, UINT: 2, WCHAR: 2, S5TIME: 2, DATE: 2, COUNTER: 2, TIMER: 2,
  DWORD: 4, DINT: 4, UDINT: 4, REAL: 4, TIME: 4, TIME_OF_DAY: 4,
  LWORD: 8, LINT: 8, ULINT: 8, LREAL: 8, LTIME: 8, DATE_AND_TIME: 8,
  DTL: 12, STRING: 2, WSTRING: 4,
});

/** Type names and their aliases, as people write them in both styles. */
const TYPE_ALIASES: Readonly<Record<string, DataTypeName>> = Object.freeze({
  BOOL: 'BOOL', X: 'BOOL',
  BYTE: 'BYTE', B: 'BYTE',
  WORD: 'WORD', W: 'WORD',
  DWORD: 'DWORD', DW: 'DWORD',
  LWORD: 'LWORD', LW: 'LWORD',
  SINT: 'SINT', USINT: 'USINT',
  INT: 'INT', I: 'INT',
  UINT: 'UINT',
  DINT: 'DINT', DI: 'DINT',
  UDINT: 'UDINT',
  LINT: 'LINT', ULINT: 'ULINT',
  REAL: 'REAL', R: 'REAL',
  LREAL: 'LREAL', LR: 'LREAL',
  CHAR: 'CHAR', C: 'CHAR',
  WCHAR: 'WCHAR',
  STRING: 'STRING', S: 'STRING',
  WSTRING: 'WSTRING', WS: 'WSTRING',
  S5TIME: 'S5TIME',
  TIME: 'TIME', T: 'TIME',
  LTIME: 'LTIME',
  DATE: 'DATE',
  TIME_OF_DAY: 'TIME_OF_DAY', TOD: 'TIME_OF_DAY',
  DATE_AND_TIME: 'DATE_AND_TIME', DT: 'DATE_AND_TIME',
  DTL: 'DTL',
  COUNTER: 'COUNTER',
  TIMER: 'TIMER',
});

/** Bytes one element of `type` occupies (STRING[n] is n + 2, WSTRING[n] is 2n + 4). */
export function elementSize(type: DataTypeName, stringLength = 0): number {
  if (type === 'STRING') return stringLength + 2;
  if (type === 'WSTRING') return 2 * stringLength + 4;
  return SIZES[type];
}

/** Bytes a tag covers from its byte offset (bits: the bytes the bits touch). */
export function tagBytes(type: DataTypeName, count: number, stringLength: number, bitOffset: number): number {
  if (type === 'BOOL') return Math.ceil((bitOffset + count) / 8);
  return elementSize(type, stringLength) * count;
}

/**
 * Parses a type spec like `INT`, `REAL[20]`, `STRING[30]`, `CHAR[10]`. For
 * STRING/WSTRING the bracket is the declared length; `STRING[30][4]` is an
 * array of 4 strings.
 */
export function parseTypeSpec(
  spec: string,
  address: string,
): { type: DataTypeName; count: number; isArray: boolean; stringLength: number } {
  const m = /^([A-Z_0-9]+?)(?:\[(\d+)\])?(?:\[(\d+)\])?$/.exec(spec.trim().toUpperCase());
  if (!m) throw new AddressError(address, `"${spec}" is not a type (e.g. INT, REAL[20], STRING[30])`);
  const type = TYPE_ALIASES[m[1]!];
  if (!type) throw new AddressError(address, `unknown type "${m[1]}"`);
  const first = m[2] === undefined ? undefined : Number(m[2]);
  const second = m[3] === undefined ? undefined : Number(m[3]);
  if (type === 'STRING' || type === 'WSTRING') {
    const stringLength = first ?? (type === 'STRING' ? MAX_STRING : MAX_STRING);
    checkStringLength(type, stringLength, address);
    return { type, stringLength, ...arrayCount(second, address) };
  }
  if (second !== undefined) throw new AddressError(address, `only STRING and WSTRING take two brackets`);
  return { type, stringLength: 0, ...arrayCount(first, address) };
}

function arrayCount(n: number | undefined, address: string): { count: number; isArray: boolean } {
  if (n === undefined) return { count: 1, isArray: false };
  if (n < 1) throw new AddressError(address, `array length ${n} (must be at least 1)`);
  if (n > MAX_COUNT) throw new AddressError(address, `array length ${n} out of range (1..${MAX_COUNT})`);
  return { count: n, isArray: true };
}

function checkStringLength(type: 'STRING' | 'WSTRING', n: number, address: string): void {
  const max = type === 'STRING' ? MAX_STRING : MAX_WSTRING;
  if (n < 1 || n > max) throw new AddressError(address, `${type} length ${n} out of range (1..${max})`);
}

interface Location {
  area: AreaName;
  dbNumber: number;
  byteOffset: number;
  bitOffset: number;
}

/** Area letters (English and German mnemonics) → area. */
const AREAS: Readonly<Record<string, AreaName>> = Object.freeze({ I: 'I', E: 'I', Q: 'Q', A: 'Q', M: 'M', PI: 'PE', PE: 'PE', PQ: 'PA', PA: 'PA' });
/** Width letters of the IEC style → the default type of that width. */
const WIDTHS: Readonly<Record<string, DataTypeName>> = Object.freeze({ X: 'BOOL', B: 'BYTE', W: 'WORD', D: 'DWORD' });
/** nodes7 short area+type forms: MR4, MI4, MDI4 … */
const NODES7_AREA_TYPES: Readonly<Record<string, DataTypeName>> = Object.freeze({ R: 'REAL', I: 'INT', DI: 'DINT', C: 'CHAR' });

/**
 * Parses an address. Throws AddressError naming the address and what is
 * wrong; never anything else.
 */
export function parseAddress(address: string): Tag {
  if (typeof address !== 'string') throw new AddressError(String(address), 'an address must be text');
  const text = address.trim().toUpperCase();
  if (text === '') throw new AddressError(address, 'empty address');
  if (text.length > 200) throw new AddressError(address.slice(0, 40) + '…', 'too long');

  const colon = text.indexOf(':');
  const body = (colon >= 0 ? text.slice(0, colon) : text).replace(/^%/, '').trim();
  const override = colon >= 0 ? parseTypeSpec(text.slice(colon + 1), address) : undefined;

  let m: RegExpExecArray | null;
  // nodes7: DB1,INT2  DB1,X0.1  DB1,REAL0.20  DB10,S20.30  DB1,X0.1.8
  if ((m = /^DB(\d+),([A-Z_]+)(\d+)(?:\.(\d+))?(?:\.(\d+))?$/.exec(body))) {
    if (override) throw new AddressError(address, 'a nodes7-style address names its type; drop the ":TYPE" override');
    const db = dbNumber(m[1]!, address);
    const type = TYPE_ALIASES[m[2]!];
    if (!type) throw new AddressError(address, `unknown type "${m[2]}"`);
    return nodes7Tag(address, { area: 'DB', dbNumber: db, byteOffset: offset(m[3]!, address), bitOffset: 0 }, type, m[4], m[5]);
  }
  if (/^DB\d+,/.test(body)) throw new AddressError(address, 'expected DB<n>,<TYPE><offset>[.<bit or length>], e.g. DB1,INT2');
  // IEC: DB1.DBX0.1  DB1.DBW2  DB1.DBB0
  if ((m = /^DB(\d+)\.DB([XBWD])(\d+)(?:\.(\d+))?$/.exec(body))) {
    const loc: Location = { area: 'DB', dbNumber: dbNumber(m[1]!, address), byteOffset: offset(m[3]!, address), bitOffset: 0 };
    return iecTag(address, loc, m[2]!, m[4], override);
  }
  if (/^DB\d+\./.test(body)) throw new AddressError(address, 'expected DB<n>.DBX<byte>.<bit>, DB<n>.DBB, DBW or DBD<byte>');
  // S7-200 V memory = DB1: VB10, VW10, VD10, V10.1, VX10.1
  if ((m = /^V([XBWD]?)(\d+)(?:\.(\d+))?$/.exec(body))) {
    const width = m[1] || (m[3] !== undefined ? 'X' : 'B');
    return iecTag(address, { area: 'DB', dbNumber: 1, byteOffset: offset(m[2]!, address), bitOffset: 0 }, width, m[3], override);
  }
  // Timers and counters: T3, C5, Z5 (German counter)
  if ((m = /^([TCZ])(\d+)$/.exec(body))) {
    const area: AreaName = m[1] === 'T' ? 'T' : 'C';
    const n = offset(m[2]!, address);
    const type: DataTypeName = area === 'T' ? 'TIMER' : 'COUNTER';
    if (override && override.type !== type) throw new AddressError(address, `${area === 'T' ? 'a timer' : 'a counter'} is ${type}, not ${override.type}`);
    const count = override?.count ?? 1;
    return makeTag(address, { area, dbNumber: 0, byteOffset: n, bitOffset: 0 }, type, count, override?.isArray ?? false, 0);
  }
  // Peripheral and process image / flags: PIW256, PQW4, IW16, QD30, MB0, M32.2, I0.1, MR4 (nodes7)
  if ((m = /^(PI|PE|PQ|PA|I|E|Q|A|M)(X|B|W|D|R|DI|I|C)?(\d+)(?:\.(\d+))?(?:\.(\d+))?$/.exec(body))) {
    const area = AREAS[m[1]!]!;
    const letter = m[2];
    const loc: Location = { area, dbNumber: 0, byteOffset: offset(m[3]!, address), bitOffset: 0 };
    if (letter !== undefined && NODES7_AREA_TYPES[letter]) {
      if (override) throw new AddressError(address, `"${m[1]}${letter}" names its type; drop the ":TYPE" override`);
      return nodes7Tag(address, loc, NODES7_AREA_TYPES[letter]!, m[4], m[5]);
    }
    if (m[5] !== undefined) throw new AddressError(address, 'too many dots');
    const width = letter ?? (m[4] !== undefined ? 'X' : '');
    if (width === '') throw new AddressError(address, `expected a bit (${m[1]}0.1) or a width B, W or D (${m[1]}B0)`);
    return iecTag(address, loc, width, m[4], override);
  }
  throw new AddressError(address, 'not an S7 address (e.g. DB1,INT2, DB1.DBW2, MW4, I0.1, VW10, T3)');
}

function dbNumber(text: string, address: string): number {
  const n = Number(text);
  if (n < 1 || n > MAX_DB) throw new AddressError(address, `DB${n} is not a valid data block number (1..${MAX_DB})`);
  return n;
}

function offset(text: string, address: string): number {
  const n = Number(text);
  if (!Number.isSafeInteger(n) || n > MAX_OFFSET) throw new AddressError(address, `offset ${text} out of range (0..${MAX_OFFSET})`);
  return n;
}

function bit(text: string, address: string): number {
  const n = Number(text);
  if (n > 7) throw new AddressError(address, `bit ${n} out of range (0..7)`);
  return n;
}

/** nodes7 semantics: the number after the dot is the bit for X, the string length for S, else an array length. */
function nodes7Tag(address: string, loc: Location, type: DataTypeName, second?: string, third?: string): Tag {
  if (type === 'BOOL') {
    if (second === undefined) throw new AddressError(address, 'a bit address needs .<bit>, e.g. DB1,X0.1');
    const b = bit(second, address);
    const arr = arrayCount(third === undefined ? undefined : Number(third), address);
    return makeTag(address, { ...loc, bitOffset: b }, 'BOOL', arr.count, arr.isArray, 0);
  }
  if (type === 'STRING' || type === 'WSTRING') {
    const len = second === undefined ? MAX_STRING : Number(second);
    checkStringLength(type, len, address);
    const arr = arrayCount(third === undefined ? undefined : Number(third), address);
    return makeTag(address, loc, type, arr.count, arr.isArray, len);
  }
  if (third !== undefined) throw new AddressError(address, 'too many dots');
  const arr = arrayCount(second === undefined ? undefined : Number(second), address);
  return makeTag(address, loc, type, arr.count, arr.isArray, 0);
}

/** IEC semantics: a width letter, an optional bit, and an optional :TYPE override that must fit the width. */
function iecTag(
  address: string,
  loc: Location,
  width: string,
  bitText: string | undefined,
  override: ReturnType<typeof parseTypeSpec> | undefined,
): Tag {
  if (width === 'X') {
    if (bitText === undefined) throw new AddressError(address, 'a bit address needs .<bit>, e.g. DB1.DBX0.1');
    const b = bit(bitText, address);
    if (override && override.type !== 'BOOL') throw new AddressError(address, `${override.type} cannot start at a bit; use a B, W or D address`);
    return makeTag(address, { ...loc, bitOffset: b }, 'BOOL', override?.count ?? 1, override?.isArray ?? false, 0);
  }
  if (bitText !== undefined) throw new AddressError(address, `a ${width} address has no bit; use X for bits`);
  const natural = WIDTHS[width]!;
  if (!override) return makeTag(address, loc, natural, 1, false, 0);
  if (override.type === 'BOOL') throw new AddressError(address, 'BOOL needs a bit address (X)');
  // A scalar override of up to 4 bytes must have the width the address names; arrays,
  // strings and 8/12-byte types (no width letter exists for them) start at the byte.
  if (!override.isArray && override.type !== 'STRING' && override.type !== 'WSTRING' && SIZES[override.type] <= 4) {
    const have = SIZES[natural];
    const need = SIZES[override.type];
    if (have !== need) {
      const names: Record<number, string> = { 1: 'a byte (B)', 2: 'a word (W)', 4: 'a double word (D)', 8: 'eight bytes' };
      throw new AddressError(address, `${override.type} needs ${names[need]}, ${width} is ${names[have]}`);
    }
  }
  return makeTag(address, loc, override.type, override.count, override.isArray, override.stringLength);
}

function makeTag(address: string, loc: Location, type: DataTypeName, count: number, isArray: boolean, stringLength: number): Tag {
  const byteLength = loc.area === 'C' || loc.area === 'T' ? 2 * count : tagBytes(type, count, stringLength, loc.bitOffset);
  const last = loc.area === 'C' || loc.area === 'T' ? loc.byteOffset + count - 1 : loc.byteOffset + byteLength - 1;
  if (last > MAX_OFFSET) throw new AddressError(address, `ends at byte ${last}, beyond ${MAX_OFFSET}`);
  return Object.freeze({ address, ...loc, type, count, isArray, stringLength, byteLength });
}

const AREA_PREFIX: Readonly<Record<AreaName, string>> = Object.freeze({ I: 'I', Q: 'Q', M: 'M', DB: 'DB', PE: 'PI', PA: 'PQ', C: 'C', T: 'T' });

/** The canonical IEC form of a tag, e.g. `DB1.DBD4:REAL`, `M0.1`, `DB1.DBB0:CHAR[10]`; it parses back to the same tag. */
export function formatAddress(tag: Omit<Tag, 'address' | 'byteLength'>): string {
  const typeSpec = (): string => {
    const base = tag.type === 'STRING' || tag.type === 'WSTRING' ? `${tag.type}[${tag.stringLength}]` : tag.type;
    return tag.isArray ? `${base}[${tag.count}]` : base;
  };
  if (tag.area === 'C' || tag.area === 'T') return `${tag.area}${tag.byteOffset}${tag.isArray ? `:${typeSpec()}` : ''}`;
  const prefix = tag.area === 'DB' ? `DB${tag.dbNumber}.DB` : AREA_PREFIX[tag.area];
  if (tag.type === 'BOOL') return `${prefix}${tag.area === 'DB' ? 'X' : ''}${tag.byteOffset}.${tag.bitOffset}${tag.isArray ? `:${typeSpec()}` : ''}`;
  const natural: Partial<Record<DataTypeName, string>> = { BYTE: 'B', WORD: 'W', DWORD: 'D' };
  if (!tag.isArray && natural[tag.type]) return `${prefix}${natural[tag.type]}${tag.byteOffset}`;
  const size = SIZES[tag.type];
  const width = !tag.isArray && tag.type !== 'STRING' && tag.type !== 'WSTRING' && (size === 2 ? 'W' : size === 4 ? 'D' : size === 1 ? 'B' : undefined);
  return `${prefix}${width || 'B'}${tag.byteOffset}:${typeSpec()}`;
}
