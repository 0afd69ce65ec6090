import { abortError, PlcError, TimeoutError } from '../errors';

interface Entry<T> {
  resolve(value: T): void;
  reject(err: Error): void;
  timer: NodeJS.Timeout;
  signal?: AbortSignal;
  onAbort?: () => void;
}

/**
 * Requests awaiting a reply, by id: each settles exactly once — by a reply,
 * its timeout, its abort signal, or rejectAll() when the link goes down.
 */
export class PendingRequests<T> {
  private readonly entries = new Map<number, Entry<T>>();

  get size(): number {
    return this.entries.size;
  }

  has(id: number): boolean {
    return this.entries.has(id);
  }

  /**
   * Registers request `id`. A timeout rejects with a TimeoutError whose stack shows where the request was made, and whose
   * message is `timeoutMessage` when given ("<description> timed out after <timeoutMs> ms" otherwise).
   */
  add(id: number, timeoutMs: number, description: string, signal?: AbortSignal, timeoutMessage?: string): Promise<T> {
    if (this.entries.has(id)) return Promise.reject(new PlcError('PROTOCOL_ERROR', `request id ${id} is already pending`));
    const caller: { stack?: string } = {};
    Error.captureStackTrace(caller, PendingRequests.prototype.add);
    return new Promise<T>((resolve, reject) => {
      if (signal?.aborted) return reject(abortError(description, signal));
      const timer = setTimeout(() => {
        const err = new TimeoutError(timeoutMessage ?? `${description} timed out after ${timeoutMs} ms`);
        err.stack = `${err.name}: ${err.message}${caller.stack?.replace(/^Error\n?/, '\n') ?? ''}`;
        this.settle(id)?.reject(err);
      }, timeoutMs);
      const entry: Entry<T> = { resolve, reject, timer };
      if (signal) {
        entry.signal = signal;
        entry.onAbort = () => this.settle(id)?.reject(abortError(description, signal));
        signal.addEventListener('abort', entry.onAbort, { once: true });
      }
      this.entries.set(id, entry);
    });
  }

  /** Settles `id` with a value; false when no such request is pending (a late or duplicate reply). */
  resolve(id: number, value: T): boolean {
    const entry = this.settle(id);
    entry?.resolve(value);
    return entry !== undefined;
  }

  reject(id: number, err: Error): boolean {
    const entry = this.settle(id);
    entry?.reject(err);
    return entry !== undefined;
  }

  rejectAll(err: Error): void {
    for (const id of [...this.entries.keys()]) this.settle(id)?.reject(err);
  }

  private settle(id: number): Entry<T> | undefined {
    const entry = this.entries.get(id);
    if (!entry) return undefined;
    this.entries.delete(id);
    clearTimeout(entry.timer);
    if (entry.onAbort) entry.signal!.removeEventListener('abort', entry.onAbort);
    return entry;
  }
}
