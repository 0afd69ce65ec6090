/**
 * The cells of an `.xlsx` workbook (Office Open XML, ECMA-376), as far as a
 * tag table needs them: the sheets by name, each row's cell texts by column.
 * The zip container is read here (its central directory, stored and deflated
 * parts, through node:zlib with a cap on what a part may inflate to), and the
 * few XML parts (workbook, its relationships, shared strings, worksheets)
 * with a small scanner: no formulas, styles or dates are evaluated, a cell's
 * text is what the file stores.
 *
 * Anything that is not such a workbook (random bytes, a truncated or
 * encrypted zip, a part that inflates past the cap) is a SourceError at
 * line 1, column 1 of the file; nothing else is thrown.
 */
import { inflateRawSync } from 'node:zlib';
import { SourceError } from '../errors';

/** A part larger than this (inflated) is refused: a tag table of 100,000 rows is some 20 MB of sheet XML. */
const MAX_PART_BYTES = 64 * 1024 * 1024;
/** Central directory entries beyond this are not a workbook's. */
const MAX_ENTRIES = 10_000;

const enum Zip {
  EndOfDirectory = 0x06054b50,
  DirectoryEntry = 0x02014b50,
  LocalHeader = 0x04034b50,
  EndOfDirectoryLength = 22,
  Stored = 0,
  Deflated = 8,
}

export interface SheetRow {
  /** 1-based row number, as Excel shows it. */
  readonly line: number;
  /** Cell texts by 1-based column number (index 0 unused); missing cells are undefined. */
  readonly cells: readonly (string | undefined)[];
}

export interface Sheet {
  readonly name: string;
  readonly rows: readonly SheetRow[];
}

interface Entry {
  method: number;
  flags: number;
  compressedSize: number;
  size: number;
  localOffset: number;
}

