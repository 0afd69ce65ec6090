/**
 * REAL values for people (the command line, Node-RED messages): each REAL a
 * read returns, a STRUCT's REAL members too, as the shortest decimal that is
 * the same float32 (40.4, not 40.400001525878906), as TIA Portal shows it
 * (lib/values/float32.ts). LREAL and every other type stay as read. The
 * library's read results keep the float32's exact value: docs/performance.md,
 * "REAL values", has the measurement that decided it.
 */
import { isAddress } from '../address';
import type { SymbolEntry, SymbolTable } from '../symbols/model';
import { resolveSymbol, wholeBlock, type SymbolShape } from '../symbols/resolve';
import type { DriverTag } from '../link/driver';
import { shortestFloat32 } from '../values/float32';

type Convert = (value: unknown) => unknown;

/** A REAL (or an array of them) with the digits TIA shows; anything else as it is. */
const shortReal: Convert = (value) => {
  if (typeof value === 'number') return shortestFloat32(value);
  return Array.isArray(value) ? value.map(shortReal) : value;
};

/** The conversion of a value of `shape`, or undefined when it holds no REAL. */
function ofShape<T>(shape: SymbolShape<T>): Convert | undefined {
  if (shape.kind === 'leaf') return shape.s7.type === 'REAL' ? shortReal : undefined;
  if (shape.kind === 'array') {
    const elements = shape.elements.map(ofShape);
    if (elements.every((e) => e === undefined)) return undefined;
    return (value) => (Array.isArray(value) ? value.map((v: unknown, i) => (elements[i] ? elements[i](v) : v)) : value);
  }
  const members = new Map<string, Convert>();
  for (const [name, member] of shape.members) {
    const convert = ofShape(member);
    if (convert) members.set(name, convert);
  }
  if (members.size === 0) return undefined;
  return byMember(members);
}

/** A struct's value with each member that `members` names converted. */
function byMember(members: ReadonlyMap<string, Convert>): Convert {
  return (value) => {
    if (typeof value !== 'object' || value === null || Array.isArray(value)) return value;
    const out: Record<string, unknown> = {};
    for (const [k, v] of Object.entries(value)) {
      const convert = members.get(k);
      Object.defineProperty(out, k, { value: convert ? convert(v) : v, enumerable: true, writable: true, configurable: true });
    }
    return out;
  };
}

/** The conversion of a value of `entry` (by its children: the browsed table of an S7CommPlus PLC), or undefined without a REAL. */
function ofEntry(table: SymbolTable, entry: SymbolEntry): Convert | undefined {
  if (entry.kind === 'elementary') return entry.dataType === 'REAL' ? shortReal : undefined;
  const children = (entry.children ?? []).map((c) => table.lookup(c)).filter((c): c is SymbolEntry => c !== undefined);
  const converts = children.map((c) => ofEntry(table, c));
  if (converts.every((c) => c === undefined)) return undefined;
  if (entry.kind === 'array') {
    return (value) => (Array.isArray(value) ? value.map((v: unknown, i) => (converts[i] ? converts[i](v) : v)) : value);
  }
  const members = new Map<string, Convert>();
  children.forEach((c, i) => {
    const convert = converts[i];
    if (convert) members.set(memberKey(entry, c), convert);
  });
  return byMember(members);
}

/** A member's key in its struct's value: its name after the parent's, quotes off (client/name-values.ts puts values so). */
function memberKey(parent: SymbolEntry, child: SymbolEntry): string {
  const rest = child.name.slice(parent.name.length + 1);
  return rest.startsWith('"') && rest.endsWith('"') ? rest.slice(1, -1) : rest;
}

/**
 * How to show what a read of `target` returns: a function when it holds a
 * REAL (an address of type REAL, a REAL name, a STRUCT with REAL members),
 * undefined when it is shown as read. `client.tag(target)` must parse (it
 * throws as the read would).
 */
export function realsForPeople(
  client: { tag(address: string): unknown; readonly browsedTable?: SymbolTable | undefined },
  given: SymbolTable | undefined,
  target: string,
): Convert | undefined {
  // Without sources, an S7CommPlus client's names are the PLC's own (its browsed table).
  const table = given ?? client.browsedTable;
  if (table && !isAddress(target)) {
    const entry = table.lookup(target) ?? wholeBlock(table, target);
    if (entry?.kind === 'elementary') return entry.dataType === 'REAL' ? shortReal : undefined;
    // The PLC's own table (no sources: the client reads by name) or a member of an optimized block (no address): the
    // entry tree's shape.
    if (entry && (given === undefined || entry.address === null)) return ofEntry(table, entry);
    if (given === undefined) return undefined;
    const resolved = resolveSymbol(table, target, (address) => client.tag(address) as DriverTag);
    if (resolved?.shape) return ofShape(resolved.shape);
  }
  return (client.tag(target) as { type?: unknown }).type === 'REAL' ? shortReal : undefined;
}
