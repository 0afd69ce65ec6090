/**
 * Symbol tables compiled by compileSymbols from the sources of
 * test/fixtures/symbols/client/ (TIA .udt/.db, a STEP 7 .awl and its
 * symbol table .asc), as a user compiles a PLC's own sources.
 */
import * as fs from 'node:fs';
import * as path from 'node:path';
import { compileSymbols } from '../../lib/symbols';
import type { SymbolSource, SymbolTable } from '../../lib/symbols';

export const CLIENT_FIXTURES = path.resolve(__dirname, '../../../test/fixtures/symbols/client');

/** The block numbers TIA sources do not carry (DB2 "Recipe" is numbered by its STEP 7 source and Symbols.asc). */
export const CLIENT_DB_NUMBERS = { Tank: 1, MW10: 3, Field: 4 } as const;

/** The named files of the client fixtures, as SymbolSources. */
export function clientSources(...files: string[]): SymbolSource[] {
  return files.map((name) => ({ name, content: fs.readFileSync(path.join(CLIENT_FIXTURES, name)) }));
}

/** compileSymbols of the named client fixtures, numbered as CLIENT_DB_NUMBERS. */
export function compileClientSources(...files: string[]): SymbolTable {
  const db = Object.fromEntries(Object.entries(CLIENT_DB_NUMBERS).filter(([name]) => files.includes(`${name}.db`)));
  return compileSymbols(clientSources(...files), { db });
}
