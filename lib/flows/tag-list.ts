/**
 * The tag lists a flow works with: a node's configured table and the tags a
 * message asks for. Plain data in, plain data out.
 */
import type { TagRow } from '../tags/table';

/** Normalises a table of { name, address }: names default to the address, blank rows are dropped. */
export function tagTable(rows: unknown): TagRow[] {
  if (!Array.isArray(rows)) return [];
  const out: TagRow[] = [];
  for (const row of rows as ({ name?: unknown; address?: unknown } | null | undefined)[]) {
    if (!row) continue;
    const address = String(row.address ?? '').trim();
    if (!address) continue;
    const name = String(row.name ?? '').trim() || address;
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
  if (Array.isArray(value)) return tagTable(value.map((v) => (typeof v === 'string' ? { address: v } : v)));
  if (typeof value === 'object') return tagTable(Object.entries(value).map(([name, address]) => ({ name, address })));
  return undefined;
}
