/**
 * The layout engine: from the declarations of DBs and UDTs to the byte and
 * bit of every member, as a CPU lays out a block with standard
 * (non-optimized) access. Pure: declarations in, a tree of placed members
 * out; SourceError at the declaration that cannot be laid out.
 *
 * The rules, and the Siemens documentation and observations they rest on,
 * are in docs/symbols.md ("Layout rules"). In short, with a cursor that
 * counts bits from the start of the block:
 *  - BOOL takes the next bit;
 *  - BYTE, CHAR, SINT, USINT the next whole byte;
 *  - every type of 16 bits or more (WORD … LREAL, DATE_AND_TIME, DTL) starts
 *    on the next even byte;
 *  - STRING[n] (n+2 bytes) and WSTRING[n] (4+2n bytes) start on an even byte;
 *    no pad follows them: a BYTE or BOOL after an odd STRING[n] takes the
 *    very next byte;
 *  - a STRUCT, a UDT and an ARRAY start on an even byte and occupy memory
 *    up to the next word limit (what follows starts on an even byte);
 *  - array elements follow each other by these same rules (BOOL elements
 *    bit by bit, BYTE-sized ones byte by byte, a STRING or STRUCT element
 *    padded to an even length); a multi-dimensional ARRAY OF BOOL starts
 *    each run of its last index on a new byte; the last index runs fastest;
 *  - the block is a STRUCT: its length is even.
 */
import { SourceError } from '../errors';
import type { DataTypeName } from '../types';
import { elementByteLength } from '../values/types-table';
import type { BlockDecl, DataBlockDecl, MemberDecl, SourcePosition, TypeDecl, TypeRef } from './model';
import { isSystemTypeName, KNOWN_LAYOUTS, systemAlias, systemStructure, systemStructureBytes } from './system-types';
import { TIA_SPELLING, blockRef, child, elementIndex, typeRef, whereText, type Where } from './layout-names';
import type { ArrayNode, BlockLayout, ElementaryNode, LayoutNode, LayoutOptions, StructNode } from './layout-nodes';

export { blockRef, elementIndex, memberRef } from './layout-names';
export type { BlockLayout, LayoutNode } from './layout-nodes';

/** Bytes a data block with standard access can hold: 64 KB (S7-300/400 and S7-1200/1500 with standard access); the last byte, 65535, is the last our addresses reach. */
const MAX_BLOCK_BYTES = 65536;
/** Elements of one array: the element count of an address (`:BOOL[65535]`) and of an S7-300 array indexed by INT. */
const MAX_ARRAY_ELEMENTS = 65535;

const BLOCK_BITS = MAX_BLOCK_BYTES * 8;

/** Checked as members are placed, so that a huge declaration is refused before it is built. */
function tooLong(at: SourcePosition, where: Where, optimized: boolean): SourceError {
  const limit = optimized
    ? `plcwire compiles a block with optimized access up to ${MAX_BLOCK_BYTES} bytes (64 KB) counted as if it had standard access`
    : `a block with standard access holds at most ${MAX_BLOCK_BYTES} bytes (64 KB)`;
  return new SourceError(at, `${whereText(where)} ends beyond byte ${MAX_BLOCK_BYTES - 1}: ${limit}`);
}

/** Types that take one byte and may start on any byte. */
const BYTE_TYPES: ReadonlySet<DataTypeName> = new Set<DataTypeName>(['BYTE', 'CHAR', 'SINT', 'USINT']);
/** Parameter types of STEP 7 blocks: a timer or counter number, not data a DB holds. */
const NOT_IN_A_DB: ReadonlySet<DataTypeName> = new Set<DataTypeName>(['TIMER', 'COUNTER']);

// ---------------------------------------------------------------- the engine

/** Rounds a bit position up to the next byte. */
function nextByte(bits: number): number {
  return Math.ceil(bits / 8) * 8;
}

/** Rounds a bit position up to the next even byte (word limit). */
function nextWord(bits: number): number {
  return Math.ceil(bits / 16) * 16;
}

class Engine {
  private readonly byName = new Map<string, TypeDecl>();
  private readonly byNumber = new Map<number, TypeDecl>();
  /** UDTs being laid out, innermost last: a UDT met again contains itself. */
  private readonly open: TypeDecl[] = [];
  /** The block being laid out has optimized access (only the words of the 64 KB refusal differ). */
  optimized = false;

