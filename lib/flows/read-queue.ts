/**
 * Reads one at a time: a poll never overlaps the previous one, and a read
 * asked for while one runs waits its turn. Waiting is bounded: more than
 * `limit` reads waiting is a QUEUE_FULL error for the one asked, not memory
 * growth while a PLC answers slower than messages arrive.
 */
import { PlcError } from '../errors';

/** Reads waiting behind the running one at most, by default. */
export const MAX_WAITING_READS = 100;

export class ReadQueue {
  private chain: Promise<unknown> = Promise.resolve();
  private queued = 0;

  constructor(private readonly limit = MAX_WAITING_READS) {}

  /** How many jobs wait for the running one (not counting it). */
  get waiting(): number {
    return this.queued;
  }

  /** Runs `job` after every job run before it has settled; resolves or rejects with its result. */
  run<T>(job: () => T | Promise<T>): Promise<T> {
    if (this.queued >= this.limit) {
      return Promise.reject(
        new PlcError('QUEUE_FULL', `more than ${this.limit} reads waiting; the PLC answers slower than messages arrive`),
      );
    }
    this.queued++;
    const run = this.chain.then(() => {
      this.queued--;
      return job();
    });
    this.chain = run.catch(() => undefined);
    return run;
  }
}
