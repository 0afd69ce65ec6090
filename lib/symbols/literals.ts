/**
 * Start values of DB and UDT sources, evaluated for their member's type to
 * the JS value plcwire uses for it (lib/types.ts PlcValue, lib/values/):
 * integers up to 32 bits, REAL, LREAL, TIME, TOD, S5TIME → number (ms for
 * the times); LINT, ULINT, LWORD → bigint; LTIME → bigint ns; DATE, DT,
 * DTL → Date of UTC fields; CHAR, STRING → string; BOOL → boolean.
 *
 * The literals are those of TIA Portal (IEC 61131-3 style: `16#FF`,
 * `INT#5`, `T#1h2m3s`, `LT#5us`, `D#2024-01-31`, `TOD#12:00:00.5`,
 * `DT#2024-01-31-12:00:00`, `DTL#…`, `WSTRING#'…'`) and of STEP 7 (`L#10`,
 * `B#16#FF`, `W#16#FF`, `DW#16#…`, `LW#16#…`, `B#(1, 2)`, `S5T#1S`,
 * `C#12`, `DT#90-1-1-0:0:0.000`, `1.000000e+000`).
 *
 * Decisions:
 * - `B#(b1, b2)` and `B#(b1, b2, b3, b4)` are STEP 7's byte-sequence
 *   constants: the bytes high first, a WORD or DWORD value (B#(1, 2) is
 *   16#0102).
 * - `C#n` is a counter value: n for a COUNTER, its BCD word (C#12 is
 *   16#0012) for a WORD.
 * - Strings take the IEC `$` escapes (`$$ $' $L $N $P $R $T`, `$hh` as two
 *   hex digits, single-quoted WSTRING literals too) and `''` for a quote.
 * - A typed literal of another family than the member's is refused
 *   (`REAL#1.5` for an INT); INT# for a REAL, CHAR# for a STRING and
 *   STRING# for a WSTRING are the widenings TIA does implicitly.
 * - DTL holds nanoseconds, a JS Date whole milliseconds: digits below the
 *   millisecond are dropped, as when a DTL is read.
 *
 * Range checks are lib/values' (validateValue), so a start value is
 * accepted exactly when a write of it would be.
 */
import { SourceError, ValueError } from '../errors';
import type { DataTypeName, PlcScalar } from '../types';
import { validateValue } from '../values';
import type { Literal } from './model';

type Family = 'bool' | 'int' | 'real' | 'char' | 'string' | DataTypeName;

const INT_TYPES = new Set<DataTypeName>([
  'BYTE',
  'WORD',
  'DWORD',
  'LWORD',
  'SINT',
  'USINT',
  'INT',
  'UINT',
  'DINT',
  'UDINT',
  'LINT',
  'ULINT',
]);
const BIGINT_TYPES = new Set<DataTypeName>(['LWORD', 'LINT', 'ULINT']);

function familyOf(type: DataTypeName): Family {
  if (type === 'BOOL') return 'bool';
  if (INT_TYPES.has(type)) return 'int';
  if (type === 'REAL' || type === 'LREAL') return 'real';
  if (type === 'CHAR' || type === 'WCHAR') return 'char';
  if (type === 'STRING' || type === 'WSTRING') return 'string';
  return type;
}

/** Typed-literal prefixes (`INT#`, `T#`, …) and the type whose rules read what follows them. */
const PREFIXES: Readonly<Record<string, DataTypeName>> = {
  T: 'TIME',
  LT: 'LTIME',
  D: 'DATE',
  TOD: 'TIME_OF_DAY',
  DT: 'DATE_AND_TIME',
  S5T: 'S5TIME',
};
const ELEMENTARY_PREFIXES = new Set<string>([
  'BOOL',
  ...INT_TYPES,
  'REAL',
  'LREAL',
  'CHAR',
  'WCHAR',
  'STRING',
  'WSTRING',
  'TIME',
  'LTIME',
  'DATE',
  'TIME_OF_DAY',
  'DATE_AND_TIME',
  'DTL',
  'S5TIME',
]);
/** STEP 7's bit-string prefixes and their widths in bits. */
const BIT_WIDTHS: Readonly<Record<string, number>> = { B: 8, W: 16, DW: 32, LW: 64 };

/** May a typed literal of `prefix` stand for a member of `member`? */
function compatible(prefix: DataTypeName, member: DataTypeName): boolean {
  const p = familyOf(prefix);
  const m = familyOf(member);
  if (p === m) return true;
  if (m === 'real' && p === 'int') return true;
  if (m === 'string' && p === 'char') return true;
  if (member === 'TIMER' && prefix === 'S5TIME') return true;
  return false;
}

