import type { Tag } from '../../types';
import { maxReadItems, type PlanOptions } from './limits';
import { planRead, type ReadPlan } from './read';

/**
 * The one owner of the read plans made for tag lists, each kept as an entry
 * `E` made from the plan (the plan itself in ReadPlanCache; in an S7 client
 * the plan with its request frames). The same list (the same array, or the
 * same addresses in the same order) at the same PDU size and options (item
 * limit, merge) is not planned again. Bounded: when `capacity` entries are
 * remembered by list, the next new one forgets them all and starts again (no
 * age is tracked); an entry found by its array is found as long as the array
 * lives (a WeakMap index of the same entries). Whoever keeps an entry
 * (a prepared list) holds a reference to it, never a copy.
 */
export class PlanStore<E> {
  private readonly byArray = new WeakMap<readonly Tag[], E>();
  private readonly byKey = new Map<string, { tags: readonly Tag[]; entry: E }[]>();
  private count = 0;
  hits = 0;
  misses = 0;

  /** `make` turns a new plan into its entry; `planOf` gives an entry's plan back. */
  constructor(
    readonly capacity: number,
    private readonly make: (plan: ReadPlan, tags: readonly Tag[]) => E,
    private readonly planOf: (entry: E) => ReadPlan,
  ) {}

  get(tags: readonly Tag[], pduSize: number, options: PlanOptions = {}): E {
    const same = this.byArray.get(tags);
    const plan = same === undefined ? undefined : this.planOf(same);
    if (
      plan &&
      plan.pduSize === pduSize &&
      plan.maxItems === maxReadItems(pduSize, options.maxItems) &&
      plan.merged === (options.merge ?? true)
    ) {
      this.hits++;
      return same!;
    }
    const key = cacheKey(tags, pduSize, options);
    const bucket = this.byKey.get(key);
    const found = bucket?.find((e) => sameTags(e.tags, tags));
    if (found) {
      this.hits++;
      this.byArray.set(tags, found.entry);
      return found.entry;
    }
    this.misses++;
    const entry = this.make(planRead(tags, pduSize, options), tags);
    if (this.count >= this.capacity) {
      this.byKey.clear();
      this.count = 0;
    }
    const remembered = { tags: [...tags], entry };
    if (bucket) bucket.push(remembered);
    else this.byKey.set(key, [remembered]);
    this.count++;
    this.byArray.set(tags, entry);
    return entry;
  }

  clear(): void {
    this.byKey.clear();
    this.count = 0;
  }
}

/** Remembers read plans by tag list (PlanStore of the plans themselves). */
export class ReadPlanCache extends PlanStore<ReadPlan> {
  constructor(capacity = 64) {
    super(capacity, samePlan, samePlan);
  }
}

const samePlan = (plan: ReadPlan): ReadPlan => plan;

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
