/**
 * Tags by name in the client: a name as the user writes it (`"Tank".Level`,
 * `"Tank".Motor`, `"Recipe".Step[3]`) resolved through a compiled
 * SymbolTable (its lookup() applies the names rules) to the driver's tag for
 * the entry's bytes, keyed by the name as given, so results and errors name
 * what the user wrote. The client resolves each name once, in its parse
 * cache: a poll of symbols is a poll of addresses.
 *
 * A whole STRUCT / UDT instance, or an array of them, is one tag over its
 * bytes (one item of one request) and a shape that decodes the members from
 * those bytes into an object (an array of objects). A write of such an
 * object becomes one write per member it names (docs/symbols.md, "Reading
 * and writing by name").
 */
import { parseAddress } from '../address';
import { AddressError, OptimizedBlockError, PlcError, toPlcError } from '../errors';
import type { DriverTag } from '../link/driver';
import type { PlcData, PlcValue, Tag } from '../types';
import { tagDecoder, validateValue, type TagDecoder } from '../values';
import { orList } from '../values/text';
import type { SymbolEntry, SymbolTable } from './model';
import { canonicalName, splitSymbol } from './names';
import { assembleStruct, expandStruct, memberKey, type StructTree } from './struct-tree';

/**
 * How the bytes of a struct (or of an array of structs) become a value, and
 * a value its member writes: a tree of the entry's members down to the
 * elementary ones, each with its offset from the struct's first byte.
 */
export type SymbolShape<T> = StructTree<ShapeLeaf<T>>;

/** A struct's elementary member as a driver reaches it by address. */
interface ShapeLeaf<T> {
  /** The driver's tag of the member, named by its full symbol (the key of its errors). */
  readonly tag: T;
  /** Its shape for the value codecs (S7 syntax, as every entry address is written). */
  readonly s7: Tag;
  /** Bytes from the outer struct's first byte. */
  readonly offset: number;
  readonly decode: TagDecoder;
}

/** A resolved name: the entry, the driver's tag for its bytes, and for structs their shape. */
export interface ResolvedSymbol<T> {
  readonly entry: SymbolEntry;
  readonly tag: T;
  readonly shape?: SymbolShape<T>;
}

/** What a tag's text stands for: the driver's tag, and the table's entry when the text is a name. */
export interface AddressOrSymbol<T> {
  readonly tag: T;
  readonly symbol?: ResolvedSymbol<T>;
}

/**
 * The rule "addresses first" (docs/symbols.md), written once for the client,
 * the editor and the doctor: text that `parse` (the driver's address parser)
 * reads is that address, so a symbol table never changes what an address
 * means; anything else is a name, looked up in `table`. Throws a PlcError:
 * the address error when there is no table, the unknown-name error
 * (unknownSymbol: the name and the closest names) for a name the table
 * lacks, and the driver's reach error for an entry it cannot reach.
 */
export function addressOrSymbol<T extends DriverTag>(
  text: string,
  parse: (address: string) => T,
  table: SymbolTable | undefined,
): AddressOrSymbol<T> {
  let asAddress: PlcError;
  try {
    return { tag: parse(text) };
  } catch (err) {
    asAddress = toPlcError(err, 'INVALID_ADDRESS');
  }
  if (!table || typeof text !== 'string') throw asAddress;
  let symbol: ResolvedSymbol<T> | undefined;
  try {
    symbol = resolveSymbol(table, text, parse);
  } catch (err) {
    throw toPlcError(err, 'INVALID_ADDRESS');
  }
  if (!symbol) throw unknownSymbol(table, text, asAddress);
  return { tag: symbol.tag, symbol };
}

/** A name the table does not know (see addressOrSymbol): INVALID_ADDRESS naming it and the closest names the table has. */
function unknownSymbol(table: SymbolTable, name: string, asAddress: PlcError): PlcError {
  const quoted = name.includes('"');
  let suggestions: string[] = [];
  try {
    suggestions = table.suggest(name);
  } catch {
    // A table without suggestions still names the symbol.
  }
  const parent = suggestions.length === 0 ? knownParent(table, name) : undefined;
  // The sources were given: the address parser's hint to give them does not apply.
  const problem = asAddress instanceof AddressError ? asAddress.problem : asAddress.message;
  if (!quoted && suggestions.length === 0 && !parent)
    return asAddress instanceof AddressError ? new AddressError(name, problem) : asAddress;
  const hint =
    suggestions.length > 0
      ? `; did you mean ${orList(suggestions)}?`
      : parent
        ? `; ${parent.name} has no such member${membersOf(parent)}`
        : '; the sources declare no such name';
  // An unquoted name may have been meant as an address: say what is wrong with it as one too.
  const address = quoted ? '' : ` (nor an address: ${problem})`;
  return new PlcError('INVALID_ADDRESS', `unknown symbol ${name}${hint}${address}`, { tag: name, cause: asAddress });
}

