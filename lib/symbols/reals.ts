/**
 * REAL values for people (the command line, Node-RED messages): each REAL a
 * read returns, a STRUCT's REAL members too, as the shortest decimal that is
 * the same float32 (40.4, not 40.400001525878906), as TIA Portal shows it
 * (lib/values/float32.ts). LREAL and every other type stay as read. The
 * library's read results keep the float32's exact value: docs/performance.md,
 * "REAL values", has the measurement that decided it.
 */
import { isAddress } from '../address';
import type { SymbolTable } from './model';
import { resolveSymbol, wholeBlock, type ShapeLeaf } from './resolve';
import { convertStruct, entryTree, type EntryLeaf, type StructTree } from './struct-tree';
import type { DriverTag } from '../link/driver';
import { shortestFloat32 } from '../values/float32';

type Convert = (value: unknown) => unknown;

/** A REAL (or an array of them) with the digits TIA shows; anything else as it is. */
const shortReal: Convert = (value) => {
  if (typeof value === 'number') return shortestFloat32(value);
  return Array.isArray(value) ? value.map(shortReal) : value;
};

/** The conversion of a value of `tree` (a struct's shape, or an entry of the PLC's browsed table), or undefined when it holds no REAL. */
function ofTree<L>(tree: StructTree<L>, isReal: (leaf: L) => boolean): Convert | undefined {
  return convertStruct(tree, (leaf) => (isReal(leaf) ? shortReal : undefined));
}

const shapeReal = (leaf: ShapeLeaf<unknown>): boolean => leaf.s7.type === 'REAL';
const entryReal = (leaf: EntryLeaf): boolean => leaf.entry.dataType === 'REAL';

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
    if (entry && (given === undefined || entry.address === null)) return ofTree(entryTree(table, entry), entryReal);
    if (given === undefined) return undefined;
    const resolved = resolveSymbol(table, target, (address) => client.tag(address) as DriverTag);
    if (resolved?.shape) return ofTree(resolved.shape, shapeReal);
  }
  return (client.tag(target) as { type?: unknown }).type === 'REAL' ? shortReal : undefined;
}

/** `value`, read from `target`, as people see it: its REALs with the digits TIA shows (realsForPeople), else as read. */
export function realsShown(
  client: { tag(address: string): unknown; readonly browsedTable?: SymbolTable | undefined },
  table: SymbolTable | undefined,
  target: string,
  value: unknown,
): unknown {
  const convert = realsForPeople(client, table, target);
  return convert ? convert(value) : value;
}
