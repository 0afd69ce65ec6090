/**
 * The one chunker of the client: items (of a read, a write, a browse) go in
 * requests of at most the item limit, one request at a time, in order. A PLC
 * that refuses a request as a whole, or drops the connection on it, has
 * shown its limit: the limit goes below that request's size, and a refused
 * request's items go again in smaller requests.
 */
import type { PlcError } from '../../errors';

/** What the client gives the reads, writes and browses: the item limit, and how to learn a lower one. */
export interface Limits {
  maxItems(): number;
  /** The PLC refused a request of `items` items as a whole, or reset the connection on it: the limit goes below it. */
  refused(items: number): void;
}

/**
 * Sends a request of `items` items; a PLC that drops the connection on it
 * (PLCSIM is reported to reset on requests past about 1 kB) has shown its
 * limit too: it is lowered before the link error goes on, so the request
 * after the reconnect is smaller.
 */
async function sized<A>(items: number, limits: Limits, send: () => Promise<A>): Promise<A> {
  try {
    return await send();
  } catch (err) {
    if (items > 1 && (err as PlcError).code === 'CONNECTION_LOST') limits.refused(items);
    throw err;
  }
}

/**
 * `items` in requests of at most `limits.maxItems()`: `send` asks the PLC for
 * one chunk, `take` reads its answer; `take` returns 'again' when the PLC
 * refused a request of several items as a whole, and its items then go again
 * in smaller requests (a single item's refusal is `take`'s to report).
 */
export async function inChunks<I, A>(
  items: readonly I[],
  limits: Limits,
  send: (chunk: I[]) => Promise<A>,
  take: (chunk: I[], answer: A) => 'again' | void,
): Promise<void> {
  let pending = items;
  while (pending.length > 0) {
    const size = limits.maxItems();
    const again: I[] = [];
    for (let at = 0; at < pending.length; at += size) {
      const chunk = pending.slice(at, at + size);
      if (take(chunk, await sized(chunk.length, limits, () => send(chunk))) === 'again' && chunk.length > 1) {
        limits.refused(chunk.length);
        again.push(...chunk);
      }
    }
    pending = again;
  }
}
