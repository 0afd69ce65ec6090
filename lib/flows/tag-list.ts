/**
 * The tag lists a flow works with: a node's configured table and the tags a
 * message asks for. Plain data in, plain data out.
 */
import type { TagRow } from '../tags/table';

/** Normalises a table of { name, address }: names default to the address, blank rows are dropped. */
/** A cell of a tag row as trimmed text; an object is shown as its JSON, so the address error names what was given. */
function text(v: unknown): string {
  if (v === undefined || v === null) return '';
  return (typeof v === 'object' ? JSON.stringify(v) : String(v as string | number | boolean | bigint)).trim();
}

export function tagTable(rows: unknown): TagRow[] {
  if (!Array.isArray(rows)) return [];
  const out: TagRow[] = [];
  for (const row of rows as ({ name?: unknown; address?: unknown } | null | undefined)[]) {
    if (!row) continue;
    const address = text(row.address);
    if (!address) continue;
    const name = text(row.name) || address;
    out.push({ name, address });
  }
  return out;
}

/**
 * The tags a message asks for with `msg.tags`: an address, an array of
 * addresses or of { name, address }, or an object { name: address }.
 * Returns undefined when the message names none.
 */
export function tagsOfMessage(value: unknown): TagRow[] | undefined {
  if (value === undefined || value === null) return undefined;
  if (typeof value === 'string') return tagTable([{ address: value }]);
  if (Array.isArray(value)) return tagTable((value as unknown[]).map((v) => (typeof v === 'string' ? { address: v } : v)));
  if (typeof value === 'object')
    return tagTable(Object.entries(value as Record<string, unknown>).map(([name, address]) => ({ name, address })));
  return undefined;
}
