import type { EventEmitter } from 'node:events';
import type { PlcClient } from '../../lib/types';

/** Waits for `event` on `emitter` (optionally one whose args satisfy `match`), or rejects after `ms`. */
export function waitFor<T = unknown>(
  source: EventEmitter | PlcClient,
  event: string,
  ms = 3000,
  match: (...args: any[]) => boolean = () => true,
): Promise<T> {
  // A client types its events (ClientEvents); this waits for any name, the client's own events included.
  const emitter = source as EventEmitter;
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => {
      emitter.removeListener(event, listener);
      reject(new Error(`no "${event}" event within ${ms} ms`));
    }, ms);
    function listener(...args: any[]) {
      if (!match(...args)) return;
      clearTimeout(timer);
      emitter.removeListener(event, listener);
      resolve(args[0] as T);
    }
    emitter.on(event, listener);
  });
}

/** Polls `condition` every few ms until it holds, or rejects after `ms` (for state with no event). */
export async function until(condition: () => boolean, ms = 3000, what = 'condition'): Promise<void> {
  const deadline = Date.now() + ms;
  while (!condition()) {
    if (Date.now() > deadline) throw new Error(`${what} did not hold within ${ms} ms`);
    await new Promise((r) => setTimeout(r, 5));
  }
}

/** Active handles other than stdio, for leak checks. */
export function activeHandles(): number {
  const handles = (process as any)._getActiveHandles() as any[];
  return handles.filter((h) => !(h && (h === process.stdout || h === process.stderr || h === process.stdin))).length;
}

/** Settles after pending close callbacks ran, so handle counts are stable. */
export function settle(): Promise<void> {
  return new Promise((r) => setImmediate(() => setImmediate(r)));
}
