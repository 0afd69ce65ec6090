/**
 * The entries of a symbol table from laid-out blocks (compile.ts): each
 * member, array and element named as TIA writes it after its block, with
 * its address, type and comment, and the start values of its declaration
 * and its block's BEGIN section, evaluated once the table is built.
 */
import { formatAddress } from '../address';
import { SourceError } from '../errors';
import type { DataTypeName, PlcScalar } from '../types';
import { elementIndex, memberRef, type BlockLayout, type LayoutNode } from './layout';
import type { Literal, SourcePosition, StartValue, SymbolEntry } from './model';

/** Evaluates a start value's literal for a member's type (lib/symbols/literals.ts). */
export type EvaluateLiteral = (literal: Literal, type: DataTypeName, stringLength: number) => PlcScalar;

/** A name as a key: case-insensitive, as TIA compares names. */
export function key(name: string): string {
  return name.toLowerCase();
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
export function iecElementary(type: DataTypeName, stringLength: number): string {
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

export class TableBuilder {
  readonly entries: SymbolEntry[] = [];
  /** Start values per entry index (BEGIN overwrites the declarations'). */
  private readonly literals: (Literal | undefined)[] = [];
  /** Entry index by name after the block (`.motor.speed`), for the BEGIN section of the block being built. */
  private relative = new Map<string, number>();

  constructor(private readonly evaluate: EvaluateLiteral | undefined) {}

  /** The block being built has optimized access: its entries get no byte, bit or address. */
  private optimized = false;

  block(layout: BlockLayout, name: string, db: number): void {
    this.relative = new Map();
    this.optimized = layout.decl.optimized;
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
    // A member of an optimized block has no fixed offset: nothing to read by address (SymbolEntry).
    this.entries.push(this.optimized ? { ...entry, byte: null, bit: null, address: null } : entry);
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
