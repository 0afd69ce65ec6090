/**
 * The one way a test here skips: with a reason, which the summary reporter
 * (test/support/summary-reporter.js) prints at the end of the run, so no test
 * goes missing from `npm test` without the summary saying what and why.
 */
import type { Context, Runnable, Suite } from 'mocha';

/** Shared with summary-reporter.js, which reads it off the skipped test or its suites. */
export const SKIP_REASON = Symbol.for('plcwire.skipReason');

/**
 * Skips the current test (in a test or a `beforeEach` hook) or, in a `before`
 * hook, every test of its suite, and records why. Use it instead of `this.skip()`.
 */
export function skipBecause(ctx: Context, reason: string): never {
  const runnable = ctx.test as (Runnable & { type?: string; originalTitle?: string }) | undefined;
  if (!runnable) throw new Error('skipBecause: call it from a test or a hook');
  // A test skips itself, "before each" skips the test it runs for, "before all" its whole suite.
  let target: Runnable | Suite = runnable;
  if (runnable.type === 'hook')
    target = /^"before each" hook/.test(runnable.originalTitle ?? runnable.title) ? ctx.currentTest! : runnable.parent!;
  (target as unknown as Record<symbol, string>)[SKIP_REASON] = reason;
  return ctx.skip();
}
