/** Text for humans: dates in ISO, bigints as digits, arrays bracketed. */
export function valueToText(value: unknown): string {
  if (Array.isArray(value)) return `[${value.map(valueToText).join(', ')}]`;
  if (value instanceof Date) return value.toISOString();
  if (typeof value === 'string') return JSON.stringify(value);
  return String(value);
}

/** Text already written for people (a TIA time literal in a struct): textOf prints it as it is, unquoted. */
export class Literal {
  constructor(readonly text: string) {}
}

/**
 * Text for people of any value read: as valueToText, and a STRUCT (an object
 * keyed by member name, read by symbol) as `{ Speed: 1.5, On: true }`, a key
 * quoted when it is not a plain name.
 */
export function textOf(value: unknown): string {
  if (value instanceof Literal) return value.text;
  if (Array.isArray(value)) return `[${value.map(textOf).join(', ')}]`;
  if (typeof value !== 'object' || value === null || value instanceof Date) return valueToText(value);
  const members = Object.entries(value).map(([k, v]) => `${/^[A-Za-z_]\w*$/.test(k) ? k : JSON.stringify(k)}: ${textOf(v)}`);
  return members.length === 0 ? '{}' : `{ ${members.join(', ')} }`;
}

/** A 16-bit number as four lowercase hex digits, no prefix: 0x102 → `0102` (TSAPs, SZL ids, PLC codes in messages). */
export function hex4(n: number): string {
  return n.toString(16).padStart(4, '0');
}

/** Names as a list in words: `a`, `a or b`, `a, b or c`. */
export function orList(names: readonly string[]): string {
  return names.length > 1 ? `${names.slice(0, -1).join(', ')} or ${names.at(-1)!}` : names.join('');
}
