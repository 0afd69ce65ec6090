/**
 * Tags by name on the command line: `plcwire symbols` lists what DB sources
 * and symbol tables compile to (name, address, type, byte, bit; the members
 * of an optimized block without byte, bit and address); read, write
 * and watch take them with --symbols, `serve` builds its data blocks from them
 * with --source; --db numbers the blocks of TIA sources, which do not carry
 * their numbers.
 */
import { isAddress } from '../address';
import type { AnyClient, ConnectOptions } from '../connect';
import { DRIVERS } from '../drivers';
import { ValueError } from '../errors';
import { compileSymbols } from '../symbols/compile';
import type { SymbolEntry, SymbolSource, SymbolTable } from '../symbols/model';
import { expandWrite, resolveSymbol, type SymbolShape } from '../symbols/resolve';
import type { LayoutMismatchEvent, LayoutUnknownEvent } from '../types';
import { UsageError, listFlag, type ParsedArgs } from './args';
import { readInputFile } from './files';
import { EXIT, type CliIo } from './io';
import { toJson, valueFromText } from './values';

/** The value flags of tags by name, all repeatable. */
export const SYMBOL_FLAGS = ['db', 'symbols', 'source'];

const DB_EXAMPLE = 'give NAME=NUMBER, e.g. --db Tank=1 or --db "Motor 1"=2';

/**
 * The block numbers of `--db NAME=N` (repeatable): `Tank=1`, `"Tank"=1` (the
 * name as TIA quotes it) and `"Motor 1"=2` alike. A malformed one, a number
 * outside 1..65535, a name given two numbers or a number given to two names
 * is a usage error that quotes it.
 */
function dbNumbers(args: ParsedArgs): Record<string, number> {
  const out: Record<string, number> = {};
  const owner = new Map<number, string>();
  for (const raw of listFlag(args, 'db')) {
    const eq = raw.lastIndexOf('=');
    let name = (eq < 0 ? raw : raw.slice(0, eq)).trim();
    const number = eq < 0 ? '' : raw.slice(eq + 1).trim();
    if (name.length >= 2 && name.startsWith('"') && name.endsWith('"')) name = name.slice(1, -1);
    if (eq < 0 || name === '' || name.includes('"')) throw new UsageError(`--db ${JSON.stringify(raw)}: ${DB_EXAMPLE}`);
    if (!/^\d{1,5}$/.test(number) || Number(number) < 1 || Number(number) > 65535) {
      throw new UsageError(`--db ${JSON.stringify(raw)}: "${number}" is not a DB number 1..65535`);
    }
    const db = Number(number);
    const before = out[name];
    if (before !== undefined && before !== db) throw new UsageError(`--db gives "${name}" two numbers: ${before} and ${db}`);
    const other = owner.get(db);
    if (other !== undefined && other !== name) throw new UsageError(`--db gives DB${db} to two blocks: "${other}" and "${name}"`);
    out[name] = db;
    owner.set(db, name);
  }
  return out;
}

function readSource(file: string): SymbolSource {
  // Bytes: the readers tell UTF-8 from UTF-16 by the byte order mark, and .xlsx is binary.
  return { name: file, content: readInputFile(file) };
}

/**
 * Compiles the files (DB/UDT sources, symbol tables, told apart by their
 * extension as compileSymbols() does) with the --db numbers; a SourceError
 * names file:line:column.
 */
function loadSymbols(files: readonly string[], args: ParsedArgs): SymbolTable {
  const db = dbNumbers(args);
  return compileSymbols(files.map(readSource), { db });
}

/** The table of the files given with `--<flag>` (repeatable), or undefined when none was given. */
export function symbolsFlag(args: ParsedArgs, flag: 'symbols' | 'source'): SymbolTable | undefined {
  const files = listFlag(args, flag);
  if (files.length === 0) {
    if (args.lists.has('db')) throw new UsageError(`--db numbers the blocks of --${flag} files: give --${flag} too`);
    return undefined;
  }
  return loadSymbols(files, args);
}

/** The files given with `--<flag>` read but not compiled, with the --db numbers (the S7CommPlus simulator builds its own model of them), or undefined when none was given. */
export function sourceFilesFlag(args: ParsedArgs, flag: 'source'): { sources: SymbolSource[]; db: Record<string, number> } | undefined {
  const files = listFlag(args, flag);
  if (files.length === 0) {
    symbolsFlag(args, flag); // --db without --source: its usage error
    return undefined;
  }
  return { sources: files.map(readSource), db: dbNumbers(args) };
}

