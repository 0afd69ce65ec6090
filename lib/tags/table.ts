/**
 * Tag tables as people keep them in spreadsheets: rows of name, address and
 * an optional type, imported from and exported to CSV. Pure functions; the
 * address parser is passed in, so each protocol checks its own addresses.
 */
import { parseAddress, parseTypeSpec, type TypeSpec } from '../address';

/** One row of a tag table; an empty name means "named by its address". */
export interface TagRow {
  name: string;
  address: string;
}

/** What an address parser tells about an address (S7's parseAddress, parseFreeportAddress, client.tag). */
interface ParsedShape {
  readonly type: string;
  readonly count: number;
  readonly isArray: boolean;
  readonly stringLength: number;
}

export type AddressParser = (address: string) => ParsedShape;

export type TagTableProblemCode = 'DUPLICATE_NAME' | 'TYPE_MISMATCH' | 'INVALID_TYPE';

/** Something in an imported table worth telling the user; the row is imported all the same. */
export interface TagTableProblem {
  /** Line of the CSV text the row starts on (1 = the first line). */
  line: number;
  code: TagTableProblemCode;
  /** The row's name (its address when it has none). */
  name: string;
  address: string;
  message: string;
}

export interface CsvImport {
  tags: TagRow[];
  problems: TagTableProblem[];
}

interface CsvRecord {
  line: number;
  fields: string[];
}

/** The name a row is known by: its name, or its address when it has none. */
function tagName(row: TagRow): string {
  return String(row.name ?? '').trim() || String(row.address ?? '').trim();
}

/** Each name given to more than one row, with the indexes of those rows. */
export function duplicateNames(rows: readonly TagRow[]): { name: string; rows: number[] }[] {
  const seen = new Map<string, number[]>();
  rows.forEach((row, i) => {
    const name = tagName(row);
    if (name) seen.set(name, [...(seen.get(name) ?? []), i]);
  });
  return [...seen].filter(([, at]) => at.length > 1).map(([name, at]) => ({ name, rows: at }));
}

/**
 * The separator of a CSV text, from its first line: a semicolon (spreadsheets
 * in German locales; it never occurs in an address) or a tab when the line
 * has one outside quotes, else a comma.
 */
function separatorOf(text: string): string {
  const firstLine = (text.split(/\r?\n/, 1)[0] ?? '').replace(/"[^"]*"/g, '');
  if (firstLine.includes(';')) return ';';
  if (firstLine.includes('\t')) return '\t';
  return ',';
}

function records(text: string): CsvRecord[] {
  const body = text.replace(/^\uFEFF/, '');
  const sep = separatorOf(body);
  const out: CsvRecord[] = [];
  let fields: string[] = [];
  let field = '';
  let quoted = false;
  let line = 1;
  let start = 1;
  const endRecord = () => {
    fields.push(field);
    if (fields.some((f) => f.trim() !== '')) out.push({ line: start, fields });
    fields = [];
    field = '';
  };
  for (let i = 0; i < body.length; i++) {
    const ch = body[i]!;
    if (ch === '\n') line++;
    if (quoted) {
      if (ch === '"' && body[i + 1] === '"') {
        field += '"';
        i++;
      } else if (ch === '"') quoted = false;
      else field += ch;
    } else if (ch === '"') quoted = true;
    else if (ch === sep) {
      fields.push(field);
      field = '';
    } else if (ch === '\n' || ch === '\r') {
      if (ch === '\r' && body[i + 1] === '\n') {
        i++;
        line++;
      }
      endRecord();
      start = line;
    } else field += ch;
  }
  if (field !== '' || fields.length > 0) endRecord();
  return out;
}

/** CSV text (comma, semicolon or tab; quoted fields; CRLF or LF) as rows of fields; blank rows are dropped. */
export function parseCsv(text: string): string[][] {
  return records(text).map((r) => r.fields);
}

const HEADERS: Readonly<Record<string, 'name' | 'address' | 'type'>> = Object.freeze({
  name: 'name',
  address: 'address',
  type: 'type',
  datatype: 'type',
  'data type': 'type',
});

interface Columns {
  name?: number;
  address: number;
  type?: number;
}

/** Column positions from a header row (one that has an "address" cell), or undefined when the row is data. */
function headerColumns(fields: string[]): Columns | undefined {
  const found: Partial<Record<'name' | 'address' | 'type', number>> = {};
  fields.forEach((f, i) => {
    const column = HEADERS[f.trim().toLowerCase()];
    if (column && found[column] === undefined) found[column] = i;
  });
  return found.address === undefined ? undefined : { name: found.name, address: found.address, type: found.type };
}

