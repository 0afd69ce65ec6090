/**
 * Fuzz targets of "tags by name": the DB/UDT source compiler, the symbol
 * table readers and the name lookup, fed mutations of the repository's own
 * fixtures. A source or a table may compile or be refused with a
 * SourceError (a PlcError); anything else is a finding.
 */
import { readdirSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { compileSymbols } from '../../lib/symbols/compile';
import { parseBlockSource } from '../../lib/symbols/source-parser';
import { readSymbolTable } from '../../lib/symbols/symbol-files';
import type { FuzzTarget } from './engine';

const FIXTURES = join(__dirname, '..', '..', '..', 'test', 'fixtures', 'symbols');

function fixtures(dir: string, extensions: RegExp): { name: string; bytes: Buffer }[] {
  return readdirSync(join(FIXTURES, dir))
    .filter((f) => extensions.test(f))
    .map((f) => ({ name: f, bytes: readFileSync(join(FIXTURES, dir, f)) }));
}

export function symbolTargets(): FuzzTarget[] {
  const sources = [...fixtures('golden', /\.(db|awl)$/), ...fixtures('parser', /\.(db|scl|awl)$/)];
  const tables = fixtures('tables', /\.(sdf|asc|seq|csv|xlsx)$/);
  const table = compileSymbols(
    fixtures('golden', /^corners\.db$/).map((f) => ({ name: f.name, content: f.bytes })),
    { db: { Corners: 1 } },
  );
  const names = table.entries.slice(0, 40).map((e) => Buffer.from(e.name, 'utf8'));
  return [
    // TIA sources (.db) and STEP 7 ones (.awl: its symbolic blocks count as standard) from the same seeds.
    ...['db', 'awl'].map((ext) => ({
      name: `symbols compileSymbols (.${ext})`,
      seeds: sources.map((f) => f.bytes),
      run: (b: Buffer) => {
        const source = { name: `fuzz.${ext}`, content: b };
        // Numbers for the TIA blocks that parse, so the layout and naming run and not only the number check.
        const db: Record<string, number> = {};
        let next = 1000;
        for (const block of parseBlockSource(source)) if (block.kind === 'db' && block.number === undefined) db[`"${block.name}"`] = next++;
        compileSymbols([source], { db });
      },
    })),
    ...tables.map((f) => ({
      name: `symbols readSymbolTable (${f.name.slice(f.name.lastIndexOf('.'))})`,
      seeds: [f.bytes],
      run: (b: Buffer) => void readSymbolTable({ name: f.name, content: b }),
    })),
    {
      name: 'symbols lookup / suggest',
      seeds: names,
      run: (b) => {
        const name = b.toString('utf8');
        // Neither throws: an unknown or malformed name is undefined / no suggestion.
        if (table.lookup(name) === undefined) table.suggest(name);
      },
    },
  ];
}
