/**
 * The S5-era BCD types. S5TIME/TIMER word: bits 13–12 time base
 * (0 = 10 ms, 1 = 100 ms, 2 = 1 s, 3 = 10 s), bits 11–0 three BCD digits,
 * 0..999 units, so at most 999 × 10 s = 2h46m30s. COUNTER word: bits 11–0
 * three BCD digits, 0..999. Unused high bits are written 0, ignored on read.
 */
import { integerIn, reject, type CodecTable } from './checks';

const TIME_BASES_MS = [10, 100, 1000, 10000] as const;
const MAX_UNITS = 999;
const S5TIME_MAX_MS = MAX_UNITS * TIME_BASES_MS[3];

/** Three BCD digits of 0..999. */
function toBcd3(n: number): number {
  return (Math.floor(n / 100) << 8) | ((Math.floor(n / 10) % 10) << 4) | (n % 10);
}

/** Three BCD digits; a non-decimal nibble (only a corrupt word has one) reads as 9, never throws. */
function fromBcd3(word: number): number {
  const digit = (shift: number) => Math.min((word >> shift) & 0x0f, 9);
  return digit(8) * 100 + digit(4) * 10 + digit(0);
}

/** The finest time base that holds `ms` exactly, so no precision is lost; else a ValueProblem. */
function encodeS5Time(type: 'S5TIME' | 'TIMER', value: unknown): number {
  const ms = integerIn(type, value, 0, S5TIME_MAX_MS);
  for (let base = 0; base < TIME_BASES_MS.length; base++) {
    const units = ms / TIME_BASES_MS[base]!;
    if (Number.isInteger(units) && units <= MAX_UNITS) return (base << 12) | toBcd3(units);
  }
  return reject(`${ms} ms cannot be represented exactly in ${type} (999 units of 10 ms, 100 ms, 1 s or 10 s); round it`);
}

function decodeS5Time(word: number): number {
  return fromBcd3(word) * TIME_BASES_MS[(word >> 12) & 0x03]!;
}

export const BCD_CODECS: CodecTable<'S5TIME' | 'TIMER' | 'COUNTER'> = {
  S5TIME: {
    encode: (_t, v, b, o) => void b.writeUInt16BE(encodeS5Time('S5TIME', v), o),
    decode: (_t, b, o) => decodeS5Time(b.readUInt16BE(o)),
  },
  TIMER: {
    encode: (_t, v, b, o) => void b.writeUInt16BE(encodeS5Time('TIMER', v), o),
    decode: (_t, b, o) => decodeS5Time(b.readUInt16BE(o)),
  },
  COUNTER: {
    encode: (t, v, b, o) => void b.writeUInt16BE(toBcd3(integerIn(t.type, v, 0, MAX_UNITS)), o),
    decode: (_t, b, o) => fromBcd3(b.readUInt16BE(o)),
  },
};
