/**
 * The PLC's own symbol table for the editor's questions (s7plus://): from
 * the connection's live client when one is connected (its session browses
 * once, no new connection), else from a connection of its own made for the
 * question and closed after it. Those answers are kept a few seconds per
 * PLC, so a dialog that asks about every row, or a flow of many nodes
 * validated at once, costs the PLC one browse, not one per question. No Node-RED.
 */
import { createClient } from '../connect';
import { PlcError, abortError } from '../errors';
import type { SymbolTable } from '../symbols';
import { endpointKey, parseUrl } from '../url';

/** How long a browsed table (or the reason there is none) answers further questions. */
const KEEP_MS = 10_000;
/** The longest a browse made for a question may take. */
const BROWSE_DEADLINE_MS = 10_000;

/** A client that can give its PLC's table (S7PlusClient). */
interface Browser {
  readonly state: string;
  browse(options?: { signal?: AbortSignal }): Promise<SymbolTable>;
}

const canBrowse = (client: unknown): client is Browser => typeof (client as Partial<Browser> | undefined)?.browse === 'function';

/** The PLC's table through a connection made for it (password given when the PLC needs one), closed on every path. */
export async function browsePlc(url: string, options: { password?: string; signal?: AbortSignal } = {}): Promise<SymbolTable> {
  const client = createClient(url, options.password === undefined ? {} : { password: options.password });
  try {
    if (!canBrowse(client)) throw new PlcError('NOT_SUPPORTED', `${parseUrl(url).protocol}:// cannot browse the PLC's names`);
    const signal = options.signal;
    const stop = () => void client.close().catch(() => undefined);
    signal?.addEventListener('abort', stop, { once: true });
    try {
      await client.connect();
      if (signal?.aborted) throw abortError('the browse', signal);
      return await client.browse(signal ? { signal } : {});
    } finally {
      signal?.removeEventListener('abort', stop);
    }
  } finally {
    await client.close().catch(() => undefined);
  }
}

/** Browsed tables kept per PLC (endpointKey of the URL) for KEEP_MS; one browse at a time per PLC. */
export class PlcTables {
  private readonly kept = new Map<string, { until: number; table: Promise<SymbolTable> }>();

  constructor(
    private readonly keepMs = KEEP_MS,
    private readonly now: () => number = Date.now,
  ) {}

  /**
   * The table of the PLC `url` names: `live`'s (the connection's open client)
   * when it is connected, else one browse of its own (with `password`), kept
   * `keepMs`. Rejects with the reason there is none (kept as long as a table would be).
   */
  tableOf(url: string, options: { live?: unknown; password?: string } = {}): Promise<SymbolTable> {
    const key = endpointKey(parseUrl(url));
    const live = options.live;
    const signal = AbortSignal.timeout(BROWSE_DEADLINE_MS);
    // The live session browses once and knows of a download: its table is the one the connection's reads use.
    if (canBrowse(live) && live.state === 'connected') return live.browse({ signal });
    const known = this.kept.get(key);
    if (known && known.until > this.now()) return known.table;
    const table = browsePlc(url, { signal, ...(options.password === undefined ? {} : { password: options.password }) });
    table.catch(() => undefined);
    this.kept.set(key, { until: this.now() + this.keepMs, table });
    for (const [k, v] of this.kept) if (v.until <= this.now()) this.kept.delete(k);
    return table;
  }
}