  constructor(
    types: readonly TypeDecl[],
    private readonly typeNumbers: ReadonlyMap<string, number>,
  ) {
    for (const t of types) {
      const key = t.name.toLowerCase();
      const known = this.byName.get(key) ?? (t.number === undefined ? undefined : this.byNumber.get(t.number));
      if (known)
        throw new SourceError(t.at, `UDT ${typeRef(t)} is declared twice (first at ${known.at.file}:${known.at.line}:${known.at.column})`);
      this.byName.set(key, t);
      if (t.number !== undefined) this.byNumber.set(t.number, t);
    }
  }

  /** The UDT a named reference stands for: one of the sources, else a system structure (system-types.ts); or undefined. */
  find(ref: Extract<TypeRef, { kind: 'named' }>): TypeDecl | undefined {
    if (ref.number !== undefined) return this.byNumber.get(ref.number);
    const key = ref.name.toLowerCase();
    const byName = this.byName.get(key);
    if (byName) return byName;
    const number = this.typeNumbers.get(key);
    return (number === undefined ? undefined : this.byNumber.get(number)) ?? systemStructure(ref.name);
  }

  /** The refusal of a named type neither the sources nor the system table know. */
  unknown(ref: Extract<TypeRef, { kind: 'named' }>, at: SourcePosition, usedAs: string): SourceError {
    const written = ref.number === undefined ? `"${ref.name}"` : `UDT ${ref.number}`;
    if (ref.number === undefined && isSystemTypeName(ref.name))
      return new SourceError(
        at,
        `${usedAs} ${ref.name}, a system type whose layout in a block with standard access plcwire does not know ` +
          `(it knows ${KNOWN_LAYOUTS.join(', ')}): read the block by absolute address`,
      );
    return new SourceError(at, `${usedAs} ${written}, which is not a UDT of the sources`);
  }

  /** Lays out a type at bit `pos`; returns the node and the bit where the next member may start. */
  place(type: TypeRef, pos: number, where: Where, decl: MemberDecl | undefined): { node: LayoutNode; next: number } {
    switch (type.kind) {
      case 'elementary':
        return this.elementary(type, pos, where, decl);
      case 'array':
        return this.array(type, pos, where, decl);
      case 'struct':
        return this.struct(type.members, 'Struct', pos, where, decl, decl?.at ?? type.at, undefined);
      case 'named': {
        const udt = this.find(type);
        if (udt) return this.udt(udt, pos, where, decl);
        const alias = type.number === undefined ? systemAlias(type.name) : undefined;
        if (alias) return this.elementary({ kind: 'elementary', type: alias, stringLength: 0, at: type.at }, pos, where, decl);
        const written = type.number === undefined ? `"${type.name}"` : `UDT ${type.number}`;
        if (type.number === undefined && isSystemTypeName(type.name)) throw this.unknown(type, type.at, `${whereText(where)} is of type`);
        throw new SourceError(type.at, `unknown type ${written} (used by ${whereText(where)}): no UDT of that name is among the sources`);
      }
    }
  }

  udt(udt: TypeDecl, pos: number, where: Where, decl: MemberDecl | undefined): { node: LayoutNode; next: number } {
    const from = this.open.indexOf(udt);
    if (from >= 0) {
      const chain = [...this.open.slice(from), udt].map(typeRef).join(' → ');
      throw new SourceError(udt.at, `UDT ${typeRef(udt)} contains itself (${chain}): a type cannot be laid out inside itself`);
    }
    this.open.push(udt);
    try {
      const placed = this.struct(udt.body.members, typeRef(udt), pos, where, decl, decl?.at ?? udt.at, udt);
      // A system structure the CPU keeps larger than its members (an IEC timer's reserve after its bits).
      const bytes = systemStructureBytes(udt);
      if (bytes === undefined || bytes <= placed.node.size) return placed;
      return { node: { ...placed.node, size: bytes }, next: (placed.node.byte + bytes) * 8 };
    } finally {
      this.open.pop();
    }
  }

