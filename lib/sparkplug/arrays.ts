/**
 * The array datatypes' bytes_value (Sparkplug 3.0, section 6.4.17 "Array
 * Types"): little-endian packed elements; BooleanArray a 4-byte little-endian
 * count then the bits, most significant bit first, padded to a byte;
 * StringArray UTF-8 strings each ended by a NUL; DateTimeArray 8-byte
 * little-endian milliseconds since the epoch.
 *
 * Pure: values to bytes and back. `what` names the metric in errors.
 */
import { PlcError, ValueError } from '../errors';
import { ARRAY_ELEMENT, DataType, dataTypeName } from './datatypes';
import { checkInteger } from './integers';

/** The JS value of an array metric. */
export type ArrayValue = readonly number[] | readonly bigint[] | readonly boolean[] | readonly string[] | readonly Date[];

interface Packing {
  bytes: number;
  write(buf: Buffer, offset: number, value: unknown, what: string): void;
  read(buf: Buffer, offset: number): number | bigint | Date;
}

function int(bytes: 1 | 2 | 4, signed: boolean, type: number): Packing {
  return {
    bytes,
    write: (buf, offset, value, what) => {
      const n = checkInteger(value, type, what) as number;
      if (signed) buf.writeIntLE(n, offset, bytes);
      else buf.writeUIntLE(n, offset, bytes);
    },
    read: (buf, offset) => (signed ? buf.readIntLE(offset, bytes) : buf.readUIntLE(offset, bytes)),
  };
}

function long(signed: boolean, type: number): Packing {
  return {
    bytes: 8,
    write: (buf, offset, value, what) => {
      const n = BigInt(checkInteger(value, type, what));
      if (signed) buf.writeBigInt64LE(n, offset);
      else buf.writeBigUInt64LE(n, offset);
    },
    read: (buf, offset) => (signed ? buf.readBigInt64LE(offset) : buf.readBigUInt64LE(offset)),
  };
}

function real(bytes: 4 | 8): Packing {
  return {
    bytes,
    write: (buf, offset, value, what) => {
      if (typeof value !== 'number') throw new ValueError(what, `expected a number, got ${typeof value}`);
      if (bytes === 4) buf.writeFloatLE(value, offset);
      else buf.writeDoubleLE(value, offset);
    },
    read: (buf, offset) => (bytes === 4 ? buf.readFloatLE(offset) : buf.readDoubleLE(offset)),
  };
}

const DATE_TIME: Packing = {
  bytes: 8,
  write: (buf, offset, value, what) => buf.writeBigUInt64LE(BigInt(epochMillis(value, what)), offset),
  read: (buf, offset) => new Date(Number(buf.readBigUInt64LE(offset))),
};

const PACKINGS: Readonly<Partial<Record<number, Packing>>> = {
  [DataType.Int8Array]: int(1, true, DataType.Int8),
  [DataType.Int16Array]: int(2, true, DataType.Int16),
  [DataType.Int32Array]: int(4, true, DataType.Int32),
  [DataType.Int64Array]: long(true, DataType.Int64),
  [DataType.UInt8Array]: int(1, false, DataType.UInt8),
  [DataType.UInt16Array]: int(2, false, DataType.UInt16),
  [DataType.UInt32Array]: int(4, false, DataType.UInt32),
  [DataType.UInt64Array]: long(false, DataType.UInt64),
  [DataType.FloatArray]: real(4),
  [DataType.DoubleArray]: real(8),
  [DataType.DateTimeArray]: DATE_TIME,
};

/** Milliseconds since the epoch of a Date (or a number of them), checked to fit a uint64. */
export function epochMillis(value: unknown, what: string): number {
  const ms = value instanceof Date ? value.getTime() : value;
  if (typeof ms !== 'number' || !Number.isInteger(ms) || ms < 0) {
    throw new ValueError(
      what,
      `expected a Date at or after 1970-01-01, got ${value instanceof Date ? 'an invalid or earlier Date' : String(value)}`,
    );
  }
  return ms;
}

