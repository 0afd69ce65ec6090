/**
 * compileSymbols(): a PLC's own DB and UDT sources and symbol tables in, a
 * table of every member with its standard-access address out. The source
 * parser and the symbol-table readers read the files, the layout engine
 * places the members (lib/symbols/layout.ts); this file gives the blocks
 * their numbers, names every member as TIA writes it, evaluates the start
 * values and indexes the names (docs/symbols.md).
 */
import { formatAddress, parseAddress } from '../address';
import { PlcError, SourceError } from '../errors';
import type { DataTypeName, PlcScalar } from '../types';
import { literalValue } from './literals';
import { NameIndex } from './names';
import { distance } from './distance';
import { parseBlockSource } from './source-parser';
import { readSymbolTable } from './symbol-files';
import { blockRef, elementIndex, layoutBlocks, memberRef, type BlockLayout, type LayoutNode } from './layout';
import type {
  BlockDecl,
  BlockSummary,
  CompileOptions,
  DataBlockDecl,
  Literal,
  SourcePosition,
  StartValue,
  SymbolEntry,
  SymbolSource,
  SymbolTable,
  SymbolTableRow,
} from './model';

/** Evaluates a start value's literal for a member's type (lib/symbols/literals.ts). */
export type EvaluateLiteral = (literal: Literal, type: DataTypeName, stringLength: number) => PlcScalar;

/** Where an option (not a file) is wrong: the messages name the option. */
const OPTIONS_AT: SourcePosition = Object.freeze({ file: 'options.db', line: 0, column: 0 });
const MAX_DB_NUMBER = 65535;
/** Rows of a symbol table that name blocks other than DBs and UDTs: nothing to read by name. */
const OTHER_BLOCKS = /^(?:OB|FB|FC|SFB|SFC|SDB|VAT|DI)\s*\d+$/i;

/** A name as a key: case-insensitive, as TIA compares names. */
function key(name: string): string {
  return name.toLowerCase();
}

/** An option key as the user typed it: `Tank`, `"Tank"`, `"Motor 1"`. */
function optionKey(name: string): string {
  const t = name.trim();
  return key(t.length >= 2 && t.startsWith('"') && t.endsWith('"') ? t.slice(1, -1) : t);
}

/**
 * The start-value path of a BEGIN section (`Motor.Speed`, `"Speed.Set"`,
 * `Step[3].Temp`, `Grid[1, 2]`) in the form entry names use after the block,
 * as a key; undefined when it is not a path.
 */
