/**
 * The S7 address parser. Each syntax is a family (recognised by how the
 * address starts) with one pattern, so an error can say what was expected in
 * that family, or which trailing text is left over.
 */
import { AddressError } from '../errors';
import type { AreaName, DataTypeName, Tag } from '../types';
import { elementBytes, MAX_DB_NUMBER, MAX_OFFSET, startsAtByte, tagBytes } from './sizes';
import { arrayCount, parseTypeSpec, plain, stringLength, typeNamed, type TypeSpec } from './type-spec';

/** Longer input is not an address; the message quotes only its start. */
const MAX_ADDRESS_LENGTH = 256;

interface Location {
  area: AreaName;
  dbNumber: number;
  byteOffset: number;
  bitOffset: number;
}

interface Syntax {
  /** How an address of this family starts. */
  family: RegExp;
  /** Anchored at the start only: a shorter match means trailing garbage. None: the family is only recognised to give a hint. */
  pattern?: RegExp;
  expected: (body: string) => string;
  build?: (address: string, m: RegExpExecArray, override: TypeSpec | undefined) => Tag;
}

/** Area mnemonics, English and German (E = I, A = Q, PE = PI, PA = PQ). */
const AREAS: Readonly<Record<string, AreaName>> = Object.freeze({
  I: 'I',
  E: 'I',
  Q: 'Q',
  A: 'Q',
  M: 'M',
  PI: 'PE',
  PE: 'PE',
  PQ: 'PA',
  PA: 'PA',
});
/** Width letters of the IEC style and the type each names by default. */
const WIDTHS: Readonly<Record<string, DataTypeName>> = Object.freeze({ X: 'BOOL', B: 'BYTE', W: 'WORD', D: 'DWORD' });
const WIDTH_NAMES: Readonly<Record<number, string>> = Object.freeze({ 1: 'a byte', 2: 'a word', 4: 'a double word' });
/** nodes7 area forms that name a type instead of a width: MR4, MI4, MDI4, MC4. */
const NODES7_AREA_TYPES: Readonly<Record<string, DataTypeName>> = Object.freeze({ R: 'REAL', I: 'INT', DI: 'DINT', C: 'CHAR' });

