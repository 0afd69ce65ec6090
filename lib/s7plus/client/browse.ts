/**
 * client.browse(): the PLC's data blocks as a symbol table in the shape
 * compiled sources give (lib/symbols/model.ts). The block list comes from
 * an Explore of thePLCProgram, each block's type object RID from its LID 1,
 * the members (LID, software type, offsets, names) from an Explore of the
 * type-info container. The members become declarations that the symbol
 * compiler names and types as it does a source's, so lookup() and suggest()
 * behave alike; each entry gets its S7CommPlus access path (area and LIDs),
 * and a standard block's members the byte and bit the PLC gives.
 *
 * Layouts: s7commplus (MIT), typeinfo.py (parse_vartype_list,
 * parse_offset_info in its numbering 8..14, the classic flag 0x08 and the
 * bit offsets of bitoffsetinfo), client.py (_read_typeinfo_rid: LID 1 of a
 * block answers its type object's RID).
 */
import { formatAddress } from '../../address';
import { PlcError } from '../../errors';
import { compileDeclarations } from '../../symbols/compile';
import { elementIndex, memberRef } from '../../symbols/layout';
import { NameIndex } from '../../symbols/names';
import type { DataBlockDecl, MemberDecl, SourcePosition, SymbolEntry, SymbolTable, SymbolTableRow, TypeRef } from '../../symbols/model';
import type { DataTypeName } from '../../types';
import { attributeOf, walkObjects, type PObject } from '../codec/object';
import { decodeGetMultiVariablesResponse, encodeGetMultiVariablesRequest, readRequest } from '../codec/variables';
import { AreaTypeInfoRID, dbAccessArea, ElementId, FunctionCode, Ids, SoftDataType } from '../constants';
import { dataBlocks, explore } from './services';
import type { S7PlusSession } from './session';

/** Where a browsed declaration "stands": the PLC, not a file. */
const AT: SourcePosition = Object.freeze({ file: 'PLC', line: 0, column: 0 });
/** The most elements of an array the symbol compiler lays out (lib/symbols/layout.ts). */
const MAX_ELEMENTS = 65535;

const TYPE_OF: Readonly<Record<number, DataTypeName>> = Object.freeze({
  [SoftDataType.Bool]: 'BOOL',
  [SoftDataType.Byte]: 'BYTE',
  [SoftDataType.Char]: 'CHAR',
  [SoftDataType.Word]: 'WORD',
  [SoftDataType.Int]: 'INT',
  [SoftDataType.DWord]: 'DWORD',
  [SoftDataType.DInt]: 'DINT',
  [SoftDataType.Real]: 'REAL',
  [SoftDataType.Date]: 'DATE',
  [SoftDataType.TimeOfDay]: 'TIME_OF_DAY',
  [SoftDataType.Time]: 'TIME',
  [SoftDataType.S5Time]: 'S5TIME',
  [SoftDataType.DateAndTime]: 'DATE_AND_TIME',
  [SoftDataType.String]: 'STRING',
  [SoftDataType.LReal]: 'LREAL',
  [SoftDataType.ULInt]: 'ULINT',
  [SoftDataType.LInt]: 'LINT',
  [SoftDataType.LWord]: 'LWORD',
  [SoftDataType.USInt]: 'USINT',
  [SoftDataType.UInt]: 'UINT',
  [SoftDataType.UDInt]: 'UDINT',
  [SoftDataType.SInt]: 'SINT',
  [SoftDataType.WChar]: 'WCHAR',
  [SoftDataType.WString]: 'WSTRING',
  [SoftDataType.LTime]: 'LTIME',
  [SoftDataType.DTL]: 'DTL',
});

/** One member of a type object, as its vartype element and name give it. */
interface Member {
  name: string;
  lid: number;
  soft: number;
  /** Offset in a standard block (classic), from the start of its struct; undefined in an optimized one. */
  byte?: number;
  bit?: number;
  stringLength: number;
  /** Arrays: bounds per dimension, outermost first. */
  dims?: { low: number; high: number }[];
  /** Structs and arrays of structs: the RID of the struct's type object. */
  structRid?: number;
}