/** Without a header: one column is the address; two are name, address; three are name, address, type. */
function positionalColumns(width: number): Columns {
  return width === 1 ? { address: 0 } : { name: 0, address: 1, type: 2 };
}

function tryParse(parse: AddressParser, address: string): ParsedShape | undefined {
  try {
    return parse(address);
  } catch {
    return undefined;
  }
}

function sameShape(tag: ParsedShape, spec: TypeSpec): boolean {
  return tag.type === spec.type && tag.count === spec.count && tag.isArray === spec.isArray && tag.stringLength === spec.stringLength;
}

function describe(tag: ParsedShape): string {
  const base = tag.type === 'STRING' || tag.type === 'WSTRING' ? `${tag.type}[${tag.stringLength}]` : tag.type;
  return tag.isArray ? `${base}[${tag.count}]` : base;
}

/**
 * The address a row of `address` and `type` stands for. An address that
 * already is of that type stays as written (`DB1,INT6` with INT); otherwise
 * the type becomes its `:TYPE` (`DB1.DBW6` with INT is `DB1.DBW6:INT`). When
 * the address names another type the parser cannot override, the address
 * stays and `problem` says so.
 */
export function addressWithType(
  address: string,
  type: string,
  parse: AddressParser = parseAddress,
): { address: string; problem?: { code: 'TYPE_MISMATCH' | 'INVALID_TYPE'; message: string } } {
  const wanted = type.trim();
  if (!wanted) return { address };
  let spec: TypeSpec;
  try {
    spec = parseTypeSpec(wanted, address);
  } catch (err) {
    return { address, problem: { code: 'INVALID_TYPE', message: (err as Error).message } };
  }
  const own = tryParse(parse, address);
  if (own && sameShape(own, spec)) return { address };
  const typed = address.includes(':') ? undefined : `${address}:${wanted}`;
  if (typed && tryParse(parse, typed)) return { address: typed };
  if (own)
    return { address, problem: { code: 'TYPE_MISMATCH', message: `"${address}" is ${describe(own)}, the type column says ${wanted}` } };
  // Invalid either way: keep the type the user gave; validating the address names what is wrong.
  return { address: typed ?? address };
}

/**
 * Tags from CSV text: columns name, address and type, by a header row
 * (skipped) or by position. Rows without an address are dropped; a type
 * that does not fit and a name used twice are listed in `problems`.
 */
export function tagsFromCsv(text: string, parse: AddressParser = parseAddress): CsvImport {
  const rows = records(text);
  const header = rows.length > 0 ? headerColumns(rows[0]!.fields) : undefined;
  if (header) rows.shift();
  const tags: TagRow[] = [];
  const lines: number[] = [];
  const problems: TagTableProblem[] = [];
  for (const { line, fields } of rows) {
    const columns = header ?? positionalColumns(fields.length);
    const cell = (i: number | undefined) => (i === undefined ? '' : (fields[i] ?? '').trim());
    const raw = cell(columns.address);
    if (!raw) continue;
    const name = cell(columns.name);
    const { address, problem } = addressWithType(raw, cell(columns.type), parse);
    if (problem) problems.push({ line, ...problem, name: name || raw, address });
    tags.push({ name, address });
    lines.push(line);
  }
  for (const { name, rows: at } of duplicateNames(tags)) {
    for (const i of at.slice(1)) {
      problems.push({
        line: lines[i]!,
        code: 'DUPLICATE_NAME',
        name,
        address: tags[i]!.address,
        message: `"${name}" is also the name on line ${lines[at[0]!]}`,
      });
    }
  }
  problems.sort((a, b) => a.line - b.line);
  return { tags, problems };
}

function csvField(text: string): string {
  return /[",;\t\r\n]|^\s|\s$/.test(text) ? `"${text.replace(/"/g, '""')}"` : text;
}

/** A tag table as CSV (name,address with a header row, CRLF), which tagsFromCsv reads back unchanged. */
export function tagsToCsv(rows: readonly TagRow[]): string {
  return (
    ['name,address', ...rows.map((r) => `${csvField(String(r.name ?? ''))},${csvField(String(r.address ?? ''))}`)].join('\r\n') + '\r\n'
  );
}
