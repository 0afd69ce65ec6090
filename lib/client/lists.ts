/**
 * Prepared lists: an address list parsed once, with what the driver prepared
 * for it (behind a PreparedRead, or the array read() is given again), and the
 * compiled object literal that builds its results.
 */
import { PlcError, type TagResult } from '../errors';
import type { DriverTag } from '../link/driver';
import type { PlcValue } from '../types';
import type { ListSymbols } from './symbols';
import type { TagCache } from './tag-cache';

/** A parsed address list and what the driver prepared for it (behind a PreparedRead, or an array read() sees again). */
export interface ReadList<T, M> {
  /** A copy of the list, to notice a caller that changed its array between polls. */
  addresses: readonly string[];
  tags: T[];
  bad: { address: string; error: PlcError }[];
  /** The driver's prepareRead(tags). */
  prepared: M | undefined;
  /** Reads of this list so far; from the second on, results are built by a compiled object literal. */
  uses: number;
  /** Undefined when no tag of the list is a symbol; else their DBs (the layout check) and the structs among them. */
  symbols?: ListSymbols<T>;
  values?: RecordBuilder | null;
  results?: RecordBuilder | null;
}

type RecordBuilder = (read: readonly unknown[]) => Record<string, unknown>;

/**
 * A function returning `{ "DB1,INT2": read[0], … }` for a polled list.
 * Adding hundreds of string keys to an object one by one turns it into a
 * hash table, slower to build and to read than this literal, which is built
 * in one step (the figure: bench/README.md, "Figures that used to be in comments"). Keys are JSON-quoted
 * address strings. Falls back to the loop (null) where code generation is
 * disabled or a key would be special in a literal.
 */
export function recordBuilder(
  prepared: ReadList<{ readonly address: string }, unknown>,
  kind: 'values' | 'results',
): RecordBuilder | undefined {
  let build = prepared[kind];
  if (build !== undefined) return build ?? undefined;
  if (++prepared.uses < 2) return undefined;
  build = null;
  const keys = prepared.tags.map((t) => t.address);
  if (!keys.includes('__proto__')) {
    try {
      // eslint-disable-next-line @typescript-eslint/no-implied-eval -- keys are JSON-quoted (see above)
      build = new Function('read', `return {${keys.map((k, i) => `${JSON.stringify(k)}: read[${i}]`).join(',\n')}};`) as RecordBuilder;
    } catch {
      build = null;
    }
  }
  prepared[kind] = build;
  return build ?? undefined;
}

/** Result objects from values and errors (a loop: `values` has holes where tags failed). */
export function toResults(values: readonly PlcValue[], errors: readonly (PlcError | undefined)[] | undefined): TagResult<PlcValue>[] {
  const results = new Array<TagResult<PlcValue>>(values.length);
  for (let i = 0; i < values.length; i++) {
    const error = errors?.[i];
    results[i] = error ? { ok: false, error } : { ok: true, value: values[i]! };
  }
  return results;
}

function sameStrings(a: readonly string[], b: readonly string[]): boolean {
  if (a.length !== b.length) return false;
  for (let i = 0; i < a.length; i++) if (a[i] !== b[i]) return false;
  return true;
}

/**
 * A client's read lists: parsed with its tag cache, prepared by its driver
 * (`prepare`, the driver's prepareRead), the arrays read() was given
 * remembered by identity.
 */
export class ReadLists<T extends DriverTag, M> {
  /** The lists behind arrays read() was given, by identity (see PreparedRead). */
  private readonly lists = new WeakMap<readonly string[], ReadList<T, M>>();

  constructor(
    private readonly tags: TagCache<T>,
    private readonly prepare: (tags: T[]) => M | undefined,
  ) {}

  /**
   * The list behind an array read() is given: polls that pass the same
   * array again are recognised by identity (and checked element by element,
   * in case the caller changed it), and get what a PreparedRead keeps.
   */
  of(addresses: readonly string[]): ReadList<T, M> {
    const known = this.lists.get(addresses);
    if (known && sameStrings(known.addresses, addresses)) return known;
    const list = this.parse(addresses);
    this.lists.set(addresses, list);
    return list;
  }

  /** Parses an address list and has the driver prepare its tags. */
  parse(addresses: readonly string[]): ReadList<T, M> {
    const tags: T[] = [];
    const bad: { address: string; error: PlcError }[] = [];
    for (const address of addresses) {
      const tag = this.tags.get(address);
      if (tag instanceof PlcError) bad.push({ address, error: tag });
      else tags.push(tag);
    }
    return this.ofTags(addresses.slice(), tags, bad);
  }

  /** A list of tags already parsed (`bad`: the addresses that were not), prepared by the driver. */
  ofTags(addresses: readonly string[], tags: T[], bad: { address: string; error: PlcError }[]): ReadList<T, M> {
    const prepared = tags.length > 0 ? this.prepare(tags) : undefined;
    const list: ReadList<T, M> = { addresses, tags, bad, prepared, uses: 0 };
    const symbols = this.tags.symbols?.ofList(tags);
    if (symbols) list.symbols = symbols;
    return list;
  }
}