interface TypeObject {
  members: Member[];
}

/** Reads the vartype elements (typeinfo.py parse_vartype_element / parse_offset_info). */
function vartypes(raw: Buffer): Omit<Member, 'name'>[] {
  const out: Omit<Member, 'name'>[] = [];
  let at = 0;
  let first = true;
  for (;;) {
    const len = raw.readUInt16BE(at);
    at += 2;
    if (len === 0) return out;
    const end = at + len;
    if (first) {
      at += 4;
      first = false;
    }
    while (at < end) {
      const lid = raw.readUInt32LE(at);
      const soft = raw[at + 8]!;
      const flags = raw.readUInt16BE(at + 9);
      const bitInfo = raw[at + 11]!;
      at += 12;
      const oi = (flags >> 12) & 0x0f;
      const classic = (bitInfo & 0x08) !== 0;
      const m: Omit<Member, 'name'> = { lid, soft, stringLength: 0 };
      const bit = soft === SoftDataType.Bool ? (classic ? (bitInfo & 0x70) >> 4 : flags & 7) : undefined;
      const place = (nonopt: number) => {
        if (!classic) return;
        m.byte = nonopt;
        if (bit !== undefined) m.bit = bit;
      };
      switch (oi) {
        case 8:
          place(raw.readUInt16LE(at + 2));
          at += 4;
          break;
        case 9:
          m.stringLength = raw.readUInt16LE(at);
          place(raw.readUInt32LE(at + 8));
          at += 12;
          break;
        case 10:
        case 11:
        case 13:
        case 14: {
          m.stringLength = raw.readUInt16LE(at);
          place(raw.readUInt32LE(at + 8));
          const low = raw.readInt32LE(at + 12);
          const count = raw.readUInt32LE(at + 16);
          at += 20;
          if (oi === 10 || oi === 13) m.dims = [{ low, high: low + count - 1 }];
          else {
            const dims: { low: number; high: number }[] = [];
            for (let i = 0; i < 6; i++) {
              const c = raw.readUInt32LE(at + 24 + 4 * i);
              if (c > 0) dims.push({ low: raw.readInt32LE(at + 4 * i), high: raw.readInt32LE(at + 4 * i) + c - 1 });
            }
            // Index 0 is the dimension that runs fastest: the last one written.
            m.dims = dims.reverse();
            at += 48;
          }
          if (oi === 13 || oi === 14) {
            m.structRid = raw.readUInt32LE(at + 8);
            at += 28;
          }
          break;
        }
        case 12:
          place(raw.readUInt32LE(at + 8));
          m.structRid = raw.readUInt32LE(at + 12);
          at += 32;
          break;
        default:
          throw new PlcError('PROTOCOL_ERROR', `S7CommPlus browse: offset info ${oi} of LID ${lid} is not one this client reads`);
      }
      out.push(m);
    }
  }
}

/** The names of the varname list: length byte, UTF-8 bytes, a 0 (typeinfo.py VarnameList). */
function varnames(raw: Buffer): string[] {
  const names: string[] = [];
  let at = 0;
  for (let len = raw.readUInt16BE(at); len !== 0; len = raw.readUInt16BE(at)) {
    const end = at + 2 + len;
    at += 2;
    while (at < end) {
      const n = raw[at]!;
      names.push(raw.toString('utf8', at + 1, at + 1 + n));
      at += n + 2;
    }
  }
  return names;
}

function typeObjects(objects: PObject[]): Map<number, TypeObject> {
  const types = new Map<number, TypeObject>();
  for (const o of walkObjects(objects)) {
    const lists = o.members.filter((m) => m.kind === 'list');
    const vt = lists.find((l) => l.tag === ElementId.VartypeList);
    const vn = lists.find((l) => l.tag === ElementId.VarnameList);
    if (!vt || !vn) continue;
    try {
      const elements = vartypes(vt.raw);
      const names = varnames(vn.raw);
      types.set(o.relationId >>> 0, { members: elements.map((e, i) => ({ ...e, name: names[i] ?? `LID${e.lid}` })) });
    } catch (err) {
      if (err instanceof PlcError) throw err;
      throw new PlcError('PROTOCOL_ERROR', `S7CommPlus browse: the type object 0x${o.relationId.toString(16)} is cut short`);
    }
  }
  return types;
}

