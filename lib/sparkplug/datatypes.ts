/**
 * Sparkplug B datatypes with the numbers of the Sparkplug 3.0 specification,
 * section 6.4.16 "DataType Details" (the DataType enum of the payload schema).
 */
export const DataType = Object.freeze({
  Unknown: 0,
  Int8: 1,
  Int16: 2,
  Int32: 3,
  Int64: 4,
  UInt8: 5,
  UInt16: 6,
  UInt32: 7,
  UInt64: 8,
  Float: 9,
  Double: 10,
  Boolean: 11,
  String: 12,
  DateTime: 13,
  Text: 14,
  UUID: 15,
  DataSet: 16,
  Bytes: 17,
  File: 18,
  Template: 19,
  PropertySet: 20,
  PropertySetList: 21,
  Int8Array: 22,
  Int16Array: 23,
  Int32Array: 24,
  Int64Array: 25,
  UInt8Array: 26,
  UInt16Array: 27,
  UInt32Array: 28,
  UInt64Array: 29,
  FloatArray: 30,
  DoubleArray: 31,
  BooleanArray: 32,
  StringArray: 33,
  DateTimeArray: 34,
});

export type DataTypeName = keyof typeof DataType;
export type DataTypeId = (typeof DataType)[DataTypeName];

const NAMES: readonly string[] = Object.keys(DataType);

/** The datatype's name ('Int16'), or `Unknown(<n>)` for a number the specification does not define. */
export function dataTypeName(id: number): string {
  return NAMES[id] ?? `Unknown(${id})`;
}

/** Whether `id` is one of the specification's datatypes. */
export function isDataType(id: number): id is DataTypeId {
  return Number.isInteger(id) && id >= 0 && id < NAMES.length;
}

/** Width in bits and signedness of the integer datatypes (scalars and the elements of their arrays). */
export const INTEGER_TYPES: Readonly<Partial<Record<number, { bits: 8 | 16 | 32 | 64; signed: boolean }>>> = Object.freeze({
  [DataType.Int8]: { bits: 8, signed: true },
  [DataType.Int16]: { bits: 16, signed: true },
  [DataType.Int32]: { bits: 32, signed: true },
  [DataType.Int64]: { bits: 64, signed: true },
  [DataType.UInt8]: { bits: 8, signed: false },
  [DataType.UInt16]: { bits: 16, signed: false },
  [DataType.UInt32]: { bits: 32, signed: false },
  [DataType.UInt64]: { bits: 64, signed: false },
});

/** The scalar datatype of an array datatype's elements (Int16Array → Int16), or undefined for a scalar type. */
export const ARRAY_ELEMENT: Readonly<Partial<Record<number, DataTypeId>>> = Object.freeze({
  [DataType.Int8Array]: DataType.Int8,
  [DataType.Int16Array]: DataType.Int16,
  [DataType.Int32Array]: DataType.Int32,
  [DataType.Int64Array]: DataType.Int64,
  [DataType.UInt8Array]: DataType.UInt8,
  [DataType.UInt16Array]: DataType.UInt16,
  [DataType.UInt32Array]: DataType.UInt32,
  [DataType.UInt64Array]: DataType.UInt64,
  [DataType.FloatArray]: DataType.Float,
  [DataType.DoubleArray]: DataType.Double,
  [DataType.BooleanArray]: DataType.Boolean,
  [DataType.StringArray]: DataType.String,
  [DataType.DateTimeArray]: DataType.DateTime,
});