function label(type: DataTypeName, stringLength: number): string {
  return type === 'STRING' || type === 'WSTRING' ? `${type}[${stringLength}]` : type;
}

/**
 * The value of a start-value literal for a member of `type` (STRING/WSTRING:
 * declared length `stringLength`). SourceError at the literal when it is not
 * a literal of that type or its value does not fit.
 */
export function literalValue(literal: Literal, type: DataTypeName, stringLength: number): PlcScalar {
  const reader = new LiteralReader(literal, type, stringLength);
  const value = reader.value();
  try {
    validateValue({ address: literal.text, type, count: 1, isArray: false, stringLength, bitOffset: 0 }, value);
  } catch (err) {
    if (!(err instanceof ValueError)) throw err;
    const problem = err.message.slice(`invalid value for "${literal.text}": `.length);
    const range = /is out of range for \S+ (\(.*\))$/.exec(problem);
    throw reader.fail(
      range ? `does not fit ${label(type, stringLength)} ${range[1]}` : `does not fit ${label(type, stringLength)}: ${problem}`,
    );
  }
  return value;
}

class LiteralReader {
  constructor(
    private readonly literal: Literal,
    private readonly type: DataTypeName,
    private readonly stringLength: number,
  ) {}

  fail(problem: string): SourceError {
    return new SourceError(this.literal.at, `start value ${this.literal.text} ${problem}`);
  }

  private expected(example: string): SourceError {
    return this.fail(`is not a ${label(this.type, this.stringLength)} literal (expected e.g. ${example})`);
  }

  value(): PlcScalar {
    let text = this.literal.text.trim();
    const typed = /^([A-Za-z_][A-Za-z0-9_]*)#(.*)$/s.exec(text);
    if (typed) {
      const prefix = typed[1]!.toUpperCase();
      const rest = typed[2]!;
      const prefixType = PREFIXES[prefix] ?? (ELEMENTARY_PREFIXES.has(prefix) ? (prefix as DataTypeName) : undefined);
      if (prefixType) {
        if (!compatible(prefixType, this.type)) {
          throw this.fail(`is a ${prefixType} literal; the member is ${label(this.type, this.stringLength)}`);
        }
        return this.read(rest, prefixType);
      }
      if (BIT_WIDTHS[prefix] !== undefined || prefix === 'L' || prefix === 'C') return this.read(text, this.type);
      throw this.fail(`has an unknown prefix ${typed[1]}#`);
    }
    text = text.replace(/^\+/, '');
    return this.read(text, this.type);
  }

  /** Reads `text` (after any type prefix) by the rules of `as`, producing the member type's JS value. */
  private read(text: string, as: DataTypeName): PlcScalar {
    switch (familyOf(this.type)) {
      case 'bool':
        return this.bool(text);
      case 'int':
        return this.integerValue(text);
      case 'real':
        return familyOf(as) === 'int' ? Number(this.integer(text)) : this.real(text);
      case 'char':
      case 'string':
        return this.string(text);
      default:
        return this.timeValue(text);
    }
  }

  private bool(text: string): boolean {
    const t = text.toUpperCase();
    if (t === 'TRUE' || t === '1') return true;
    if (t === 'FALSE' || t === '0') return false;
    throw this.expected('TRUE, FALSE, 1 or 0');
  }

  private integerValue(text: string): number | bigint {
    const n = this.integer(text);
    if (BIGINT_TYPES.has(this.type)) return n;
    // Beyond ±2^53 the number would be rounded; validateValue refuses it anyway (no 32-bit type holds it).
    return Number(n);
  }

  /** Decimal, `2#…` `8#…` `16#…`, `L#…`, `B#16#…` `W#…` `DW#…` `LW#…`, `B#(1, 2)`, `C#12` (BCD here). */
  private integer(text: string): bigint {
    const t = text.replace(/_/g, '');
    let m = /^([+-]?)(\d+)$/.exec(t);
    if (m) return BigInt(m[1] + m[2]!);
    m = /^([+-]?)(2|8|16)#([0-9A-F]+)$/i.exec(t);
    if (m) return this.radix(m[2]!, m[3]!, m[1] === '-');
    m = /^L#([+-]?\d+)$/i.exec(t);
    if (m) {
      const n = BigInt(m[1]!);
      if (n < -(2n ** 31n) || n >= 2n ** 31n) throw this.fail('does not fit L# (a 32-bit integer, -2147483648..2147483647)');
      return n;
    }
    m = /^(B|W|DW|LW)#(2|8|16)#([0-9A-F]+)$/i.exec(t);
    if (m) {
      const n = this.radix(m[2]!, m[3]!, false);
      const width = BIT_WIDTHS[m[1]!.toUpperCase()]!;
      if (n >= 2n ** BigInt(width)) throw this.fail(`does not fit ${m[1]!.toUpperCase()}# (${width} bits)`);
      return n;
    }
    m = /^B#\((.*)\)$/i.exec(t);
    if (m) return this.bytes(m[1]!);
    m = /^C#(\d+)$/i.exec(t);
    if (m) {
      const n = Number(m[1]);
      if (n > 999) throw this.fail('does not fit a counter (C#0..C#999)');
      return this.type === 'COUNTER' ? BigInt(n) : BigInt(parseInt(String(n), 16)); // the BCD word: C#12 = 16#0012
    }
    if (/^[+-]?\d+(\.\d+)?(E[+-]?\d+)?$/i.test(t)) throw this.fail(`is not a whole number (${this.type})`);
    throw this.expected('12, -5, 16#FF or 2#1010');
  }