/** The bytes_value of an array metric of `type`. */
export function packArray(type: number, values: unknown, what: string): Buffer {
  if (!Array.isArray(values)) throw new ValueError(what, `a ${dataTypeName(type)} takes an array, got ${typeof values}`);
  if (type === DataType.BooleanArray) return packBooleans(values, what);
  if (type === DataType.StringArray) return packStrings(values, what);
  const packing = PACKINGS[type];
  if (!packing) throw new ValueError(what, `${dataTypeName(type)} is not an array datatype`);
  const buf = Buffer.alloc(values.length * packing.bytes);
  values.forEach((v, i) => packing.write(buf, i * packing.bytes, v, `${what}[${i}]`));
  return buf;
}

/** The elements of an array metric's bytes_value; a length that does not fit the type is a PROTOCOL_ERROR. */
export function unpackArray(type: number, bytes: Uint8Array, what: string): ArrayValue {
  const buf = Buffer.from(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (type === DataType.BooleanArray) return unpackBooleans(buf, what);
  if (type === DataType.StringArray) return unpackStrings(buf, what);
  const packing = PACKINGS[type];
  if (!packing || ARRAY_ELEMENT[type] === undefined) throw malformed(what, `${dataTypeName(type)} is not an array datatype`);
  if (buf.length % packing.bytes !== 0) {
    throw malformed(what, `${buf.length} bytes are not a whole number of ${packing.bytes}-byte ${dataTypeName(type)} elements`);
  }
  const out: (number | bigint | Date)[] = [];
  for (let offset = 0; offset < buf.length; offset += packing.bytes) out.push(packing.read(buf, offset));
  return out as ArrayValue;
}

function packBooleans(values: readonly unknown[], what: string): Buffer {
  const buf = Buffer.alloc(4 + Math.ceil(values.length / 8));
  buf.writeUInt32LE(values.length, 0);
  values.forEach((v, i) => {
    if (typeof v !== 'boolean') throw new ValueError(`${what}[${i}]`, `expected a boolean, got ${typeof v}`);
    if (v) buf[4 + (i >> 3)]! |= 0x80 >> (i & 7);
  });
  return buf;
}

function unpackBooleans(buf: Buffer, what: string): boolean[] {
  if (buf.length < 4) throw malformed(what, `a BooleanArray needs its 4-byte count, got ${buf.length} bytes`);
  const count = buf.readUInt32LE(0);
  if (Math.ceil(count / 8) !== buf.length - 4) {
    throw malformed(what, `a BooleanArray of ${count} values takes ${Math.ceil(count / 8)} bytes after its count, got ${buf.length - 4}`);
  }
  const out: boolean[] = [];
  for (let i = 0; i < count; i++) out.push((buf[4 + (i >> 3)]! & (0x80 >> (i & 7))) !== 0);
  return out;
}

function packStrings(values: readonly unknown[], what: string): Buffer {
  const parts: Buffer[] = [];
  values.forEach((v, i) => {
    if (typeof v !== 'string') throw new ValueError(`${what}[${i}]`, `expected a string, got ${typeof v}`);
    if (v.includes('\0')) throw new ValueError(`${what}[${i}]`, 'a StringArray element cannot hold a NUL character (it ends each element)');
    parts.push(Buffer.from(v, 'utf8'), Buffer.alloc(1));
  });
  return Buffer.concat(parts);
}

function unpackStrings(buf: Buffer, what: string): string[] {
  if (buf.length === 0) return [];
  if (buf[buf.length - 1] !== 0) throw malformed(what, 'a StringArray must end with a NUL');
  return buf
    .subarray(0, buf.length - 1)
    .toString('utf8')
    .split('\0');
}

function malformed(what: string, problem: string): PlcError {
  return new PlcError('PROTOCOL_ERROR', `Sparkplug payload: metric ${what}: ${problem}`, { tag: what });
}
