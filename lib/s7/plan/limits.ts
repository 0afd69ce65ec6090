/**
 * Sizes and limits of Read Var / Write Var jobs at a negotiated PDU size.
 *
 * Sizes (lib/s7/constants.ts: VAR_REQUEST_BASE 12 and VAR_RESPONSE_BASE 14,
 * READ_ITEM 12, item headers 4; docs/protocols.md, "Sizes and limits"):
 *   read request   12 + 12·items                       ≤ PDU
 *   read response  14 + Σ(4 + len + fill)              ≤ PDU
 *   write request  12 + 12·items + Σ(4 + len + fill)   ≤ PDU
 *   write response 14 + items                          ≤ PDU
 * where fill is one byte after odd-length data, except after the last item.
 */
import { PlcError } from '../../errors';
import {
  MAX_ITEMS,
  MAX_PDU_SIZE,
  MIN_PDU_SIZE,
  READ_ITEM,
  READ_RESPONSE_ITEM_HEADER,
  VAR_REQUEST_BASE,
  VAR_RESPONSE_BASE,
  WRITE_DATA_HEADER,
} from '../constants';

export interface PlanOptions {
  /** false: every tag is its own item (used to isolate a failing tag from good neighbours). Default true. */
  merge?: boolean;
  /** At most this many items per PDU (the peer's limit, e.g. 20 for snap7's server). Default 255, the protocol's. */
  maxItems?: number;
}

/** Bytes one read item can return in a PDU of `pduSize`. */
export function maxReadItemData(pduSize: number): number {
  return pduSize - VAR_RESPONSE_BASE - READ_RESPONSE_ITEM_HEADER;
}

/** Bytes one write item can carry in a PDU of `pduSize`. */
export function maxWriteItemData(pduSize: number): number {
  return pduSize - VAR_REQUEST_BASE - READ_ITEM - WRITE_DATA_HEADER;
}

/** Items one read request can carry. */
export function maxReadItems(pduSize: number, maxItems = MAX_ITEMS): number {
  return Math.max(1, Math.min(maxItems, MAX_ITEMS, Math.floor((pduSize - VAR_REQUEST_BASE) / READ_ITEM)));
}

export function checkPduSize(pduSize: number): void {
  if (!Number.isInteger(pduSize) || pduSize < MIN_PDU_SIZE || pduSize > MAX_PDU_SIZE) {
    throw new PlcError('INVALID_VALUE', `unusable S7 PDU size ${pduSize} (expected ${MIN_PDU_SIZE}..${MAX_PDU_SIZE})`);
  }
}
