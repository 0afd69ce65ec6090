/**
 * The S7 request planner (pure): which Read Var / Write Var items go into
 * which PDU at the negotiated PDU size. Sizes and limits in limits.ts, read
 * planning in read.ts (its drafts in draft*.ts), the plan cache in cache.ts,
 * write planning in write.ts. The lower bound (bound.ts) is for tests and
 * the benchmark and is not re-exported here.
 */
export { maxReadItemData, maxReadItems, maxWriteItemData, type PlanOptions } from './limits';
export { planRead, tagData, type PlannedReadItem, type ReadPdu, type ReadPlan, type TagPieces, type TagSlice } from './read';
export { ReadPlanCache } from './cache';
export { planWrite, type PlannedWriteItem, type WritePdu, type WritePlan } from './write';
