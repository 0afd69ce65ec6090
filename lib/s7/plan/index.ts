/**
 * The S7 request planner (pure): which Read Var / Write Var items go into
 * which PDU at the negotiated PDU size. Sizes and limits in limits.ts, read
 * planning in read.ts (its drafts in draft*.ts), the plan store and cache in cache.ts,
 * write planning in write.ts. The lower bound (bound.ts) is for tests and
 * the benchmark and is not re-exported here.
 */
import * as cache from './cache';
import * as limits from './limits';
import * as read from './read';
import * as write from './write';

export type { PlanOptions } from './limits';
export type { PlannedReadItem, ReadPdu, ReadPlan, TagPieces, TagSlice } from './read';
export type { PlannedWriteItem, WritePdu, WritePlan } from './write';

// Plain properties rather than `export { … } from`: TypeScript compiles a
// re-export to a getter, and those put this module's exports in V8's slow
// (dictionary) mode, which doubled the cost of tagData, called once per tag
// per poll by the client.
export const { maxReadItemData, maxReadItems, maxWriteItemData } = limits;
export const { planRead, tagData } = read;
export const { planWrite } = write;
export const ReadPlanCache = cache.ReadPlanCache;
export type ReadPlanCache = cache.ReadPlanCache;
export const PlanStore = cache.PlanStore;
export type PlanStore<E> = cache.PlanStore<E>;