const SYNTAXES: readonly Syntax[] = [
  {
    // nodes7: DB1,INT2  DB1,X0.1  DB1,X0.1.8  DB1,REAL0.20  DB10,S20.30
    family: /^DB\d+,/i,
    pattern: /^DB(\d+),(S5TIME|[A-Z_]+)(\d+)(?:\.(\d+))?(?:\.(\d+))?/i,
    expected: () => 'expected DB<n>,<TYPE><byte>[.<bit or length>], e.g. DB1,INT2',
    build: (address, m, override) => {
      if (override) throw new AddressError(address, 'a nodes7-style address names its type; drop the ":TYPE" override');
      const loc: Location = { area: 'DB', dbNumber: dbNumber(m[1]!, address), byteOffset: offset(m[3]!, address), bitOffset: 0 };
      return nodes7Tag(address, loc, typeNamed(m[2]!, address), m[4], m[5]);
    },
  },
  {
    // IEC / TIA: DB1.DBX0.1  DB1.DBB0  DB1.DBW2  DB1.DBD4
    family: /^DB\d+\./i,
    pattern: /^DB(\d+)\.DB([XBWD])(\d+)(?:\.(\d+))?/i,
    expected: () => 'expected DB<n>.DBX<byte>.<bit> or DB<n>.DBB, DBW, DBD<byte>, e.g. DB1.DBW2',
    build: (address, m, override) => {
      const loc: Location = { area: 'DB', dbNumber: dbNumber(m[1]!, address), byteOffset: offset(m[3]!, address), bitOffset: 0 };
      return iecTag(address, loc, `DB${m[2]!.toUpperCase()}`, m[4], override);
    },
  },
  {
    // Any other DB…: only a hint.
    family: /^DB/i,
    expected: () => 'expected DB<n>.DBW<byte> (IEC) or DB<n>,<TYPE><byte> (nodes7), e.g. DB1.DBW2 or DB1,INT2',
  },
  {
    // S7-200 V memory = DB1: VB10  VW10  VD10  V10.1  VX10.1
    family: /^V/i,
    pattern: /^V([XBWD]?)(\d+)(?:\.(\d+))?/i,
    expected: () => 'expected VB, VW, VD<byte> or V<byte>.<bit>, e.g. VW10',
    build: (address, m, override) => {
      const width = m[1] || (m[3] === undefined ? '' : 'X');
      if (width === '') throw new AddressError(address, `expected a bit (V${plain(m[2]!)}.0) or a width B, W or D (VB${plain(m[2]!)})`);
      const loc: Location = { area: 'DB', dbNumber: 1, byteOffset: offset(m[2]!, address), bitOffset: 0 };
      return iecTag(address, loc, `V${width.toUpperCase()}`, m[3], override);
    },
  },
  {
    // Timers and counters (German counter Z): T3  C5  Z5  T3:TIMER[4]
    family: /^[TCZ]/i,
    pattern: /^([TCZ])(\d+)/i,
    expected: () => 'expected a timer T<n> or a counter C<n>, e.g. T3',
    build: (address, m, override) => timerCounterTag(address, m[1]!.toUpperCase() === 'T' ? 'T' : 'C', m[2]!, override),
  },
  {
    // Process image, flags, peripherals: IW16  QD30  MB0  M32.2  I0.1  PIW256  MR4 (nodes7)
    family: /^(P[IEQA]|[IEQAM])/i,
    pattern: /^(P[IEQA]|[IEQAM])(X|B|W|D|R|DI|I|C)?(\d+)(?:\.(\d+))?(?:\.(\d+))?/i,
    expected: (body) => {
      const area = /^(P[IEQA]|[IEQAM])/i.exec(body)![0].toUpperCase();
      return `expected ${area}B, ${area}W, ${area}D<byte> or ${area}<byte>.<bit>, e.g. ${area}W4`;
    },
    build: areaTag,
  },
];

/**
 * Parses an S7 address: nodes7 style (`DB1,INT2`, `MR4`), IEC / TIA style
 * (`DB1.DBW2`, `%MW4`) with an optional `:TYPE` / `:TYPE[n]` override, S7-200
 * (`VW10` = DB1), timers and counters (`T3`, `C5`). Case-insensitive; the
 * tag keeps the address exactly as given. Throws AddressError naming the
 * address and what is wrong — never anything else.
 */
export function parseAddress(address: string): Tag {
  if (typeof address !== 'string') throw new AddressError(String(address), 'an address must be text');
  const text = address.trim();
  if (text === '') throw new AddressError(address, 'empty address');
  if (text.length > MAX_ADDRESS_LENGTH) throw new AddressError(`${text.slice(0, 40)}…`, `longer than ${MAX_ADDRESS_LENGTH} characters`);
  // Printable ASCII only: a lookalike ('ı', 'ſ', a fullwidth digit) is named rather than half-matched.
  const odd = /[^\x20-\x7e]/.exec(text);
  if (odd) throw new AddressError(address, `unexpected character ${JSON.stringify(odd[0])}`);

  const colon = text.indexOf(':');
  const body = (colon < 0 ? text : text.slice(0, colon)).trim().replace(/^%/, '');
  const override = colon < 0 ? undefined : parseTypeSpec(text.slice(colon + 1), address);
  for (const syntax of SYNTAXES) {
    if (!syntax.family.test(body)) continue;
    const m = syntax.pattern?.exec(body);
    if (!m || !syntax.build) throw new AddressError(address, syntax.expected(body), looksLikeName(text, true) ? NAME_HINT : undefined);
    if (m[0].length < body.length) throw new AddressError(address, `unexpected "${body.slice(m[0].length)}" after "${m[0]}"`);
    return syntax.build(address, m, override);
  }
  throw new AddressError(
    address,
    'not an S7 address (e.g. DB1,INT2, DB1.DBW2, MW4, I0.1, VW10, T3)',
    looksLikeName(text) ? NAME_HINT : undefined,
  );
}

