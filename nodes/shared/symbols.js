'use strict';
/**
 * Tags by name on the Node-RED side: the symbol sources a connection node
 * keeps in the flow (`symbolSources: [{ name, content, encoding? }]`, `.xlsx`
 * as base64; `dbNumbers: [{ block, db }]`), compiled with the library's
 * compileSymbols(); what the editor is told about a compiled table; and how a
 * tag row is resolved against one (the same answer for the dialogs and the
 * red triangle). No Node-RED and no sockets.
 */
const crypto = require('node:crypto');
const plc = require('../..');

/** Compile errors given to the editor and written to the log at most. */
const MAX_ERRORS = 50;
/** Compiled tables kept for the editor's questions (the same sources are asked about while a dialog is open). */
const CACHE_SIZE = 8;

/** The flow's sources as compileSymbols() takes them: base64 content as bytes, entries without a name dropped. */
function sourcesOf(list) {
  if (!Array.isArray(list)) return [];
  const out = [];
  for (const s of list) {
    if (!s || typeof s !== 'object' || !String(s.name || '').trim()) continue;
    const name = String(s.name).trim();
    const text = typeof s.content === 'string' ? s.content : '';
    out.push({ name, content: s.encoding === 'base64' ? new Uint8Array(Buffer.from(text, 'base64')) : text });
  }
  return out;
}

/** `[{ block, db }]` as compileSymbols()' `db` option; rows without a block or a DB number from 1 to 65535 are dropped. */
function dbNumbersOf(list) {
  const out = {};
  if (!Array.isArray(list)) return out;
  for (const row of list) {
    const block = String((row && row.block) || '').trim();
    const db = Number(row && row.db);
    if (block && Number.isInteger(db) && db >= 1 && db <= 65535) out[block] = db;
  }
  return out;
}

/** Whether a connection's configuration names any source. */
function hasSources(config) {
  return sourcesOf(config && config.symbolSources).length > 0;
}

/**
 * A fingerprint of what a client's symbols are made of (sources, numbers,
 * strictness): two connection nodes share a client only when theirs agree,
 * and the editor's questions are cached by it. '' without sources.
 */
function symbolsKey(config) {
  const sources = (config && config.symbolSources) || [];
  if (!hasSources(config)) return '';
  const db = dbNumbersOf(config.dbNumbers);
  const plain = sourcesOf(sources).map((s) => [
    s.name,
    typeof s.content === 'string' ? s.content : Buffer.from(s.content).toString('base64'),
  ]);
  const numbers = Object.keys(db)
    .sort()
    .map((k) => [k, db[k]]);
  return crypto
    .createHash('sha256')
    .update(JSON.stringify([plain, numbers, !!config.strictSymbols]))
    .digest('hex');
}

/** A compile error as plain data: file, line, column when the library knows them (SourceError). */
function problemOf(err) {
  const p = { code: (err && err.code) || 'INVALID_SOURCE', message: err && err.message ? err.message : String(err) };
  if (err && typeof err.file === 'string') Object.assign(p, { file: err.file, line: err.line, column: err.column });
  return p;
}

/** The errors a failed compile reports: every one of an AggregateError-like `errors` list, else the error itself. */
function problemsOf(err) {
  const list = err && Array.isArray(err.errors) && err.errors.length > 0 ? err.errors : [err];
  return list.slice(0, MAX_ERRORS).map(problemOf);
}

/**
 * Compiles a connection's sources: { table } or { problems } (a compile that
 * fails gives no table; the connection then works with absolute addresses).
 * { } without sources.
 */
function compile(config) {
  const sources = sourcesOf(config && config.symbolSources);
  if (sources.length === 0) return {};
  try {
    return { table: plc.compileSymbols(sources, { db: dbNumbersOf(config.dbNumbers) }) };
  } catch (err) {
    return { problems: problemsOf(err) };
  }
}

/** compile() with the last few answers kept by symbolsKey (the editor asks about one set of sources many times). */
const cache = new Map();
function compileCached(config) {
  const key = symbolsKey(config);
  if (!key) return {};
  let result = cache.get(key);
  if (result) {
    cache.delete(key); // most recently used last
  } else {
    result = compile(config);
    if (cache.size >= CACHE_SIZE) cache.delete(cache.keys().next().value);
  }
  cache.set(key, result);
  return result;
}

/** An entry as the editor lists it: what completion, the row's hint and "add all members" need. */
function entryInfo(e) {
  const out = { name: e.name, address: e.address, type: e.type, kind: e.kind };
  if (e.children && e.children.length > 0) out.children = e.children;
  return out;
}

/** What the editor is told about a compile: { blocks, entries, types, errors }. */
function describe(result) {
  if (!result.table) return { blocks: [], entries: [], types: [], errors: result.problems || [] };
  const { table } = result;
  return { blocks: table.blocks.map((b) => ({ ...b })), entries: table.entries.map(entryInfo), types: [...table.types], errors: [] };
}

/**
 * A tag row's address, as the client will take it (docs/symbols.md, "Reading
 * and writing by name": text that parses as an absolute address is that
 * address; anything else is looked up in the table). `parse` is the
 * protocol's address parser, `named` the parser of a client given the table
 * (its reach checks and its words for an unknown name), undefined without a
 * URL. An absolute address → { ok, type, count }; a name → { ok, symbol,
 * address, type, kind } (the entry's own name, absolute address and IEC
 * type); neither → { ok: false, code, message }.
 */
function resolveAddress(address, parse, table, named) {
  let asAddress;
  try {
    const tag = parse(address);
    return { ok: true, type: tag.type, count: tag.count };
  } catch (err) {
    asAddress = err;
  }
  const failed = (err) => ({ ok: false, code: err.code || 'INVALID_ADDRESS', message: err.message });
  if (!table) return failed(asAddress);
  if (named) {
    try {
      named(address);
    } catch (err) {
      return failed(err);
    }
  }
  const entry = table.lookup(address);
  if (entry) return { ok: true, symbol: entry.name, address: entry.address, type: entry.type, kind: entry.kind };
  const close = table.suggest(address);
  const hint = close.length > 0 ? `; did you mean ${close.join(', ')}?` : '';
  return { ok: false, code: 'INVALID_ADDRESS', message: `unknown symbol ${address}${hint} (nor an address: ${asAddress.message})` };
}

module.exports = {
  symbolsKey,
  compile,
  compileCached,
  describe,
  resolveAddress,
};