  private elementary(
    type: Extract<TypeRef, { kind: 'elementary' }>,
    pos: number,
    where: Where,
    decl: MemberDecl | undefined,
  ): { node: ElementaryNode; next: number } {
    const dataType = type.type;
    if (NOT_IN_A_DB.has(dataType))
      throw new SourceError(type.at, `${whereText(where)}: ${TIA_SPELLING[dataType]} is a block parameter type, not data a DB can hold`);
    const stringLength = dataType === 'STRING' || dataType === 'WSTRING' ? type.stringLength : 0;
    const typeText = stringLength > 0 ? `${TIA_SPELLING[dataType]}[${stringLength}]` : TIA_SPELLING[dataType];
    const at = decl?.at ?? type.at;
    const base = decl ? { decl } : {};
    if (dataType === 'BOOL') {
      const node: ElementaryNode = {
        kind: 'elementary',
        dataType,
        stringLength,
        byte: pos >> 3,
        bit: pos & 7,
        size: 1,
        typeText,
        at,
        ...base,
      };
      return { node, next: pos + 1 };
    }
    const bytes = elementByteLength(dataType, stringLength);
    const start = BYTE_TYPES.has(dataType) ? nextByte(pos) : nextWord(pos);
    const node: ElementaryNode = {
      kind: 'elementary',
      dataType,
      stringLength,
      byte: start >> 3,
      bit: null,
      size: bytes,
      typeText,
      at,
      ...base,
    };
    // A STRING[n] starts on an even byte and takes n + 2 bytes, no pad after it: a BYTE or BOOL after an odd
    // STRING[n] takes the very next byte (the struct, UDT or array around it still ends on a word limit).
    return { node, next: start + bytes * 8 };
  }

  private struct(
    members: readonly MemberDecl[],
    typeText: string,
    pos: number,
    where: Where,
    decl: MemberDecl | undefined,
    at: SourcePosition,
    udt: TypeDecl | undefined,
  ): { node: StructNode; next: number } {
    const start = nextWord(pos);
    let cursor = start;
    const placed: { name: string; node: LayoutNode }[] = [];
    const seen = new Map<string, MemberDecl>();
    for (const m of members) {
      const key = m.name.toLowerCase();
      const before = seen.get(key);
      if (before)
        throw new SourceError(
          m.at,
          `${whereText(child(where, m.name))} is declared twice (first at line ${before.at.line}, column ${before.at.column})`,
        );
      seen.set(key, m);
      const { node, next } = this.place(m.type, cursor, child(where, m.name), m);
      placed.push({ name: m.name, node });
      cursor = next;
      if (cursor > BLOCK_BITS) throw tooLong(m.at, child(where, m.name), this.optimized);
    }
    // A STRUCT occupies memory up to the next word limit.
    const end = nextWord(cursor);
    const node: StructNode = {
      kind: 'struct',
      members: placed,
      byte: start >> 3,
      bit: null,
      size: (end - start) >> 3,
      typeText,
      at,
      ...(decl ? { decl } : {}),
      ...(udt ? { typeName: udt.name, typeDecl: udt } : {}),
    };
    return { node, next: end };
  }

  private array(
    type: Extract<TypeRef, { kind: 'array' }>,
    pos: number,
    where: Where,
    decl: MemberDecl | undefined,
  ): { node: ArrayNode; next: number } {
    if (type.dims.length === 0) throw new SourceError(type.at, `${whereText(where)}: an array needs at least one dimension`);
    let count = 1;
    for (const { low, high } of type.dims) {
      if (!Number.isSafeInteger(low) || !Number.isSafeInteger(high))
        throw new SourceError(type.at, `${whereText(where)}: array bounds ${low}..${high} must be whole numbers`);
      if (low > high)
        throw new SourceError(type.at, `${whereText(where)}: array bounds ${low}..${high}: the low bound is above the high bound`);
      count *= high - low + 1;
      if (count > MAX_ARRAY_ELEMENTS)
        throw new SourceError(
          type.at,
          `${whereText(where)}: the array has more than ${MAX_ARRAY_ELEMENTS} elements (at most ${MAX_ARRAY_ELEMENTS})`,
        );
    }
    const element = type.element;
    if (element.kind === 'array')
      throw new SourceError(
        element.at,
        `${whereText(where)}: an array of arrays is not an S7 type; declare one array of several dimensions (Array[1..3, 1..2] of …)`,
      );
    const start = nextWord(pos);
    const isBool = element.kind === 'elementary' && element.type === 'BOOL';
    const rowLength = type.dims[type.dims.length - 1]!.high - type.dims[type.dims.length - 1]!.low + 1;
    const elements: LayoutNode[] = new Array<LayoutNode>(count);
    let cursor = start;
    let dataEnd = start;
    for (let k = 0; k < count; k++) {
      // In a multi-dimensional bit array each run of the last index starts on a new byte.
      if (isBool && type.dims.length > 1 && k % rowLength === 0) cursor = nextByte(cursor);
      const { node, next } = this.place(element, cursor, { parent: where, segment: `[${elementIndex(type.dims, k)}]` }, undefined);
      elements[k] = node;
      if (next > BLOCK_BITS) throw tooLong(type.at, where, this.optimized);
      dataEnd = node.kind === 'elementary' && node.bit !== null ? node.byte * 8 + node.bit + 1 : (node.byte + node.size) * 8;
      cursor = next;
    }
    const elementText = this.typeText(element);
    const dimsText = type.dims.map((d) => `${d.low}..${d.high}`).join(', ');
    let elementType: ArrayNode['elementType'];
    let contiguous = false;
    if (element.kind === 'elementary') {
      const stringLength = element.type === 'STRING' || element.type === 'WSTRING' ? element.stringLength : 0;
      elementType = { dataType: element.type, stringLength };
      contiguous = isBool
        ? type.dims.length === 1 || rowLength % 8 === 0
        : elementByteLength(element.type, stringLength) % 2 === 0 || BYTE_TYPES.has(element.type);
    }
    const node: ArrayNode = {
      kind: 'array',
      dims: type.dims,
      elements,
      contiguous,
      byte: start >> 3,
      bit: isBool ? 0 : null,
      size: (nextByte(dataEnd) - start) >> 3,
      typeText: `Array[${dimsText}] of ${elementText}`,
      at: decl?.at ?? type.at,
      ...(decl ? { decl } : {}),
      ...(elementType ? { elementType } : {}),
    };
    // An array occupies memory up to the next word limit.
    return { node, next: nextWord(cursor) };
  }

