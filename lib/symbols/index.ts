/**
 * Tags by name (errors: SourceError, from lib/errors.ts): compile a PLC's own DB and UDT sources and symbol tables
 * into a table of every member with its standard-access address (a member of an optimized block: none; its
 * S7CommPlus access path when a browse or the simulator gives it) (docs/symbols.md).
 */
export { compileSymbols } from './compile';
export type {
  BlockSummary,
  CompileOptions,
  SymbolAccess,
  SymbolEntry,
  SymbolSource,
  SymbolTable,
  SymbolTableRow,
  SourcePosition,
} from './model';
