/**
 * What `plcwire serve <protocol>` asks of a protocol's simulator: the CLI
 * hands each registry entry (lib/drivers.ts) its flags through this contract,
 * so a protocol's folder starts its own simulator without importing the CLI.
 */
import type { SymbolSource, SymbolTable } from '../symbols/model';

/** The command line of `plcwire serve`, as a protocol's serve function reads it. */
export interface ServeFlags {
  /** --host, 127.0.0.1 by default. */
  readonly host: string;
  /** True when the flag was given. */
  has(flag: string): boolean;
  /** A flag's text; undefined when absent. */
  string(flag: string): string | undefined;
  /** A whole-number flag within min..max; `fallback` when absent; a usage error otherwise. */
  int(flag: string, fallback: number, min: number, max: number): number;
  /** The data blocks of the --source files (with --db), compiled; undefined without --source. */
  source(): SymbolTable | undefined;
  /** The --source files read but not compiled, with the --db numbers; undefined without --source. */
  sourceFiles(): { sources: SymbolSource[]; db: Record<string, number> } | undefined;
  /** The --source file names as given (a simulator that reloads its program watches them). */
  sourcePaths(): string[];
  /** True when --source was given (also when it names no file). */
  hasSource(): boolean;
  /**
   * The command that reads the first member of the sources by name: over `url`
   * with the sources; when no member has an address (optimized blocks only), over
   * `s7plusUrl` by the name the PLC's browse gives; else the symbols command.
   */
  tryRead(url: string, table: SymbolTable, s7plusUrl?: string): string;
  /** An error the CLI reports as a usage error (exit code 2). */
  usage(message: string): Error;
  /** A file named on the command line (--layout); a missing one is the CLI's "no such file" error. */
  readFile(file: string): Buffer;
  /** Runs `start` (a server's listen); a bind error in words naming `flag`. */
  listen<R>(start: () => Promise<R>, flag: string): Promise<R>;
  /** Prints a line. */
  say(line: string): void;
}

/** What a started simulator leaves the CLI: how to stop it. */
export interface Served {
  close(): Promise<void>;
}

/**
 * The data blocks built from --source, one line each: what a client's block
 * info will report. A block with optimized access has no standard-access
 * image to serve by address (lib/sim/symbol-memory.ts): its line says so.
 */
export function servedBlocks(table: SymbolTable): string[] {
  return table.blocks.map((b) =>
    b.length === null
      ? `not serving DB${b.db} "${b.name}" by address: it has optimized access, its members are read by name over s7plus:// (${b.file})`
      : `serving DB${b.db} "${b.name}" of ${b.length} bytes (${b.file})`,
  );
}