  private radix(base: string, digits: string, negative: boolean): bigint {
    const valid = { '2': /^[01]+$/, '8': /^[0-7]+$/, '16': /^[0-9A-F]+$/i }[base as '2' | '8' | '16'];
    if (!valid.test(digits)) throw this.fail(`has a digit that base ${base} does not have`);
    const prefix = { '2': '0b', '8': '0o', '16': '0x' }[base as '2' | '8' | '16'];
    const n = BigInt(prefix + digits);
    return negative ? -n : n;
  }

  /** `B#(1, 2)` → 16#0102; `B#(1, 2, 3, 4)` → 16#01020304. */
  private bytes(list: string): bigint {
    const parts = list.split(',').map((p) => p.trim());
    if ((parts.length !== 2 && parts.length !== 4) || !parts.every((p) => /^\d+$/.test(p) && Number(p) <= 255)) {
      throw this.fail('is not a byte sequence B#(b1, b2) or B#(b1, b2, b3, b4) of bytes 0..255');
    }
    return parts.reduce((n, p) => (n << 8n) | BigInt(p), 0n);
  }

  private real(text: string): number {
    const t = text.replace(/_/g, '');
    if (!/^[+-]?\d+(\.\d+)?(E[+-]?\d+)?$/i.test(t)) throw this.expected('1.5, -1.0 or 1.5E3');
    return Number(t);
  }

  private string(text: string): string {
    if (text.length < 2 || !text.startsWith("'") || !text.endsWith("'")) {
      throw this.expected(familyOf(this.type) === 'char' ? "'a'" : "'text'");
    }
    const out: string[] = [];
    const body = text.slice(1, -1);
    for (let i = 0; i < body.length; i++) {
      const c = body[i]!;
      if (c === "'") {
        if (body[i + 1] !== "'") throw this.fail("has a lone ' inside (write '' or $' for a quote)");
        out.push("'");
        i++;
      } else if (c === '$') {
        const e = body[i + 1] ?? '';
        const simple: Readonly<Record<string, string>> = { $: '$', "'": "'", L: '\n', N: '\n', P: '\f', R: '\r', T: '\t' };
        const s = simple[e.toUpperCase()];
        if (s !== undefined) {
          out.push(s);
          i++;
        } else if (/^[0-9A-F]{2}$/i.test(body.slice(i + 1, i + 3))) {
          out.push(String.fromCharCode(parseInt(body.slice(i + 1, i + 3), 16)));
          i += 2;
        } else throw this.fail(`has the unknown escape $${e} (known: $$ $' $L $N $P $R $T $hh)`);
      } else out.push(c);
    }
    const s = out.join('');
    if (familyOf(this.type) === 'char' && s.length !== 1) throw this.fail(`is ${s.length} characters; ${this.type} holds one`);
    return s;
  }

  // ------------------------------------------------------------ times and dates

