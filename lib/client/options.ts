/** A client's options, and those its endpoint (URL) carries. */
import type { BackoffOptions } from '../link/backoff';
import type { SymbolTable } from '../symbols/model';

export interface ClientOptions {
  /** For messages, e.g. "s7://127.0.0.1:102". */
  name: string;
  /** Milliseconds, per request and for connecting. */
  timeout?: number;
  backoff?: BackoffOptions;
  /** Jobs waiting at most before QUEUE_FULL. */
  maxQueued?: number;
  /** Injected for tests (backoff jitter). */
  random?: () => number;
  /** Refuse every write before anything is sent (code WRITE_NOT_ALLOWED). */
  readOnly?: boolean;
  /** Only writes inside these areas ("DB10", "M", "ST5") or addresses ("DB1.DBW2") are allowed. */
  allow?: readonly string[];
  /**
   * A compiled symbol table (compileSymbols): tags may then be named as the
   * sources name them, `"Tank".Level`, beside absolute addresses
   * (docs/symbols.md, "Reading and writing by name").
   */
  symbols?: SymbolTable;
  /**
   * Refuse reads and writes by name (LAYOUT_MISMATCH) in a data block whose
   * length in the PLC differs from what the sources declare, instead of
   * returning values from shifted offsets (the URL's `strictSymbols=true`).
   */
  strictSymbols?: boolean;
}

export const DEFAULT_TIMEOUT = 5000;

/** What every endpoint carries for its client: the request timeout and the write safety. */
export interface EndpointOptions {
  timeout: number;
  readOnly?: boolean;
  allow?: readonly string[];
  strictSymbols?: boolean;
}

/** A client's options from its endpoint (`name` for messages), overridden by the caller's. */
export function endpointOptions(name: string, endpoint: EndpointOptions, options: Partial<ClientOptions>): ClientOptions {
  return {
    name,
    timeout: endpoint.timeout,
    ...(endpoint.readOnly ? { readOnly: true } : {}),
    ...(endpoint.allow ? { allow: endpoint.allow } : {}),
    ...(endpoint.strictSymbols ? { strictSymbols: true } : {}),
    ...options,
  };
}
