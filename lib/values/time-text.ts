/**
 * Times and dates as TIA Portal writes their literals (and shows them in a
 * watch table): TIME `T#1D_2H_3M_4S_5MS` (units that are 0 left out, `T#0MS`
 * for nothing, `T#-5S` below zero), LTIME `LT#…_US_NS`, S5TIME `S5T#2M_7S`,
 * TIME_OF_DAY `TOD#12:00:00.000`, DATE `D#2024-01-31`, DATE_AND_TIME
 * `DT#2024-01-31-12:00:00.000`, DTL `DTL#2024-01-31-12:00:00.000` (Siemens,
 * TIA Portal help "Time" / "Date and time" data types, the literal formats).
 * For people only: a read's value stays the number, bigint or Date the
 * library documents (lib/values/index.ts), and so does the CLI's JSON.
 */
const UNITS_MS: readonly (readonly [string, number])[] = [
  ['D', 86_400_000],
  ['H', 3_600_000],
  ['M', 60_000],
  ['S', 1000],
  ['MS', 1],
];
const UNITS_NS: readonly (readonly [string, bigint])[] = [
  ['D', 86_400_000_000_000n],
  ['H', 3_600_000_000_000n],
  ['M', 60_000_000_000n],
  ['S', 1_000_000_000n],
  ['MS', 1_000_000n],
  ['US', 1000n],
  ['NS', 1n],
];

/** `1D_2H_3M_4S_5MS` of a whole number of ms (0 → `0MS`). */
function durationMs(ms: number): string {
  let rest = Math.abs(ms);
  const parts: string[] = [];
  for (const [unit, size] of UNITS_MS) {
    const n = Math.floor(rest / size);
    rest -= n * size;
    if (n > 0) parts.push(`${n}${unit}`);
  }
  return `${ms < 0 ? '-' : ''}${parts.length > 0 ? parts.join('_') : '0MS'}`;
}

function durationNs(ns: bigint): string {
  let rest = ns < 0n ? -ns : ns;
  const parts: string[] = [];
  for (const [unit, size] of UNITS_NS) {
    const n = rest / size;
    rest -= n * size;
    if (n > 0n) parts.push(`${n}${unit}`);
  }
  return `${ns < 0n ? '-' : ''}${parts.length > 0 ? parts.join('_') : '0NS'}`;
}

const pad = (n: number, width = 2) => String(n).padStart(width, '0');

/** `hh:mm:ss.mmm` of ms since midnight. */
function timeOfDay(ms: number): string {
  return `${pad(Math.floor(ms / 3_600_000))}:${pad(Math.floor(ms / 60_000) % 60)}:${pad(Math.floor(ms / 1000) % 60)}.${pad(ms % 1000, 3)}`;
}

/** `yyyy-mm-dd` of a Date's UTC fields (the PLC clock's fields, as the library reads them). */
function day(d: Date): string {
  return `${pad(d.getUTCFullYear(), 4)}-${pad(d.getUTCMonth() + 1)}-${pad(d.getUTCDate())}`;
}

/** The TIA literal of one value of `type`, or undefined when `type` is no time type or the value not of its kind. */
function literal(type: string, value: unknown): string | undefined {
  if (typeof value === 'number' && Number.isInteger(value)) {
    if (type === 'TIME') return `T#${durationMs(value)}`;
    if (type === 'S5TIME') return `S5T#${durationMs(value)}`;
    if (type === 'TIME_OF_DAY' && value >= 0) return `TOD#${timeOfDay(value)}`;
    if (type === 'LTIME') return `LT#${durationNs(BigInt(value))}`;
  }
  if (typeof value === 'bigint' && type === 'LTIME') return `LT#${durationNs(value)}`;
  if (value instanceof Date && !Number.isNaN(value.getTime())) {
    const ms = value.getTime() - Date.UTC(value.getUTCFullYear(), value.getUTCMonth(), value.getUTCDate());
    if (type === 'DATE') return `D#${day(value)}`;
    if (type === 'DATE_AND_TIME') return `DT#${day(value)}-${timeOfDay(ms)}`;
    if (type === 'DTL') return `DTL#${day(value)}-${timeOfDay(ms)}`;
  }
  return undefined;
}

/** True for the types this file writes as TIA literals. */
export function isTimeType(type: string | undefined): boolean {
  return type !== undefined && ['TIME', 'LTIME', 'S5TIME', 'TIME_OF_DAY', 'DATE', 'DATE_AND_TIME', 'DTL'].includes(type);
}

/**
 * A value of `type` (one, or an array of them) as TIA writes it; undefined
 * when it is not a time type, so the caller shows it as it would anyway.
 */
export function timeText(type: string | undefined, value: unknown): string | undefined {
  if (!isTimeType(type)) return undefined;
  if (Array.isArray(value)) {
    const items = value.map((v) => literal(type!, v));
    return items.every((t) => t !== undefined) ? `[${items.join(', ')}]` : undefined;
  }
  return literal(type!, value);
}
