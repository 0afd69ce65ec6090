/**
 * What the Node-RED editor asks the runtime about a connection and its tag
 * tables, answered by the library (the connection node only serves them,
 * nodes/connection.js): addresses and names checked with the URL's own
 * parser and the connection's sources (validate), CSV import and export, and
 * URL ⇄ fields for the dialog. Requests are the editor's JSON bodies, loose
 * by nature: every field is read defensively. No Node-RED.
 */
import { parseAddress } from '../address';
import { createClient } from '../connect';
import { toPlcError } from '../errors';
import type { SymbolTable } from '../symbols';
import type { DriverTag } from '../link/driver';
import { duplicateNames, tagsFromCsv, tagsToCsv, type TagRow, type TagTableProblem } from '../tags/table';
import { endpointKey, formatUrl, parseUrl, type Endpoint } from '../url';
import { checkAddresses, type NameAnswer } from './name-check';
import { compileCached, type SymbolConfig } from './symbol-config';
import type { UrlFields } from './url-field-table';
import { urlOfFields, type FieldsProblem, type FieldsUrl } from './url-fields';
import { fieldsOf, looseFieldsOf, placeholdersOf, presetFields } from './url-fields-read';

type Body = Record<string, unknown>;
/** What the address parsers of every protocol give (an S7 Tag, a FreeportTag): what validate and the CSV import read. */
type Parse = (address: string) => DriverTag & { type: string; count: number; isArray: boolean; stringLength: number };

/** Addresses one validate question may ask about at most (a tag table of a node is far smaller). */
const MAX_ADDRESSES = 1000;
/** Rows the editor may ask to export at most. */
const MAX_EXPORT_ROWS = 100000;

/** An invalid URL as the editor is told it. */
export type UrlProblem = { ok: false; code: string; message: string };

const problemOf = (err: unknown): UrlProblem => {
  const e = toPlcError(err, 'INVALID_URL');
  return { ok: false, code: e.code, message: e.message };
};

const textOf = (value: unknown): string => (typeof value === 'string' ? value : value == null ? '' : String(value as number));

/**
 * The address parser of a URL's protocol (the client's own, which knows the
 * URL's settings), or the S7 parser without a URL. `done()` frees it.
 * { error } when the URL itself is invalid.
 */
function parserFor(url: string): { parse: Parse; done: () => void } | { error: UrlProblem } {
  if (!url) return { parse: parseAddress as Parse, done: () => undefined };
  try {
    const client = createClient(url);
    return { parse: (a) => client.tag(a), done: () => void client.close().catch(() => undefined) };
  } catch (err) {
    return { error: problemOf(err) };
  }
}

/** The sources of a request body, the way a connection node's config carries them. */
export function symbolConfig(body: Body): SymbolConfig {
  return { symbolSources: body.symbolSources, dbNumbers: body.dbNumbers, strictSymbols: false };
}

export interface ValidateAnswer {
  url: { ok: true } | UrlProblem;
  symbols?: { ok: true } | { ok: false; errors: { code?: string; message: string }[] };
  results: Record<string, NameAnswer>;
}

/**
 * POST plcwire/validate { url?, addresses, symbolSources?, dbNumbers? }: each
 * address with the URL's parser and the sources' table; a name the URL's
 * client reads by name (s7plus://) against the sources, else the PLC's table
 * (`browse`, asked only when such a name is there; lib/flows/name-check.ts).
 */
export async function validateAnswer(body: Body, browse?: (url: string) => Promise<SymbolTable>): Promise<ValidateAnswer> {
  const url = textOf(body.url);
  const addresses = Array.isArray(body.addresses) ? body.addresses.slice(0, MAX_ADDRESSES).map(textOf) : [];
  const parser = parserFor(url);
  if ('error' in parser) return { url: parser.error, results: {} };
  const compiled = compileCached(symbolConfig(body));
  let symbols: ValidateAnswer['symbols'] = compiled.problems ? { ok: false, errors: compiled.problems } : { ok: true };
  // A protocol may refuse symbols (freeport): then names are no tags of this connection.
  let table = compiled.table;
  if (table && url) {
    try {
      void createClient(url, { symbols: table })
        .close()
        .catch(() => undefined);
    } catch (err) {
      const e = toPlcError(err, 'NOT_SUPPORTED');
      symbols = { ok: false, errors: [{ code: e.code, message: e.message }] };
      table = undefined;
    }
  }
  try {
    const results = await checkAddresses(addresses, {
      parse: parser.parse,
      table,
      ...(url && browse ? { browse: () => browse(url) } : {}),
    });
    return { url: { ok: true }, symbols, results };
  } finally {
    parser.done();
  }
}