  /** A type as TIA shows it, without laying it out. */
  typeText(type: TypeRef): string {
    switch (type.kind) {
      case 'elementary': {
        const n = type.type === 'STRING' || type.type === 'WSTRING' ? type.stringLength : 0;
        return n > 0 ? `${TIA_SPELLING[type.type]}[${n}]` : TIA_SPELLING[type.type];
      }
      case 'array':
        return `Array[${type.dims.map((d) => `${d.low}..${d.high}`).join(', ')}] of ${this.typeText(type.element)}`;
      case 'struct':
        return 'Struct';
      case 'named': {
        const udt = this.find(type);
        if (udt) return typeRef(udt);
        return type.number === undefined ? `"${type.name}"` : `UDT ${type.number}`;
      }
    }
  }
}

/**
 * Lays out every data block of the declarations (UDTs are laid out where
 * they are used, and each once on its own so that a UDT nobody uses is
 * checked too). Throws SourceError at the first declaration that cannot be
 * laid out: an unknown type, a UDT that contains itself, an instance of an
 * FB, bad array bounds, a block over 64 KB (refused at the member that
 * crosses the limit, before the rest is built). A block with optimized
 * access is laid out by the same rules and limits, for its members and their
 * types (its table gives them no offsets: compile.ts, table-builder.ts).
 */
export function layoutBlocks(blocks: readonly BlockDecl[], options: LayoutOptions = {}): BlockLayout[] {
  const types = blocks.filter((b): b is TypeDecl => b.kind === 'type');
  const engine = new Engine(types, options.typeNumbers ?? new Map());
  for (const t of types) engine.udt(t, 0, { segment: typeRef(t) }, undefined);
  const out: BlockLayout[] = [];
  for (const block of blocks) if (block.kind === 'db') out.push(layoutBlock(engine, block));
  return out;
}

function layoutBlock(engine: Engine, db: DataBlockDecl): BlockLayout {
  const name = blockRef(db);
  engine.optimized = db.optimized;
  const where: Where = { segment: name };
  let root: StructNode;
  let instanceOf: string | undefined;
  const body = db.body;
  if (body.kind === 'struct') {
    root = engine.place(body, 0, where, undefined).node as StructNode;
  } else if (body.kind === 'named') {
    const udt = engine.find(body);
    if (!udt && body.number === undefined && isSystemTypeName(body.name)) throw engine.unknown(body, db.at, `DB ${name} is an instance of`);
    if (!udt) {
      const written = body.number === undefined ? `"${body.name}"` : `UDT ${body.number}`;
      throw new SourceError(
        db.at,
        `DB ${name} is an instance of ${written}, which is not a UDT of the sources: an instance DB of a function block cannot be laid out ` +
          `from DB and UDT sources (give the UDT's source, or read the block by absolute address)`,
      );
    }
    root = engine.udt(udt, 0, where, undefined).node as StructNode;
    instanceOf = root.typeText;
  } else {
    throw new SourceError(db.at, `DB ${name}: a block's body is a STRUCT or a UDT, not ${engine.typeText(body)}`);
  }
  return { decl: db, root, length: root.size, ...(instanceOf === undefined ? {} : { instanceOf }) };
}
