/**
 * One model of a struct's value for every driver: a tree of members (a
 * struct's by member key, an array's by index) down to elementary leaves,
 * and the walks over it that s7://, fetchwrite:// and s7plus:// share — the
 * member writes of a value (a struct partly given writes the members it
 * names), a value put back together from its leaves, and a conversion of the
 * leaves (the REAL digits people see). The leaf's payload is the driver's
 * own: an address and codec over S7, the browsed entry over S7CommPlus.
 */
import { ValueError } from '../errors';
import type { SymbolEntry, SymbolTable } from './model';

export type StructTree<L> =
  | (L & { readonly kind: 'leaf'; readonly name: string })
  | { readonly kind: 'struct'; readonly name: string; readonly members: ReadonlyMap<string, StructTree<L>> }
  | { readonly kind: 'array'; readonly name: string; readonly elements: readonly StructTree<L>[] };

/** A leaf of an entry tree: the table's entry of an elementary member. */
export interface EntryLeaf {
  readonly entry: SymbolEntry;
}

/** A member's key in its struct's object: its name after the parent's, quotes off (`"Tank".Motor.Speed` → `Speed`, `."Speed.Set"` → `Speed.Set`). */
export function memberKey(parent: string, child: string): string {
  const rest = child.startsWith(parent) ? child.slice(parent.length).replace(/^\./, '') : (child.split('.').at(-1) ?? child);
  return rest.length >= 2 && rest.startsWith('"') && rest.endsWith('"') ? rest.slice(1, -1) : rest;
}

/** The direct children of a struct or array entry, in order (a child the table lacks is left out). */
function childrenOf(table: SymbolTable, entry: SymbolEntry): SymbolEntry[] {
  return (entry.children ?? []).map((c) => table.lookup(c)).filter((c): c is SymbolEntry => c !== undefined);
}

/** Trees per entry, built once per table (a poll reads the same names again and again). */
const TREES = new WeakMap<SymbolEntry, StructTree<EntryLeaf>>();

/** The tree of `entry` in `table`: its elementary members as leaves carrying their entries. */
export function entryTree(table: SymbolTable, entry: SymbolEntry): StructTree<EntryLeaf> {
  let tree = TREES.get(entry);
  if (tree) return tree;
  if (entry.kind === 'elementary') tree = { kind: 'leaf', name: entry.name, entry };
  else {
    const children = childrenOf(table, entry);
    tree =
      entry.kind === 'array'
        ? { kind: 'array', name: entry.name, elements: children.map((c) => entryTree(table, c)) }
        : { kind: 'struct', name: entry.name, members: new Map(children.map((c) => [memberKey(entry.name, c.name), entryTree(table, c)])) };
  }
  TREES.set(entry, tree);
  return tree;
}

/**
 * The member writes of `value` for `tree`: one per elementary member the
 * value names, nested objects and arrays followed; members not named (and
 * array holes, undefined) are not written. `check` sees each leaf's value and
 * throws when it does not fit. Throws ValueError, before anything is sent,
 * for a value that is not an object (array of the right length) and for
 * members the type does not have (naming them and the members it has).
 */
export function expandStruct<L, R>(tree: StructTree<L>, value: unknown, check: (leaf: L & { name: string }, value: unknown) => R): R[] {
  const out: R[] = [];
  const walk = (s: StructTree<L>, v: unknown): void => {
    if (s.kind === 'leaf') return void out.push(check(s as L & { name: string }, v));
    if (s.kind === 'array') {
      if (!Array.isArray(v) || v.length !== s.elements.length) {
        throw new ValueError(
          s.name,
          `expected an array of ${s.elements.length} values (holes or undefined keep an element), got ${describe(v)}`,
        );
      }
      s.elements.forEach((e, i) => {
        const element: unknown = v[i];
        if (element !== undefined) walk(e, element);
      });
      return;
    }
    if (v === null || typeof v !== 'object' || Array.isArray(v) || v instanceof Date || Buffer.isBuffer(v)) {
      throw new ValueError(s.name, `expected an object of its members (${[...s.members.keys()].join(', ')}), got ${describe(v)}`);
    }
    const record = v as Record<string, unknown>;
    const unknown = Object.keys(record).filter((k) => !s.members.has(k));
    if (unknown.length > 0) {
      throw new ValueError(
        s.name,
        `no member${unknown.length > 1 ? 's' : ''} ${unknown.map((k) => JSON.stringify(k)).join(', ')} (its members: ${[...s.members.keys()].join(', ')})`,
      );
    }
    for (const [key, member] of s.members) if (record[key] !== undefined) walk(member, record[key]);
  };
  walk(tree, value);
  return out;
}

/** The value of `tree` from its leaves' values: objects keyed by member, arrays by index. */
export function assembleStruct<L>(tree: StructTree<L>, leaf: (leaf: L & { name: string }) => unknown): unknown {
  if (tree.kind === 'leaf') return leaf(tree as L & { name: string });
  if (tree.kind === 'array') return tree.elements.map((e) => assembleStruct(e, leaf));
  const out: Record<string, unknown> = {};
  for (const [key, member] of tree.members) out[key] = assembleStruct(member, leaf);
  return out;
}

type Convert = (value: unknown) => unknown;

/**
 * A conversion of values of `tree` that applies `ofLeaf(leaf)` to each leaf
 * it returns a function for and leaves the rest as they are; undefined when
 * no leaf is converted (the value is shown as read).
 */
export function convertStruct<L>(tree: StructTree<L>, ofLeaf: (leaf: L & { name: string }) => Convert | undefined): Convert | undefined {
  if (tree.kind === 'leaf') return ofLeaf(tree as L & { name: string });
  if (tree.kind === 'array') {
    const elements = tree.elements.map((e) => convertStruct(e, ofLeaf));
    if (elements.every((e) => e === undefined)) return undefined;
    return (value) => (Array.isArray(value) ? value.map((v: unknown, i) => (elements[i] ? elements[i](v) : v)) : value);
  }
  const members = new Map<string, Convert>();
  for (const [key, member] of tree.members) {
    const convert = convertStruct(member, ofLeaf);
    if (convert) members.set(key, convert);
  }
  if (members.size === 0) return undefined;
  return (value) => {
    if (typeof value !== 'object' || value === null || Array.isArray(value)) return value;
    const out: Record<string, unknown> = {};
    for (const [k, v] of Object.entries(value)) {
      const convert = members.get(k);
      // defineProperty: a member named __proto__ stays a member.
      Object.defineProperty(out, k, { value: convert ? convert(v) : v, enumerable: true, writable: true, configurable: true });
    }
    return out;
  };
}

function describe(v: unknown): string {
  if (Array.isArray(v)) return `an array of ${v.length}`;
  if (v === null) return 'null';
  if (v instanceof Date) return 'a Date';
  if (typeof v === 'object') return 'an object';
  if (typeof v === 'bigint') return `bigint ${v}n`;
  return `${typeof v} ${JSON.stringify(v) ?? 'undefined'}`;
}
