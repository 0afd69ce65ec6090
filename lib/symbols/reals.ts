/**
 * REAL values for people (the command line, Node-RED messages): each REAL a
 * read returns, a STRUCT's REAL members too, as the shortest decimal that is
 * the same float32 (40.4, not 40.400001525878906), as TIA Portal shows it
 * (lib/values/float32.ts). LREAL and every other type stay as read. The
 * library's read results keep the float32's exact value: docs/performance.md,
 * "REAL values", has the measurement that decided it.
 */
import type { SymbolTable } from './model';
import { byLeafType, type Convert } from './leaf-types';
import { shortestFloat32 } from '../values/float32';

/** A REAL (or an array of them) with the digits TIA shows; anything else as it is. */
const shortReal: Convert = (value) => {
  if (typeof value === 'number') return shortestFloat32(value);
  return Array.isArray(value) ? value.map(shortReal) : value;
};

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
  return byLeafType(client, given, target, (type) => (type === 'REAL' ? shortReal : undefined));
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
