/** Text for humans: dates in ISO, bigints as digits, arrays bracketed. */
export function valueToText(value: unknown): string {
  if (Array.isArray(value)) return `[${value.map(valueToText).join(', ')}]`;
  if (value instanceof Date) return value.toISOString();
  if (typeof value === 'string') return JSON.stringify(value);
  return String(value);
}

/**
 * Text for people of any value read: as valueToText, and a STRUCT (an object
 * keyed by member name, read by symbol) as `{ Speed: 1.5, On: true }`, a key
 * quoted when it is not a plain name.
 */
export function textOf(value: unknown): string {
  if (Array.isArray(value)) return `[${value.map(textOf).join(', ')}]`;
  if (typeof value !== 'object' || value === null || value instanceof Date) return valueToText(value);
  const members = Object.entries(value).map(([k, v]) => `${/^[A-Za-z_]\w*$/.test(k) ? k : JSON.stringify(k)}: ${textOf(v)}`);
  return members.length === 0 ? '{}' : `{ ${members.join(', ')} }`;
}
