/**
 * A conversion of what a read of a target returns, chosen by the declared
 * type of each value in it: the target's own type (an address, a name), or,
 * for a STRUCT, each member's (the one struct model, lib/symbols/struct-tree.ts,
 * walked by the compiled shape or the PLC's browsed entry). The REAL digits
 * (reals.ts) and the CLI's TIA time literals (lib/cli/values.ts) both use it,
 * so a member is shown as the same value named alone would be.
 */
import { isAddress } from '../address';
import type { DriverTag } from '../link/driver';
import type { SymbolTable } from './model';
import { resolveSymbol, wholeBlock } from './resolve';
import { convertStruct, entryTree } from './struct-tree';

export type Convert = (value: unknown) => unknown;

/** What is asked of a client: its tags, and the PLC's own table where it browsed one. */
export interface TypedClient {
  tag(address: string): unknown;
  readonly browsedTable?: SymbolTable | undefined;
}

/**
 * The conversion of a value read from `target`: `ofType(type)` for each
 * value of a declared type (the target's, or each struct member's); undefined
 * when `ofType` converts none of them. `client.tag(target)` must parse (it
 * throws as the read would).
 */
export function byLeafType(
  client: TypedClient,
  given: SymbolTable | undefined,
  target: string,
  ofType: (type: string | undefined) => Convert | undefined,
): Convert | undefined {
  // Without sources, an S7CommPlus client's names are the PLC's own (its browsed table).
  const table = given ?? client.browsedTable;
  if (table && !isAddress(target)) {
    const entry = table.lookup(target) ?? wholeBlock(table, target);
    if (entry?.kind === 'elementary') return ofType(entry.dataType);
    // The PLC's own table (no sources: the client reads by name) or a member of an optimized block (no address): the
    // entry tree's shape.
    if (entry && (given === undefined || entry.address === null))
      return convertStruct(entryTree(table, entry), (leaf) => ofType(leaf.entry.dataType));
    if (given === undefined) return undefined;
    const resolved = resolveSymbol(table, target, (address) => client.tag(address) as DriverTag);
    if (resolved?.shape) return convertStruct(resolved.shape, (leaf) => ofType(leaf.s7.type));
  }
  const type = (client.tag(target) as { type?: unknown }).type;
  return ofType(typeof type === 'string' ? type : undefined);
}
