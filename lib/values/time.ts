/**
 * IEC durations and dates. TIME: signed 32-bit ms; LTIME: signed 64-bit ns;
 * TIME_OF_DAY: unsigned 32-bit ms since midnight; DATE: unsigned 16-bit days
 * since 1990-01-01; DATE_AND_TIME: 8 BCD bytes (yy mm dd hh mm ss, then
 * 3 ms digits and the weekday nibble, 1 = Sunday), years 1990..2089;
 * DTL: year u16, month, day, weekday (1 = Sunday), hour, minute, second
 * bytes, nanoseconds u32. Dates are read and written as UTC fields.
 *
 * Decoding never throws: a DATE_AND_TIME or DTL whose fields are not a real
 * date (for example the zeros of a never-written DB) decodes to an Invalid
 * Date, which JSON shows as null.
 */
import { bigIntegerIn, integerIn, reject, show, validDate, type CodecTable } from './checks';

const DAY_MS = 86_400_000;
const EPOCH_1990 = Date.UTC(1990, 0, 1);
const DATE_MAX_DAYS = (Date.UTC(2168, 11, 31) - EPOCH_1990) / DAY_MS; // D#2168-12-31, the documented maximum
const DTL_MIN = Date.UTC(1970, 0, 1);
const DTL_MAX = Date.UTC(2262, 3, 11, 23, 47, 16, 854); // DTL#2262-04-11-23:47:16.854775807
const NS_PER_MS = 1_000_000;

/** A Date from UTC fields, or an Invalid Date when a field is out of its range (no JS roll-over, no 19xx for years < 100). */
function utcFields(year: number, month: number, day: number, hour: number, minute: number, second: number, ms: number): Date {
  const d = new Date(0);
  d.setUTCFullYear(year, month - 1, day);
  d.setUTCHours(hour, minute, second, ms);
  const exact =
    d.getUTCFullYear() === year &&
    d.getUTCMonth() === month - 1 &&
    d.getUTCDate() === day &&
    d.getUTCHours() === hour &&
    d.getUTCMinutes() === minute &&
    d.getUTCSeconds() === second;
  return exact ? d : new Date(Number.NaN);
}

function toBcd2(n: number): number {
  return (Math.floor(n / 10) << 4) | (n % 10);
}

/** Two BCD digits, or NaN when a nibble is not decimal. */
function fromBcd2(byte: number): number {
  const hi = byte >> 4;
  const lo = byte & 0x0f;
  return hi > 9 || lo > 9 ? Number.NaN : hi * 10 + lo;
}

function dateInRange(type: 'DATE_AND_TIME' | 'DTL', value: unknown, min: number, max: number, range: string): Date {
  const d = validDate(type, value);
  if (d.getTime() < min || d.getTime() > max) reject(`${show(d)} is out of range for ${type} (${range})`);
  return d;
}

/** Writes a Date as 8 BCD DATE_AND_TIME bytes (its UTC fields); throws a ValueProblem outside 1990..2089. */
export function encodeDateAndTime(value: unknown, b: Buffer, o: number): void {
  const d = dateInRange('DATE_AND_TIME', value, EPOCH_1990, Date.UTC(2089, 11, 31, 23, 59, 59, 999), '1990-01-01..2089-12-31');
  const ms = d.getUTCMilliseconds();
  b[o] = toBcd2(d.getUTCFullYear() % 100);
  b[o + 1] = toBcd2(d.getUTCMonth() + 1);
  b[o + 2] = toBcd2(d.getUTCDate());
  b[o + 3] = toBcd2(d.getUTCHours());
  b[o + 4] = toBcd2(d.getUTCMinutes());
  b[o + 5] = toBcd2(d.getUTCSeconds());
  b[o + 6] = toBcd2(Math.floor(ms / 10));
  b[o + 7] = ((ms % 10) << 4) | (d.getUTCDay() + 1);
}

