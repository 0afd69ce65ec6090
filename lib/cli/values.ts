import { ValueError } from '../errors';
import { byLeafType, type Convert, type TypedClient } from '../symbols/leaf-types';
import type { SymbolTable } from '../symbols/model';
import type { DataTypeName, PlcScalar, PlcValue } from '../types';
import { Literal, textOf, valueToText } from '../values/text';
import { isTimeType, timeText } from '../values/time-text';
export { valueToText };

/**
 * A read value as the CLI's text output shows it: TIME, DATE, TIME_OF_DAY and
 * the other time types as TIA writes them (`T#5S`, `D#2024-01-31`,
 * `TOD#12:00:00.000`, lib/values/time-text.ts), a struct's members of those
 * types too (by its shape or the PLC's browsed entry, lib/symbols/leaf-types.ts),
 * everything else as textOf. The JSON output keeps the value (numbers of ms,
 * ISO dates).
 */
export function textForPeople(client: TypedClient, table: SymbolTable | undefined, target: string, value: unknown): string {
  let convert: Convert | undefined;
  try {
    convert = byLeafType(client, table, target, timeLiteral);
  } catch {
    convert = undefined; // a target that does not parse was refused before its value was read
  }
  return textOf(convert ? convert(value) : value);
}

/** The conversion of a value of `type` to its TIA literal, or undefined for a type that has none. */
function timeLiteral(type: string | undefined): Convert | undefined {
  if (!isTimeType(type)) return undefined;
  return (value) => {
    const text = timeText(type, value);
    return text === undefined ? value : new Literal(text);
  };
}

/** The part of a tag the CLI needs to turn text into a value. */
export interface TypedTag {
  readonly address: string;
  readonly type: DataTypeName;
  readonly isArray: boolean;
}

const BIGINT_TYPES = new Set<DataTypeName>(['LWORD', 'LINT', 'ULINT', 'LTIME']);
const TEXT_TYPES = new Set<DataTypeName>(['CHAR', 'WCHAR', 'STRING', 'WSTRING']);
const DATE_TYPES = new Set<DataTypeName>(['DATE', 'DATE_AND_TIME', 'DTL']);

/**
 * Turns command-line text into a value of the tag's type: `true`/`false`/`1`/`0`
 * for BOOL, decimal or 0x-hex integers, ISO dates, text as is; arrays as a JSON
 * array or comma-separated. Range checks are the value codec's job.
 */
export function valueFromText(tag: TypedTag, text: string): PlcValue {
  if (!tag.isArray) return scalarFromText(tag, text);
  // CHAR[10]=hello: a character array is written as text.
  if ((tag.type === 'CHAR' || tag.type === 'WCHAR') && !text.startsWith('[')) return [...text];
  let parts: unknown[];
  if (text.trim().startsWith('[')) {
    try {
      parts = JSON.parse(text) as unknown[];
    } catch {
      throw new ValueError(tag.address, `"${text}" is not a JSON array`);
    }
    if (!Array.isArray(parts)) throw new ValueError(tag.address, 'expected an array');
  } else {
    parts = text.split(',');
  }
  return parts.map((p) => scalarFromText(tag, String(p)));
}

function scalarFromText(tag: TypedTag, raw: string): PlcScalar {
  const text = TEXT_TYPES.has(tag.type) ? raw : raw.trim();
  if (tag.type === 'BOOL') {
    const t = text.toLowerCase();
    if (t === 'true' || t === '1' || t === 'on') return true;
    if (t === 'false' || t === '0' || t === 'off') return false;
    throw new ValueError(tag.address, `"${text}" is not a BOOL (true/false/1/0)`);
  }
  if (TEXT_TYPES.has(tag.type)) return text;
  if (DATE_TYPES.has(tag.type)) {
    const d = new Date(text);
    if (Number.isNaN(d.getTime())) throw new ValueError(tag.address, `"${text}" is not a date (use ISO 8601, e.g. 2024-05-01T12:00:00Z)`);
    return d;
  }
  if (BIGINT_TYPES.has(tag.type)) {
    try {
      return BigInt(text);
    } catch {
      throw new ValueError(tag.address, `"${text}" is not an integer`);
    }
  }
  const n = /^[-+]?0x[0-9a-f]+$/i.test(text) ? Number.parseInt(text, 16) : Number(text);
  if (text === '' || Number.isNaN(n)) throw new ValueError(tag.address, `"${text}" is not a number`);
  return n;
}

/**
 * JSON text where a bigint (LINT, ULINT, LWORD, LTIME) is written as its exact
 * digits, unquoted, and a Date as its ISO text; everything else as
 * JSON.stringify writes it (non-finite numbers and undefined in arrays become
 * null, undefined properties are left out). A serializer of its own because
 * JSON.stringify cannot emit a bare bigint and a replacer's marker string
 * comes back escaped.
 */
export function toJson(value: unknown): string {
  return jsonOf(value) ?? 'null';
}

/** undefined where JSON.stringify would leave the value out (undefined, functions, symbols). */
function jsonOf(value: unknown): string | undefined {
  switch (typeof value) {
    case 'bigint':
      return value.toString();
    case 'number':
      return Number.isFinite(value) ? JSON.stringify(value) : 'null';
    case 'string':
    case 'boolean':
      return JSON.stringify(value);
    case 'object':
      if (value === null) return 'null';
      if (value instanceof Date) return Number.isNaN(value.getTime()) ? 'null' : JSON.stringify(value.toISOString());
      if (Array.isArray(value)) return `[${value.map((v: unknown) => jsonOf(v) ?? 'null').join(',')}]`;
      return `{${Object.entries(value)
        .flatMap(([k, v]) => {
          const text = jsonOf(v);
          return text === undefined ? [] : [`${JSON.stringify(k)}:${text}`];
        })
        .join(',')}}`;
    default:
      return undefined;
  }
}