/** The RID of each block's type object: LID 1 of the block, all blocks in one request. */
async function typeRids(session: S7PlusSession, numbers: number[], signal?: AbortSignal): Promise<Map<number, number>> {
  const rids = new Map<number, number>();
  const addresses = numbers.map((n) => ({ symbolCrc: 0, accessArea: dbAccessArea(n), accessSubArea: Ids.DBValueActual, lids: [1] }));
  for (let at = 0; at < addresses.length; at += 20) {
    const chunk = addresses.slice(at, at + 20);
    const answer = await session.request(
      FunctionCode.GetMultiVariables,
      (sequence, sessionId, integrityId) =>
        encodeGetMultiVariablesRequest({
          ...readRequest(sequence, sessionId, chunk),
          ...(integrityId === undefined ? {} : { integrityId }),
        }),
      { signal },
    );
    const { body } = decodeGetMultiVariablesResponse(answer, { integrity: session.integrityOn });
    chunk.forEach((_, k) => {
      const v = body.values.get(k + 1)?.value;
      if (typeof v === 'number') rids.set(numbers[at + k]!, v >>> 0);
    });
  }
  return rids;
}

/** Per entry name (as compiled), the LIDs and the PLC's offset of a member of a standard block. */
interface Facts {
  lids: Map<string, number[]>;
  place: Map<string, { byte: number; bit: number | null }>;
}

const key = (name: string) => name.toLowerCase();

/** A member's declaration; records its access path under its entry name (and those of its elements and members). */
function declare(
  m: Member,
  types: Map<number, TypeObject>,
  path: { name: string; lids: number[]; base: number | undefined },
  facts: Facts,
  depth: number,
): MemberDecl {
  if (depth > 32) throw new PlcError('PROTOCOL_ERROR', `S7CommPlus browse: types nested deeper than 32 at ${path.name}`);
  const name = `${path.name}.${memberRef(m.name)}`;
  const lids = [...path.lids, m.lid];
  facts.lids.set(key(name), lids);
  const abs = path.base !== undefined && m.byte !== undefined ? path.base + m.byte : undefined;
  if (abs !== undefined) facts.place.set(key(name), { byte: abs, bit: m.bit ?? null });
  const struct = (rid: number, prefix: string, prefixLids: number[], base: number | undefined): TypeRef => {
    const t = types.get(rid);
    if (!t)
      throw new PlcError(
        'PROTOCOL_ERROR',
        `S7CommPlus browse: ${name} names the type object 0x${rid.toString(16)}, which the PLC did not list`,
      );
    return {
      kind: 'struct',
      members: t.members.map((c) => declare(c, types, { name: prefix, lids: prefixLids, base }, facts, depth + 1)),
      at: AT,
    };
  };
  let type: TypeRef;
  const elementary = (): TypeRef => {
    const t = TYPE_OF[m.soft];
    if (!t)
      throw new PlcError('NOT_SUPPORTED', `S7CommPlus browse: ${name} has the software type ${m.soft}, which this client does not read`);
    return { kind: 'elementary', type: t, stringLength: t === 'STRING' || t === 'WSTRING' ? m.stringLength : 0, at: AT };
  };
  if (m.dims) {
    // Elements: LIDs <member>.<0-based index>, and for an element of an array of structs 1 before its member's LID.
    const count = m.dims.reduce((n, d) => n * (d.high - d.low + 1), 1);
    // The symbol compiler lays out arrays up to 65535 elements; a larger count is no program this client can name.
    if (!(count >= 1 && count <= MAX_ELEMENTS))
      throw new PlcError('PROTOCOL_ERROR', `S7CommPlus browse: ${name} is an array of ${count} elements, more than ${MAX_ELEMENTS}`);
    const element = m.structRid !== undefined ? undefined : elementary();
    let elementType: TypeRef | undefined = element;
    for (let k = 0; k < count; k++) {
      const index = elementIndex(m.dims, k);
      const elName = `${name}[${index}]`;
      facts.lids.set(key(elName), [...lids, k]);
      if (m.structRid !== undefined) {
        const t = struct(m.structRid, elName, [...lids, k, 1], undefined);
        elementType ??= t;
      }
    }
    type = { kind: 'array', dims: m.dims, element: elementType ?? elementary(), at: AT };
  } else if (m.structRid !== undefined) type = struct(m.structRid, name, lids, abs);
  else type = elementary();
  return { name: m.name, type, attributes: {}, comment: '', at: AT };
}

