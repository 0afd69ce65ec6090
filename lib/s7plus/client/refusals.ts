/**
 * The one mapper of the PLC's refusal of an item (its per-item error, or the
 * request's return value standing for it) to a tag's error, for reads and
 * writes, by address and by name: the code in words, and always the code as
 * `plcCode` (its low 16 bits). 0x8104 is what a PLC answers for an item it
 * has no object for (s7commplus (MIT), server.py _ITEM_ERROR).
 */
import { PlcError } from '../../errors';
import { ITEM_ERROR_UNRESOLVED } from '../constants';

export interface RefusedItem {
  /** The tag as the caller wrote it (the error's `tag`). */
  tag: string;
  /** Given for a name read or written by LID: the browsed member the PLC refused. */
  name?: string;
  write?: boolean;
}

export function itemRefusal(code: bigint, item: RefusedItem): PlcError {
  const hex = `0x${code.toString(16)}`;
  const details = { tag: item.tag, plcCode: Number(code & 0xffffn) };
  if (item.name !== undefined) {
    return item.write
      ? new PlcError('PLC_ERROR', `${item.name}: the PLC refused the write (${hex})`, details)
      : new PlcError('OBJECT_DOES_NOT_EXIST', `${item.name}: the PLC refused it (${hex}); was its program changed?`, details);
  }
  if (code === ITEM_ERROR_UNRESOLVED) {
    return new PlcError(
      'OBJECT_DOES_NOT_EXIST',
      `${item.tag}: the PLC has no such item (no such data block or area, or past its end)`,
      details,
    );
  }
  return new PlcError('PLC_ERROR', `${item.tag}: the PLC refused the item (${hex})`, details);
}
