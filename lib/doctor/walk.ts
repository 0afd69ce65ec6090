/**
 * The connection doctor's walk, whatever the protocol: the steps in order, each told to `onStep` as it ends; one
 * deadline for the whole walk; the caller's abort; the first failed step ending the walk. A driver's steps
 * (lib/s7/doctor for s7://, lib/s7plus/doctor for s7plus://) run inside `walk()` and see it as DoctorSteps.
 */
import type { DiagnoseOptions, DoctorReport, DoctorStep, DoctorSteps } from '../doctor-steps';
import { abortError, PlcError, toPlcError } from '../errors';

/** What to do when the deadline ends a step. */
const DEADLINE_HINT = "Give the doctor more time (the timeout option, or --timeout), or raise the URL's timeout on a slow link.";

/** The whole walk's deadline when the caller gives none. */
const DEFAULT_DEADLINE = 20_000;

/** The whole walk's deadline in ms; throws INVALID_VALUE for one that is not a positive number. */
function deadlineOf(options: DiagnoseOptions): number {
  const ms = options.timeout ?? DEFAULT_DEADLINE;
  if (!Number.isFinite(ms) || ms <= 0)
    throw new PlcError('INVALID_VALUE', `diagnose: timeout must be a positive number of ms, got ${String(ms)}`);
  return ms;
}

/** Thrown inside the walk to end it at a failed step. */
class Stop extends Error {}

export class DoctorWalk implements DoctorSteps {
  private readonly steps: DoctorStep[] = [];
  private readonly ctl = new AbortController();
  /** The whole walk's deadline in ms. */
  readonly ms: number;
  private readonly timer: NodeJS.Timeout;
  private readonly onUserAbort = () => this.ctl.abort();
  private readonly deadlineHint = DEADLINE_HINT;

  constructor(readonly options: DiagnoseOptions) {
    this.ms = deadlineOf(options);
    this.timer = setTimeout(() => this.ctl.abort(), this.ms);
    if (options.signal?.aborted) this.ctl.abort();
    else options.signal?.addEventListener('abort', this.onUserAbort, { once: true });
  }

  report(): DoctorReport {
    return { ok: this.steps.length > 0 && this.steps.every((s) => s.ok), steps: this.steps };
  }

  /** Ends the deadline and lets go of the caller's signal, once the steps closed what they opened. */
  dispose(): void {
    clearTimeout(this.timer);
    this.options.signal?.removeEventListener('abort', this.onUserAbort);
  }

  /** Aborts at the deadline or when the caller aborts. */
  get signal(): AbortSignal {
    return this.ctl.signal;
  }

  /** The step that ended last, undefined before the first. */
  private get lastStep(): string | undefined {
    return this.steps.at(-1)?.step;
  }

  private record(step: string, ok: boolean, detail: string, hint?: string): void {
    const s: DoctorStep = { step, ok, detail };
    if (hint !== undefined) s.hint = hint;
    this.steps.push(s);
    this.options.onStep?.(s);
  }

  pass(step: string, detail: string, hint?: string): void {
    this.record(step, true, detail, hint);
  }

  fail(step: string, detail: string, hint?: string): never {
    this.record(step, false, detail, hint);
    throw new Stop();
  }

  /** An error inside a step: the caller's abort ends the walk, the deadline fails the step, anything else is `other`. */
  failed(step: string, err: unknown, other: (e: PlcError) => never): never {
    if (err instanceof Stop) throw err;
    if (this.options.signal?.aborted) throw abortError('the connection doctor', this.options.signal);
    if (this.signal.aborted) this.fail(step, `no result before the doctor's deadline of ${this.ms} ms`, this.deadlineHint);
    return other(toPlcError(err, 'CONNECT_FAILED'));
  }

  /**
   * Runs `steps`: a failed step ends them; the caller's abort rejects with ABORTED; the deadline running out where no
   * step caught it (between steps, or inside one's own retries) is a failed "deadline" step, not a rejection.
   */
  async walk(steps: () => Promise<void>): Promise<void> {
    try {
      await steps();
    } catch (err) {
      if (err instanceof Stop) return;
      if (this.options.signal?.aborted) throw abortError('the connection doctor', this.options.signal);
      if (this.signal.aborted) {
        const after = this.lastStep;
        this.record(
          'deadline',
          false,
          `no result before the doctor's deadline of ${this.ms} ms${after ? ` (after the ${after} step)` : ''}`,
          this.deadlineHint,
        );
        return;
      }
      throw err;
    }
  }
}