/**
 * Each type object's VariableTypeStructModificationTime (attribute 529), by RID, where the PLC reports one: what a
 * download changes (s7commplus (MIT) client.py _type_info_times; PLCSIM Advanced and a CPU 1215C report it).
 */
export type TypeTimes = ReadonlyMap<number, bigint>;

function timesOf(objects: PObject[]): Map<number, bigint> {
  const times = new Map<number, bigint>();
  for (const o of walkObjects(objects)) {
    const v = attributeOf(o, Ids.VariableTypeStructModificationTime)?.value;
    if (typeof v === 'bigint' || typeof v === 'number') times.set(o.relationId >>> 0, BigInt(v));
  }
  return times;
}

/**
 * The type objects' modification times now: one Explore of the type-info container asking for attribute 529 only,
 * which the PLC answers with each type object's head and time (about 20 bytes a type). Undefined when the PLC refuses
 * the question (the program cannot be watched this way; a link error still throws).
 */
export async function typeTimes(session: S7PlusSession, signal?: AbortSignal): Promise<TypeTimes | undefined> {
  try {
    return timesOf(await explore(session, Ids.ObjectOmsTypeInfoContainer, [Ids.VariableTypeStructModificationTime], 'its types', signal));
  } catch (err) {
    if (err instanceof PlcError && (err.code === 'PLC_ERROR' || err.code === 'OBJECT_DOES_NOT_EXIST')) return undefined;
    throw err;
  }
}

/** True when two sets of modification times differ: a type object changed, came or went. */
export function timesDiffer(a: TypeTimes, b: TypeTimes): boolean {
  if (a.size !== b.size) return true;
  for (const [rid, time] of a) if (b.get(rid) !== time) return true;
  return false;
}

/** The I, Q and M areas: the type object holding the tag table's names of each. */
const TAG_AREAS: readonly { area: 'I' | 'Q' | 'M'; rid: number; typeRid: number }[] = Object.freeze([
  { area: 'I', rid: Ids.NativeTheIAreaRID, typeRid: AreaTypeInfoRID.I },
  { area: 'Q', rid: Ids.NativeTheQAreaRID, typeRid: AreaTypeInfoRID.Q },
  { area: 'M', rid: Ids.NativeTheMAreaRID, typeRid: AreaTypeInfoRID.M },
]);

/**
 * The PLC tag table's names in the I, Q and M areas as the rows a tag table export gives (name, address), so the
 * symbol compiler makes the entries a compiled tag table gives; a tag without a standard offset or of a type this
 * client does not read is left out (it has no address to give).
 */
function tagRows(types: Map<number, TypeObject>, lids: Map<string, number[]>, areas: Map<string, number>): SymbolTableRow[] {
  const rows: SymbolTableRow[] = [];
  for (const { area, rid, typeRid } of TAG_AREAS) {
    for (const m of types.get(typeRid)?.members ?? []) {
      const type = TYPE_OF[m.soft];
      if (m.byte === undefined || m.dims || m.structRid !== undefined || !type) continue;
      const address = formatAddress({
        area,
        dbNumber: 0,
        byteOffset: m.byte,
        bitOffset: m.bit ?? 0,
        type,
        count: 1,
        isArray: false,
        stringLength: m.stringLength,
      });
      const name = `"${m.name}"`;
      lids.set(key(name), [m.lid]);
      areas.set(key(name), rid);
      rows.push({ name: m.name, address, dataType: type, comment: '', at: AT });
    }
  }
  return rows;
}

