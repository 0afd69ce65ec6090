/**
 * compileSymbols(): a PLC's own DB and UDT sources and symbol tables in, a
 * table of every member with its standard-access address out (a member of a
 * block with optimized access: with its type and structure, no address). The source
 * parser and the symbol-table readers read the files, the layout engine
 * places the members (lib/symbols/layout.ts); this file gives the blocks
 * their numbers, names every member as TIA writes it, evaluates the start
 * values and indexes the names (docs/symbols.md).
 */
import { formatAddress, parseAddress } from '../address';
import { PlcError, SourceError } from '../errors';
import { literalValue } from './literals';
import { NameIndex } from './names';
import { distance } from './distance';
import { parseBlockSource } from './source-parser';
import { readSymbolTable } from './symbol-files';
import { blockRef, layoutBlocks } from './layout';
import { TableBuilder, iecElementary, key, type EvaluateLiteral } from './table-builder';
import type {
  BlockDecl,
  BlockSummary,
  CompileOptions,
  DataBlockDecl,
  SourcePosition,
  SymbolEntry,
  SymbolSource,
  SymbolTable,
  SymbolTableRow,
} from './model';

export { pathKey, type EvaluateLiteral } from './table-builder';

/** Where an option (not a file) is wrong: the messages name the option. */
const OPTIONS_AT: SourcePosition = Object.freeze({ file: 'options.db', line: 0, column: 0 });
const MAX_DB_NUMBER = 65535;
/** Rows of a symbol table that name blocks other than DBs and UDTs: nothing to read by name. */
const OTHER_BLOCKS = /^(?:OB|FB|FC|SFB|SFC|SDB|VAT|DI)\s*\d+$/i;

/** An option key as the user typed it: `Tank`, `"Tank"`, `"Motor 1"`. */
function optionKey(name: string): string {
  const t = name.trim();
  return key(t.length >= 2 && t.startsWith('"') && t.endsWith('"') ? t.slice(1, -1) : t);
}

/** What the symbol tables say: block numbers by name, UDT numbers by name, and the I/Q/M symbols. */
interface TableFacts {
  readonly dbNumbers: Map<string, { number: number; row: SymbolTableRow }>;
  readonly dbSymbols: Map<number, string>;
  readonly typeNumbers: Map<string, number>;
  readonly areaRows: SymbolTableRow[];
}

function readRows(rows: readonly SymbolTableRow[]): TableFacts {
  const facts: TableFacts = { dbNumbers: new Map(), dbSymbols: new Map(), typeNumbers: new Map(), areaRows: [] };
  for (const row of rows) {
    const address = row.address.trim();
    const db = /^DB\s*(\d+)$/i.exec(address);
    const udt = /^UDT\s*(\d+)$/i.exec(address);
    if (db) {
      facts.dbNumbers.set(key(row.name), { number: Number(db[1]), row });
      facts.dbSymbols.set(Number(db[1]), row.name);
    } else if (udt) facts.typeNumbers.set(key(row.name), Number(udt[1]));
    else if (!OTHER_BLOCKS.test(address)) facts.areaRows.push(row);
  }
  return facts;
}

function areaEntry(row: SymbolTableRow): SymbolEntry {
  let tag;
  try {
    tag = parseAddress(row.address);
  } catch (err) {
    throw new SourceError(row.at, `symbol "${row.name}": ${(err as PlcError).message}`);
  }
  if (tag.area === 'DB')
    throw new SourceError(row.at, `symbol "${row.name}": ${row.address} is in a DB; DB members come from the DB's source`);
  return Object.freeze({
    name: `"${row.name}"`,
    type: tag.isArray
      ? `ARRAY[0..${tag.count - 1}] OF ${iecElementary(tag.type, tag.stringLength)}`
      : iecElementary(tag.type, tag.stringLength),
    kind: tag.isArray ? 'array' : 'elementary',
    dataType: tag.type,
    stringLength: tag.stringLength,
    area: tag.area,
    db: null,
    byte: tag.byteOffset,
    bit: tag.type === 'BOOL' ? tag.bitOffset : null,
    size: tag.byteLength,
    address: formatAddress(tag),
    comment: row.comment,
    at: row.at,
  });
}

/** The number of each DB: its own (STEP 7), the db option's, or a symbol table's; SourceError when none, or one twice. */
function numberBlocks(dbs: readonly DataBlockDecl[], facts: TableFacts, options: CompileOptions): Map<DataBlockDecl, number> {
  const given = new Map<string, { number: number; written: string }>();
  for (const [written, number] of Object.entries(options.db ?? {})) {
    if (!Number.isInteger(number) || number < 1 || number > MAX_DB_NUMBER)
      throw new SourceError(OPTIONS_AT, `the number given for "${optionKey(written)}" is ${number}: a DB number is 1..${MAX_DB_NUMBER}`);
    given.set(optionKey(written), { number, written });
  }
  // A name no block has is the mistake to report, before any block is found without its number.
  const known = new Set(dbs.flatMap((d) => [key(d.name), ...(d.number === undefined ? [] : [key(`DB${d.number}`)])]));
  for (const [k, g] of given)
    if (!known.has(k)) {
      const limit = Math.max(1, Math.floor(k.length / 3));
      const near = dbs
        .map((d) => ({ d, by: distance(k, key(d.name), limit) }))
        .filter((c) => c.by <= limit)
        .sort((a, b) => a.by - b.by)[0];
      const list = dbs.map((d) => blockRef(d)).join(', ') || 'none';
      const hint = near ? `did you mean ${blockRef(near.d)}? DBs: ${list}` : `DBs: ${list}`;
      throw new SourceError(OPTIONS_AT, `a number is given for "${g.written}", which is not a DB of the sources (${hint})`);
    }
  const numbers = new Map<DataBlockDecl, number>();
  const byNumber = new Map<number, DataBlockDecl>();
  for (const db of dbs) {
    const names = [key(db.name), ...(db.number === undefined ? [] : [key(`DB${db.number}`)])];
    const option = names.map((n) => given.get(n)).find((g) => g !== undefined);
    const row = facts.dbNumbers.get(key(db.name));
    let number: number;
    if (db.number !== undefined) {
      if (option && option.number !== db.number)
        throw new SourceError(db.at, `DB ${blockRef(db)} is DB ${db.number} in its source, but the db option gives it ${option.number}`);
      number = db.number;
    } else if (option) number = option.number;
    else if (row) number = row.number;
    else
      throw new SourceError(
        db.at,
        `DB ${blockRef(db)} has no number: a TIA source does not carry it. Give it with the db option ` +
          `(--db ${blockRef(db)}=1 on the command line) or in a symbol table (a row "${db.name}" with the address DB 1)`,
      );
    const other = byNumber.get(number);
    if (other)
      throw new SourceError(
        db.at,
        `DB ${blockRef(db)} and DB ${blockRef(other)} (${other.at.file}:${other.at.line}:${other.at.column}) both have the number ${number}`,
      );
    byNumber.set(number, db);
    numbers.set(db, number);
  }
  return numbers;
}

