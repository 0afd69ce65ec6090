/**
 * Tags by name on the command line: `plcwire symbols` lists what DB sources
 * and symbol tables compile to (name, address, type, byte, bit); read, write
 * and watch take them with --symbols, `serve` builds its data blocks from them
 * with --source; --db numbers the blocks of TIA sources, which do not carry
 * their numbers.
 */
import { readFileSync } from 'node:fs';
import { parseAddress } from '../address';
import { PlcError, ValueError, type TagResult } from '../errors';
import { compileDeclarations } from '../symbols/compile';
import { literalValue } from '../symbols/literals';
import { parseBlockSource } from '../symbols/source-parser';
import { readSymbolTable } from '../symbols/symbol-files';
import type { SymbolEntry, SymbolSource, SymbolTable } from '../symbols/model';
import type { PlcValue, Tag } from '../types';
import { validateValue } from '../values';
import { UsageError, listFlag, type ParsedArgs } from './args';
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

/** Symbol table exports (lib/symbols/symbol-files.ts); any other file is a DB/UDT source. */
const SYMBOL_TABLE = /\.(sdf|asc|seq|xlsx|csv)$/i;

function readSource(file: string): SymbolSource {
  try {
    // Bytes: the readers tell UTF-8 from UTF-16 by the byte order mark, and .xlsx is binary.
    return { name: file, content: readFileSync(file) };
  } catch (err) {
    throw new UsageError(`cannot read ${file}: ${(err as NodeJS.ErrnoException).code ?? (err as Error).message}`);
  }
}

