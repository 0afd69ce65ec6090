import { abortError, PlcError } from '../errors';
import { Fifo } from './fifo';

interface Queued {
  job: () => Promise<unknown>;
  resolve(value: unknown): void;
  reject(err: Error): void;
  signal?: AbortSignal;
  onAbort?: () => void;
}

export interface JobQueueOptions {
  /** Jobs running at once (S7: the negotiated AmQ; a half-duplex bus: 1). */
  concurrency: number;
  /** Jobs waiting at most; one more is refused with QUEUE_FULL instead of growing memory. */
  maxQueued?: number;
}

const DEFAULT_MAX_QUEUED = 1000;

/** A FIFO queue with a concurrency limit and a bound. Every job's promise settles. */
export class JobQueue {
  private readonly waiting = new Fifo<Queued>();
  private active = 0;
  private readonly maxQueued: number;
  private idleWaiters: (() => void)[] = [];
  private limit: number;

  constructor(options: JobQueueOptions) {
    this.limit = Math.max(1, options.concurrency);
    this.maxQueued = options.maxQueued ?? DEFAULT_MAX_QUEUED;
  }

  get concurrency(): number {
    return this.limit;
  }

  set concurrency(value: number) {
    this.limit = Math.max(1, value);
    this.drain();
  }

  get queued(): number {
    return this.waiting.size;
  }

  get running(): number {
    return this.active;
  }

  run<T>(job: () => Promise<T>, signal?: AbortSignal): Promise<T> {
    if (signal?.aborted) return Promise.reject(abortError('request', signal));
    if (this.queued >= this.maxQueued) {
      return Promise.reject(new PlcError('QUEUE_FULL', `request queue is full (${this.maxQueued} waiting)`));
    }
    return new Promise<T>((resolve, reject) => {
      const item: Queued = { job, resolve: resolve as (v: unknown) => void, reject };
      if (signal) {
        item.signal = signal;
        item.onAbort = () => this.remove(item, abortError('request', signal));
        signal.addEventListener('abort', item.onAbort, { once: true });
      }
      this.waiting.push(item);
      this.drain();
    });
  }

  /** Rejects every job that has not started. Running jobs finish on their own. */
  rejectAll(err: Error): void {
    for (const item of this.waiting.takeAll()) {
      this.detach(item);
      item.reject(err);
    }
    this.notifyIdle();
  }

  /** Resolves when nothing is queued or running. */
  idle(): Promise<void> {
    if (this.active === 0 && this.queued === 0) return Promise.resolve();
    return new Promise((resolve) => this.idleWaiters.push(resolve));
  }

  private drain(): void {
    while (this.active < this.limit && this.waiting.size > 0) {
      const item = this.waiting.shift()!;
      this.detach(item);
      this.active++;
      let started: Promise<unknown>;
      try {
        started = item.job();
      } catch (err) {
        started = Promise.reject(err);
      }
      started.then(item.resolve, item.reject).finally(() => {
        this.active--;
        this.drain();
        this.notifyIdle();
      });
    }
  }

  private remove(item: Queued, err: Error): void {
    if (!this.waiting.remove(item)) return;
    this.detach(item);
    item.reject(err);
    this.notifyIdle();
  }

  private detach(item: Queued): void {
    if (item.onAbort) item.signal!.removeEventListener('abort', item.onAbort);
  }

  private notifyIdle(): void {
    if (this.active !== 0 || this.queued !== 0 || this.idleWaiters.length === 0) return;
    const waiters = this.idleWaiters;
    this.idleWaiters = [];
    for (const w of waiters) w();
  }
}
