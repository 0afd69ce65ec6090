/**
 * Tags by name (errors: SourceError, from lib/errors.ts): compile a PLC's own DB and UDT sources and symbol tables
 * into a table of every member with its standard-access address
 * (docs/symbols.md).
 */
export { compileSymbols } from './compile';
export type { BlockSummary, CompileOptions, SymbolEntry, SymbolSource, SymbolTable, SymbolTableRow, SourcePosition } from './model';
