/**
 * Freeport addresses: `ST<station>,<TYPE><byte>[.<bit>|.<count>]`, a value
 * inside one station's data area (4 bytes with the default profile):
 *
 *   ST5,DWORD0   ST5,BYTE1   ST5,INT2   ST5,REAL0   ST5,X0.3 (bit 3 of byte 0)
 *   ST5,B0.4     (4 BYTEs from byte 0, an array)    ST5,INT0.2 (2 INTs)
 */
import { AddressError } from '../errors';
import type { DataTypeName } from '../types';
import { tagByteLength, type TagShape } from '../values';

export interface FreeportTag extends TagShape {
  readonly station: number;
  /** The station's data area ("ST" of "ST5"); allow-lists name it with the station, "ST5". */
  readonly area: 'ST';
  readonly byteOffset: number;
  readonly byteLength: number;
}

/** Type names (nodes7 style, with their short forms) of the types that fit a small data area. */
const TYPES: Readonly<Record<string, DataTypeName>> = Object.freeze({
  X: 'BOOL',
  B: 'BYTE',
  BYTE: 'BYTE',
  C: 'CHAR',
  CHAR: 'CHAR',
  SINT: 'SINT',
  USINT: 'USINT',
  I: 'INT',
  INT: 'INT',
  W: 'WORD',
  WORD: 'WORD',
  UINT: 'UINT',
  DI: 'DINT',
  DINT: 'DINT',
  UDINT: 'UDINT',
  DW: 'DWORD',
  DWORD: 'DWORD',
  R: 'REAL',
  REAL: 'REAL',
});

const SYNTAX = /^ST(\d{1,5})\s*,\s*([A-Z]+)(\d{1,3})(?:\.(\d{1,3}))?$/i;

export interface FreeportAddressLimits {
  /** Highest station address (255 with 2-character DA). */
  maxStation?: number;
  /** Bytes in a station's data area (4). */
  dataBytes?: number;
}

/** Parses a freeport address; throws AddressError naming the address and what is wrong. */
export function parseFreeportAddress(address: string, limits: FreeportAddressLimits = {}): FreeportTag {
  const maxStation = limits.maxStation ?? 255;
  const dataBytes = limits.dataBytes ?? 4;
  if (typeof address !== 'string') throw new AddressError(String(address), 'an address is a string like "ST5,DWORD0"');
  const m = SYNTAX.exec(address.trim());
  if (!m) throw new AddressError(address, 'expected ST<station>,<TYPE><byte>[.<bit>], e.g. "ST5,DWORD0" or "ST5,X0.3"');
  const station = Number(m[1]);
  const typeName = m[2]!.toUpperCase();
  const byteOffset = Number(m[3]);
  const suffix = m[4] === undefined ? undefined : Number(m[4]);
  if (station > maxStation) throw new AddressError(address, `station ${station} is beyond the highest address ${maxStation}`);
  const type = TYPES[typeName];
  if (!type) {
    throw new AddressError(
      address,
      `unknown type "${typeName}" (use X, BYTE/B, CHAR, SINT, USINT, INT, WORD, UINT, DINT, UDINT, DWORD, REAL)`,
    );
  }
  let bitOffset = 0;
  let count = 1;
  let isArray = false;
  if (type === 'BOOL') {
    if (suffix === undefined) throw new AddressError(address, 'a bit needs its number: X<byte>.<bit>, e.g. X0.3');
    if (suffix > 7) throw new AddressError(address, `bit ${suffix} does not exist (0–7)`);
    bitOffset = suffix;
  } else if (suffix !== undefined) {
    if (suffix < 1) throw new AddressError(address, 'an array needs at least one element');
    count = suffix;
    isArray = true;
  }
  const shape = { type, count, stringLength: 0, bitOffset };
  const byteLength = tagByteLength(shape);
  if (byteOffset + byteLength > dataBytes) {
    throw new AddressError(
      address,
      `${type}${isArray ? `[${count}]` : ''} at byte ${byteOffset} ends at byte ${byteOffset + byteLength - 1}, past the station's ${dataBytes}-byte data area`,
    );
  }
  return Object.freeze({ address, station, area: 'ST', byteOffset, bitOffset, type, count, isArray, stringLength: 0, byteLength });
}
