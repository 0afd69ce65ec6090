import type { EventEmitter } from 'node:events';
import { isLastingRefusal, PlcError, TimeoutError, toPlcError } from '../errors';
import type { LinkState } from '../types';
import { backoffDelay, type BackoffOptions } from './backoff';
import type { DriverSession } from './driver';

export type { DriverSession };

export interface SupervisorOptions<S extends DriverSession> {
  /** Opens a session: transport and handshakes. Must honour `signal`. */
  open(signal: AbortSignal): Promise<S>;
  /** For messages, e.g. "s7://127.0.0.1:102". */
  name: string;
  /** Deadline of one connection attempt, ms. */
  connectTimeout: number;
  backoff?: BackoffOptions;
  /** Injected for tests (jitter). */
  random?: () => number;
  /** Where state events are emitted (the client). */
  events: EventEmitter;
}

/**
 * Keeps one session open: connects, and after a failure or loss reconnects
 * forever with capped exponential backoff and jitter, until close().
 *
 * Emits on `events`: `state` (LinkState), `connecting`, `connected`,
 * `disconnected` (PlcError), `reconnecting` ({ delay, attempt, error }),
 * `error` (PlcError, only when someone listens, so it can never crash a process), `closed`.
 */
export class LinkSupervisor<S extends DriverSession> {
  private current: LinkState = 'idle';
  private live: S | undefined;
  private attempt = 0;
  private retryTimer: NodeJS.Timeout | undefined;
  private opening: AbortController | undefined;
  private firstWaiters: { resolve(): void; reject(err: PlcError): void }[] = [];

  constructor(private readonly options: SupervisorOptions<S>) {}

  /**
   * The link's state: the one source of it. The client's `state`, the pooled
   * link's `status` (lib/flows/client-pool.ts), the connection node's
   * `linkStatus` and a node's `linkState` (nodes/) read it; none keeps a copy.
   */
  get state(): LinkState {
    return this.current;
  }

  get session(): S | undefined {
    return this.live;
  }

  /** Starts connecting, and reconnecting forever. Idempotent. */
  start(): void {
    if (this.current === 'idle') this.connectNow();
  }

  /** Starts and waits for the first connection; on the first failure, stops and rejects with its error. */
  connectOnce(): Promise<void> {
    if (this.current === 'connected') return Promise.resolve();
    if (this.current === 'closed') return Promise.reject(closedError(this.options.name));
    const first = new Promise<void>((resolve, reject) => this.firstWaiters.push({ resolve, reject }));
    this.start();
    return first;
  }

  /** The driver reports that a live session died. Ignored for a session that is not the live one. */
  lost(session: S, err: PlcError): void {
    if (session !== this.live) return;
    this.live = undefined;
    session.destroy();
    this.options.events.emit('disconnected', err);
    this.emitError(err);
    this.scheduleRetry(err);
  }

  /** Stops everything. Always resolves. */
  async close(): Promise<void> {
    if (this.current === 'closed') return;
    this.setState('closed');
    clearTimeout(this.retryTimer);
    this.retryTimer = undefined;
    this.opening?.abort(closedError(this.options.name));
    this.opening = undefined;
    const session = this.live;
    this.live = undefined;
    session?.destroy();
    this.settleFirst(closedError(this.options.name));
    if (session) this.options.events.emit('disconnected', closedError(this.options.name));
    this.options.events.emit('closed');
  }

  private connectNow(): void {
    this.retryTimer = undefined;
    this.setState('connecting');
    this.options.events.emit('connecting');
    const controller = new AbortController();
    this.opening = controller;
    const { connectTimeout, name } = this.options;
    const deadline = setTimeout(
      () => controller.abort(new TimeoutError(`connecting to ${name} timed out after ${connectTimeout} ms`)),
      connectTimeout,
    );
    let opened: Promise<S>;
    try {
      opened = this.options.open(controller.signal);
    } catch (err) {
      opened = Promise.reject(err);
    }
    const aborted = new Promise<never>((_, reject) => {
      controller.signal.addEventListener('abort', () => reject(controller.signal.reason), { once: true });
    });
    aborted.catch(() => {});
    Promise.race([opened, aborted]).then(
      (session) => {
        clearTimeout(deadline);
        if (this.opening !== controller) return session.destroy();
        this.opening = undefined;
        this.live = session;
        this.attempt = 0;
        this.setState('connected');
        this.options.events.emit('connected');
        this.settleFirst();
      },
      (reason: unknown) => {
        clearTimeout(deadline);
        // A session that opens after its attempt was abandoned is closed at once.
        opened.then(
          (late) => late.destroy(),
          () => {},
        );
        if (this.opening !== controller) return;
        this.opening = undefined;
        const err = toPlcError(reason, 'CONNECT_FAILED');
        this.emitError(err);
        if (this.firstWaiters.length > 0) {
          this.settleFirst(err);
          void this.close();
          return;
        }
        this.scheduleRetry(err);
      },
    );
  }

  private scheduleRetry(error: PlcError): void {
    if (this.current === 'closed') return;
    this.attempt++;
    // A lasting refusal (a wrong password) waits the longest delay at once: the growing schedule is for faults that pass.
    const delay = backoffDelay(isLastingRefusal(error) ? Infinity : this.attempt, this.options.backoff, this.options.random);
    this.setState('reconnecting');
    this.options.events.emit('reconnecting', { delay, attempt: this.attempt, error });
    this.retryTimer = setTimeout(() => this.connectNow(), delay);
  }

  private setState(state: LinkState): void {
    if (this.current === state) return;
    this.current = state;
    this.options.events.emit('state', state);
  }

  private emitError(err: PlcError): void {
    if (this.options.events.listenerCount('error') > 0) this.options.events.emit('error', err);
  }

  private settleFirst(err?: PlcError): void {
    const waiters = this.firstWaiters;
    this.firstWaiters = [];
    for (const w of waiters) err ? w.reject(err) : w.resolve();
  }
}

function closedError(name: string): PlcError {
  return new PlcError('CLOSED', `connection to ${name} was closed`);
}
