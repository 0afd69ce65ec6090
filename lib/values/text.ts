/** Text for humans: dates in ISO, bigints as digits, arrays bracketed. */
export function valueToText(value: unknown): string {
  if (Array.isArray(value)) return `[${value.map(valueToText).join(', ')}]`;
  if (value instanceof Date) return value.toISOString();
  if (typeof value === 'string') return JSON.stringify(value);
  return String(value);
}
