/**
 * PLC data types as Sparkplug datatypes (Sparkplug 3.0, section 6.4.16), so a
 * device's metrics are typed by the PLC's own declarations: from an address
 * (parseAddress: `DB1.DBW2:INT`), or from a symbol table entry (compiled
 * sources, or an S7CommPlus browse). Structs are flattened to one metric per
 * elementary member, named by its path (docs/sparkplug.md, "Structs").
 *
 * The JS value a read gives (lib/values) is the value the datatype takes:
 * TIME as ms (Int32), LTIME as ns (Int64), TIME_OF_DAY as ms since midnight
 * (UInt32), DATE, DATE_AND_TIME and DTL as Dates (DateTime).
 */
import { parseAddress } from '../address';
import { PlcError, type TagResult } from '../errors';
import type { SymbolEntry, SymbolTable } from '../symbols/model';
import { wholeBlock } from '../symbols/resolve';
import type { DataTypeName } from '../types';
import { DataType, type DataTypeId } from './datatypes';
import { Quality, type PropertySet } from './model';

/** The scalar Sparkplug datatype of each PLC data type. */
export const PLC_DATATYPES: Readonly<Record<DataTypeName, DataTypeId>> = Object.freeze({
  BOOL: DataType.Boolean,
  SINT: DataType.Int8,
  INT: DataType.Int16,
  DINT: DataType.Int32,
  LINT: DataType.Int64,
  USINT: DataType.UInt8,
  BYTE: DataType.UInt8,
  UINT: DataType.UInt16,
  WORD: DataType.UInt16,
  UDINT: DataType.UInt32,
  DWORD: DataType.UInt32,
  ULINT: DataType.UInt64,
  LWORD: DataType.UInt64,
  REAL: DataType.Float,
  LREAL: DataType.Double,
  CHAR: DataType.String,
  WCHAR: DataType.String,
  STRING: DataType.String,
  WSTRING: DataType.String,
  S5TIME: DataType.Int32,
  TIMER: DataType.Int32,
  TIME: DataType.Int32,
  LTIME: DataType.Int64,
  COUNTER: DataType.UInt16,
  TIME_OF_DAY: DataType.UInt32,
  DATE: DataType.DateTime,
  DATE_AND_TIME: DataType.DateTime,
  DTL: DataType.DateTime,
});

/** The array datatype of each scalar datatype that has one. */
const ARRAY_OF: Readonly<Partial<Record<number, DataTypeId>>> = Object.freeze({
  [DataType.Int8]: DataType.Int8Array,
  [DataType.Int16]: DataType.Int16Array,
  [DataType.Int32]: DataType.Int32Array,
  [DataType.Int64]: DataType.Int64Array,
  [DataType.UInt8]: DataType.UInt8Array,
  [DataType.UInt16]: DataType.UInt16Array,
  [DataType.UInt32]: DataType.UInt32Array,
  [DataType.UInt64]: DataType.UInt64Array,
  [DataType.Float]: DataType.FloatArray,
  [DataType.Double]: DataType.DoubleArray,
  [DataType.Boolean]: DataType.BooleanArray,
  [DataType.String]: DataType.StringArray,
  [DataType.DateTime]: DataType.DateTimeArray,
});

/**
 * The datatype of a PLC type, an array of it when `isArray`. CHAR[n] is one
 * String of n characters (lib/values reads it as a string), not an array.
 */
export function datatypeOfPlcType(type: DataTypeName, isArray: boolean): DataTypeId {
  const scalar = PLC_DATATYPES[type];
  if (!isArray || type === 'CHAR' || type === 'WCHAR') return scalar;
  return ARRAY_OF[scalar] ?? scalar;
}

/** The datatype of an absolute address (`DB1.DBD4:REAL`, `M10.0`, `DB2.DBW0:INT[4]`); its parse error as it is. */
export function datatypeOfAddress(address: string): DataTypeId {
  const tag = parseAddress(address);
  return datatypeOfPlcType(tag.type, tag.isArray);
}

/** The datatype of a symbol table entry: an elementary member or an array of them; a struct is flattened (flattenSymbol). */
export function datatypeOfEntry(entry: SymbolEntry): DataTypeId {
  if (entry.kind === 'struct' || entry.dataType === undefined) {
    throw new PlcError(
      'TYPE_NOT_SUPPORTED',
      `${entry.name} is a ${entry.type}: a Sparkplug metric holds one elementary value or an array of them; flatten it to its members`,
      {
        tag: entry.name,
      },
    );
  }
  return datatypeOfPlcType(entry.dataType, entry.kind === 'array');
}

/**
 * A symbol's elementary members (and arrays of elementary types) under it, each as a metric name and the symbol that reads it:
 * `"Tank".Motor.Speed` under prefix `Tank` is the metric `Tank/Motor/Speed` (an element `Tank/Steps[0]/Temp`), the names Sparkplug hosts show as folders.
 */
export function flattenSymbol(table: SymbolTable, symbol: string, prefix: string): Record<string, string> {
  const entry = table.lookup(symbol) ?? wholeBlock(table, symbol);
  if (!entry) throw new PlcError('INVALID_ADDRESS', `no symbol ${symbol} in the symbol table`, { tag: symbol });
  const out: Record<string, string> = {};
  const walk = (e: SymbolEntry, name: string): void => {
    if (e.kind !== 'struct' && e.dataType !== undefined) {
      out[name] = e.name;
      return;
    }
    for (const child of e.children ?? []) {
      const c = table.lookup(child);
      const part = lastPart(child, e.name);
      if (c) walk(c, part.startsWith('[') ? `${name}${part}` : `${name}/${part}`);
    }
  };
  walk(entry, prefix);
  return out;
}

/** The child's own part of its name: `Motor` of `"Tank".Motor`, `[3]` of `"Recipe".Step[3]`. */
function lastPart(child: string, parent: string): string {
  const rest = child.startsWith(parent) ? child.slice(parent.length) : child;
  return rest.startsWith('.') ? rest.slice(1) : rest;
}

/**
 * The Quality property of a read's result (section 6.4.10): none for a good
 * value (the specification asks for it only when not GOOD), BAD (0) for a
 * failed read; STALE (500) is the host's to set.
 */
export function qualityOf(result: TagResult<unknown>): PropertySet | undefined {
  return result.ok ? undefined : { Quality: { type: DataType.Int32, value: Quality.BAD } };
}
