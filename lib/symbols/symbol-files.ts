/**
 * Symbol tables as STEP 7 and TIA Portal export them, read into rows of
 * name, address (in this library's syntax), data type and comment:
 *
 * - STEP 7 (SIMATIC Manager, symbol editor, "Export"), Windows-1252 text:
 *   `.sdf` (System Data Format: `"Symbol","Address","Data type","Comment"`,
 *   fields quoted and padded), `.asc` (fixed width: `126,`, then the symbol in
 *   24 characters, the address in 12, the data type in 10, the comment in
 *   80) and `.seq` (assignment list: TAB address TAB symbol TAB comment; no
 *   data type). Addresses in German or English mnemonics with a space before
 *   the number: `E 0.0` / `I 0.0`, `AW 4` / `QW 4`, `MD 20`, `PEW 256` /
 *   `PIW 256`, `T 5`, `Z 5` / `C 5`, `DB 10`, `FB 3`, `UDT 1`.
 * - TIA Portal's PLC tag table export (`.xlsx`, sheet "PLC Tags": Name, Path,
 *   Data Type, Logical Address, Comment, the HMI columns, …) and a `.csv`
 *   with the same columns (separator `,`, `;` or tab), UTF-8 (with or
 *   without BOM), UTF-16 with BOM, or Windows-1252. Logical addresses as TIA
 *   writes them: `%I0.0`, `%MW10`, `%MD20`, `%QB3`.
 *
 * An address becomes ours with its type when the type is not the address's
 * own (`MW 10` INT → `MW10:INT`, `MD 20` REAL → `MD20:REAL`, `I 0.0` BOOL →
 * `I0.0`, `MW 10` WORD → `MW10`), and is checked by parseAddress(). Blocks
 * keep their number: `DB 1` → `DB1`. Unknown columns are ignored. A row that
 * cannot be read is a SourceError naming the file, the line (the row), the
 * column and the symbol.
 */
import { parseAddress, parseTypeSpec } from '../address';
import { PlcError, SourceError } from '../errors';
import type { SourcePosition, SymbolSource, SymbolTableRow } from './model';
import { readWorkbook, type SheetRow } from './xlsx';

/** A text table larger than this is not a symbol table (STEP 7 allows 65,535 symbols of some 130 bytes). */
const MAX_TEXT_BYTES = 64 * 1024 * 1024;

/** The rows of a symbol table file; the file's extension selects the format. */
export function readSymbolTable(source: SymbolSource): SymbolTableRow[] {
  const file = source.name;
  const extension = /\.([a-z0-9]+)$/i.exec(file)?.[1]?.toLowerCase();
  const start: SourcePosition = { file, line: 1, column: 1 };
  switch (extension) {
    case 'sdf':
      return readSdf(file, decodeText(source.content, start));
    case 'asc':
      return readAsc(file, decodeText(source.content, start));
    case 'seq':
      return readSeq(file, decodeText(source.content, start));
    case 'csv': {
      const text = decodeText(source.content, start);
      return readTiaRows(file, csvRecords(text, detectSeparator(text)));
    }
    case 'xlsx': {
      if (typeof source.content === 'string')
        throw new SourceError(start, 'an .xlsx file must be given as bytes (a Uint8Array), not as text');
      return readXlsx(file, source.content);
    }
    default:
      throw new SourceError(start, `not a symbol table: expected a .sdf, .asc, .seq (STEP 7), .xlsx or .csv (TIA Portal) file`);
  }
}

// ---------------------------------------------------------------- text encodings

/** Windows-1252 at 0x80–0x9F (the rest of the range is Latin-1); undefined bytes keep their C1 code. */
const CP1252_HIGH =
  '\u20ac\u0081\u201a\u0192\u201e\u2026\u2020\u2021\u02c6\u2030\u0160\u2039\u0152\u008d\u017d\u008f' +
  '\u0090\u2018\u2019\u201c\u201d\u2022\u2013\u2014\u02dc\u2122\u0161\u203a\u0153\u009d\u017e\u0178';

/**
 * The text of a file: a string as it is; bytes by their BOM (UTF-8,
 * UTF-16 LE/BE), else UTF-8 when they are valid UTF-8, else Windows-1252
 * (what STEP 7 writes; its umlauts are not valid UTF-8).
 */
