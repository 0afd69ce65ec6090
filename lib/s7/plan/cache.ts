import type { Tag } from '../../types';
import { maxReadItems, type PlanOptions } from './limits';
import { planRead, type ReadPlan } from './read';

/**
 * Remembers read plans by tag list: the same list (the same array, or the
 * same addresses in the same order) at the same PDU size and options (item
 * limit, merge) is not planned again. Bounded: when `capacity` plans are
 * remembered by list, the next new one forgets them all and starts again
 * (no age is tracked); a plan remembered by its array lives as long as the
 * array does (a WeakMap).
 */
export class ReadPlanCache {
  private readonly byArray = new WeakMap<readonly Tag[], ReadPlan>();
  private readonly byKey = new Map<string, { tags: readonly Tag[]; plan: ReadPlan; options: PlanOptions }[]>();
  private count = 0;
  hits = 0;
  misses = 0;

  constructor(readonly capacity = 64) {}

  get(tags: readonly Tag[], pduSize: number, options: PlanOptions = {}): ReadPlan {
    const same = this.byArray.get(tags);
    if (
      same &&
      same.pduSize === pduSize &&
      same.maxItems === maxReadItems(pduSize, options.maxItems) &&
      same.merged === (options.merge ?? true)
    ) {
      this.hits++;
      return same;
    }
    const key = cacheKey(tags, pduSize, options);
    const bucket = this.byKey.get(key);
    const found = bucket?.find((e) => sameTags(e.tags, tags));
    if (found) {
      this.hits++;
      this.byArray.set(tags, found.plan);
      return found.plan;
    }
    this.misses++;
    const plan = planRead(tags, pduSize, options);
    if (this.count >= this.capacity) {
      this.byKey.clear();
      this.count = 0;
    }
    const entry = { tags: [...tags], plan, options };
    if (bucket) bucket.push(entry);
    else this.byKey.set(key, [entry]);
    this.count++;
    this.byArray.set(tags, plan);
    return plan;
  }

  clear(): void {
    this.byKey.clear();
    this.count = 0;
  }
}

function cacheKey(tags: readonly Tag[], pduSize: number, options: PlanOptions): string {
  const first = tags[0]?.address ?? '';
  const last = tags[tags.length - 1]?.address ?? '';
  return `${pduSize}|${options.merge ?? true}|${options.maxItems ?? ''}|${tags.length}|${first}|${last}`;
}

function sameTags(a: readonly Tag[], b: readonly Tag[]): boolean {
  if (a.length !== b.length) return false;
  for (let i = 0; i < a.length; i++) if (a[i] !== b[i] && a[i]!.address !== b[i]!.address) return false;
  return true;
}