/** The longest leading part of a name that the table knows (`"Tank".Motor` of `Tank.Motor.Nope`), when there is one. */
function knownParent(table: SymbolTable, name: string): Pick<SymbolEntry, 'name' | 'children'> | undefined {
  const parts = splitSymbol(name);
  if (!parts) return undefined;
  for (let k = parts.length - 1; k >= 1; k--) {
    const entry = table.lookup(canonicalName(parts.slice(0, k)));
    if (entry) return entry;
  }
  // The block itself has no entry: its members are the entries one part below it.
  const first = parts[0]!;
  if (parts.length < 2 || first.index) return undefined;
  const wanted = first.name.toLowerCase();
  // `DB1.DBW` is a broken address, not a member of DB1: it keeps the address parser's words.
  const looksAbsolute = /^DB[XBWD]?\d*$/i.test(parts[1]!.name);
  const block = table.blocks.find((b) => b.name.toLowerCase() === wanted || (!looksAbsolute && `db${b.db}` === wanted));
  if (!block) return undefined;
  const prefix = `"${block.name}".`;
  const children = table.entries.filter((e) => e.name.startsWith(prefix) && splitSymbol(e.name)?.length === 2 && !/\]$/.test(e.name));
  return { name: `"${block.name}"`, children: children.map((e) => e.name) };
}

/** ` (its members: Level, Motor)`, at most 8 named; '' for an entry without children. */
function membersOf(entry: Pick<SymbolEntry, 'name' | 'children'>): string {
  const children = entry.children ?? [];
  if (children.length === 0) return '';
  const names = children.slice(0, 8).map((c) => c.slice(entry.name.length).replace(/^\./, ''));
  return ` (its members: ${names.join(', ')}${children.length > 8 ? `, … ${children.length - 8} more` : ''})`;
}

/**
 * Resolves `name` through the table to a driver tag (`parse` is the driver's
 * address parser: its reach checks apply to the entry's address), or
 * undefined when the table has no such name. A name whose entry the driver
 * cannot reach throws that error, naming the symbol; a name in a block with
 * optimized access, which has no address, throws OptimizedBlockError
 * (OPTIMIZED_BLOCK): this path reads by address (PUT/GET, FETCH/WRITE).
 */
export function resolveSymbol<T extends DriverTag>(
  table: SymbolTable,
  name: string,
  parse: (address: string) => T,
): ResolvedSymbol<T> | undefined {
  const entry = table.lookup(name) ?? wholeBlock(table, name);
  if (!entry) return undefined;
  const named = (address: string, as: string): T => {
    let tag: T;
    try {
      tag = parse(address);
    } catch (err) {
      const problem = err instanceof Error ? err.message : String(err);
      throw new PlcError('INVALID_ADDRESS', `symbol ${as} (${address}): ${problem}`, { tag: as, cause: err });
    }
    return { ...tag, address: as };
  };
  const { address, byte } = placed(table, entry, name);
  if (isElementary(entry)) return { entry, tag: named(address, name) };
  const shape = shapeOf(table, byte, entry, named);
  return { entry, tag: named(spanAddress(entry, byte), name), shape };
}

/** An entry's address and byte; OptimizedBlockError, naming `as` and the block, for one of an optimized block (no address). */
function placed(table: SymbolTable, entry: SymbolEntry, as: string): { address: string; byte: number } {
  if (entry.address !== null && entry.byte !== null) return { address: entry.address, byte: entry.byte };
  const db = entry.db ?? 0;
  const block = table.blocks.find((b) => b.db === db);
  throw new OptimizedBlockError(as, block?.name ?? `DB${db}`, db);
}

/** Per table: each data block's first entry and the names of its top-level members (wholeBlock). */
const blockMembers = new WeakMap<SymbolTable, Map<number, { first: SymbolEntry; top: string[] }>>();

/**
 * A whole data block named alone (`"Tank"`, `tank`, `DB10`) as a struct
 * entry over its declared length, whose children are its top-level members:
 * compileSymbols lists the members of a block but no entry for the block
 * itself. The name is matched with the table's own rules: it names the
 * block when it finds the block's first member with that member's part
 * after it. Undefined when it names no block.
 */
