/**
 * Acknowledging an alarm is an operator's write: a read-only connection
 * refuses it, and a connection with a write allow-list acknowledges only the
 * alarms the list names — `ALARMS` (every alarm) or `ALARM<id>` (one alarm,
 * id in decimal or 16#hex), beside its addresses and areas. Both generations'
 * clients ask this before the first byte goes out.
 */
import { PlcError } from '../errors';

/** Why acknowledging alarm `id` is refused (WRITE_NOT_ALLOWED), or undefined when it may go. */
export function ackRefusal(id: number, readOnly: boolean | undefined, allow: readonly string[] | undefined): PlcError | undefined {
  const name = `alarm ${id}`;
  if (readOnly) {
    return new PlcError('WRITE_NOT_ALLOWED', `acknowledge of ${name} refused: the connection is read-only`, { tag: `ALARM${id}` });
  }
  if (!allow || allow.length === 0) return undefined;
  for (const entry of allow) {
    const allowed = alarmEntry(entry);
    if (allowed === 'all' || allowed === id) return undefined;
  }
  return new PlcError(
    'WRITE_NOT_ALLOWED',
    `acknowledge of ${name} refused: the connection's write allow-list (${allow.join(', ')}) names neither ALARMS nor ALARM${id}`,
    { tag: `ALARM${id}` },
  );
}

/**
 * What an allow-list entry says of alarms: `'all'` (ALARMS), one alarm id
 * (ALARM<id>), or undefined when it names an address or an area — which the
 * write guard (lib/client/write-guard.ts) then reads as one.
 */
export function alarmEntry(entry: string): 'all' | number | undefined {
  const e = entry.trim().toUpperCase();
  if (e === 'ALARMS') return 'all';
  const m = /^ALARM(?:16#([0-9A-F]+)|(\d+))$/.exec(e);
  return m ? (m[1] !== undefined ? parseInt(m[1], 16) : Number(m[2])) : undefined;
}
