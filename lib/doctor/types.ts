/**
 * The connection doctor's report and options, and the port by which a
 * driver offers its doctor (DriverEntry.diagnose in lib/drivers.ts): the
 * types every protocol's steps and every caller (CLI, Node-RED, library)
 * share. Imports no protocol.
 */
import type { SymbolTable } from '../symbols/model';

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
 * A driver's connection doctor: the steps of its protocol, after the URL was
 * parsed to its endpoint (lib/doctor/ parses it and says what is wrong with a
 * URL that does not parse). `formatUrl` writes an endpoint back as a URL the
 * user can paste (a hint proposing a changed URL), with the common parameters.
 */
export interface DiagnosePort<E> {
  /** What to change when a URL of this driver's schemes does not parse. */
  readonly urlHint: string;
  /** Walks the connection up to the first failed step; rejects only with ABORTED when `options.signal` aborts. */
  run(endpoint: E, addresses: readonly string[], options: DiagnoseOptions, formatUrl: (endpoint: E) => string): Promise<DoctorReport>;
}
