/**
 * The simulated CPU's object model for S7CommPlus, built from the same DB
 * and UDT sources as the S7 simulator: every DB, optimized or not, with its
 * members, their LIDs and the type objects a browse reads. Optimized blocks
 * are laid out by the standard rules for the simulator's own storage only:
 * their offsets never leave the simulator (a client reads them by LID), and
 * PUT/GET refuses them (lib/s7/server/jobs.ts).
 *
 * LIDs: the first member of a block or struct has LID 0xA, the next 0xB and
 * so on in declaration order (s7commplus (MIT) tests address the first
 * member of DB1 as `8A0E0001.A`; thomas-v2/S7CommPlusDriver's test program
 * numbers members upwards the same way). LID 1 of a DB answers the RID of
 * its type object (client.py `_read_typeinfo_rid`).
 */
import { compileDeclarations } from '../../symbols/compile';
import { layoutBlocks, type BlockLayout, type LayoutNode } from '../../symbols/layout';
import { literalValue } from '../../symbols/literals';
import { parseBlockSource } from '../../symbols/source-parser';
import { readSymbolTable } from '../../symbols/symbol-files';
import { SourceError } from '../../errors';
import type { BlockDecl, CompileOptions, SymbolSource, SymbolTable, SymbolTableRow } from '../../symbols/model';
import type { ElementaryNode, StructNode } from '../../symbols/layout-nodes';
import type { DataTypeName } from '../../types';
import { AreaTypeInfoRID, dbAccessArea, Ids, SoftDataType } from '../constants';

/** The LID of the first member of a block or struct. */
export const FIRST_LID = 0xa;
/** RIDs of the simulator's type objects: a DB's is this base plus its number, a struct's or UDT's the other base plus its index. */
const DB_TYPE_RID = 0x92000000;
const STRUCT_TYPE_RID = 0x93000000;

/** One member of a type object as a browse sees it. */
export interface PlusMember {
  readonly name: string;
  readonly lid: number;
  /** Offset from the start of its struct (byte, and bit for BOOL). */
  readonly byte: number;
  readonly bit: number | null;
  readonly node: LayoutNode;
  /** The software data type (ids.ts SOFT); STRUCT for structs and arrays of structs. */
  readonly soft: number;
  /** The struct's type object for a struct or an array of structs. */
  readonly type?: PlusType;
}

/** A struct, UDT or block body: its members in declaration order. */
export interface PlusType {
  readonly rid: number;
  readonly size: number;
  readonly members: readonly PlusMember[];
}

export interface PlusDb {
  readonly name: string;
  readonly number: number;
  readonly optimized: boolean;
  /** The access area of its values: 0x8A0E0000 + number. */
  readonly rid: number;
  readonly type: PlusType;
  /** The block's own layout (a shared type object's members are those of the UDT's first use). */
  readonly root: StructNode;
  readonly length: number;
}

/** A process image area (I, Q or M) with the PLC tag table's names in it, as a CPU serves it. */
export interface PlusArea {
  readonly area: 'I' | 'Q' | 'M';
  /** Its native object, the access area of its items: 80, 81, 82. */
  readonly rid: number;
  /** Its type object (0x90010000, 0x90020000, 0x90030000): one member per tag, at its byte and bit in the area. */
  readonly type: PlusType;
}

export interface PlusModel {
  /** The compiled table of every block, optimized ones laid out by the standard rules (the simulator's storage). */
  readonly table: SymbolTable;
  readonly dbs: readonly PlusDb[];
  /** Every type object of the blocks, for the type-info container. */
  readonly types: readonly PlusType[];
  /** The I, Q and M areas with the tag table's names (each area's type object is in the container too). */
  readonly areas: readonly PlusArea[];
  readonly optimizedDbs: ReadonlySet<number>;
  /**
   * Each type object's VariableTypeStructModificationTime (attribute 529), by RID:
   * when its layout last changed. A reload keeps the time of a type whose layout
   * is the same and gives a changed or new one a later time.
   */
  readonly times: ReadonlyMap<number, bigint>;
  /** Each type object's layout in words (what a reload compares). */
  readonly layouts: ReadonlyMap<number, string>;
}

const SOFT_OF: Readonly<Partial<Record<DataTypeName, number>>> = Object.freeze({
  BOOL: SoftDataType.Bool,
  BYTE: SoftDataType.Byte,
  CHAR: SoftDataType.Char,
  WORD: SoftDataType.Word,
  INT: SoftDataType.Int,
  DWORD: SoftDataType.DWord,
  DINT: SoftDataType.DInt,
  REAL: SoftDataType.Real,
  DATE: SoftDataType.Date,
  TIME_OF_DAY: SoftDataType.TimeOfDay,
  TIME: SoftDataType.Time,
  S5TIME: SoftDataType.S5Time,
  DATE_AND_TIME: SoftDataType.DateAndTime,
  STRING: SoftDataType.String,
  LREAL: SoftDataType.LReal,
  ULINT: SoftDataType.ULInt,
  LINT: SoftDataType.LInt,
  LWORD: SoftDataType.LWord,
  USINT: SoftDataType.USInt,
  UINT: SoftDataType.UInt,
  UDINT: SoftDataType.UDInt,
  SINT: SoftDataType.SInt,
  WCHAR: SoftDataType.WChar,
  WSTRING: SoftDataType.WString,
  LTIME: SoftDataType.LTime,
  DTL: SoftDataType.DTL,
});

