/**
 * What the simulated CPU reports as its SystemLimits (ObjectRoot RID 201,
 * sub-area 1037; constants.ts SystemLimits) and refuses past them, per
 * family as its order code names it:
 * - S7-1200: 50 tags per request. A CPU 1215C FW V4.2 answers a read of 50
 *   items and refuses one of 51 (s7commplus (MIT) client.py, the comment of
 *   max_items_per_request; the public reports of issue #25).
 * - S7-1500: 100. An S7-1513 FW V2.9 reports it, and a client that reads it
 *   sends reads of 100 items (thomas-v2/S7CommPlusDriver issue #62: "splits
 *   the read requests into chunks of 100 variables"; its CommRessources.cs
 *   reads TagsPerReadRequestMax from LID 1000).
 * Read and write limits are the same on every CPU seen (S7CommPlusDriver,
 * CommRessources.cs ReadMax: "for all CPUs which have been seen both values
 * were the same").
 */

export interface SystemLimitValues {
  /** LID 1000: the most items one GetMultiVariables may carry. */
  readonly tagsPerRead: number;
  /** LID 1001: the most items one SetMultiVariables may carry. */
  readonly tagsPerWrite: number;
}

const S7_1200: SystemLimitValues = Object.freeze({ tagsPerRead: 50, tagsPerWrite: 50 });
const S7_1500: SystemLimitValues = Object.freeze({ tagsPerRead: 100, tagsPerWrite: 100 });

/** The limits of the CPU an order code names ("6ES7 214-1AG40-0XB0": an S7-1200); an S7-1500's when it names neither family. */
export function systemLimitsOf(orderCode: string | undefined): SystemLimitValues {
  return /^6ES7\s?21\d/i.test(orderCode?.trim() ?? '') ? S7_1200 : S7_1500;
}

/** The same limit for reads and writes (S7PlusOptions.maxItems: a test's, or `plcwire serve`'s override). */
export function uniformLimits(items: number): SystemLimitValues {
  return Object.freeze({ tagsPerRead: items, tagsPerWrite: items });
}
