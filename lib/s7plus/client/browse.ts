/**
 * client.browse(): the PLC's data blocks and tag table as a symbol table in
 * the shape compiled sources give (lib/symbols/model.ts). The block list
 * comes from an Explore of thePLCProgram, each block's type object RID from
 * its LID 1, the members (LID, software type, offsets, names) from an
 * Explore of the type-info container (typeinfo.ts). The members become
 * declarations that the symbol compiler names and types as it does a
 * source's, so lookup() and suggest() behave alike; each entry gets its
 * S7CommPlus access path (area and LIDs), and a standard block's members the
 * byte and bit the PLC gives. The I, Q and M areas' type objects (0x90010000,
 * 0x90020000, 0x90030000) hold the PLC tag table's names: they become the
 * rows a tag table export gives, read by the area's object (80, 81, 82) and
 * the tag's LID.
 *
 * Layouts: s7commplus (MIT), client.py (_read_typeinfo_rid: LID 1 of a block
 * answers its type object's RID; _browse_layout: the areas' type objects);
 * thomas-v2/S7CommPlusDriver (LGPL, facts only), S7CommPlusConnection.cs
 * Browse (the same areas and type-info RIDs).
 */
import { formatAddress } from '../../address';
import { PlcError } from '../../errors';
import { compileDeclarations } from '../../symbols/compile';
import { elementIndex, memberRef } from '../../symbols/layout';
import { NameIndex } from '../../symbols/names';
import type { DataBlockDecl, MemberDecl, SourcePosition, SymbolEntry, SymbolTable, SymbolTableRow, TypeRef } from '../../symbols/model';
import { symbolCrc, type SymbolLevel } from '../codec/symbol-crc';
import { AreaTypeInfoRID, dbAccessArea, Ids } from '../constants';
import { readAsk } from './asks';
import { inChunks, type Limits } from './chunks';
import { dataBlocks, explore } from './services';
import type { S7PlusSession } from './session';
import { timesOf, TYPE_OF, typeObjects, type Member, type TypeObject, type TypeTimes } from './typeinfo';

/** Where a browsed declaration "stands": the PLC, not a file. */
const AT: SourcePosition = Object.freeze({ file: 'PLC', line: 0, column: 0 });
/** The most elements of an array the symbol compiler lays out (lib/symbols/layout.ts). */
const MAX_ELEMENTS = 65535;

/** Blocks whose LID 1 a browse reads per request (no PLC is known to refuse 20 items). */
const BROWSE_LIMITS: Limits = { maxItems: () => 20, refused: () => {} };

/** The RID of each block's type object: LID 1 of each block, 20 blocks per request. */
async function typeRids(session: S7PlusSession, numbers: number[], signal?: AbortSignal): Promise<Map<number, number>> {
  const rids = new Map<number, number>();
  const address = (n: number) => ({ symbolCrc: 0, accessArea: dbAccessArea(n), accessSubArea: Ids.DBValueActual, lids: [1] });
  const send = (chunk: number[]) => session.request(readAsk(chunk.map(address)), { signal });
  await inChunks(numbers, BROWSE_LIMITS, send, (chunk, body) => {
    chunk.forEach((n, k) => {
      const v = body.values.get(k + 1)?.value;
      if (typeof v === 'number') rids.set(n, v >>> 0);
    });
  });
  return rids;
}

/** Per entry name (as compiled), the LIDs, the SymbolCrc and the PLC's offset of a member of a standard block. */
interface Facts {
  lids: Map<string, number[]>;
  crcs: Map<string, number>;
  place: Map<string, { byte: number; bit: number | null }>;
}

/**
 * A member's level of a symbol path: its name and software type, an array's lower bound too; undefined for a
 * multi-dimensional array, whose bound in the CRC no public source gives (codec/symbol-crc.ts).
 */
function levelOf(m: Member): SymbolLevel | undefined {
  if (!m.dims) return { name: m.name, soft: m.soft };
  return m.dims.length === 1 ? { name: m.name, soft: m.soft, low: m.dims[0]!.low } : undefined;
}

const key = (name: string) => name.toLowerCase();

/** A member's declaration; records its access path under its entry name (and those of its elements and members). */
function declare(
  m: Member,
  types: Map<number, TypeObject>,
  path: { name: string; lids: number[]; base: number | undefined; levels: SymbolLevel[] | undefined },
  facts: Facts,
  depth: number,
): MemberDecl {
  if (depth > 32) throw new PlcError('PROTOCOL_ERROR', `S7CommPlus browse: types nested deeper than 32 at ${path.name}`);
  const name = `${path.name}.${memberRef(m.name)}`;
  const lids = [...path.lids, m.lid];
  facts.lids.set(key(name), lids);
  const level = levelOf(m);
  const levels = path.levels && level ? [...path.levels, level] : undefined;
  // Every element of an array has the array's CRC: an index is not part of it.
  const crc = levels && symbolCrc(levels);
  if (crc !== undefined) facts.crcs.set(key(name), crc);
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
      members: t.members.map((c) => declare(c, types, { name: prefix, lids: prefixLids, base, levels }, facts, depth + 1)),
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
      if (crc !== undefined) facts.crcs.set(key(elName), crc);
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
function tagRows(types: Map<number, TypeObject>, facts: Facts, areas: Map<string, number>): SymbolTableRow[] {
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
      facts.lids.set(key(name), [m.lid]);
      facts.crcs.set(key(name), symbolCrc([{ name: m.name, soft: m.soft }]));
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
  const rids =
    blocks.length === 0
      ? new Map<number, number>()
      : await typeRids(
          session,
          blocks.map((b) => b.number),
          signal,
        );
  const container = await explore(session, Ids.ObjectOmsTypeInfoContainer, [], 'its types', signal);
  const types = typeObjects(container);
  const decls: DataBlockDecl[] = [];
  const facts: Facts = { lids: new Map(), crcs: new Map(), place: new Map() };
  const areas = new Map<string, number>();
  for (const b of blocks) {
    const rid = rids.get(b.number);
    const t = rid === undefined ? undefined : types.get(rid);
    if (!t) continue;
    const optimized = t.members.length > 0 && t.members.every((m) => m.byte === undefined);
    const blockName = `"${b.name}"`;
    areas.set(key(blockName), dbAccessArea(b.number));
    const members = t.members.map((m) =>
      declare(m, types, { name: blockName, lids: [], base: optimized ? undefined : 0, levels: [] }, facts, 0),
    );
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
  const rows = tagRows(types, facts, areas);
  return { table: tableOf(decls, rows, facts, areas), times: timesOf(container), blocks: blockWords(blocks) };
}

function tableOf(decls: DataBlockDecl[], rows: SymbolTableRow[], facts: Facts, areas: Map<string, number>): SymbolTable {
  const { lids, crcs, place } = facts;
  const compiled = compileDeclarations(decls, rows, {});
  const entries = compiled.entries.map((e): SymbolEntry => {
    const blockKey = key(e.name.slice(0, e.name.indexOf('"', 1) + 1));
    const area = areas.get(blockKey) ?? dbAccessArea(e.db ?? 0);
    const crc = crcs.get(key(e.name));
    const access = { area, lids: Object.freeze(lids.get(key(e.name)) ?? []), ...(crc === undefined ? {} : { symbolCrc: crc }) };
    const withAccess = { ...e, access: Object.freeze(access) };
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
