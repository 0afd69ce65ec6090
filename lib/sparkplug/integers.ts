/**
 * The integer datatypes in the payload's uint32 and uint64 fields
 * (Sparkplug 3.0, section 6.4.16): a signed value is stored as its two's
 * complement, sign-extended to the field's width (Int8 -1 is int_value
 * 0xFFFFFFFF, Int64 -1 is long_value 0xFFFFFFFFFFFFFFFF), as Eclipse Tahu's
 * Java encoder writes it; decoding keeps the datatype's own width, so a
 * peer that wrote Int8 -1 as 0xFF reads back -1 as well.
 */
import { ValueError } from '../errors';
import { INTEGER_TYPES, dataTypeName } from './datatypes';

/** `value` as an integer of `type`, range-checked: a number for 8–32 bits, a number or bigint for 64 bits. */
export function checkInteger(value: unknown, type: number, what: string): number | bigint {
  const spec = INTEGER_TYPES[type];
  if (!spec) throw new ValueError(what, `${dataTypeName(type)} is not an integer datatype`);
  let big: bigint;
  if (typeof value === 'bigint') big = value;
  else if (typeof value === 'number' && Number.isInteger(value)) big = BigInt(value);
  else throw new ValueError(what, `a ${dataTypeName(type)} takes an integer, got ${typeof value === 'number' ? value : typeof value}`);
  const min = spec.signed ? -(1n << BigInt(spec.bits - 1)) : 0n;
  const max = spec.signed ? (1n << BigInt(spec.bits - 1)) - 1n : (1n << BigInt(spec.bits)) - 1n;
  if (big < min || big > max) throw new ValueError(what, `${value} is out of the ${dataTypeName(type)} range ${min}..${max}`);
  return spec.bits === 64 ? big : Number(big);
}

/** The int_value (uint32) of an 8–32-bit integer. */
export function toUint32(value: number): number {
  return value >>> 0;
}

/** An 8–32-bit integer of `type` from an int_value, at the datatype's width. */
export function fromUint32(raw: number, type: number): number {
  const spec = INTEGER_TYPES[type]!;
  const shift = 32 - spec.bits;
  return spec.signed ? (raw << shift) >> shift : (raw << shift) >>> shift;
}

/** The long_value (uint64) of a 64-bit integer, as protobufjs' low/high words. */
export function toUint64Bits(value: bigint | number): { low: number; high: number; unsigned: true } {
  const u = BigInt.asUintN(64, BigInt(value));
  return { low: Number(u & 0xffffffffn) | 0, high: Number(u >> 32n) | 0, unsigned: true };
}

/** A 64-bit value from protobufjs (a Long, or a number when it fits), unsigned. */
export function fromUint64(raw: unknown): bigint {
  if (typeof raw === 'number') return BigInt(raw);
  if (typeof raw === 'bigint') return BigInt.asUintN(64, raw);
  const { low, high } = raw as { low: number; high: number };
  return (BigInt(high >>> 0) << 32n) | BigInt(low >>> 0);
}

/** A 64-bit integer of `type` (Int64 signed, UInt64 or DateTime unsigned) from its long_value. */
export function fromLong(raw: unknown, signed: boolean): bigint {
  const u = fromUint64(raw);
  return signed ? BigInt.asIntN(64, u) : u;
}
