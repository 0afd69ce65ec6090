/**
 * Strict checks that turn a JS value into what an element encoder writes.
 * They throw ValueProblem (the problem without the tag); the tag-level
 * functions in index.ts turn it into a ValueError naming the address and,
 * for arrays, the element.
 */
import type { DataTypeName, PlcScalar } from '../types';
import type { TagShape } from './types-table';

export class ValueProblem extends Error {}

export function reject(problem: string): never {
  throw new ValueProblem(problem);
}

/** Encodes one validated element of `tag` at buf[off]; decodes one element (never throws on any bytes). */
export interface ElementCodec {
  encode(tag: TagShape, value: unknown, buf: Buffer, off: number): void;
  decode(tag: TagShape, buf: Buffer, off: number): PlcScalar;
}

export type CodecTable<K extends DataTypeName> = Readonly<Record<K, ElementCodec>>;

/** A short rendering of a value for error messages. */
export function show(value: unknown): string {
  if (typeof value === 'string') return JSON.stringify(value.length > 40 ? `${value.slice(0, 40)}…` : value);
  if (typeof value === 'bigint') return `${value}n`;
  if (value instanceof Date) return Number.isNaN(value.getTime()) ? 'Invalid Date' : value.toISOString();
  if (Array.isArray(value)) return `an array of ${value.length}`;
  if (value === null) return 'null';
  if (value === undefined) return 'undefined';
  if (typeof value === 'object') return 'an object';
  if (typeof value === 'function') return 'a function';
  // A primitive is left (number, string, boolean, bigint, symbol): String() shows it as it is.
  // eslint-disable-next-line @typescript-eslint/no-base-to-string
  return String(value);
}

/** An integer in min..max for a type of up to 32 bits; a bigint in range is accepted too. */
export function integerIn(type: DataTypeName, value: unknown, min: number, max: number): number {
  let n: number;
  if (typeof value === 'number') n = value;
  else if (typeof value === 'bigint') {
    if (value < BigInt(min) || value > BigInt(max)) reject(`${show(value)} is out of range for ${type} (${min}..${max})`);
    n = Number(value);
  } else return reject(`expected a number for ${type}, got ${show(value)}`);
  if (!Number.isInteger(n)) return reject(`${show(value)} is not an integer (${type})`);
  if (n < min || n > max) return reject(`${show(value)} is out of range for ${type} (${min}..${max})`);
  return n === 0 ? 0 : n; // -0 is written as 0
}

/** A 64-bit integer: a bigint, or a number that is a safe integer. */
export function bigIntegerIn(type: DataTypeName, value: unknown, min: bigint, max: bigint): bigint {
  let n: bigint;
  if (typeof value === 'bigint') n = value;
  else if (typeof value === 'number') {
    if (!Number.isSafeInteger(value)) {
      return reject(`${show(value)} is not a safe integer; pass a bigint for ${type}`);
    }
    n = BigInt(value);
  } else return reject(`expected a bigint or an integer number for ${type}, got ${show(value)}`);
  if (n < min || n > max) return reject(`${show(value)} is out of range for ${type} (${min}..${max})`);
  return n;
}

export function numberFor(type: DataTypeName, value: unknown): number {
  if (typeof value !== 'number') return reject(`expected a number for ${type}, got ${show(value)}`);
  return value;
}

export function validDate(type: DataTypeName, value: unknown): Date {
  if (!(value instanceof Date)) return reject(`expected a Date for ${type}, got ${show(value)}`);
  if (Number.isNaN(value.getTime())) return reject(`Invalid Date for ${type}`);
  return value;
}