/** The sheets of a workbook in the order the workbook lists them. */
export function readWorkbook(bytes: Uint8Array, file: string): Sheet[] {
  const fail = (problem: string): never => {
    throw new SourceError({ file, line: 1, column: 1 }, `not a readable .xlsx workbook: ${problem}`);
  };
  const zip = Buffer.from(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const entries = directory(zip, fail);
  const part = (name: string): string | undefined => {
    const entry = entries.get(name);
    return entry ? inflate(zip, name, entry, fail).toString('utf8') : undefined;
  };

  const workbook = part('xl/workbook.xml') ?? fail('it has no xl/workbook.xml');
  const rels = relationships(part('xl/_rels/workbook.xml.rels') ?? '');
  const shared = sharedStrings(part('xl/sharedStrings.xml') ?? '');
  const sheets: Sheet[] = [];
  for (const tag of elements(workbook, 'sheet')) {
    const name = decodeXml(attribute(tag, 'name') ?? '');
    const id = /\s(?:[\w.-]+:)?id\s*=\s*"([^"]*)"/.exec(tag)?.[1];
    const target = id === undefined ? undefined : rels.get(id);
    if (target === undefined) continue;
    const path = target.startsWith('/') ? target.slice(1) : `xl/${target}`;
    const xml = part(path.replace(/\/\.\//g, '/')) ?? fail(`sheet "${name}" (${path}) is missing`);
    sheets.push({ name, rows: sheetRows(xml, shared, `${file} (sheet "${name}")`, fail) });
  }
  return sheets;
}

/** The central directory: each part's name, method, sizes and where its data starts. */
function directory(zip: Buffer, fail: (problem: string) => never): Map<string, Entry> {
  if (zip.length < Zip.EndOfDirectoryLength) fail('too short for a zip file');
  // The end record is the last 22 bytes, or fewer than 64 KiB earlier when the zip has a comment.
  let end = -1;
  for (let at = zip.length - Zip.EndOfDirectoryLength; at >= 0 && at >= zip.length - Zip.EndOfDirectoryLength - 0xffff; at--) {
    if (zip.readUInt32LE(at) === Zip.EndOfDirectory) {
      end = at;
      break;
    }
  }
  if (end < 0) fail('no zip directory (not a zip file, or truncated)');
  const count = zip.readUInt16LE(end + 10);
  const size = zip.readUInt32LE(end + 12);
  const offset = zip.readUInt32LE(end + 16);
  if (count === 0xffff || offset === 0xffffffff) fail('a ZIP64 archive (larger than any tag table)');
  if (count > MAX_ENTRIES) fail(`${count} parts`);
  if (offset + size > end) fail('its zip directory lies outside the file (truncated?)');

  const entries = new Map<string, Entry>();
  let at = offset;
  for (let i = 0; i < count; i++) {
    if (at + 46 > end || zip.readUInt32LE(at) !== Zip.DirectoryEntry) fail(`zip directory entry ${i + 1} is damaged`);
    const nameLength = zip.readUInt16LE(at + 28);
    const extraLength = zip.readUInt16LE(at + 30);
    const commentLength = zip.readUInt16LE(at + 32);
    const name = zip.toString('latin1', at + 46, at + 46 + nameLength);
    entries.set(name, {
      flags: zip.readUInt16LE(at + 8),
      method: zip.readUInt16LE(at + 10),
      compressedSize: zip.readUInt32LE(at + 20),
      size: zip.readUInt32LE(at + 24),
      localOffset: zip.readUInt32LE(at + 42),
    });
    at += 46 + nameLength + extraLength + commentLength;
  }
  return entries;
}

function inflate(zip: Buffer, name: string, entry: Entry, fail: (problem: string) => never): Buffer {
  if (entry.flags & 1) fail(`${name} is encrypted`);
  if (entry.size > MAX_PART_BYTES) fail(`${name} would inflate to ${entry.size} bytes (at most ${MAX_PART_BYTES})`);
  const local = entry.localOffset;
  if (local + 30 > zip.length || zip.readUInt32LE(local) !== Zip.LocalHeader) fail(`${name}: its zip header is damaged`);
  const start = local + 30 + zip.readUInt16LE(local + 26) + zip.readUInt16LE(local + 28);
  const data = zip.subarray(start, start + entry.compressedSize);
  if (data.length < entry.compressedSize) fail(`${name} is truncated`);
  if (entry.method === Zip.Stored) return data;
  if (entry.method !== Zip.Deflated) fail(`${name} uses zip compression method ${entry.method}`);
  try {
    // The size in the directory may lie: the cap holds whatever the data inflates to.
    return inflateRawSync(data, { maxOutputLength: MAX_PART_BYTES });
  } catch (err) {
    const code = (err as { code?: string }).code;
    return fail(
      code === 'ERR_BUFFER_TOO_LARGE' ? `${name} inflates past ${MAX_PART_BYTES} bytes` : `${name} does not inflate (${code ?? 'damaged'})`,
    );
  }
}

// ---------------------------------------------------------------- the XML parts

/** Start tags (with their attributes) of an element, any namespace prefix. */
function elements(xml: string, name: string): string[] {
  return xml.match(new RegExp(`<(?:[\\w.-]+:)?${name}(?=[\\s/>])[^>]*>`, 'g')) ?? [];
}

/** One pattern per attribute name, made once (a sheet asks for `r` and `t` of every cell). */
const ATTRIBUTES = new Map<string, RegExp>();

function attribute(tag: string, name: string): string | undefined {
  let pattern = ATTRIBUTES.get(name);
  if (!pattern) ATTRIBUTES.set(name, (pattern = new RegExp(`\\s${name}\\s*=\\s*(?:"([^"]*)"|'([^']*)')`)));
  const m = pattern.exec(tag);
  return m ? (m[1] ?? m[2]) : undefined;
}

function relationships(xml: string): Map<string, string> {
  const out = new Map<string, string>();
  for (const tag of elements(xml, 'Relationship')) {
    const id = attribute(tag, 'Id');
    const target = attribute(tag, 'Target');
    if (id !== undefined && target !== undefined) out.set(id, decodeXml(target));
  }
  return out;
}

/** The text of the `<t>` runs in a piece of XML, phonetic hints (`<rPh>`) left out. */
function runsText(xml: string): string {
  const plain = xml.replace(/<(?:[\w.-]+:)?rPh\b[\s\S]*?<\/(?:[\w.-]+:)?rPh>/g, '');
  let text = '';
  for (const m of plain.matchAll(/<(?:[\w.-]+:)?t(?:\s[^>]*)?(?:\/>|>([\s\S]*?)<\/(?:[\w.-]+:)?t>)/g)) text += decodeXml(m[1] ?? '');
  return text;
}

function sharedStrings(xml: string): string[] {
  const out: string[] = [];
  for (const m of xml.matchAll(/<(?:[\w.-]+:)?si(?:\s[^>]*)?(?:\/>|>([\s\S]*?)<\/(?:[\w.-]+:)?si>)/g)) out.push(runsText(m[1] ?? ''));
  return out;
}

/** `B12` → column 2; undefined for a malformed reference. */
function columnOf(ref: string): number | undefined {
  const m = /^([A-Z]{1,3})\d*$/i.exec(ref);
  if (!m) return undefined;
  let n = 0;
  for (const ch of m[1]!.toUpperCase()) n = n * 26 + ch.charCodeAt(0) - 64;
  return n;
}

const ROW = /<(?:[\w.-]+:)?row\b([^>]*?)(?:\/>|>([\s\S]*?)<\/(?:[\w.-]+:)?row>)/g;
const CELL = /<(?:[\w.-]+:)?c\b([^>]*?)(?:\/>|>([\s\S]*?)<\/(?:[\w.-]+:)?c>)/g;
const VALUE = /<(?:[\w.-]+:)?v(?:\s[^>]*)?>([\s\S]*?)<\/(?:[\w.-]+:)?v>/;
const INLINE = /<(?:[\w.-]+:)?is(?:\s[^>]*)?>([\s\S]*?)<\/(?:[\w.-]+:)?is>/;

function sheetRows(xml: string, shared: readonly string[], where: string, fail: (problem: string) => never): SheetRow[] {
  const rows: SheetRow[] = [];
  let lastLine = 0;
  for (const row of xml.matchAll(ROW)) {
    const r = attribute(` ${row[1]!}`, 'r');
    const line = r !== undefined && /^\d+$/.test(r) ? Number(r) : lastLine + 1;
    lastLine = line;
    const cells: (string | undefined)[] = [];
    let lastColumn = 0;
    for (const cell of (row[2] ?? '').matchAll(CELL)) {
      const attrs = ` ${cell[1]!}`;
      const ref = attribute(attrs, 'r');
      const column = (ref === undefined ? undefined : columnOf(ref)) ?? lastColumn + 1;
      lastColumn = column;
      const body = cell[2] ?? '';
      const type = attribute(attrs, 't') ?? 'n';
      const value = VALUE.exec(body)?.[1];
      let text: string | undefined;
      if (type === 'inlineStr') text = runsText(INLINE.exec(body)?.[1] ?? '');
      else if (value === undefined) text = undefined;
      else if (type === 's') {
        const index = Number(value);
        if (!Number.isInteger(index) || index < 0 || index >= shared.length)
          fail(`${where}: cell ${ref ?? `row ${line}`} names shared string ${value.trim()} of ${shared.length}`);
        text = shared[index];
      } else if (type === 'b') text = value.trim() === '1' ? 'TRUE' : 'FALSE';
      else text = decodeXml(value);
      if (column <= 16384) cells[column] = text;
    }
    rows.push({ line, cells });
  }
  return rows;
}

const ENTITIES: Readonly<Record<string, string>> = Object.freeze({ lt: '<', gt: '>', amp: '&', quot: '"', apos: "'" });

/** XML character references and entities, then OOXML's `_xHHHH_` escapes (for characters XML cannot carry). */
function decodeXml(text: string): string {
  return text
    .replace(/&(#x[0-9a-f]+|#\d+|lt|gt|amp|quot|apos);/gi, (whole, ref: string) => {
      if (ref[0] !== '#') return ENTITIES[ref.toLowerCase()] ?? whole;
      const code = ref[1] === 'x' || ref[1] === 'X' ? parseInt(ref.slice(2), 16) : Number(ref.slice(1));
      return code <= 0x10ffff ? String.fromCodePoint(code) : whole;
    })
    .replace(/_x([0-9a-f]{4})_/gi, (_, hex: string) => String.fromCharCode(parseInt(hex, 16)));
}