/** 8 BCD DATE_AND_TIME bytes as a Date of those UTC fields; an Invalid Date when a field is not a date (never throws). */
export function decodeDateAndTime(b: Buffer, o: number): Date {
  const yy = fromBcd2(b[o]!);
  const msDigit = b[o + 7]! >> 4;
  const ms = fromBcd2(b[o + 6]!) * 10 + (msDigit > 9 ? Number.NaN : msDigit);
  const [month, day, hour, minute, second] = [1, 2, 3, 4, 5].map((i) => fromBcd2(b[o + i]!)) as [number, number, number, number, number];
  if ([yy, month, day, hour, minute, second, ms].some(Number.isNaN)) return new Date(Number.NaN);
  return utcFields(yy >= 90 ? 1900 + yy : 2000 + yy, month, day, hour, minute, second, ms);
}

function encodeDtl(value: unknown, b: Buffer, o: number): void {
  const d = dateInRange('DTL', value, DTL_MIN, DTL_MAX, '1970-01-01..2262-04-11T23:47:16.854Z');
  b.writeUInt16BE(d.getUTCFullYear(), o);
  b[o + 2] = d.getUTCMonth() + 1;
  b[o + 3] = d.getUTCDate();
  b[o + 4] = d.getUTCDay() + 1;
  b[o + 5] = d.getUTCHours();
  b[o + 6] = d.getUTCMinutes();
  b[o + 7] = d.getUTCSeconds();
  b.writeUInt32BE(d.getUTCMilliseconds() * NS_PER_MS, o + 8);
}

function decodeDtl(b: Buffer, o: number): Date {
  const ns = b.readUInt32BE(o + 8);
  if (ns >= 1000 * NS_PER_MS) return new Date(Number.NaN);
  // Sub-millisecond nanoseconds are dropped: a JS Date holds whole ms.
  return utcFields(b.readUInt16BE(o), b[o + 2]!, b[o + 3]!, b[o + 5]!, b[o + 6]!, b[o + 7]!, Math.floor(ns / NS_PER_MS));
}

export const TIME_CODECS: CodecTable<'TIME' | 'LTIME' | 'TIME_OF_DAY' | 'DATE' | 'DATE_AND_TIME' | 'DTL'> = {
  TIME: {
    encode: (t, v, b, o) => void b.writeInt32BE(integerIn(t.type, v, -0x80000000, 0x7fffffff), o),
    decode: (_t, b, o) => b.readInt32BE(o),
  },
  LTIME: {
    encode: (t, v, b, o) => void b.writeBigInt64BE(bigIntegerIn(t.type, v, -(2n ** 63n), 2n ** 63n - 1n), o),
    decode: (_t, b, o) => b.readBigInt64BE(o),
  },
  TIME_OF_DAY: {
    encode: (t, v, b, o) => void b.writeUInt32BE(integerIn(t.type, v, 0, DAY_MS - 1), o),
    decode: (_t, b, o) => b.readUInt32BE(o),
  },
  DATE: {
    encode: (_t, v, b, o) => {
      const d = validDate('DATE', v);
      const ms = d.getTime() - EPOCH_1990;
      if (ms % DAY_MS !== 0) reject(`${show(d)} is not a UTC midnight (DATE has no time of day)`);
      const days = ms / DAY_MS;
      if (days < 0 || days > DATE_MAX_DAYS) reject(`${show(d)} is out of range for DATE (1990-01-01..2168-12-31)`);
      b.writeUInt16BE(days, o);
    },
    decode: (_t, b, o) => new Date(EPOCH_1990 + b.readUInt16BE(o) * DAY_MS),
  },
  DATE_AND_TIME: {
    encode: (_t, v, b, o) => encodeDateAndTime(v, b, o),
    decode: (_t, b, o) => decodeDateAndTime(b, o),
  },
  DTL: {
    encode: (_t, v, b, o) => encodeDtl(v, b, o),
    decode: (_t, b, o) => decodeDtl(b, o),
  },
};