/** The software data type of an elementary type. */
function softOf(type: DataTypeName): number {
  return SOFT_OF[type] ?? SoftDataType.Byte;
}

const BLOCK_SOURCES = /\.(db|udt|scl|awl)$/i;

/**
 * Builds the model from source files (as `--source` gives them) and block numbers (as `--db` gives them). Throws SourceError.
 * `previous`: the model these sources replace (a reload, the simulator's download): type objects whose layout is
 * unchanged keep their modification time, the others get a later one.
 */
export function buildPlusModel(sources: readonly SymbolSource[], options: CompileOptions = {}, previous?: PlusModel): PlusModel {
  const blocks: BlockDecl[] = [];
  const rows: SymbolTableRow[] = [];
  for (const source of sources) {
    if (BLOCK_SOURCES.test(source.name)) blocks.push(...parseBlockSource(source));
    else rows.push(...readSymbolTable(source));
  }
  return modelOf(blocks, rows, options, previous);
}

/** The last modification time given, so that every change gets a later one even within a millisecond. */
let lastTime = 0n;

/** A modification time: microseconds since 1970, later than any given before. */
function nextTime(): bigint {
  const now = BigInt(Date.now()) * 1000n;
  lastTime = now > lastTime ? now : lastTime + 1n;
  return lastTime;
}

/** A type object's layout in words: its members' names, LIDs, types, places and the layouts of their struct types. */
function layoutOf(type: PlusType, seen: Map<PlusType, string>): string {
  const known = seen.get(type);
  if (known !== undefined) return known;
  const text = JSON.stringify(
    type.members.map((m) => [m.name, m.lid, m.soft, m.byte, m.bit, m.node.size, m.node.typeText, m.type ? layoutOf(m.type, seen) : null]),
  );
  seen.set(type, text);
  return text;
}

/** The native objects of the I, Q and M areas and their type objects (s7commplus (MIT) client.py _browse_layout). */
const AREAS: readonly { area: 'I' | 'Q' | 'M'; rid: number; typeRid: number }[] = Object.freeze([
  { area: 'I', rid: Ids.NativeTheIAreaRID, typeRid: AreaTypeInfoRID.I },
  { area: 'Q', rid: Ids.NativeTheQAreaRID, typeRid: AreaTypeInfoRID.Q },
  { area: 'M', rid: Ids.NativeTheMAreaRID, typeRid: AreaTypeInfoRID.M },
]);

/** The tag table's names of each area as members of its type object: LIDs from 0xA in the table's order, each at its byte and bit. */
function areasOf(table: SymbolTable): PlusArea[] {
  return AREAS.map(({ area, rid, typeRid }) => {
    const members = table.entries
      .filter((e) => e.area === area && e.db === null && e.kind === 'elementary' && e.dataType !== undefined && e.byte !== null)
      .map((e, i): PlusMember => {
        const node: ElementaryNode = {
          kind: 'elementary',
          byte: e.byte!,
          bit: e.bit,
          size: e.size,
          typeText: e.type,
          dataType: e.dataType!,
          stringLength: e.stringLength,
          at: e.at ?? { file: '', line: 0, column: 0 },
        };
        const name = e.name.startsWith('"') && e.name.endsWith('"') ? e.name.slice(1, -1) : e.name;
        return Object.freeze({ name, lid: FIRST_LID + i, byte: e.byte!, bit: e.bit, node, soft: softOf(e.dataType!) });
      });
    const size = members.reduce((n, m) => Math.max(n, m.byte + m.node.size), 0);
    return Object.freeze({ area, rid, type: Object.freeze({ rid: typeRid, size, members: Object.freeze(members) }) });
  });
}