function decodeText(content: string | Uint8Array, at: SourcePosition): string {
  if (typeof content === 'string') return content.replace(/^\uFEFF/, '');
  if (content.byteLength > MAX_TEXT_BYTES) throw new SourceError(at, `${content.byteLength} bytes: larger than any symbol table`);
  const b = content;
  if (b[0] === 0xef && b[1] === 0xbb && b[2] === 0xbf) return new TextDecoder('utf-8').decode(b.subarray(3));
  if (b[0] === 0xff && b[1] === 0xfe) return new TextDecoder('utf-16le').decode(b.subarray(2));
  if (b[0] === 0xfe && b[1] === 0xff) return new TextDecoder('utf-16be').decode(b.subarray(2));
  try {
    return new TextDecoder('utf-8', { fatal: true }).decode(b);
  } catch {
    let text = '';
    for (const byte of b) text += byte >= 0x80 && byte < 0xa0 ? CP1252_HIGH[byte - 0x80] : String.fromCharCode(byte);
    return text;
  }
}

/** Lines of a text with their 1-based numbers (CRLF, LF or CR alone end a line). */
function lines(text: string): { line: number; text: string }[] {
  return text.split(/\r\n|\n|\r/).map((t, i) => ({ line: i + 1, text: t }));
}

// ---------------------------------------------------------------- delimited text

interface Field {
  readonly text: string;
  /** 1-based column of the field's first character (its opening quote, when quoted). */
  readonly column: number;
}
interface CsvRecord {
  readonly line: number;
  readonly fields: readonly Field[];
}

/** The separator of a CSV table, from its first line outside quotes: `;` (German Excel), tab, else `,`. */
function detectSeparator(text: string): string {
  const first = (text.split(/\r?\n/, 1)[0] ?? '').replace(/"[^"]*"/g, '');
  if (first.includes(';')) return ';';
  if (first.includes('\t')) return '\t';
  return ',';
}

/** Records of a delimited text, fields with their columns; quotes as in RFC 4180 (`""` inside quotes is `"`); blank lines dropped. */
function csvRecords(text: string, separator: string): CsvRecord[] {
  const out: CsvRecord[] = [];
  let fields: Field[] = [];
  let field = '';
  let fieldColumn = 1;
  let quoted = false;
  let line = 1;
  let lineStart = 0;
  let recordLine = 1;
  const endField = (next: number) => {
    fields.push({ text: field, column: fieldColumn });
    field = '';
    fieldColumn = next - lineStart + 1;
  };
  const endRecord = () => {
    if (fields.some((f) => f.text.trim() !== '')) out.push({ line: recordLine, fields });
    fields = [];
  };
  for (let i = 0; i < text.length; i++) {
    const ch = text[i]!;
    if (quoted) {
      if (ch === '"' && text[i + 1] === '"') {
        field += '"';
        i++;
      } else if (ch === '"') quoted = false;
      else {
        field += ch;
        if (ch === '\n' || (ch === '\r' && text[i + 1] !== '\n')) {
          line++;
          lineStart = i + 1;
        }
      }
    } else if (ch === '"') quoted = true;
    else if (ch === separator) endField(i + 1);
    else if (ch === '\n' || ch === '\r') {
      if (ch === '\r' && text[i + 1] === '\n') i++;
      line++;
      lineStart = i + 1;
      endField(i + 1);
      endRecord();
      recordLine = line;
      fieldColumn = 1;
    } else field += ch;
  }
  if (field !== '' || fields.length > 0) {
    endField(text.length);
    endRecord();
  }
  return out;
}

// ---------------------------------------------------------------- STEP 7 formats

/** One row as the table writes it, each cell with where it stands. */
interface RawRow {
  readonly name: Field;
  readonly address: Field;
  /** Undefined: the format has no data type column (SEQ). */
  readonly type?: Field;
  readonly comment: string;
  readonly line: number;
}

function readSdf(file: string, text: string): SymbolTableRow[] {
  return csvRecords(text, ',').map((r) => {
    if (r.fields.length < 2)
      throw new SourceError(
        { file, line: r.line, column: 1 },
        `expected "Symbol","Address","Data type","Comment", found ${r.fields.length} field`,
      );
    const [name, address, type, comment] = r.fields;
    return symbolRow(file, {
      name: name!,
      address: address!,
      type: type ?? { text: '', column: address!.column },
      comment: comment?.text ?? '',
      line: r.line,
    });
  });
}

/** Columns of an ASC record (0-based character offsets): `126,`, symbol, address, data type, comment. */
const ASC = Object.freeze({ prefix: '126,', symbol: 4, address: 28, type: 40, comment: 50, end: 130 });