/** Whether `text` is an absolute address (parseAddress takes it): a text that is not is a tag name, or a mistake. */
export function isAddress(text: string): boolean {
  try {
    parseAddress(text);
    return true;
  } catch {
    return false;
  }
}

/**
 * What to do about a tag name given where only addresses are known: the
 * same words serve the library (connect(url, { symbols })), the command line
 * (--symbols) and Node-RED (the connection node's Symbol sources).
 */
export const NAME_HINT =
  'it looks like a tag name: names are read through the DB sources or symbol table that declare them (exported from TIA Portal or STEP 7), given to the connection as its symbols';

/** `"Tank".Level`, `Tank.Motor.Speed`, `Tank.Set[2]`, `Tank`: a name as TIA writes it, quoted parts or plain. */
const NAME = /^(?:"[^"]+"|[A-Za-z_]\w*)(?:\.(?:"[^"]+"|[A-Za-z_]\w*)|\[\s*-?\d+(?:\s*,\s*-?\d+)*\s*\])*$/;

/**
 * `family`: the text starts as an address family does (T for timers, M for
 * markers, DB…): a name only when quoted or when it starts with four
 * letters (`Tank`, `Motor.Speed`), which no address does (DBX, PIW: three).
 */
function looksLikeName(text: string, family = false): boolean {
  return NAME.test(text) && (!family || text.includes('"') || /^[A-Za-z_]{4}/.test(text));
}

function dbNumber(digits: string, address: string): number {
  const n = Number(digits);
  if (n < 1 || n > MAX_DB_NUMBER)
    throw new AddressError(address, `DB${plain(digits)} is not a valid data block number (1..${MAX_DB_NUMBER})`);
  return n;
}

function offset(digits: string, address: string): number {
  const n = Number(digits);
  if (n > MAX_OFFSET) throw new AddressError(address, `offset ${plain(digits)} out of range (0..${MAX_OFFSET})`);
  return n;
}

function bit(digits: string, address: string): number {
  const n = Number(digits);
  if (n > 7) throw new AddressError(address, `bit ${plain(digits)} out of range (0..7)`);
  return n;
}

function areaTag(address: string, m: RegExpExecArray, override: TypeSpec | undefined): Tag {
  const areaLetters = m[1]!.toUpperCase();
  const letter = m[2]?.toUpperCase();
  const loc: Location = { area: AREAS[areaLetters]!, dbNumber: 0, byteOffset: offset(m[3]!, address), bitOffset: 0 };
  if (letter !== undefined && NODES7_AREA_TYPES[letter]) {
    if (override) throw new AddressError(address, `"${areaLetters}${letter}" names its type; drop the ":TYPE" override`);
    return nodes7Tag(address, loc, NODES7_AREA_TYPES[letter]!, m[4], m[5]);
  }
  if (m[5] !== undefined) throw new AddressError(address, `unexpected ".${m[5]}" after "${m[0].slice(0, -m[5].length - 1)}"`);
  const width = letter ?? (m[4] === undefined ? '' : 'X');
  const at = plain(m[3]!);
  if (width === '') throw new AddressError(address, `expected a bit (${areaLetters}${at}.0) or a width B, W or D (${areaLetters}B${at})`);
  return iecTag(address, loc, `${areaLetters}${width}`, m[4], override);
}

/** nodes7 semantics: after the offset, X takes .bit[.count], STRING .length[.count], the others .count. */
function nodes7Tag(address: string, loc: Location, type: DataTypeName, second?: string, third?: string): Tag {
  if (type === 'BOOL') {
    if (second === undefined) throw new AddressError(address, 'a bit address needs .<bit>, e.g. DB1,X0.1');
    return makeTag(address, { ...loc, bitOffset: bit(second, address) }, { type, stringLength: 0, ...arrayCount(third, address) });
  }
  if (type === 'STRING' || type === 'WSTRING') {
    return makeTag(address, loc, { type, stringLength: stringLength(type, second, address), ...arrayCount(third, address) });
  }
  if (third !== undefined)
    throw new AddressError(address, `unexpected ".${third}": ${type} takes one number after the offset (the array length)`);
  return makeTag(address, loc, { type, stringLength: 0, ...arrayCount(second, address) });
}