/** One row of `plcwire symbols --json`: byte, bit and address null for a member of an optimized block. */
interface SymbolRow {
  name: string;
  type: string;
  db: number | null;
  byte: number | null;
  bit: number | null;
  address: string | null;
}

function rowOf(e: SymbolEntry): SymbolRow {
  return { name: e.name, type: e.type, db: e.db, byte: e.byte, bit: e.bit, address: e.address };
}

/** A CSV field as RFC 4180 writes it: quoted (quotes doubled) when it holds a quote, a comma or a line break. */
function csvField(text: string): string {
  return /[",\r\n]/.test(text) ? `"${text.replace(/"/g, '""')}"` : text;
}

/** Columns padded to their widest cell, two spaces apart; the last one not padded. */
function alignedTable(rows: readonly (readonly string[])[]): string[] {
  const widths = rows[0]!.map((_, c) => Math.max(...rows.map((r) => r[c]!.length)));
  return rows.map((r) =>
    r
      .map((cell, c) => (c === r.length - 1 ? cell : cell.padEnd(widths[c]!)))
      .join('  ')
      .trimEnd(),
  );
}

/** `plcwire symbols <files...> [--db NAME=N ...] [--json | --csv]`. */
export function symbols(rest: string[], args: ParsedArgs, io: CliIo): number {
  if (rest.length === 0)
    throw new UsageError('symbols needs one or more DB sources or symbol tables (.db, .udt, .sdf, .asc, .seq, .xlsx, .csv)');
  if (args.flags.has('json') && args.flags.has('csv')) throw new UsageError('give --json or --csv, not both');
  const table = loadSymbols(rest, args);
  // Said once per block, on stderr: stdout stays the table a script reads.
  for (const b of table.blocks.filter((block) => block.optimized))
    io.stderr.write(
      `note: ${blockName(b.name, b.db)} has optimized access: its members have no byte, bit or address; ` +
        'they are read and written by name over s7plus:// (S7CommPlus), not over s7:// or fetchwrite://\n',
    );
  printSymbolRows(table, args, io);
  return EXIT.OK;
}

/** A table's rows on stdout as `plcwire symbols` prints them: aligned text, --json or --csv. */
export function printSymbolRows(table: SymbolTable, args: ParsedArgs, io: CliIo): void {
  const rows = table.entries.map(rowOf);
  if (args.flags.has('json')) {
    io.stdout.write(`${toJson(rows)}\n`);
  } else if (args.flags.has('csv')) {
    const fields = ['name', 'address', 'type', 'db', 'byte', 'bit'] as const;
    const lines = [fields.join(','), ...rows.map((r) => fields.map((f) => csvField(r[f] === null ? '' : String(r[f]))).join(','))];
    io.stdout.write(lines.map((l) => `${l}\r\n`).join(''));
  } else {
    const cells = rows.map((r) => [
      r.name,
      r.address ?? '',
      r.type,
      r.byte === null ? '' : String(r.byte),
      r.bit === null ? '' : String(r.bit),
    ]);
    for (const line of alignedTable([['name', 'address', 'type', 'byte', 'bit'], ...cells])) io.stdout.write(`${line}\n`);
  }
}

/**
 * The client options of `--symbols` and `--strict-symbols`: the compiled
 * table handed to the client, which then resolves names, reads a STRUCT as an
 * object and writes the members an object names (lib/symbols/resolve.ts):
 * the command line and the library take one code path. Undefined table: no
 * --symbols.
 */
export function symbolOptions(args: ParsedArgs): { table: SymbolTable | undefined; options: ConnectOptions } {
  const table = symbolsFlag(args, 'symbols');
  const strict = args.flags.has('strict-symbols');
  if (strict && !table) throw new UsageError('--strict-symbols checks the names of --symbols files: give --symbols too');
  return { table, options: table ? { symbols: table, ...(strict ? { strictSymbols: true } : {}) } : {} };
}

/**
 * Command-line text as the value of a whole STRUCT (or an array of them)
 * named `target`: JSON, an object keyed by member name
 * (`{"Speed": 2.5, "On": true}`) whose members are each parsed per their own
 * type as on the command line (lib/cli/values.ts), then checked as the
 * client checks the write (members the type lacks, values that do not fit),
 * before anything is sent. Undefined when `target` is no such symbol: an
 * address, or an elementary member, is parsed as its tag says.
 */
export function structValueFromText(
  client: AnyClient,
  table: SymbolTable | undefined,
  target: string,
  text: string,
): { value: unknown } | undefined {
  // Text that parses as an address is that address, as the client reads it (lib/client/base.ts).
  if (!table || isAddress(target)) return undefined;
  const resolved = resolveSymbol(table, target, (address) => client.tag(address));
  if (!resolved?.shape) return undefined;
  let json: unknown;
  try {
    json = JSON.parse(text);
  } catch {
    throw new ValueError(
      target,
      `"${text}" is not JSON (a ${resolved.entry.type} is written as an object keyed by member name, e.g. {"Speed": 1.5})`,
    );
  }
  const value = typedJson(resolved.shape, json);
  expandWrite(resolved.shape, value);
  return { value };
}

/**
 * JSON with each elementary member's value parsed per its type (a date of a
 * DTL, a bigint of a LINT); anything that does not fit the shape is left as
 * it is, for expandWrite to name.
 */
function typedJson<T>(shape: SymbolShape<T>, json: unknown): unknown {
  if (json === undefined || json === null) return json;
  if (shape.kind === 'leaf') {
    return valueFromText(shape.s7, typeof json === 'string' ? json : toJson(json));
  }
  if (shape.kind === 'array') {
    if (!Array.isArray(json) || json.length !== shape.elements.length) return json;
    return json.map((element: unknown, i) => typedJson(shape.elements[i]!, element));
  }
  if (typeof json !== 'object' || Array.isArray(json)) return json;
  return Object.fromEntries(
    Object.entries(json as Record<string, unknown>).map(([key, value]) => {
      const member = shape.members.get(key);
      return [key, member ? typedJson(member, value) : value];
    }),
  );
}

/** `DB1 "Tank"`; a STEP 7 block without symbol just `DB10`. */
function blockName(block: string, db: number): string {
  return block === `DB${db}` ? block : `DB${db} "${block}"`;
}

/**
 * Tells on stderr what the client's layout check finds (lib/symbols/layout-check.ts):
 * a data block whose length in the PLC is not what the sources declare, as a
 * warning (the client says it once per connect), and a PLC that cannot tell,
 * as a one-line note.
 */
export function reportLayout(client: AnyClient, io: CliIo, strict: boolean): void {
  const consequence = strict
    ? 'reads and writes by name in it are refused (--strict-symbols)'
    : "names in it are read at the offsets of the sources and may show other members' bytes";
  client.on('layoutMismatch', (e: LayoutMismatchEvent) => {
    const which = blockName(e.block, e.db);
    const finding =
      e.actual === null
        ? `${which} is not in the PLC, the sources declare it with ${e.declared} bytes`
        : `${which} is ${e.actual} bytes in the PLC, the sources declare ${e.declared}`;
    io.stderr.write(`warning: ${finding}: ${consequence}; recompile the sources or download the block\n`);
  });
  client.on('layoutUnknown', (e: LayoutUnknownEvent) => {
    io.stderr.write(`note: ${layoutUnknownText(DRIVERS[client.protocol].noBlockLength, e)}\n`);
  });
}

/**
 * The note for a PLC that cannot tell its blocks' lengths, in a user's words:
 * what it means (a changed DB is not detected) and what to do (export the
 * sources again after every change). An S7-1200/1500 answers block info
 * "function not implemented" (NOT_SUPPORTED); a protocol without such a
 * service says so in its registry entry (noBlockLength: FETCH/WRITE). Any other reason (a protection level, say) is named as the client
 * gives it.
 */
function layoutUnknownText(noBlockLength: string | undefined, e: LayoutUnknownEvent): string {
  const blocks = e.checks.map((c) => blockName(c.block, c.db)).join(', ');
  const advice = `so a DB changed in the PLC's project (${blocks}) is not detected here; export the sources again after every change`;
  if (noBlockLength !== undefined) return `${noBlockLength}, ${advice}`;
  if (e.error.code === 'NOT_SUPPORTED') {
    return `this CPU does not report the length of its data blocks (S7-1200 and S7-1500 do not), ${advice.replace("the PLC's project", 'TIA Portal')}`;
  }
  return `the length of ${blocks} could not be checked against the sources (${e.error.message}); names are read at the offsets of the sources`;
}
