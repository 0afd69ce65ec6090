/**
 * The PLC's own limits, read once per session: SystemLimits (ObjectRoot RID
 * 201, sub-area 1037), LID 1000 the most tags one read request may carry,
 * 1001 one write request, each a DInt (thomas-v2/S7CommPlusDriver (LGPL,
 * facts only), Core/CommRessources.cs ReadMax: read right after the session
 * setup; an S7-1513 reports 100, its issue #62). One request of two items.
 */
import { PlcError } from '../../errors';
import type { ItemAddress, ItemResults } from '../codec/variables';
import { SystemLimits } from '../constants';
import { readAsk } from './asks';
import type { Limits } from './chunks';
import type { S7PlusSession } from './session';

/** Tags per request the PLC reports; a limit it did not report is undefined. */
export interface PlcLimits {
  readonly read: number | undefined;
  readonly write: number | undefined;
}

/** The most tags per request believed from a PLC (a larger answer is no limit this client has a use for). */
const MAX_BELIEVED = 10_000;

const address = (lid: number): ItemAddress => ({
  symbolCrc: 0,
  accessArea: SystemLimits.ObjectRoot,
  accessSubArea: SystemLimits.SubArea,
  lids: [lid],
});

/**
 * The PLC's SystemLimits. A PLC that refuses the items (or answers no whole number in 1…10000) has reported
 * nothing: both undefined, and the client keeps its own limit. A link error goes on to the caller.
 */
export async function readPlcLimits(session: S7PlusSession, signal?: AbortSignal): Promise<PlcLimits> {
  let body: ItemResults;
  try {
    body = await session.request(readAsk([address(SystemLimits.TagsPerReadRequest), address(SystemLimits.TagsPerWriteRequest)]), {
      signal,
    });
  } catch (err) {
    if (err instanceof PlcError && err.code === 'PLC_ERROR') return { read: undefined, write: undefined };
    throw err;
  }
  const limit = (item: number): number | undefined => {
    const v = body.values.get(item)?.value;
    return typeof v === 'number' && Number.isInteger(v) && v >= 1 && v <= MAX_BELIEVED ? v : undefined;
  };
  return { read: limit(1), write: limit(2) };
}

/** What the client keeps per session: its frame, the chunkers' limits for reads and writes, and the SystemLimits read. */
export interface SessionLimits {
  /** The negotiated TPDU size: the most bytes of one request frame; undefined before the handshake told it. */
  frame: number | undefined;
  /** True once the limits are the PLC's (or the URL's maxItems overrides them). */
  known: boolean;
  /** The SystemLimits read under way or done. */
  asked?: Promise<void> | undefined;
  readonly read: Limits;
  readonly write: Limits;
}
