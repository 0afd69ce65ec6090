/**
 * Tags by name on the Node-RED side: the symbol sources a connection node
 * keeps in the flow (`symbolSources: [{ name, content, encoding? }]`, `.xlsx`
 * as base64; `dbNumbers: [{ block, db }]`), compiled with compileSymbols();
 * what the editor is told about a compiled table; and how a tag row is
 * resolved against one (the same answer for the dialogs and the red
 * triangle). No Node-RED and no sockets.
 */
import { createHash } from 'node:crypto';
import type { DriverTag } from '../link/driver';
import { compileSymbols } from '../symbols';
import { addressOrSymbol } from '../symbols/resolve';
import type { BlockSummary, SymbolEntry, SymbolSource, SymbolTable } from '../symbols';

/** Compile errors given to the editor and written to the log at most. */
const MAX_ERRORS = 50;
/** Compiled tables kept for the editor's questions (the same sources are asked about while a dialog is open). */
const CACHE_SIZE = 8;

/** The symbol part of a connection node's configuration, as the flow (or an editor request) carries it. */
export interface SymbolConfig {
  symbolSources?: unknown;
  dbNumbers?: unknown;
  strictSymbols?: unknown;
}

/** A compile error as plain data: file, line, column when the library knows them (SourceError). */
interface SymbolProblem {
  code: string;
  message: string;
  file?: string;
  line?: number;
  column?: number;
}

/** What compile() gives: a table, or why there is none; neither without sources. */
export interface CompiledSymbols {
  table?: SymbolTable;
  problems?: SymbolProblem[];
}

type Loose = Record<string, unknown> | null | undefined;

/** A flow value as String() makes it a string (the flow's JSON can hold anything). */
const asText = (value: unknown): string => String(value);

/** The flow's sources as compileSymbols() takes them: base64 content as bytes, entries without a name dropped. */
function sourcesOf(list: unknown): SymbolSource[] {
  if (!Array.isArray(list)) return [];
  const out: SymbolSource[] = [];
  for (const s of list as Loose[]) {
    if (!s || typeof s !== 'object' || !asText(s.name || '').trim()) continue;
    const name = asText(s.name).trim();
    const text = typeof s.content === 'string' ? s.content : '';
    out.push({ name, content: s.encoding === 'base64' ? new Uint8Array(Buffer.from(text, 'base64')) : text });
  }
  return out;
}

/** `[{ block, db }]` as compileSymbols()' `db` option; rows without a block or a DB number from 1 to 65535 are dropped. */
function dbNumbersOf(list: unknown): Record<string, number> {
  const out: Record<string, number> = {};
  if (!Array.isArray(list)) return out;
  for (const row of list as Loose[]) {
    const block = asText((row && row.block) || '').trim();
    const db = Number(row && row.db);
    if (block && Number.isInteger(db) && db >= 1 && db <= 65535) out[block] = db;
  }
  return out;
}

/**
 * A fingerprint of what a client's symbols are made of (sources, numbers,
 * strictness): two connection nodes share a client only when theirs agree,
 * and the editor's questions are cached by it. '' without sources.
 */
export function symbolsKey(config: SymbolConfig | null | undefined): string {
  const sources = sourcesOf(config && config.symbolSources);
  if (!config || sources.length === 0) return '';
  const db = dbNumbersOf(config.dbNumbers);
  const plain = sources.map((s) => [s.name, typeof s.content === 'string' ? s.content : Buffer.from(s.content).toString('base64')]);
  const numbers = Object.keys(db)
    .sort()
    .map((k) => [k, db[k]]);
  return createHash('sha256')
    .update(JSON.stringify([plain, numbers, !!config.strictSymbols]))
    .digest('hex');
}

function problemOf(err: unknown): SymbolProblem {
  const e = err as Partial<{ code: string; message: string; file: unknown; line: number; column: number }> | null | undefined;
  const p: SymbolProblem = { code: (e && e.code) || 'INVALID_SOURCE', message: e && e.message ? e.message : String(err) };
  if (e && typeof e.file === 'string') Object.assign(p, { file: e.file, line: e.line, column: e.column });
  return p;
}