function readAsc(file: string, text: string): SymbolTableRow[] {
  const out: SymbolTableRow[] = [];
  for (const { line, text: record } of lines(text)) {
    if (record.trim() === '') continue;
    if (!record.startsWith(ASC.prefix))
      throw new SourceError({ file, line, column: 1 }, `expected an ASC symbol record starting with "${ASC.prefix}"`);
    const cell = (from: number, to: number): Field => ({ text: record.slice(from, to), column: from + 1 });
    out.push(
      symbolRow(file, {
        name: cell(ASC.symbol, ASC.address),
        address: cell(ASC.address, ASC.type),
        type: cell(ASC.type, ASC.comment),
        comment: record.slice(ASC.comment, ASC.end),
        line,
      }),
    );
  }
  return out;
}

function readSeq(file: string, text: string): SymbolTableRow[] {
  return csvRecords(text, '\t').map((r) => {
    // Each record starts with a TAB: the first field is empty.
    const fields = r.fields[0]?.text.trim() === '' ? r.fields.slice(1) : r.fields;
    if (fields.length < 2)
      throw new SourceError({ file, line: r.line, column: 1 }, 'expected TAB address TAB symbol [TAB comment] (an assignment list line)');
    const [address, name, comment] = fields;
    return symbolRow(file, { name: name!, address: address!, comment: (comment?.text ?? '').trim().replace(/^;\s*/, ''), line: r.line });
  });
}

// ---------------------------------------------------------------- TIA Portal formats

/** Column titles of TIA's PLC tag table, lower case (English and German), and what they hold. */
const TIA_COLUMNS: Readonly<Record<string, 'name' | 'address' | 'type' | 'comment'>> = Object.freeze({
  name: 'name',
  symbol: 'name',
  'logical address': 'address',
  address: 'address',
  'logische adresse': 'address',
  adresse: 'address',
  operand: 'address',
  'data type': 'type',
  datatype: 'type',
  datentyp: 'type',
  comment: 'comment',
  kommentar: 'comment',
});

/** The sheet TIA Portal writes the tags to; other sheets (constants) are not tags. */
const TIA_SHEET = 'plc tags';

function readXlsx(file: string, bytes: Uint8Array): SymbolTableRow[] {
  const sheets = readWorkbook(bytes, file);
  // A row's fields by column (A is index 0), empty cells as empty text; blank rows dropped.
  const toRecords = (rows: readonly SheetRow[]): CsvRecord[] =>
    rows
      .map((r) => {
        const fields: Field[] = [];
        for (let column = 1; column < r.cells.length; column++) fields.push({ text: r.cells[column] ?? '', column });
        return { line: r.line, fields };
      })
      .filter((r) => r.fields.some((f) => f.text.trim() !== ''));
  const named = sheets.find((s) => s.name.trim().toLowerCase() === TIA_SHEET);
  const sheet = named ?? sheets.find((s) => headerOf(toRecords(s.rows)[0]) !== undefined);
  if (!sheet) {
    const names = sheets.map((s) => `"${s.name}"`).join(', ') || 'none';
    throw new SourceError(
      { file, line: 1, column: 1 },
      `no sheet "PLC Tags" nor one with Name and Logical Address columns (sheets: ${names})`,
    );
  }
  return readTiaRows(file, toRecords(sheet.rows));
}

type Columns = Partial<Record<'name' | 'address' | 'type' | 'comment', number>>;

/** Column indexes from a header row; undefined unless it names at least Name and an address column. */
function headerOf(record: CsvRecord | undefined): (Required<Pick<Columns, 'name' | 'address'>> & Columns) | undefined {
  if (!record) return undefined;
  const found: Columns = {};
  record.fields.forEach((f, i) => {
    const column = TIA_COLUMNS[f.text.trim().toLowerCase()];
    if (column && found[column] === undefined) found[column] = i;
  });
  return found.name === undefined || found.address === undefined ? undefined : { ...found, name: found.name, address: found.address };
}

function readTiaRows(file: string, records: readonly CsvRecord[]): SymbolTableRow[] {
  if (records.length === 0) return [];
  const columns = headerOf(records[0]);
  if (!columns)
    throw new SourceError(
      { file, line: records[0]!.line, column: 1 },
      'expected a header row with the columns Name and Logical Address (as TIA Portal exports a PLC tag table)',
    );
  const cell = (r: CsvRecord, index: number | undefined): Field | undefined => (index === undefined ? undefined : r.fields[index]);
  return records.slice(1).map((r) => {
    const missing = (index: number): Field => ({ text: '', column: index + 1 });
    return symbolRow(file, {
      name: cell(r, columns.name) ?? missing(columns.name),
      address: cell(r, columns.address) ?? missing(columns.address),
      type: cell(r, columns.type) ?? { text: '', column: 1 },
      comment: cell(r, columns.comment)?.text ?? '',
      line: r.line,
    });
  });
}

