export interface BackoffOptions {
  /** Delay before the first reconnect attempt, ms. */
  initialDelay?: number;
  /** Upper bound of the delay, ms. */
  maxDelay?: number;
  /** Growth per failed attempt. */
  factor?: number;
  /** Random spread as a fraction of the delay (0.2 = ±20 %), so many clients do not reconnect in step. */
  jitter?: number;
}

const DEFAULT_BACKOFF: Required<BackoffOptions> = Object.freeze({
  initialDelay: 500,
  maxDelay: 30_000,
  factor: 2,
  jitter: 0.2,
});

/** Delay before reconnect attempt `attempt` (1, 2, …): capped exponential growth with jitter. */
export function backoffDelay(attempt: number, options: BackoffOptions = {}, random: () => number = Math.random): number {
  const o = { ...DEFAULT_BACKOFF, ...options };
  const base = Math.min(o.maxDelay, o.initialDelay * o.factor ** Math.max(0, attempt - 1));
  const spread = base * o.jitter * (2 * random() - 1);
  return Math.max(0, Math.round(Math.min(o.maxDelay, base + spread)));
}