/**
 * IEC semantics: a width letter, a bit for X, and an optional override. A
 * scalar override must have the width the address names; arrays, strings and
 * types wider than a double word (no letter exists for them) start at the byte.
 */
function iecTag(address: string, loc: Location, widthLabel: string, bitDigits: string | undefined, override: TypeSpec | undefined): Tag {
  const width = widthLabel.slice(-1);
  if (width === 'X') {
    if (bitDigits === undefined) throw new AddressError(address, `a bit address needs .<bit>, e.g. ${widthLabel}0.1`);
    const b = bit(bitDigits, address);
    if (override && override.type !== 'BOOL')
      throw new AddressError(address, `${override.type} cannot start at a bit; use a B, W or D address`);
    return makeTag(address, { ...loc, bitOffset: b }, override ?? { type: 'BOOL', count: 1, isArray: false, stringLength: 0 });
  }
  if (bitDigits !== undefined) throw new AddressError(address, `${widthLabel} has no bit; use X for bits (e.g. DBX0.1, M0.1)`);
  const natural = WIDTHS[width]!;
  if (!override) return makeTag(address, loc, { type: natural, count: 1, isArray: false, stringLength: 0 });
  if (override.type === 'BOOL') throw new AddressError(address, 'BOOL needs a bit address (X), e.g. DB1.DBX0.1:BOOL[8]');
  if (!override.isArray && !startsAtByte(override.type)) {
    const need = elementBytes(override.type);
    const have = elementBytes(natural);
    if (need !== have)
      throw new AddressError(address, `${override.type} needs ${WIDTH_NAMES[need]}, ${widthLabel} is ${WIDTH_NAMES[have]}`);
  }
  return makeTag(address, loc, override);
}

function timerCounterTag(address: string, area: 'T' | 'C', digits: string, override: TypeSpec | undefined): Tag {
  const type: DataTypeName = area === 'T' ? 'TIMER' : 'COUNTER';
  if (override && override.type !== type)
    throw new AddressError(address, `${area === 'T' ? 'a timer' : 'a counter'} is ${type}, not ${override.type}`);
  const number = offset(digits, address);
  const spec = override ?? { type, count: 1, isArray: false, stringLength: 0 };
  const last = number + spec.count - 1;
  if (last > MAX_OFFSET) throw new AddressError(address, `ends at ${area}${last}, beyond ${area}${MAX_OFFSET}`);
  return tagOf(address, { area, dbNumber: 0, byteOffset: number, bitOffset: 0 }, spec, tagBytes(type, spec.count, 0, 0));
}

function makeTag(address: string, loc: Location, spec: TypeSpec): Tag {
  const byteLength = tagBytes(spec.type, spec.count, spec.stringLength, loc.bitOffset);
  const last = loc.byteOffset + byteLength - 1;
  if (last > MAX_OFFSET) throw new AddressError(address, `ends at byte ${last}, beyond ${MAX_OFFSET}`);
  return tagOf(address, loc, spec, byteLength);
}

/**
 * Every Tag is made by this one literal: one shape for all of them (the
 * poll's code sees one kind of object), all fields in the object itself (a
 * spread adds them one by one, into a separate property array, ~60 bytes
 * more per tag).
 */
function tagOf(address: string, loc: Location, spec: TypeSpec, byteLength: number): Tag {
  return Object.freeze({
    address,
    area: loc.area,
    dbNumber: loc.dbNumber,
    byteOffset: loc.byteOffset,
    bitOffset: loc.bitOffset,
    type: spec.type,
    count: spec.count,
    isArray: spec.isArray,
    stringLength: spec.stringLength,
    byteLength,
  });
}