/** Compiles the files (DB/UDT sources, symbol tables) with the --db numbers; a SourceError names file:line:column. */
function loadSymbols(files: readonly string[], args: ParsedArgs): SymbolTable {
  const db = dbNumbers(args);
  const sources = files.map(readSource);
  const tables = sources.filter((s) => SYMBOL_TABLE.test(s.name));
  const blocks = sources.filter((s) => !SYMBOL_TABLE.test(s.name)).flatMap((s) => parseBlockSource(s));
  return compileDeclarations(blocks, tables.flatMap(readSymbolTable), { db }, literalValue);
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

/** One row of `plcwire symbols --json`. */
interface SymbolRow {
  name: string;
  type: string;
  db: number | null;
  byte: number;
  bit: number | null;
  address: string;
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
  const rows = loadSymbols(rest, args).entries.map(rowOf);
  if (args.flags.has('json')) {
    io.stdout.write(`${toJson(rows)}\n`);
  } else if (args.flags.has('csv')) {
    const fields = ['name', 'address', 'type', 'db', 'byte', 'bit'] as const;
    const lines = [fields.join(','), ...rows.map((r) => fields.map((f) => csvField(r[f] === null ? '' : String(r[f]))).join(','))];
    io.stdout.write(lines.map((l) => `${l}\r\n`).join(''));
  } else {
    const cells = rows.map((r) => [r.name, r.address, r.type, String(r.byte), r.bit === null ? '' : String(r.bit)]);
    for (const line of alignedTable([['name', 'address', 'type', 'byte', 'bit'], ...cells])) io.stdout.write(`${line}\n`);
  }
  return EXIT.OK;
}

/**
 * Checks every target before connecting: an address that parses, or a name
 * of the table. Anything else is an INVALID_ADDRESS naming it, with the
 * table's closest names; nothing is sent. Returns the entries of the names.
 */
export function checkTargets(
  table: SymbolTable | undefined,
  targets: readonly string[],
  parse: (address: string) => unknown,
): Map<string, SymbolEntry> {
  const named = new Map<string, SymbolEntry>();
  for (const target of targets) {
    let problem: unknown;
    try {
      parse(target);
      continue;
    } catch (err) {
      if (!table) throw err;
      problem = err;
    }
    const entry = table.lookup(target);
    if (entry) {
      named.set(target, entry);
      continue;
    }
    const close = table.suggest(target);
    const hint = close.length > 0 ? ` (did you mean ${close.join(', ')}?)` : '';
    throw new PlcError('INVALID_ADDRESS', `"${target}" is no symbol of the --symbols files and no address${hint}`, {
      tag: target,
      cause: problem,
    });
  }
  return named;
}

/** A member's name within its parent: `Speed` of `"Tank".Motor.Speed`, unquoted. */
function memberKey(parent: SymbolEntry, child: string): string {
  const rest = child.slice(parent.name.length + 1);
  return rest.length >= 2 && rest.startsWith('"') && rest.endsWith('"') ? rest.slice(1, -1) : rest;
}

/** An elementary member (or an array of them) as a tag of its address, named as the user wrote it. */
function leafTag(entry: SymbolEntry, label: string): Tag {
  return { ...parseAddress(entry.address), address: label };
}

/** Text as a value of an elementary member or an array of them, checked against its type (a ValueError naming `label`). */
function leafValue(entry: SymbolEntry, label: string, text: string): unknown {
  const tag = leafTag(entry, label);
  const value = valueFromText(tag, text);
  validateValue(tag, value);
  return value;
}

/**
 * Command-line text as a value of a symbol's type, checked against it before
 * anything is sent: an elementary member or an array of them as for an
 * address (lib/cli/values.ts); a STRUCT (or an array of them) as JSON, an
 * object keyed by member name (`{"Speed": 2.5, "On": true}`) whose members
 * are each parsed per their own type. Errors name the symbol as the user
 * wrote it (`label`), and a member the struct lacks lists its members.
 */
export function symbolValueFromText(table: SymbolTable, entry: SymbolEntry, label: string, text: string): unknown {
  if (entry.dataType !== undefined) return leafValue(entry, label, text);
  let json: unknown;
  try {
    json = JSON.parse(text);
  } catch {
    throw new ValueError(
      label,
      `"${text}" is not JSON (a ${entry.type} is written as an object keyed by member name, e.g. {"Speed": 1.5})`,
    );
  }
  return fromJson(table, entry, label, json);
}

function fromJson(table: SymbolTable, entry: SymbolEntry, label: string, json: unknown): unknown {
  if (entry.dataType !== undefined) return leafValue(entry, label, typeof json === 'string' ? json : toJson(json));
  const children = (entry.children ?? []).map((name) => table.lookup(name)!);
  if (entry.kind === 'array') {
    if (!Array.isArray(json) || json.length !== children.length) {
      throw new ValueError(label, `expected a JSON array of ${children.length} elements for ${entry.type}`);
    }
    return json.map((v: unknown, i) => fromJson(table, children[i]!, `${label}[${i}]`, v));
  }
  if (typeof json !== 'object' || json === null || Array.isArray(json)) {
    throw new ValueError(label, `expected an object keyed by member name for ${entry.type}`);
  }
  const members = new Map(children.map((c) => [memberKey(entry, c.name), c]));
  const out: Record<string, unknown> = {};
  for (const [key, value] of Object.entries(json as Record<string, unknown>)) {
    const member = members.get(key);
    if (!member) throw new ValueError(label, `it has no member "${key}" (members: ${[...members.keys()].join(', ')})`);
    out[key] = fromJson(table, member, `${label}.${key}`, value);
  }
  return out;
}

/** The entries a target is read and written through: itself when it has a data type, else its members' (recursively). */
function leaves(table: SymbolTable, entry: SymbolEntry): SymbolEntry[] {
  if (entry.dataType !== undefined) return [entry];
  return (entry.children ?? []).flatMap((name) => leaves(table, table.lookup(name)!));
}

/** The addresses to read for the targets: an address as given, a name through its entry (a STRUCT: every member's). */
export function addressesOf(table: SymbolTable | undefined, targets: readonly string[], named: ReadonlyMap<string, SymbolEntry>): string[] {
  const out = new Set<string>();
  for (const t of targets) {
    const entry = named.get(t);
    if (!entry) out.add(t);
    else for (const leaf of leaves(table!, entry)) out.add(leaf.address);
  }
  return [...out];
}

/** A target's value from the results by address: a STRUCT as an object keyed by member name, an array of them as an array; the first failed member's error. */
export function resultOf(
  table: SymbolTable | undefined,
  target: string,
  named: ReadonlyMap<string, SymbolEntry>,
  results: Readonly<Record<string, TagResult<PlcValue>>>,
): TagResult<unknown> {
  const entry = named.get(target);
  if (!entry) return results[target]!;
  const build = (e: SymbolEntry): unknown => {
    if (e.dataType !== undefined) {
      const r = results[e.address]!;
      if (!r.ok) throw r.error;
      return r.value;
    }
    const children = (e.children ?? []).map((name) => table!.lookup(name)!);
    if (e.kind === 'array') return children.map(build);
    return Object.fromEntries(children.map((c) => [memberKey(e, c.name), build(c)]));
  };
  try {
    return { ok: true, value: build(entry) };
  } catch (err) {
    return { ok: false, error: err as PlcError };
  }
}

/** The address → value pairs a write of `value` (as symbolValueFromText gives it) to a target sends: a STRUCT's given members each at their address. */
export function writesOf(table: SymbolTable, entry: SymbolEntry, value: unknown): [string, unknown][] {
  if (entry.dataType !== undefined) return [[entry.address, value]];
  const children = (entry.children ?? []).map((name) => table.lookup(name)!);
  if (entry.kind === 'array') return children.flatMap((c, i) => writesOf(table, c, (value as unknown[])[i]));
  const given = value as Record<string, unknown>;
  return children.flatMap((c) => {
    const key = memberKey(entry, c.name);
    return Object.prototype.hasOwnProperty.call(given, key) ? writesOf(table, c, given[key]) : [];
  });
}
