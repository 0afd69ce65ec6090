/**
 * What an answer says of each item, and the one mapper of the PLC's refusal
 * of an item (its per-item error, or the request's return value standing for
 * it) to a tag's error, for reads and writes, by address and by name: the
 * code in words, and always the code as `plcCode` (its low 16 bits). 0x8104
 * is what a PLC answers for an item it has no object for (s7commplus (MIT),
 * server.py _ITEM_ERROR).
 *
 * Which answers are not to be trusted: a non-zero ReturnValue says the
 * request failed, whatever values come beside it (s7commplus (MIT),
 * client.py _parse_read_response takes no value then, _write_item_errors
 * fails every item with it; codec.py parse_or_raise_for_return_value); a
 * value whose PValue flags have a bit beside the three array kinds (0x10
 * array, 0x20 address array, 0x40 sparse array: codec/pvalue.ts, and the
 * same three in Wireshark's s7comm_plus dissector) means something no
 * public source explains.
 */
import { PlcError } from '../../errors';
import type { PValue } from '../codec/pvalue';
import { ITEM_ERROR_UNRESOLVED, PValueFlag } from '../constants';

const KNOWN_FLAGS = PValueFlag.Array | PValueFlag.AddressArray | PValueFlag.SparseArray;

/** An answer's item lists (GetMultiVariables has values, SetMultiVariables only errors). */
interface Answer {
  returnValue: bigint;
  values?: Map<number, PValue>;
  errors: Map<number, bigint>;
}

/**
 * What the answer says of item `k` (numbered from 1): its value; the code
 * that refuses it (its own error, else a non-zero return value: the request
 * failed); or undefined when it says nothing of it.
 */
export function itemAnswer(body: Answer, k: number): PValue | { code: bigint; request: boolean } | undefined {
  const own = body.errors.get(k);
  if (own !== undefined) return { code: own, request: false };
  if (body.returnValue !== 0n) return { code: body.returnValue, request: true };
  return body.values?.get(k);
}

/**
 * The PLC refused the request as a whole: a ReturnValue that is not 0 and
 * no item answered (a CPU 1215C so refuses more items than its
 * SystemLimits: 0xA027A6000054FFFC). A request of several items then goes
 * again in smaller ones (chunks.ts: 'again'); one item alone is refused
 * with that code (itemAnswer).
 */
export function refusedWhole(body: Answer): boolean {
  return body.returnValue !== 0n && body.errors.size === 0 && (body.values?.size ?? 0) === 0;
}

/** A value the answer gives for `tag` that is not to be trusted (flag bits no public source explains), as the tag's error. */
export function untrustedValue(v: PValue, tag: string): PlcError | undefined {
  const unknown = v.flags & ~KNOWN_FLAGS;
  if (unknown === 0) return undefined;
  return new PlcError(
    'PROTOCOL_ERROR',
    `${tag}: the PLC answered its value with PValue flags 0x${v.flags.toString(16)}, whose bits 0x${unknown.toString(16)} ` +
      'no public source explains: the value is not taken',
    { tag },
  );
}

/** An item the answer says nothing of: the PLC's answer failed it (a tag's error; the link is fine). */
export function notAnswered(tag: string): PlcError {
  return new PlcError('PLC_ERROR', `${tag}: the PLC's answer has neither a value nor an error for this item`, { tag });
}

export interface RefusedItem {
  /** The tag as the caller wrote it (the error's `tag`). */
  tag: string;
  /** Given for a name read or written by LID: the browsed member the PLC refused. */
  name?: string;
  write?: boolean;
  /** The code is the request's return value: the PLC answered that the whole request failed. */
  request?: boolean;
}

export function itemRefusal(code: bigint, item: RefusedItem): PlcError {
  const hex = `0x${code.toString(16)}`;
  const details = { tag: item.tag, plcCode: Number(code & 0xffffn) };
  if (item.request) {
    const what = item.write ? 'write' : 'read';
    return new PlcError(
      'PLC_ERROR',
      `${item.name ?? item.tag}: the PLC answered the ${what} with return value ${hex}, which says it failed` +
        (item.write ? '' : ': no value of it is taken'),
      details,
    );
  }
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