export function pathKey(path: string): string | undefined {
  const s = path;
  let out = '';
  let i = 0;
  const skip = (): void => {
    while (i < s.length && /\s/.test(s[i]!)) i++;
  };
  skip();
  while (i < s.length) {
    if (out !== '') {
      if (s[i] === '[') {
        const close = s.indexOf(']', i);
        if (close < 0) return undefined;
        const indices = s
          .slice(i + 1, close)
          .split(',')
          .map((x) => x.trim());
        if (indices.some((x) => !/^[+-]?\d+$/.test(x))) return undefined;
        out += `[${indices.map((x) => String(Number(x))).join(',')}]`;
        i = close + 1;
        skip();
        continue;
      }
      if (s[i] !== '.') return undefined;
      i++;
      skip();
    }
    let name: string;
    if (s[i] === '"') {
      const close = s.indexOf('"', i + 1);
      if (close < 0) return undefined;
      name = s.slice(i + 1, close);
      i = close + 1;
    } else {
      const m = /^[^.[\]"\s]+/.exec(s.slice(i));
      if (!m) return undefined;
      name = m[0];
      i += name.length;
    }
    out += `.${memberRef(name)}`;
    skip();
  }
  return out === '' ? undefined : key(out);
}

/** An elementary type as its IEC name in capitals: `REAL`, `STRING[20]`, `WSTRING[10]`, `DATE_AND_TIME`. */
function iecElementary(type: DataTypeName, stringLength: number): string {
  return stringLength > 0 ? `${type}[${stringLength}]` : type;
}

/**
 * A member's type as entries give it: the IEC name in capitals for
 * elementary types and keywords (`REAL`, `STRING[20]`, `ARRAY[1..10] OF BOOL`,
 * `ARRAY[1..2, 0..3] OF INT`, `STRUCT`), a user type by its own name as the
 * sources write it (`"Motor"`, STEP 7 `UDT 5`).
 */
function iecType(node: LayoutNode): string {
  switch (node.kind) {
    case 'elementary':
      return iecElementary(node.dataType, node.stringLength);
    case 'array':
      return `ARRAY[${node.dims.map((d) => `${d.low}..${d.high}`).join(', ')}] OF ${iecType(node.elements[0]!)}`;
    case 'struct':
      // A UDT instance's typeText is the UDT as the sources name it.
      return node.typeName === undefined ? 'STRUCT' : node.typeText;
  }
}

class TableBuilder {
  readonly entries: SymbolEntry[] = [];
  /** Start values per entry index (BEGIN overwrites the declarations'). */
  private readonly literals: (Literal | undefined)[] = [];
  /** Entry index by name after the block (`.motor.speed`), for the BEGIN section of the block being built. */
  private relative = new Map<string, number>();

  constructor(private readonly evaluate: EvaluateLiteral | undefined) {}

  block(layout: BlockLayout, name: string, db: number): void {
    this.relative = new Map();
    const top: string[] = [];
    for (const m of layout.root.members) this.node(m.node, name, `.${memberRef(m.name)}`, db, top);
    for (const sv of layout.decl.startValues) {
      const k = pathKey(sv.path);
      const index = k === undefined ? undefined : this.relative.get(k);
      if (index === undefined) throw new SourceError(sv.at, `start value for ${name}.${sv.path}: DB ${name} has no such member`);
      this.assign(index, sv.value, sv.at);
    }
  }

  /** Evaluates the start values gathered, entry by entry. */
  finish(): SymbolEntry[] {
    return this.entries.map((e, i) => {
      const literal = this.literals[i];
      if (literal === undefined || !this.evaluate) return Object.freeze(e);
      return Object.freeze({ ...e, initial: this.evaluate(literal, e.dataType!, e.stringLength) });
    });
  }

  /** Adds the entry of a node and those below it, and its name to its parent's children (an empty STRUCT, nor an array of them, has none). */
  private node(node: LayoutNode, blockName: string, rel: string, db: number, siblings: string[]): void {
    const name = blockName + rel;
    const index = this.entries.length;
    const base = { name, type: iecType(node), area: 'DB' as const, db, byte: node.byte, bit: node.bit, size: node.size };
    const comment = node.decl?.comment ?? '';
    const at = node.decl?.at ?? node.at;
    if (node.kind === 'elementary') {
      const address = formatAddress({
        area: 'DB',
        dbNumber: db,
        byteOffset: node.byte,
        bitOffset: node.bit ?? 0,
        type: node.dataType,
        count: 1,
        isArray: false,
        stringLength: node.stringLength,
      });
      this.push(
        { ...base, kind: 'elementary', dataType: node.dataType, stringLength: node.stringLength, address, comment, at },
        rel,
        siblings,
      );
      if (node.decl?.initial) this.assign(index, node.decl.initial, node.decl.at);
      return;
    }
    // An empty STRUCT (or an array of them) holds no data: it has no entry.
    if (node.size === 0) return;
    const children: string[] = [];
    const elementType = node.kind === 'array' ? node.elementType : undefined;
    const address =
      elementType && node.kind === 'array' && node.contiguous
        ? formatAddress({
            area: 'DB',
            dbNumber: db,
            byteOffset: node.byte,
            bitOffset: 0,
            type: elementType.dataType,
            count: node.elements.length,
            isArray: true,
            stringLength: elementType.stringLength,
          })
        : formatAddress({
            area: 'DB',
            dbNumber: db,
            byteOffset: node.byte,
            bitOffset: 0,
            type: 'BYTE',
            count: node.size,
            isArray: true,
            stringLength: 0,
          });
    const entry: SymbolEntry = {
      ...base,
      kind: node.kind,
      ...(elementType ? { dataType: elementType.dataType } : {}),
      stringLength: elementType?.stringLength ?? 0,
      address,
      children,
      comment,
      at,
    };
    this.push(entry, rel, siblings);
    if (node.kind === 'struct') {
      for (const m of node.members) this.node(m.node, blockName, `${rel}.${memberRef(m.name)}`, db, children);
    } else {
      node.elements.forEach((e, k) => this.node(e, blockName, `${rel}[${elementIndex(node.dims, k)}]`, db, children));
    }
    if (node.decl?.initial) this.assign(index, node.decl.initial, node.decl.at);
  }

  private push(entry: SymbolEntry, rel: string, siblings: string[]): void {
    this.relative.set(key(rel), this.entries.length);
    this.entries.push(entry);
    this.literals.push(undefined);
    siblings.push(entry.name);
  }

  /** A start value for entry `index`: one literal for an elementary member, a list (with repeats) element by element for an array. */
  private assign(index: number, value: StartValue, at: SourcePosition): void {
    const entry = this.entries[index]!;
    if (entry.kind === 'elementary') {
      if (value.kind !== 'literal') throw new SourceError(at, `start value for ${entry.name}: a ${entry.type} takes one value, not a list`);
      this.literals[index] = value.literal;
      return;
    }
    if (entry.kind !== 'array' || entry.dataType === undefined)
      throw new SourceError(at, `start value for ${entry.name}: a ${entry.type} takes start values member by member`);
    const flat: Literal[] = [];
    const flatten = (v: StartValue, times: number): void => {
      for (let t = 0; t < times; t++) {
        if (v.kind === 'literal') flat.push(v.literal);
        else for (const item of v.items) flatten(item.value, item.repeat);
        if (flat.length > entry.children!.length)
          throw new SourceError(at, `start value for ${entry.name}: more values than its ${entry.children!.length} elements`);
      }
    };
    flatten(value, 1);
    // The elements are the entries right after the array, in index order.
    flat.forEach((literal, k) => (this.literals[index + 1 + k] = literal));
  }
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
        length: layout.length,
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
 * cannot be compiled: a syntax error, an optimized block, an unknown type, a
 * block without number, … (docs/symbols.md).
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