export function wholeBlock(table: SymbolTable, name: string): SymbolEntry | undefined {
  const parts = splitSymbol(name);
  if (parts?.length !== 1 || parts[0]!.index) return undefined;
  let members = blockMembers.get(table);
  if (!members) {
    members = new Map();
    const children = new Set<string>();
    for (const e of table.entries) for (const c of e.children ?? []) children.add(c);
    for (const e of table.entries) {
      if (e.area !== 'DB' || e.db === null) continue;
      const m = members.get(e.db) ?? { first: e, top: [] };
      members.set(e.db, m);
      if (!children.has(e.name)) m.top.push(e.name);
    }
    blockMembers.set(table, members);
  }
  for (const block of table.blocks) {
    const m = members.get(block.db);
    const own = m && splitSymbol(m.first.name);
    if (!own || own.length < 2) continue;
    const blockName = canonicalName(own.slice(0, 1));
    const rest = canonicalName(own).slice(blockName.length);
    if (table.lookup(`${name.trim()}${rest}`) !== m.first) continue;
    const length = block.length;
    return {
      name: blockName,
      type: block.instanceOf ? `"${block.instanceOf}"` : 'Struct',
      kind: 'struct',
      stringLength: 0,
      area: 'DB',
      db: block.db,
      // An optimized block has no length and no address: resolveSymbol refuses it by name.
      byte: length === null ? null : 0,
      bit: null,
      size: length ?? 0,
      address: length === null ? null : `DB${block.db}.DBB0:BYTE[${length}]`,
      children: m.top,
      comment: '',
    };
  }
  return undefined;
}

/** Elementary entries and arrays of elementary types are one tag of the driver (its value: a scalar or an array). */
function isElementary(entry: SymbolEntry): boolean {
  return entry.kind === 'elementary' || (entry.kind === 'array' && entry.dataType !== undefined);
}

/** A struct's bytes (from `byte`) as one BYTE array: `DB1.DBB10:BYTE[12]`, `MB4:BYTE[2]`. */
function spanAddress(entry: SymbolEntry, byte: number): string {
  const count = Math.max(1, entry.size);
  const at = entry.area === 'DB' ? `DB${entry.db ?? 0}.DBB${byte}` : `${entry.area}B${byte}`;
  return `${at}:BYTE[${count}]`;
}

/** The shape of `entry`, its leaves' offsets counted from `rootByte` (the byte of the struct read as one tag). */
function shapeOf<T>(table: SymbolTable, rootByte: number, entry: SymbolEntry, named: (address: string, as: string) => T): SymbolShape<T> {
  if (isElementary(entry)) {
    const { address, byte } = placed(table, entry, entry.name);
    const s7 = { ...parseAddress(address), address: entry.name };
    return {
      kind: 'leaf',
      name: entry.name,
      tag: named(address, entry.name),
      s7,
      offset: byte - rootByte,
      decode: tagDecoder(s7),
    };
  }
  const children = (entry.children ?? []).map((child) => {
    const found = table.lookup(child);
    if (!found)
      throw new PlcError('INVALID_ADDRESS', `symbol ${entry.name}: its member ${child} is not in the symbol table`, { tag: entry.name });
    return found;
  });
  if (entry.kind === 'array') return { kind: 'array', name: entry.name, elements: children.map((c) => shapeOf(table, rootByte, c, named)) };
  const members = new Map<string, SymbolShape<T>>();
  for (const child of children) members.set(memberKey(entry.name, child.name), shapeOf(table, rootByte, child, named));
  return { kind: 'struct', name: entry.name, members };
}

/** The object (array of objects) of a struct's bytes: a BYTE array as read, or the bytes. */
export function decodeShape<T>(shape: SymbolShape<T>, bytes: PlcValue | Buffer): PlcData {
  const data = Buffer.isBuffer(bytes) ? bytes : Array.isArray(bytes) ? Buffer.from(bytes as number[]) : Buffer.of(bytes as number);
  return decodeAt(shape, data);
}

function decodeAt<T>(shape: SymbolShape<T>, data: Buffer): PlcData {
  return assembleStruct(shape, (leaf) => leaf.decode(data, leaf.offset)) as PlcData;
}

/**
 * The member writes of a value for a struct (an array of structs): one per
 * elementary member the object names, nested objects and arrays followed;
 * members not named are not written. Throws INVALID_VALUE, before anything
 * is sent, for a value that is not an object (array), for members the type
 * does not have (naming them) and for a member value that does not fit.
 */
export function expandWrite<T>(shape: SymbolShape<T>, value: unknown): { tag: T; value: unknown }[] {
  return expandStruct(shape, value, (leaf, v) => {
    validateValue(leaf.s7, v);
    return { tag: leaf.tag, value: v };
  });
}
