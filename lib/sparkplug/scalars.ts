/**
 * The scalar value fields shared by a metric, a property, a DataSet cell and
 * a Template parameter (Sparkplug 3.0, sections 6.4.6–6.4.16): which of
 * int_value, long_value, float_value, double_value, boolean_value and
 * string_value holds a datatype's value, both ways. Pure.
 */
import { PlcError, ValueError } from '../errors';
import { epochMillis } from './arrays';
import { DataType, INTEGER_TYPES, dataTypeName } from './datatypes';
import { checkInteger, fromLong, fromUint32, fromUint64, toUint32, toUint64Bits } from './integers';

/** A scalar value: integers up to 32 bits and floats as numbers, 64-bit integers as bigints, DateTime as a Date. */
export type ScalarValue = number | bigint | boolean | string | Date;

/** The protobuf fields of a scalar value, as protobufjs takes and gives them. */
export interface ScalarFields {
  int_value?: number;
  long_value?: unknown;
  float_value?: number;
  double_value?: number;
  boolean_value?: boolean;
  string_value?: string;
}

/** Whether `type` is held in the scalar fields (not bytes, a DataSet, a Template or a property set). */
export function isScalarType(type: number): boolean {
  return (type >= DataType.Int8 && type <= DataType.UUID) || type === DataType.Unknown;
}

/** The value field of `value` as a `type`, checked (INVALID_VALUE naming `what`). */
export function scalarFields(type: number, value: unknown, what: string): ScalarFields {
  const spec = INTEGER_TYPES[type];
  if (spec) {
    const n = checkInteger(value, type, what);
    return spec.bits === 64 ? { long_value: toUint64Bits(n) } : { int_value: toUint32(n as number) };
  }
  switch (type) {
    case DataType.Float:
    case DataType.Double:
      if (typeof value !== 'number') throw new ValueError(what, `a ${dataTypeName(type)} takes a number, got ${typeof value}`);
      return type === DataType.Float ? { float_value: value } : { double_value: value };
    case DataType.Boolean:
      if (typeof value !== 'boolean') throw new ValueError(what, `a Boolean takes true or false, got ${typeof value}`);
      return { boolean_value: value };
    case DataType.String:
    case DataType.Text:
    case DataType.UUID:
      if (typeof value !== 'string') throw new ValueError(what, `a ${dataTypeName(type)} takes a string, got ${typeof value}`);
      return { string_value: value };
    case DataType.DateTime:
      return { long_value: toUint64Bits(epochMillis(value, what)) };
    default:
      throw new ValueError(what, `${dataTypeName(type)} is not a scalar datatype`);
  }
}

/** The value of a `type` from its fields; a missing field is a PROTOCOL_ERROR naming `what`. */
export function scalarValue(type: number, fields: ScalarFields, what: string): ScalarValue {
  const spec = INTEGER_TYPES[type];
  if (spec) {
    if (spec.bits === 64) return fromLong(need(fields, 'long_value', type, what), spec.signed);
    if (has(fields, 'int_value') || !has(fields, 'long_value')) return fromUint32(need(fields, 'int_value', type, what), type);
    // Eclipse Tahu 1.0.21's Java encoder writes a UInt32 (its Long) into long_value, not the int_value of
    // section 6.4.16: taken as well, when it is in the datatype's range.
    const wide = fromLong(fields.long_value, spec.signed);
    try {
      return checkInteger(wide, type, what) as number;
    } catch (err) {
      throw new PlcError(
        'PROTOCOL_ERROR',
        `Sparkplug payload: ${what}: long_value ${wide} ${(err as Error).message.replace(/^.*?: /, '')}`,
        {
          tag: what,
        },
      );
    }
  }
  switch (type) {
    case DataType.Float:
      return need(fields, 'float_value', type, what);
    case DataType.Double:
      return need(fields, 'double_value', type, what);
    case DataType.Boolean:
      return need(fields, 'boolean_value', type, what);
    case DataType.String:
    case DataType.Text:
    case DataType.UUID:
      return need(fields, 'string_value', type, what);
    case DataType.DateTime:
      return new Date(Number(fromUint64(need(fields, 'long_value', type, what))));
    default:
      throw new PlcError('PROTOCOL_ERROR', `Sparkplug payload: ${what}: ${dataTypeName(type)} is not a scalar datatype`, { tag: what });
  }
}

/** Whether the payload holds `field` (protobufjs keeps absent fields' defaults on the prototype, not on the message). */
function has(fields: ScalarFields, field: keyof ScalarFields): boolean {
  return Object.prototype.hasOwnProperty.call(fields, field) && fields[field] !== undefined && fields[field] !== null;
}

/** A field the payload holds (protobufjs keeps absent fields' defaults on the prototype, not on the message). */
function need<K extends keyof ScalarFields>(fields: ScalarFields, field: K, type: number, what: string): NonNullable<ScalarFields[K]> {
  const value = Object.prototype.hasOwnProperty.call(fields, field) ? fields[field] : undefined;
  if (value === undefined || value === null) {
    throw new PlcError('PROTOCOL_ERROR', `Sparkplug payload: ${what}: a ${dataTypeName(type)} without its ${field}`, { tag: what });
  }
  return value as NonNullable<ScalarFields[K]>;
}