/** The errors a failed compile reports: every one of an AggregateError-like `errors` list, else the error itself. */
function problemsOf(err: unknown): SymbolProblem[] {
  const errors = (err as { errors?: unknown } | null | undefined)?.errors;
  const list = Array.isArray(errors) && errors.length > 0 ? (errors as unknown[]) : [err];
  return list.slice(0, MAX_ERRORS).map(problemOf);
}

/**
 * Compiles a connection's sources: { table } or { problems } (a compile that
 * fails gives no table; the connection then works with absolute addresses).
 * { } without sources.
 */
export function compile(config: SymbolConfig | null | undefined): CompiledSymbols {
  const sources = sourcesOf(config && config.symbolSources);
  if (!config || sources.length === 0) return {};
  try {
    return { table: compileSymbols(sources, { db: dbNumbersOf(config.dbNumbers) }) };
  } catch (err) {
    return { problems: problemsOf(err) };
  }
}

const cache = new Map<string, CompiledSymbols>();

/** compile() with the last few answers kept by symbolsKey (the editor asks about one set of sources many times). */
export function compileCached(config: SymbolConfig | null | undefined): CompiledSymbols {
  const key = symbolsKey(config);
  if (!key) return {};
  let result = cache.get(key);
  if (result) {
    cache.delete(key); // most recently used last
  } else {
    result = compile(config);
    if (cache.size >= CACHE_SIZE) cache.delete(cache.keys().next().value!);
  }
  cache.set(key, result);
  return result;
}

/** An entry as the editor lists it: what completion, the row's hint and "add all members" need. */
interface EntryInfo {
  name: string;
  /** Null for a member of an optimized block: it is read by name (s7plus://), not by address. */
  address: string | null;
  type: string;
  kind: SymbolEntry['kind'];
  children?: readonly string[];
}

/** What the editor is told about a compile. */
export interface SymbolsDescription {
  blocks: BlockSummary[];
  entries: EntryInfo[];
  types: string[];
  errors: SymbolProblem[];
}

function entryInfo(e: SymbolEntry): EntryInfo {
  const out: EntryInfo = { name: e.name, address: e.address, type: e.type, kind: e.kind };
  if (e.children && e.children.length > 0) out.children = e.children;
  return out;
}

/** What the editor is told about a compile: { blocks, entries, types, errors }. */
export function describe(result: CompiledSymbols): SymbolsDescription {
  if (!result.table) return { blocks: [], entries: [], types: [], errors: result.problems || [] };
  const { table } = result;
  return { blocks: table.blocks.map((b) => ({ ...b })), entries: table.entries.map(entryInfo), types: [...table.types], errors: [] };
}

/** A tag row's address as resolveAddress() answers for it. */
export type AddressAnswer =
  | { ok: true; type: string; count: number }
  | { ok: true; symbol: string; address: string | null; type: string; kind: SymbolEntry['kind'] }
  | { ok: false; code: string; message: string };

/**
 * A tag row's address, as the client will take it: by addressOrSymbol, the
 * client's own rule and words (docs/symbols.md, "Addresses first"). `parse`
 * is the protocol's address parser (the URL's client, with its reach
 * checks). An absolute address → { ok, type, count }; a name → { ok, symbol,
 * address, type, kind } (the entry's own name, absolute address and IEC
 * type); neither → { ok: false, code, message }.
 */
export function resolveAddress(
  address: string,
  parse: (address: string) => DriverTag & { type: string; count: number },
  table: SymbolTable | undefined,
): AddressAnswer {
  try {
    const { tag, symbol } = addressOrSymbol(address, parse, table);
    if (!symbol) return { ok: true, type: tag.type, count: tag.count };
    const { entry } = symbol;
    return { ok: true, symbol: entry.name, address: entry.address, type: entry.type, kind: entry.kind };
  } catch (err) {
    const e = err as { code?: string; message: string };
    return { ok: false, code: e.code || 'INVALID_ADDRESS', message: e.message };
  }
}
