/**
 * What a connection tells its flows about a link's errors (issue #26): the
 * first error of an outage goes to Catch, once; the ones after it (each
 * reconnect that fails, in whatever words, and each loss of a link that came
 * up for less than `stableMs`) only to the status. A PLC that is off, or
 * silent, or a link that flaps within one fault, is one Catch message, not
 * one per attempt. No Node-RED: the connection node asks `first()` and tells
 * `state()`.
 */

/** A link that stayed connected this long has ended its outage: the next error goes to Catch again. */
const STABLE_MS = 5000;

/** How the stable time is waited for (tests give their own clock). */
export interface StableTimer {
  /** Calls `fire` after `ms` (never keeping the process alive); the returned function cancels it. */
  start(fire: () => void, ms: number): () => void;
}

const realTimer: StableTimer = {
  start(fire, ms) {
    const timer = setTimeout(fire, ms);
    timer.unref();
    return () => clearTimeout(timer);
  },
};

export class OutageReports {
  /** True once this outage's first error was reported, until the link has stayed up for `stableMs`. */
  private reported = false;
  /** Cancels the running stable timer; undefined while none runs. */
  private stable: (() => void) | undefined;

  /** `connected()`: whether the link is up now (read when the stable time has passed). */
  constructor(
    private readonly connected: () => boolean,
    private readonly stableMs = STABLE_MS,
    private readonly timer: StableTimer = realTimer,
  ) {}

  /** An error of the link: true when it is the first of its outage (report it), false for the ones after it. */
  first(): boolean {
    if (this.reported) return false;
    this.reported = true;
    return true;
  }

  /** The link's state changed (as its users are told it): a link that stays connected ends the outage. */
  state(state: string): void {
    if (state !== 'connected') {
      this.close();
    } else if (this.reported && this.stable === undefined) {
      this.stable = this.timer.start(() => {
        this.stable = undefined;
        if (this.connected()) this.reported = false;
      }, this.stableMs);
    }
  }

  /** Stops the stable timer (the link went down, or the connection closes). */
  close(): void {
    this.stable?.();
    this.stable = undefined;
  }
}

/**
 * Why a link retries, when waiting alone will not help and the status should
 * say so instead of "retry in N s" (issue #31): the PLC's certificate is not
 * trusted (pin it: `fingerprint=`), is out of its dates, or the PLC refused
 * the password. Undefined for every other error (the PLC may come back).
 */
export type RetryReason = 'not-trusted' | 'expired' | 'not-yet-valid' | 'password';

export function retryReason(error: unknown): RetryReason | undefined {
  const e = error as { code?: unknown; problem?: unknown } | null | undefined;
  if (!e || typeof e !== 'object') return undefined;
  if (e.code === 'ACCESS_DENIED') return 'password';
  if (e.code !== 'CERTIFICATE_UNTRUSTED') return undefined;
  return e.problem === 'expired' || e.problem === 'not-yet-valid' ? e.problem : 'not-trusted';
}
