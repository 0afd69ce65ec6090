/**
 * An address in a data block with optimized access (DB2.DBW0 over s7plus://):
 * its members have no byte offsets, so the PLC answers the address as no
 * item at all (0x8104; s7commplus (MIT), server.py _resolve_classic_blob
 * serves standard blocks only). The tag's error then says the block is
 * optimized and names what to read instead, from the PLC's browsed table.
 */
import { PlcError } from '../../errors';
import type { SymbolTable } from '../../symbols/model';
import type { Tag } from '../../types';
import { ITEM_ERROR_UNRESOLVED } from '../constants';

const UNRESOLVED = Number(ITEM_ERROR_UNRESOLVED);

/** Errors by tag index: read with `errorAt`, replaced with `replace`. */
interface TagErrorSlots {
  errorAt(i: number): PlcError | undefined;
  replace(i: number, err: PlcError): void;
}

/** Replaces each "no such item" of an address in an optimized block with why (the table is browsed only when one is there). */
export async function explainOptimized(
  tags: readonly Tag[],
  slots: TagErrorSlots,
  table: () => Promise<SymbolTable>,
  isAddress: (tag: Tag) => boolean,
): Promise<void> {
  const suspects = tags.flatMap((tag, i) => {
    const err = slots.errorAt(i);
    return err?.plcCode === UNRESOLVED && tag.area === 'DB' && isAddress(tag) ? [i] : [];
  });
  if (suspects.length === 0) return;
  let t: SymbolTable;
  try {
    t = await table();
  } catch {
    // A PLC that gives no browse: the PLC's own words stay.
    return;
  }
  for (const i of suspects) {
    const tag = tags[i]!;
    const block = t.blocks.find((b) => b.db === tag.dbNumber);
    if (!block?.optimized) continue;
    const example = t.entries.find((e) => e.db === block.db && e.kind === 'elementary')?.name;
    const message =
      `${tag.address}: DB${block.db} ("${block.name}") has optimized access: its members have no byte offsets, ` +
      `so it cannot be read or written by address; use the members' names${example === undefined ? '' : `, e.g. ${example}`}`;
    slots.replace(i, new PlcError('OPTIMIZED_BLOCK', message, { tag: tag.address, plcCode: UNRESOLVED, cause: slots.errorAt(i) }));
  }
}