/** The PLC's data blocks and tag table as a symbol table (see the file's comment). */
export async function browseTable(session: S7PlusSession, signal?: AbortSignal): Promise<SymbolTable> {
  return (await browseProgram(session, signal)).table;
}

/** A browsed program: the table, the type objects' modification times and the block list it was browsed at. */
export interface BrowsedTable {
  table: SymbolTable;
  times: TypeTimes;
  /** The data blocks' numbers and names, in words (what a rename changes when no layout does). */
  blocks: string;
}

/** The data block list in words: number and name of each. */
export function blockWords(blocks: readonly { number: number; name: string }[]): string {
  return blocks.map((b) => `${b.number} ${b.name}`).join('\n');
}

/** The browsed table and the type objects' modification times it was browsed at (one Explore gives both). */
export async function browseProgram(session: S7PlusSession, signal?: AbortSignal): Promise<BrowsedTable> {
  const blocks = await dataBlocks(session, signal);
  const rids = blocks.length === 0 ? new Map<number, number>() : await typeRids(
    session,
    blocks.map((b) => b.number),
    signal,
  );
  const container = await explore(session, Ids.ObjectOmsTypeInfoContainer, [], 'its types', signal);
  const types = typeObjects(container);
  const decls: DataBlockDecl[] = [];
  const facts: Facts = { lids: new Map(), place: new Map() };
  const areas = new Map<string, number>();
  for (const b of blocks) {
    const rid = rids.get(b.number);
    const t = rid === undefined ? undefined : types.get(rid);
    if (!t) continue;
    const optimized = t.members.length > 0 && t.members.every((m) => m.byte === undefined);
    const blockName = `"${b.name}"`;
    areas.set(key(blockName), dbAccessArea(b.number));
    const members = t.members.map((m) => declare(m, types, { name: blockName, lids: [], base: optimized ? undefined : 0 }, facts, 0));
    decls.push({
      kind: 'db',
      name: b.name,
      number: b.number,
      attributes: {},
      optimized,
      body: { kind: 'struct', members, at: AT },
      startValues: [],
      at: AT,
    });
  }
  const rows = tagRows(types, facts.lids, areas);
  return { table: tableOf(decls, rows, facts.lids, facts.place, areas), times: timesOf(container), blocks: blockWords(blocks) };
}

function tableOf(
  decls: DataBlockDecl[],
  rows: SymbolTableRow[],
  lids: Map<string, number[]>,
  place: Map<string, { byte: number; bit: number | null }>,
  areas: Map<string, number>,
): SymbolTable {
  const compiled = compileDeclarations(decls, rows, {});
  const entries = compiled.entries.map((e): SymbolEntry => {
    const blockKey = key(e.name.slice(0, e.name.indexOf('"', 1) + 1));
    const area = areas.get(blockKey) ?? dbAccessArea(e.db ?? 0);
    const withAccess = { ...e, access: Object.freeze({ area, lids: Object.freeze(lids.get(key(e.name)) ?? []) }) };
    delete (withAccess as { at?: unknown }).at;
    const p = place.get(key(e.name));
    // The PLC's own offset of a standard member is the authority; our layout rules only fill in array elements.
    if (!p || e.byte === null || (p.byte === e.byte && p.bit === e.bit)) return Object.freeze(withAccess);
    const address =
      e.kind === 'elementary' && e.dataType
        ? formatAddress({
            area: 'DB',
            dbNumber: e.db ?? 0,
            byteOffset: p.byte,
            bitOffset: p.bit ?? 0,
            type: e.dataType,
            count: 1,
            isArray: false,
            stringLength: e.stringLength,
          })
        : e.address;
    return Object.freeze({ ...withAccess, byte: p.byte, bit: p.bit, address });
  });
  const index = new NameIndex(entries);
  return Object.freeze({
    entries: Object.freeze(entries),
    blocks: compiled.blocks.map((b) => Object.freeze({ ...b, file: 'PLC' })),
    types: Object.freeze([]),
    lookup: (name: string) => index.lookup(name),
    suggest: (name: string, max?: number) => index.suggest(name, max),
  });
}
