/**
 * Per-tag outcomes of a read as flows carry them: errors as plain data
 * (Error objects do not survive message cloning), and the one error that
 * names every failed tag of a read or write.
 */
import { PlcError, quoteTag, type PlcErrorCode, type TagResult } from '../errors';
import type { TagRow } from '../tags/table';

/** An error as it travels on a message. */
export interface TagErrorInfo {
  code: string;
  message: string;
  address: string;
}

export type TagOutcome =
  { name: string; address: string; ok: true; value: unknown } | { name: string; address: string; ok: false; error: TagErrorInfo };

/** A failed tag: its name, and its error as plain data (which carries the address). */
export interface TagFailure {
  name: string;
  error: TagErrorInfo;
}

/** `err` as plain data for `address`; anything without a code is a PLC_ERROR. */
export function errorInfo(err: unknown, address: string): TagErrorInfo {
  const e = err as { code?: unknown; message?: unknown } | null | undefined;
  return { code: (e && (e.code as string)) || 'PLC_ERROR', message: (e && (e.message as string)) || String(err), address };
}

/** readDetailed results as per-name outcomes, in table order: [{ name, address, ok, value?, error? }]. */
export function outcomes(tags: readonly TagRow[], results: Readonly<Record<string, TagResult<unknown> | undefined>>): TagOutcome[] {
  return tags.map(({ name, address }): TagOutcome => {
    const r = results[address];
    if (r && r.ok) return { name, address, ok: true, value: r.value };
    const error = r ? r.error : new Error(`no result for ${quoteTag(address)}`);
    return { name, address, ok: false, error: errorInfo(error, address) };
  });
}

/**
 * One error for a read or write in which `failed` tags failed (at least one):
 * the first one's name, address and message, how many more failed, and the
 * first one's code and name as `code` and `tag`.
 */
export function tagFailure(verb: 'read' | 'write', failed: readonly TagFailure[]): PlcError {
  const { name, error } = failed[0]!;
  const label = name === error.address ? quoteTag(name) : `${quoteTag(name)} (${error.address})`;
  const more = failed.length > 1 ? ` (+${failed.length - 1})` : '';
  return new PlcError(error.code as PlcErrorCode, `${verb} ${label}: ${error.message}${more}`, { tag: name });
}