/**
 * Compiles parsed declarations and symbol-table rows into a table (what
 * compileSymbols() does once the files are read). Throws SourceError.
 * Without `evaluate` the start values are checked (their paths, their
 * counts) but not evaluated: the entries carry no `initial`.
 */
export function compileDeclarations(
  blocks: readonly BlockDecl[],
  rows: readonly SymbolTableRow[],
  options: CompileOptions,
  evaluate?: EvaluateLiteral,
): SymbolTable {
  const facts = readRows(rows);
  const layouts = layoutBlocks(blocks, { typeNumbers: facts.typeNumbers });
  const numbers = numberBlocks(
    layouts.map((l) => l.decl),
    facts,
    options,
  );
  const builder = new TableBuilder(evaluate);
  const summaries: BlockSummary[] = [];
  for (const layout of layouts) {
    const decl = layout.decl;
    const db = numbers.get(decl)!;
    // A STEP 7 DB without a symbol in its source takes the symbol table's.
    const symbol = decl.number !== undefined && blockRef(decl) === `DB${decl.number}` ? facts.dbSymbols.get(decl.number) : undefined;
    const name = symbol ?? decl.name;
    builder.block(layout, symbol === undefined ? blockRef(decl) : `"${symbol}"`, db);
    summaries.push(
      Object.freeze({
        name,
        db,
        // An optimized block has no standard-access length; `optimized` is only written when true (BlockSummary).
        ...(decl.optimized ? { optimized: true, length: null } : { length: layout.length }),
        file: decl.at.file,
        ...(layout.instanceOf ? { instanceOf: layout.instanceOf } : {}),
      }),
    );
  }
  const entries = Object.freeze([...builder.finish(), ...facts.areaRows.map(areaEntry)]);
  // Refuses two entries whose names differ only by case or quotes, as TIA does.
  const index = new NameIndex(entries);
  const types = blocks.filter((b) => b.kind === 'type').map((t) => t.name);
  return Object.freeze({
    entries,
    blocks: Object.freeze(summaries),
    types: Object.freeze(types),
    lookup: (name: string) => index.lookup(name),
    suggest: (name: string, max?: number) => index.suggest(name, max),
  });
}

/** DB and UDT sources: TIA Portal's generated sources and STEP 7's AWL sources. */
const BLOCK_SOURCES = new Set(['.db', '.udt', '.scl', '.awl']);
/** Symbol tables: STEP 7's exports (.sdf, .asc, .seq) and TIA Portal's PLC tag tables (.xlsx, .csv). */
const SYMBOL_TABLES = new Set(['.sdf', '.asc', '.seq', '.xlsx', '.csv']);

function extensionOf(name: string): string {
  const dot = name.lastIndexOf('.');
  return dot < 0 ? '' : name.slice(dot).toLowerCase();
}

/**
 * Compiles a PLC's DB and UDT sources (`.db .udt .scl .awl`) and symbol
 * tables (`.sdf .asc .seq .xlsx .csv`) into a table of every member with
 * its standard-access address, found by name as users type it. Throws
 * SourceError (code INVALID_SOURCE, `file:line:column: problem`) for what
 * cannot be compiled: a syntax error, an unknown type, a block without
 * number, … (docs/symbols.md). A block with optimized access compiles: its
 * entries have byte, bit and address null (they are read by name over
 * S7CommPlus) and its summary says `optimized: true`, `length: null`.
 */
export function compileSymbols(sources: readonly SymbolSource[], options: CompileOptions = {}): SymbolTable {
  const blocks: BlockDecl[] = [];
  const rows: SymbolTableRow[] = [];
  for (const source of sources) {
    const ext = extensionOf(source.name);
    if (BLOCK_SOURCES.has(ext)) blocks.push(...parseBlockSource(source));
    else if (SYMBOL_TABLES.has(ext)) rows.push(...readSymbolTable(source));
    else
      throw new SourceError(
        { file: source.name, line: 1, column: 1 },
        `not a source this compiler reads: DB and UDT sources end in ${[...BLOCK_SOURCES].join(' ')}, symbol tables in ${[...SYMBOL_TABLES].join(' ')}`,
      );
  }
  return compileDeclarations(blocks, rows, options, literalValue);
}
