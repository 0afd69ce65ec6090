/**
 * Type names as people write them (`REAL`, `R`, `TOD`, `STRING[30]`) and the
 * `:TYPE[n]` override of the IEC style.
 */
import { AddressError } from '../errors';
import type { DataTypeName } from '../types';
import { MAX_COUNT, MAX_STRING_LENGTH, MAX_WSTRING_LENGTH } from './sizes';

export interface TypeSpec {
  type: DataTypeName;
  count: number;
  isArray: boolean;
  stringLength: number;
}

/** Type names and the nodes7 / STEP 7 short forms. */
const TYPE_NAMES: Readonly<Record<string, DataTypeName>> = Object.freeze({
  BOOL: 'BOOL',
  X: 'BOOL',
  BYTE: 'BYTE',
  B: 'BYTE',
  WORD: 'WORD',
  W: 'WORD',
  DWORD: 'DWORD',
  DW: 'DWORD',
  LWORD: 'LWORD',
  LW: 'LWORD',
  SINT: 'SINT',
  USINT: 'USINT',
  INT: 'INT',
  I: 'INT',
  UINT: 'UINT',
  DINT: 'DINT',
  DI: 'DINT',
  UDINT: 'UDINT',
  LINT: 'LINT',
  ULINT: 'ULINT',
  REAL: 'REAL',
  R: 'REAL',
  LREAL: 'LREAL',
  LR: 'LREAL',
  CHAR: 'CHAR',
  C: 'CHAR',
  WCHAR: 'WCHAR',
  STRING: 'STRING',
  S: 'STRING',
  WSTRING: 'WSTRING',
  WS: 'WSTRING',
  S5TIME: 'S5TIME',
  TIME: 'TIME',
  T: 'TIME',
  LTIME: 'LTIME',
  DATE: 'DATE',
  TIME_OF_DAY: 'TIME_OF_DAY',
  TOD: 'TIME_OF_DAY',
  DATE_AND_TIME: 'DATE_AND_TIME',
  DT: 'DATE_AND_TIME',
  DTL: 'DTL',
  COUNTER: 'COUNTER',
  TIMER: 'TIMER',
});

/** The type a name (any case, short forms too) stands for; AddressError when none. */
export function typeNamed(name: string, address: string): DataTypeName {
  const type = Object.prototype.hasOwnProperty.call(TYPE_NAMES, name.toUpperCase()) ? TYPE_NAMES[name.toUpperCase()] : undefined;
  if (!type) throw new AddressError(address, `unknown type "${name}"`);
  return type;
}

/** Digits as written, without leading zeros, for messages (Number() would print 1e+21). */
export function plain(digits: string): string {
  return digits.replace(/^0+(?=\d)/, '');
}

/** Array length from an optional number; no number means a scalar. */
export function arrayCount(digits: string | undefined, address: string): { count: number; isArray: boolean } {
  if (digits === undefined) return { count: 1, isArray: false };
  const n = Number(digits);
  if (n < 1) throw new AddressError(address, `array length ${plain(digits)} (must be at least 1)`);
  if (n > MAX_COUNT) throw new AddressError(address, `array length ${plain(digits)} > ${MAX_COUNT}`);
  return { count: n, isArray: true };
}

/** Declared length of a STRING (1..254) or WSTRING (1..16382); none means the TIA default 254. */
export function stringLength(type: 'STRING' | 'WSTRING', digits: string | undefined, address: string): number {
  if (digits === undefined) return MAX_STRING_LENGTH;
  const n = Number(digits);
  const max = type === 'STRING' ? MAX_STRING_LENGTH : MAX_WSTRING_LENGTH;
  if (n < 1) throw new AddressError(address, `${type} length ${plain(digits)} (must be at least 1)`);
  if (n > max) throw new AddressError(address, `${type} length ${plain(digits)} > ${max}`);
  return n;
}

/**
 * Parses a type spec like `INT`, `REAL[20]`, `STRING[30]`, `CHAR[10]` (any
 * case). For STRING/WSTRING the bracket is the declared length and a second
 * bracket the array length: `STRING[30][4]` is four STRING[30].
 */
export function parseTypeSpec(spec: string, address: string): TypeSpec {
  const text = typeof spec === 'string' ? spec.trim() : '';
  const m = /^([A-Z_][A-Z_0-9]*)(?:\[(\d+)\])?(?:\[(\d+)\])?$/i.exec(text);
  if (!m) throw new AddressError(address, `"${text}" is not a type (e.g. INT, REAL[20], STRING[30])`);
  const type = typeNamed(m[1]!, address);
  if (type === 'STRING' || type === 'WSTRING') {
    return { type, stringLength: stringLength(type, m[2], address), ...arrayCount(m[3], address) };
  }
  if (m[3] !== undefined) throw new AddressError(address, `only STRING and WSTRING take two brackets, ${type} takes one`);
  return { type, stringLength: 0, ...arrayCount(m[2], address) };
}
