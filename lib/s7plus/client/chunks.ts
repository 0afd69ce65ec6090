/**
 * The one chunker of the client: items (of a read, a write, a browse) go in
 * requests of at most the item limit, one request at a time, in order. A PLC
 * that refuses a request as a whole, or drops the connection on it, has
 * shown its limit: the limit goes below that request's size, and a refused
 * request's items go again in smaller requests. Given the items' sizes, a
 * request also stays within the frame the PLC takes (the negotiated TPDU
 * size: issue #32).
 */
import type { PlcError } from '../../errors';
import { MULTI_VARIABLES_FRAME_OVERHEAD } from '../codec/variables';

/** What the client gives the reads, writes and browses: the item limit, and how to learn a lower one. */
export interface Limits {
  maxItems(): number;
  /** The PLC refused a request of `items` items as a whole, or reset the connection on it: the limit goes below it. */
  refused(items: number): void;
  /** The most bytes of one request frame (header to trailer): the negotiated TPDU size. Undefined: no limit. */
  maxFrame?(): number | undefined;
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
  bytes?: (item: I) => number,
): Promise<void> {
  let pending = items;
  while (pending.length > 0) {
    const again: I[] = [];
    for (const chunk of cut(pending, limits, bytes)) {
      if (take(chunk, await sized(chunk.length, limits, () => send(chunk))) === 'again' && chunk.length > 1) {
        limits.refused(chunk.length);
        again.push(...chunk);
      }
    }
    pending = again;
  }
}

/**
 * `items` cut in order into requests of at most `limits.maxItems()` items and, given `bytes` (each item's bytes on
 * the wire) and `limits.maxFrame()`, of at most that frame with the request's own bytes
 * (MULTI_VARIABLES_FRAME_OVERHEAD); an item alone over it still goes, alone (the PLC's answer is its result).
 */
export function cut<I>(items: readonly I[], limits: Limits, bytes?: (item: I) => number): I[][] {
  const size = limits.maxItems();
  const frame = bytes && limits.maxFrame?.();
  if (frame === undefined) {
    const out: I[][] = [];
    for (let at = 0; at < items.length; at += size) out.push(items.slice(at, at + size));
    return out;
  }
  const budget = frame - MULTI_VARIABLES_FRAME_OVERHEAD;
  const out: I[][] = [];
  let chunk: I[] = [];
  let used = 0;
  for (const item of items) {
    const n = bytes!(item);
    if (chunk.length > 0 && (chunk.length >= size || used + n > budget)) {
      out.push(chunk);
      chunk = [];
      used = 0;
    }
    chunk.push(item);
    used += n;
  }
  if (chunk.length > 0) out.push(chunk);
  return out;
}