// ---------------------------------------------------------------- addresses

/** Area mnemonics of STEP 7 (German and English) and TIA, and the letter of ours. */
const AREA_LETTERS: Readonly<Record<string, string>> = Object.freeze({
  E: 'I',
  I: 'I',
  A: 'Q',
  Q: 'Q',
  M: 'M',
  PE: 'PI',
  PI: 'PI',
  PA: 'PQ',
  PQ: 'PQ',
});
/** The type an area address has by its width letter (none: a bit). */
const NATURAL_TYPES: Readonly<Record<string, string>> = Object.freeze({ '': 'BOOL', B: 'BYTE', W: 'WORD', D: 'DWORD' });
/** Block kinds a symbol table names by number. */
const BLOCKS = new Set(['DB', 'FB', 'FC', 'OB', 'SFB', 'SFC', 'UDT', 'VAT']);

/** A row of any format checked and turned into a SymbolTableRow. */
function symbolRow(file: string, raw: RawRow): SymbolTableRow {
  const name = raw.name.text.trim();
  const at = (column: number): SourcePosition => ({ file, line: raw.line, column });
  if (name === '') throw new SourceError(at(raw.name.column), 'a row without a symbol name');
  // eslint-disable-next-line no-control-regex
  const control = /[\u0000-\u001f\u007f]/.exec(name);
  if (control)
    throw new SourceError(
      at(raw.name.column),
      `symbol ${JSON.stringify(name)}: unexpected control character ${JSON.stringify(control[0])}`,
    );
  const dataType = (raw.type?.text ?? '').trim().replace(/\s+/g, ' ');
  const address = ourAddress(raw.address.text, dataType, (column, problem) => {
    throw new SourceError(at(column === 'type' && raw.type ? raw.type.column : raw.address.column), `symbol "${name}": ${problem}`);
  });
  return { name, address, dataType, comment: raw.comment.trim(), at: at(raw.name.column) };
}

/**
 * A STEP 7 or TIA address with the table's data type, in our syntax:
 * `MW 10` INT → `MW10:INT`, `%I0.0` Bool → `I0.0`, `DB 1` → `DB1`.
 */
function ourAddress(written: string, dataType: string, fail: (column: 'address' | 'type', problem: string) => never): string {
  const compact = written.replace(/\s+/g, '').replace(/^%/, '').toUpperCase();
  if (compact === '') return fail('address', 'no address');
  const block = /^([A-Z]+)(\d+)$/.exec(compact);
  if (block && BLOCKS.has(block[1]!)) return `${block[1]}${Number(block[2])}`;
  let address: string;
  let natural: string;
  const area = /^(P[EIAQ]|[EIAQM])([XBWD]?)(\d+)(?:\.(\d+))?$/.exec(compact);
  const timerCounter = /^([TZC])(\d+)$/.exec(compact);
  if (area) {
    const [, letters, width, byte, bit] = area;
    // A bit has no width letter (or IEC's X), a byte, word or double word has one.
    const bitWidth = width === '' || width === 'X';
    if ((bit !== undefined) !== bitWidth) return fail('address', `"${written.trim()}" is not a STEP 7 address (e.g. I 0.0, MW 10, QD 4)`);
    address = `${AREA_LETTERS[letters!]}${bitWidth ? '' : width}${Number(byte)}${bit === undefined ? '' : `.${Number(bit)}`}`;
    natural = NATURAL_TYPES[bitWidth ? '' : width!]!;
  } else if (timerCounter) {
    const timer = timerCounter[1] === 'T';
    address = `${timer ? 'T' : 'C'}${Number(timerCounter[2])}`;
    natural = timer ? 'TIMER' : 'COUNTER';
  } else {
    return fail(
      'address',
      `"${written.trim()}" is not an address a symbol table holds (I, Q, M, PI, PQ, T, C or a block: DB, FB, FC, UDT, …)`,
    );
  }
  let suffix = '';
  if (dataType !== '') {
    let spec;
    try {
      spec = parseTypeSpec(dataType, written);
    } catch {
      return fail('type', `"${dataType}" is not a data type an address can have (e.g. BOOL, INT, REAL)`);
    }
    const text = `${spec.type}${spec.type === 'STRING' || spec.type === 'WSTRING' ? `[${spec.stringLength}]` : ''}${spec.isArray ? `[${spec.count}]` : ''}`;
    if (text !== natural) suffix = `:${text}`;
  }
  try {
    parseAddress(address + suffix);
  } catch (err) {
    return fail('address', err instanceof PlcError ? err.message : String(err));
  }
  return address + suffix;
}