/**
 * POST plcwire/csv { url?, text } → { url, tags, problems }: the tag table of
 * a CSV text, a type column checked with the parser of the URL's protocol
 * (the S7 parser when the URL is invalid).
 */
export function csvImportAnswer(body: Body): { url: { ok: true } | UrlProblem; tags: TagRow[]; problems: TagTableProblem[] } {
  let parser = parserFor(textOf(body.url));
  const url = 'error' in parser ? parser.error : ({ ok: true } as const);
  if ('error' in parser) parser = parserFor('') as { parse: Parse; done: () => void };
  try {
    return { url, ...tagsFromCsv(textOf(body.text), parser.parse) };
  } finally {
    parser.done();
  }
}

/** A request's `tags: [{ name, address }]` (at most MAX_EXPORT_ROWS; anything else is an empty row). */
function tagRowsOf(body: Body): TagRow[] {
  const rows = Array.isArray(body.tags) ? (body.tags as unknown[]).slice(0, MAX_EXPORT_ROWS) : [];
  return rows.map((t) => {
    const row = (t && typeof t === 'object' ? t : {}) as Body;
    return { name: textOf(row.name), address: textOf(row.address) };
  });
}

/** POST plcwire/csv/export { tags: [{ name, address }] } → { csv }, the form csvImportAnswer reads back. */
export function csvExportAnswer(body: Body): { csv: string } {
  return { csv: tagsToCsv(tagRowsOf(body)) };
}

/**
 * POST plcwire/duplicates { tags: [{ name, address }] } → { duplicates: [{ name, rows }] }:
 * the names given to more than one row (a row without a name is known by its
 * address), with those rows' indexes, counted as the runtime counts them.
 */
export function duplicatesAnswer(body: Body): { duplicates: { name: string; rows: number[] }[] } {
  return { duplicates: duplicateNames(tagRowsOf(body)) };
}

/**
 * POST plcwire/url, the connection dialog's URL (lib/flows/url-fields.ts):
 * - { url } | { endpoint } → { ok, url, endpoint, key, fields }: a URL parsed
 *   into the dialog's fields (and written in the library's form);
 * - { fields, kept? } → { ok, url, endpoint, key, placeholders } | { ok: false, code, message,
 *   field?, url }: the URL the fields make (every scheme's own format and
 *   defaults; `kept`'s parameters no field writes kept), or the parser's
 *   error with the field it is about;
 *   A URL the parser refuses answers its message with the fields as they
 *   stand (looseFieldsOf) and the field to fix;
 * - { preset } → { ok, fields }: the fields a CPU preset sets.
 */
export function urlAnswer(body: Body): UrlAnswer {
  if (body.preset !== undefined) {
    const fields = presetFields(textOf(body.preset));
    return fields ? { ok: true, fields } : { ok: false, code: 'INVALID_URL', message: `no CPU preset "${textOf(body.preset)}"` };
  }
  if (body.fields && typeof body.fields === 'object') return urlOfFields(body.fields as UrlFields, textOf(body.kept));
  try {
    const endpoint = body.endpoint ? parseUrl(formatUrl(body.endpoint as Endpoint)) : parseUrl(textOf(body.url));
    const fields = fieldsOf(endpoint);
    return {
      ok: true,
      url: formatUrl(endpoint),
      endpoint,
      key: endpointKey(endpoint),
      fields,
      placeholders: placeholdersOf(textOf(fields.protocol)),
    };
  } catch (err) {
    // A URL the parser refuses still gives the dialog its fields, and the one to fix.
    const fields = body.endpoint ? undefined : looseFieldsOf(textOf(body.url));
    if (!fields) return problemOf(err);
    const field = urlOfFields(fields, textOf(body.url));
    const blamed = !field.ok && field.field ? { field: field.field } : {};
    return { ...problemOf(err), ...blamed, fields, placeholders: placeholdersOf(textOf(fields.protocol)) };
  }
}

type UrlAnswer =
  | { ok: true; url: string; endpoint: Endpoint; key: string; fields: UrlFields; placeholders: UrlFields }
  | FieldsUrl
  | FieldsProblem
  | { ok: true; fields: UrlFields }
  | (UrlProblem & { field?: string; fields?: UrlFields; placeholders?: UrlFields });
