/**
 * The connection doctor's report and options, and the contract between its
 * walk (lib/doctor/, above the protocols) and each driver's steps (its
 * folder's doctor/, offered as the diagnose port of its registry entry,
 * lib/drivers.ts). Below both: a protocol folder implements DiagnosePort
 * without importing lib/doctor/.
 */
import type { PlcError } from './errors';
import type { SymbolTable } from './symbols/model';

/** One step's outcome: `step` names it (`tcp`, `cotp` …, `address DB1,INT0`), `hint` says what to change. */
export interface DoctorStep {
  step: string;
  ok: boolean;
  detail: string;
  hint?: string;
}

export interface DoctorReport {
  /** Every step passed. */
  ok: boolean;
  steps: DoctorStep[];
}

export interface DiagnoseOptions {
  /** The deadline of the whole walk in ms (default 20 s); each network step also keeps the URL's timeout. */
  timeout?: number;
  /** Aborting rejects with ABORTED once every socket is closed. */
  signal?: AbortSignal;
  /** Called with each step as soon as it is known. */
  onStep?: (step: DoctorStep) => void;
  /**
   * A compiled symbol table (compileSymbols), as connect(url, { symbols })
   * takes it: each given text that is not an S7 address is then a name,
   * resolved as a read resolves it and read at its address; an unknown name
   * is a failed step with the closest names the table has.
   */
  symbols?: SymbolTable;
  /** Names in a DB whose length in the PLC differs from the sources' are refused, as with ClientOptions.strictSymbols. */
  strictSymbols?: boolean;
  /** The PLC's password, for a protocol that has one (DriverEntry.password, s7plus://): never shown in a step or the report. */
  password?: string;
}

/**
 * The doctor's walk as a driver's steps see it (lib/doctor/walk.ts keeps it):
 * each step passes or fails (a failure ends the walk), one signal aborts at
 * the walk's deadline or the caller's abort.
 */
export interface DoctorSteps {
  /** The caller's options (the symbol table, the password …). */
  readonly options: DiagnoseOptions;
  /** Aborts at the deadline or when the caller aborts. */
  readonly signal: AbortSignal;
  /** The whole walk's deadline in ms. */
  readonly ms: number;
  pass(step: string, detail: string, hint?: string): void;
  /** Records the failed step and ends the walk (throws). */
  fail(step: string, detail: string, hint?: string): never;
  /** An error inside a step: the caller's abort ends the walk, the deadline fails the step, anything else is `other`. */
  failed(step: string, err: unknown, other: (e: PlcError) => never): never;
}

/**
 * A driver's connection doctor (DriverEntry.diagnose): its protocol's steps,
 * run inside the walk of lib/doctor/ once the URL was parsed to its endpoint.
 * `formatUrl` writes an endpoint back as a URL the user can paste (a hint
 * proposing a changed URL). The steps close what they opened before they
 * return or throw.
 */
export interface DiagnosePort<E> {
  /** What to change when a URL of this driver's schemes does not parse. */
  readonly urlHint: string;
  run(endpoint: E, addresses: readonly string[], steps: DoctorSteps, formatUrl: (endpoint: E) => string): Promise<void>;
}
