/** What a message asks a write to do, resolved against a tag table. */
import { PlcError } from '../errors';
import type { TagRow } from '../tags/table';

/** The values to write by address, and the name each address was asked for by. */
export interface WriteRequest {
  values: Record<string, unknown>;
  names: Record<string, string>;
}

/**
 * Resolves a write request to { address: value } with the table's names:
 * `msg.payload = { nameOrAddress: value }`, or `msg.topic = nameOrAddress`
 * with the value as payload. Keys the table does not name are addresses.
 * Throws PlcError INVALID_VALUE (with the key as `tag` where there is one).
 */
export function writeRequest(table: readonly TagRow[], msg: { payload?: unknown; topic?: unknown }): WriteRequest {
  const byName = new Map(table.map((t) => [t.name, t.address]));
  const payload = msg.payload;
  const entries: [string, unknown][] = [];
  const topic = typeof msg.topic === 'string' ? msg.topic.trim() : '';
  if (isPlainObject(payload)) entries.push(...Object.entries(payload));
  else if (topic) entries.push([topic, payload]);
  else throw new PlcError('INVALID_VALUE', 'write needs msg.payload = { nameOrAddress: value } or msg.topic = address with a value');
  if (entries.length === 0) throw new PlcError('INVALID_VALUE', 'msg.payload names no tag to write');
  const values: Record<string, unknown> = {};
  const names: Record<string, string> = {};
  for (const [key, value] of entries) {
    if (value === undefined || value === null) throw new PlcError('INVALID_VALUE', `no value for "${key}"`, { tag: key });
    const address = byName.get(key) ?? key;
    if (Object.prototype.hasOwnProperty.call(values, address)) {
      throw new PlcError('INVALID_VALUE', `"${key}" and "${names[address]}" are the same address ${address}`, { tag: key });
    }
    values[address] = value;
    names[address] = key;
  }
  return { values, names };
}

function isPlainObject(v: unknown): v is Record<string, unknown> {
  if (v === null || typeof v !== 'object' || Array.isArray(v) || Buffer.isBuffer(v) || v instanceof Date) return false;
  const proto: unknown = Object.getPrototypeOf(v);
  return proto === Object.prototype || proto === null;
}