  private timeValue(text: string): PlcScalar {
    switch (this.type) {
      case 'TIME':
        return this.milliseconds(this.duration(text, 'T#1h2m3s4ms'), 'TIME');
      case 'LTIME':
        return this.duration(text, 'LT#1s5us');
      case 'S5TIME':
      case 'TIMER':
        return this.milliseconds(this.duration(text, 'S5T#2s'), this.type);
      case 'TIME_OF_DAY':
        return this.timeOfDay(text);
      case 'DATE':
        return this.date(text);
      case 'DATE_AND_TIME':
      case 'DTL':
        return this.dateAndTime(text);
      case 'COUNTER': {
        const m = /^(?:C#)?(\d+)$/i.exec(text);
        if (!m) throw this.expected('C#12');
        return Number(m[1]);
      }
      default:
        throw this.fail(`cannot be given for a member of type ${this.type}`);
    }
  }

  private milliseconds(ns: bigint, type: string): number {
    if (ns % 1_000_000n !== 0n) throw this.fail(`is not a whole number of milliseconds (${type})`);
    return Number(ns / 1_000_000n);
  }

  /** `1h2m3s4ms`, `-5s`, `1.5s`, `1d_2h`, `5us`, `7ns` (after the prefix) as nanoseconds. */
  private duration(text: string, example: string): bigint {
    const t = text.replace(/_/g, '');
    const m = /^([+-]?)((?:\d+(?:\.\d+)?(?:D|H|MS|M|S|US|NS))+)$/i.exec(t);
    if (!m) throw this.expected(example);
    const UNITS: readonly [string, bigint][] = [
      ['D', 86_400_000_000_000n],
      ['H', 3_600_000_000_000n],
      ['M', 60_000_000_000n],
      ['S', 1_000_000_000n],
      ['MS', 1_000_000n],
      ['US', 1_000n],
      ['NS', 1n],
    ];
    let ns = 0n;
    let last = -1;
    for (const part of m[2]!.matchAll(/(\d+)(?:\.(\d+))?(MS|US|NS|D|H|M|S)/gi)) {
      const unit = UNITS.findIndex(([u]) => u === part[3]!.toUpperCase());
      if (unit <= last) throw this.fail(`has its units out of order or twice (write d, h, m, s, ms, us, ns in that order)`);
      last = unit;
      const scale = UNITS[unit]![1];
      const frac = part[2] ?? '';
      const fracNs = (BigInt(frac || '0') * scale) / 10n ** BigInt(frac.length);
      if ((BigInt(frac || '0') * scale) % 10n ** BigInt(frac.length) !== 0n) throw this.fail('is finer than a nanosecond');
      ns += BigInt(part[1]!) * scale + fracNs;
    }
    return m[1] === '-' ? -ns : ns;
  }

  /** `12:00:00`, `12:00:00.5`, `23:59:59.999` as ms since midnight. */
  private timeOfDay(text: string): number {
    const m = /^(\d{1,2}):(\d{1,2}):(\d{1,2})(?:\.(\d{1,3}))?$/.exec(text);
    if (!m) throw this.expected('TOD#12:00:00.5');
    const [h, min, s] = [Number(m[1]), Number(m[2]), Number(m[3])];
    if (h > 23 || min > 59 || s > 59) throw this.fail('is not a time of day (00:00:00..23:59:59.999)');
    return ((h * 60 + min) * 60 + s) * 1000 + Number((m[4] ?? '').padEnd(3, '0'));
  }

  /** `2024-01-31` → UTC midnight. */
  private date(text: string): Date {
    const m = /^(\d{4})-(\d{1,2})-(\d{1,2})$/.exec(text);
    if (!m) throw this.expected('D#2024-01-31');
    return this.utc(Number(m[1]), Number(m[2]), Number(m[3]), 0, 0, 0, 0);
  }

  /** DT: `2024-01-31-12:00:00.5` or STEP 7's `90-1-1-0:0:0.000`; DTL: up to nine fraction digits. */
  private dateAndTime(text: string): Date {
    const digits = this.type === 'DTL' ? 9 : 3;
    const m = new RegExp(`^(\\d{2}|\\d{4})-(\\d{1,2})-(\\d{1,2})-(\\d{1,2}):(\\d{1,2}):(\\d{1,2})(?:\\.(\\d{1,${digits}}))?$`).exec(text);
    if (!m) throw this.expected(this.type === 'DTL' ? 'DTL#2024-01-31-12:00:00.5' : 'DT#2024-01-31-12:00:00');
    let year = Number(m[1]);
    if (m[1]!.length === 2) year += year >= 90 ? 1900 : 2000; // STEP 7's DT#90-1-1-…: 90..99 are 199x, 00..89 20xx
    const [h, min, s] = [Number(m[4]), Number(m[5]), Number(m[6])];
    if (h > 23 || min > 59 || s > 59) throw this.fail('has no valid time of day (00:00:00..23:59:59)');
    const ms = Number((m[7] ?? '').padEnd(3, '0').slice(0, 3));
    return this.utc(year, Number(m[2]), Number(m[3]), h, min, s, ms);
  }

  private utc(year: number, month: number, day: number, h: number, min: number, s: number, ms: number): Date {
    const d = new Date(0);
    d.setUTCFullYear(year, month - 1, day); // not Date.UTC, which reads years 0..99 as 19xx
    d.setUTCHours(h, min, s, ms);
    if (d.getUTCFullYear() !== year || d.getUTCMonth() !== month - 1 || d.getUTCDate() !== day)
      throw this.fail('is not a date of the calendar');
    return d;
  }
}