function modelOf(blocks: readonly BlockDecl[], rows: readonly SymbolTableRow[], options: CompileOptions, previous?: PlusModel): PlusModel {
  const optimizedDecls = new Set(blocks.filter((b) => b.kind === 'db' && b.optimized));
  // Standard rules for every block: the optimized ones get a storage layout that only the simulator sees.
  const standard = blocks.map((b) => (b.kind === 'db' && b.optimized ? { ...b, optimized: false } : b));
  const table = compileDeclarations(standard, rows, options, literalValue);
  const typeNumbers = new Map<string, number>();
  for (const row of rows) {
    const udt = /^UDT\s*(\d+)$/i.exec(row.address.trim());
    if (udt) typeNumbers.set(row.name.toLowerCase(), Number(udt[1]));
  }
  const layouts = layoutBlocks(standard, { typeNumbers });
  const builder = new TypeBuilder();
  const dbs: PlusDb[] = [];
  const optimizedDbs = new Set<number>();
  layouts.forEach((layout: BlockLayout, i) => {
    const summary = table.blocks[i];
    if (!summary) throw new SourceError(layout.decl.at, `DB ${layout.decl.name} has no number`);
    // Laid out with standard rules above, so every block has a length here.
    if (summary.length === null) throw new SourceError(layout.decl.at, `DB ${layout.decl.name} has no standard layout`);
    const optimized = optimizedDecls.has(blocks[standard.indexOf(layout.decl)] as BlockDecl);
    if (optimized) optimizedDbs.add(summary.db);
    const type = builder.struct(layout.root, DB_TYPE_RID + summary.db);
    dbs.push(
      Object.freeze({
        name: summary.name,
        number: summary.db,
        optimized,
        rid: dbAccessArea(summary.db),
        type,
        root: layout.root,
        length: layout.length,
      }),
    );
  });
  const areas = areasOf(table);
  const seen = new Map<PlusType, string>();
  const typeLayouts = new Map<number, string>();
  const times = new Map<number, bigint>();
  // A block's access (standard or optimized) is part of its type object's layout: it decides its members' offsets.
  const access = new Map(dbs.map((d) => [d.type, d.optimized ? ' optimized' : ' standard']));
  for (const type of [...builder.types, ...areas.map((a) => a.type)]) {
    const layout = layoutOf(type, seen) + (access.get(type) ?? '');
    typeLayouts.set(type.rid, layout);
    const before = previous?.times.get(type.rid);
    times.set(type.rid, before !== undefined && previous?.layouts.get(type.rid) === layout ? before : nextTime());
  }
  return Object.freeze({
    table,
    dbs: Object.freeze(dbs),
    types: Object.freeze(builder.types),
    areas: Object.freeze(areas),
    optimizedDbs,
    times,
    layouts: typeLayouts,
  });
}

/** Gives each struct its type object; instances of one UDT share one. */
class TypeBuilder {
  readonly types: PlusType[] = [];
  private readonly byUdt = new Map<string, PlusType>();

  struct(node: StructNode, rid?: number): PlusType {
    const shared = rid === undefined && node.typeName !== undefined ? this.byUdt.get(node.typeName) : undefined;
    if (shared) return shared;
    const members = node.members.map((m, i) => this.member(m.name, m.node, node.byte, FIRST_LID + i));
    const type: PlusType = Object.freeze({
      rid: rid ?? STRUCT_TYPE_RID + this.types.length,
      size: node.size,
      members: Object.freeze(members),
    });
    this.types.push(type);
    if (rid === undefined && node.typeName !== undefined) this.byUdt.set(node.typeName, type);
    return type;
  }

  private member(name: string, node: LayoutNode, base: number, lid: number): PlusMember {
    const place = { name, lid, byte: node.byte - base, bit: node.bit, node };
    if (node.kind === 'elementary') return Object.freeze({ ...place, soft: softOf(node.dataType) });
    if (node.kind === 'struct') return Object.freeze({ ...place, soft: SoftDataType.Struct, type: this.struct(node) });
    const first = node.elements[0];
    if (first?.kind === 'struct') return Object.freeze({ ...place, soft: SoftDataType.Struct, type: this.struct(first) });
    return Object.freeze({ ...place, soft: softOf(node.elementType?.dataType ?? 'BYTE') });
  }
}

/**
 * The node a LID path names in `db`: member LIDs, a 0-based element index
 * after an array, and for an element of an array of structs the marker 1
 * before its member's LID (typeinfo.py `_walk`: `<lid>.<index>.1.<lid>`).
 * A type object is shared by every instance of its UDT, so the path walks
 * the block's own layout alongside it. Undefined when the path names nothing.
 */
export function resolveLids(db: PlusDb, lids: readonly number[]): LayoutNode | undefined {
  let type: PlusType | undefined = db.type;
  let struct: StructNode | undefined = db.root;
  let node: LayoutNode | undefined;
  let i = 0;
  while (i < lids.length) {
    if (!type || !struct) return undefined;
    // Members carry LIDs FIRST_LID, FIRST_LID + 1, … in order (TypeBuilder): the LID gives the index, no search.
    const index = lids[i]! - FIRST_LID;
    if (type.members[index]?.lid !== lids[i]) return undefined;
    type = type.members[index]!.type;
    node = struct.members[index]?.node;
    if (!node) return undefined;
    i++;
    if (node.kind === 'array' && i < lids.length) {
      node = node.elements[lids[i]!];
      if (!node) return undefined;
      i++;
      if (node.kind === 'struct' && i < lids.length) {
        if (lids[i] !== 1) return undefined;
        i++;
      }
    }
    struct = node.kind === 'struct' ? node : undefined;
  }
  return node;
}

/** The tag an area's LID names (one LID: the member of the area's type object), or undefined. */
export function resolveAreaLid(area: PlusArea, lids: readonly number[]): PlusMember | undefined {
  return lids.length === 1 ? area.type.members.find((m) => m.lid === lids[0]) : undefined;
}
