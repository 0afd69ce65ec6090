/**
 * One subscription as its user sees it: the tags, the cycle, the latest
 * result of each tag and the events. What the PLC is asked for is planned
 * here (plan(): names through the browsed table as their elementary members,
 * addresses of standard DBs and I/Q/M as their byte ranges, each a reference
 * of the Subscription object's list); notifications come in as decoded by the
 * codec and go out as per-tag results. The session it lives on is push.ts's.
 *
 * Events: `state` (SubscriptionState), `active` (created on a session: the
 * first notification after it carries every value), `lost` (PlcError: the
 * link went, it is created again when the link is back), `data`
 * (SubscriptionData, every notification), `change` (SubscriptionChange, per
 * tag whose value or quality changed), `error` (PlcError, only when someone
 * listens), `closed`.
 */
import { EventEmitter } from 'node:events';
import { isDeepStrictEqual } from 'node:util';
import { PlcError, TagErrors, tagError, toPlcError, type TagResult } from '../../errors';
import type { SymbolEntry, SymbolTable } from '../../symbols/model';
import type { PlcValue, Tag } from '../../types';
import { decodeTag } from '../../values';
import type { Notification, SubscriptionItem } from '../codec/subscription';
import type { PValue } from '../codec/pvalue';
import type { ItemAddress } from '../codec/variables';
import { bytesOf, itemAddress } from './io';
import { untrustedValue } from './refusals';
import { isNamed, resolveName } from './names';
import { assemble, itemOf, leavesOf, valueOf } from './name-values';

export type SubscriptionState = 'subscribing' | 'active' | 'lost' | 'closed';

/** A notification as the user gets it: every tag's latest result, the tags that changed. */
export interface SubscriptionData {
  /** Every tag's latest result, by the address or name as given. */
  results: Record<string, TagResult<PlcValue>>;
  /** The tags whose value or quality changed with this notification. */
  changed: string[];
  /** The first notification after the subscription was (re)created: it carries every value. */
  initial: boolean;
  /** When the PLC took the values, if it said. */
  timestamp?: Date;
}

export interface SubscriptionChange {
  tag: string;
  result: TagResult<PlcValue>;
  /** Undefined for the first value. */
  previous: TagResult<PlcValue> | undefined;
}

/** The events of a subscription and their arguments: `sub.on('chnage', …)` does not compile. */
export interface S7PlusSubscriptionEvents {
  state: [state: SubscriptionState];
  /** Created on a session: the first notification after it carries every value. */
  active: [];
  /** The link went; the subscription is created again when the link is back. */
  lost: [error: PlcError];
  /** Every notification. */
  data: [data: SubscriptionData];
  /** Per tag whose value or quality changed. */
  change: [change: SubscriptionChange];
  /** Only emitted when someone listens. */
  error: [error: PlcError];
  closed: [];
}

export interface SubscribeOptions {
  /** How often the PLC samples the tags, ms (default 100; 10 to 3600000). */
  cycle?: number;
}

const DEFAULT_CYCLE_MS = 100;
const MIN_CYCLE_MS = 10;
const MAX_CYCLE_MS = 3_600_000;

/** One tag and the references of its elementary values. */
interface Planned {
  address: string;
  tag: Tag;
  /** A name's entry (a struct or array assembled from its leaves); undefined for an address. */
  entry?: SymbolEntry;
  leaves: { ref: number; entry?: SymbolEntry }[];
}

/** What the PLC is asked for on one session: the items, and how to read their values back. */
export interface Plan {
  items: SubscriptionItem[];
  tags: Planned[];
  /** Each reference's tag, and its member for a name. */
  byRef: Map<number, { planned: Planned; entry: SymbolEntry | undefined }>;
  table: SymbolTable | undefined;
}

/** What push.ts gives a subscription. */
export interface SubscriptionOwner {
  /** The PLC's name, for messages. */
  readonly name: string;
  parse(address: string): Tag;
  /** Ends the subscription on the PLC; resolves when it is gone. */
  remove(sub: S7PlusSubscription): Promise<void>;
}

export class S7PlusSubscription extends EventEmitter<S7PlusSubscriptionEvents> {
  readonly tags: readonly string[];
  readonly cycle: number;
  #state: SubscriptionState = 'subscribing';
  private readonly results = new Map<string, TagResult<PlcValue>>();
  private plan: Plan | undefined;
  /** The leaves' latest values (or errors) by reference, on the live plan. */
  private leafValues = new Map<number, PlcValue | PlcError>();
  private initial = true;
  /** Notifications held until subscribe() has resolved, so its caller's listeners see the first one. */
  private held: Notification[] | undefined = [];
  private closing: Promise<void> | undefined;

  constructor(
    private readonly owner: SubscriptionOwner,
    tags: readonly string[],
    options: SubscribeOptions,
  ) {
    super();
    if (!Array.isArray(tags) || tags.length === 0 || !tags.every((t) => typeof t === 'string'))
      throw new PlcError('INVALID_ADDRESS', 'subscribe() takes a non-empty array of addresses or names');
    const cycle = checkedCycle(options.cycle ?? DEFAULT_CYCLE_MS);
    this.tags = Object.freeze([...new Set(tags)]);
    this.cycle = cycle;
    // Parse errors before anything goes to the PLC.
    const bad = this.tags.flatMap((address) => {
      try {
        owner.parse(address);
        return [];
      } catch (err) {
        return [[address, toPlcError(err, 'INVALID_ADDRESS')] as const];
      }
    });
    if (bad.length > 0) throw new TagErrors(Object.fromEntries(bad.map(([a, error]) => [a, { ok: false as const, error }])));
  }

  get state(): SubscriptionState {
    return this.#state;
  }

  /** Every tag's latest result (none before the first notification). */
  get latest(): Record<string, TagResult<PlcValue>> {
    return Object.fromEntries(this.results);
  }

  /** Ends it: the PLC stops sending (DeleteObject), no more events. Always resolves; a second call waits for the first. */
  close(): Promise<void> {
    if (!this.closing) {
      this.setState('closed');
      this.closing = this.owner.remove(this).finally(() => this.emit('closed'));
    }
    return this.closing;
  }

  /**
   * The items for a session: each tag parsed, a name resolved through
   * `table` into its elementary members. Throws TagErrors naming every tag
   * that does not resolve (an unknown name: INVALID_ADDRESS with the closest
   * names), so nothing is subscribed silently wrong.
   */
  planWith(table: SymbolTable | undefined): Plan {
    const items: SubscriptionItem[] = [];
    const tags: Planned[] = [];
    const byRef = new Map<number, { planned: Planned; entry: SymbolEntry | undefined }>();
    const bad: [string, PlcError][] = [];
    const reference = (planned: Planned, where: ItemAddress, entry?: SymbolEntry) => {
      const ref = items.length + 1;
      items.push({ referenceId: ref, symbolCrc: 0, accessArea: where.accessArea, accessSubArea: where.accessSubArea, lids: where.lids });
      planned.leaves.push({ ref, ...(entry ? { entry } : {}) });
      byRef.set(ref, { planned, entry });
    };
    for (const address of this.tags) {
      const tag = this.owner.parse(address);
      const entry = isNamed(tag) ? (table ? resolveName(table, tag) : noTable(address)) : undefined;
      const where = entry ? undefined : itemAddress(tag);
      const failed = entry instanceof PlcError ? entry : where instanceof PlcError ? where : undefined;
      if (failed) {
        bad.push([address, tagError(address, failed)]);
        continue;
      }
      const planned: Planned = { address, tag, leaves: [], ...(entry ? { entry: entry as SymbolEntry } : {}) };
      if (entry) for (const leaf of leavesOf(table!, entry as SymbolEntry)) reference(planned, itemOf(leaf), leaf);
      else reference(planned, where as ItemAddress);
      tags.push(planned);
    }
    if (bad.length > 0) throw new TagErrors(Object.fromEntries(bad.map(([a, error]) => [a, { ok: false as const, error }])));
    return { items, tags, byRef, table };
  }

  /** push.ts: created on a session with `plan`; the next notification carries every value. */
  activated(plan: Plan): void {
    this.plan = plan;
    this.leafValues = new Map();
    this.initial = true;
    if (this.#state === 'closed') return;
    this.setState('active');
    this.emit('active');
  }

  /** push.ts: the session went (`err`); push.ts creates it again on the next one. */
  lost(err: PlcError): void {
    this.plan = undefined;
    if (this.#state === 'closed' || this.#state === 'lost') return;
    this.setState('lost');
    this.emit('lost', err);
  }

  /** push.ts: could not be created again on a new session (say, a name the program lost); tried again at the next connection. */
  failed(err: PlcError): void {
    this.plan = undefined;
    if (this.#state === 'closed') return;
    this.setState('lost');
    this.emitError(err);
  }

  /** push.ts: subscribe() has resolved; what came before goes out now. */
  release(): void {
    const held = this.held;
    this.held = undefined;
    for (const n of held ?? []) this.notified(n);
  }

  /** push.ts: a notification of this subscription. */
  notified(n: Notification): void {
    if (this.held) return void this.held.push(n);
    const plan = this.plan;
    if (!plan || this.#state !== 'active') return;
    for (const it of n.items) {
      const leaf = plan.byRef.get(it.ref);
      if (!leaf) continue;
      const where = leaf.entry?.name ?? leaf.planned.address;
      this.leafValues.set(it.ref, it.kind === 'error' ? refused(where, it.status) : this.decode(leaf.planned, leaf.entry, it.value));
    }
    const changed: string[] = [];
    for (const t of plan.tags) {
      const result = this.resultOf(plan, t);
      if (!result) continue;
      const previous = this.results.get(t.address);
      if (previous && sameResult(previous, result)) continue;
      this.results.set(t.address, result);
      changed.push(t.address);
      this.emit('change', { tag: t.address, result, previous } satisfies SubscriptionChange);
    }
    const data: SubscriptionData = { results: this.latest, changed, initial: this.initial };
    if (n.timestamp !== undefined) data.timestamp = new Date(Number(n.timestamp / 1000n));
    this.initial = false;
    this.emit('data', data);
  }

  private decode(planned: Planned, entry: SymbolEntry | undefined, v: PValue): PlcValue | PlcError {
    const untrusted = untrustedValue(v, planned.address);
    if (untrusted) return untrusted;
    try {
      if (entry) return valueOf(entry, v);
      const data = bytesOf(v);
      if (!data)
        return new PlcError('PROTOCOL_ERROR', `${planned.address}: the PLC sent a value of type 0x${v.type.toString(16)}, not its bytes`, {
          tag: planned.address,
        });
      return decodeTag(planned.tag, data, 0);
    } catch (err) {
      return tagError(planned.address, toPlcError(err, 'PROTOCOL_ERROR'));
    }
  }

  /** A tag's result from its leaves; undefined while one has no value yet. */
  private resultOf(plan: Plan, t: Planned): TagResult<PlcValue> | undefined {
    const values = t.leaves.map((l) => this.leafValues.get(l.ref));
    if (values.some((v) => v === undefined)) return undefined;
    const failed = values.find((v): v is PlcError => v instanceof PlcError);
    if (failed) return { ok: false, error: tagError(t.address, failed) };
    if (!t.entry) return { ok: true, value: values[0] as PlcValue };
    if (t.entry.kind === 'elementary') return { ok: true, value: values[0] as PlcValue };
    const byName = new Map<string, PlcValue>(t.leaves.map((l, k) => [l.entry!.name, values[k] as PlcValue]));
    return { ok: true, value: assemble(plan.table!, t.entry, byName) as PlcValue };
  }

  private setState(state: SubscriptionState): void {
    if (this.#state === state) return;
    this.#state = state;
    this.emit('state', state);
  }

  private emitError(err: PlcError): void {
    if (this.listenerCount('error') > 0) this.emit('error', err);
  }
}

function noTable(address: string): PlcError {
  return new PlcError('INVALID_ADDRESS', `${address}: the PLC's names were not browsed`, { tag: address });
}

/** An error record of a notification: the PLC does not report this item (0x03, 0x13: s7commplus subscription.py). */
function refused(address: string, status: number): PlcError {
  return new PlcError(
    'NOT_SUPPORTED',
    `${address}: the PLC does not report it in a subscription (record 0x${status.toString(16).padStart(2, '0')})`,
    {
      tag: address,
      plcCode: status,
    },
  );
}

function sameResult(a: TagResult<PlcValue>, b: TagResult<PlcValue>): boolean {
  if (a.ok && b.ok) return isDeepStrictEqual(a.value, b.value);
  if (!a.ok && !b.ok) return a.error.code === b.error.code && a.error.message === b.error.message;
  return false;
}

/**
 * The sampling cycle in whole ms. A string ('100', as a form or a flow's JSON
 * gives it) is refused as a string, not as if 100 were out of range.
 */
function checkedCycle(cycle: unknown): number {
  const range = `whole ms from ${MIN_CYCLE_MS} to ${MAX_CYCLE_MS}`;
  if (typeof cycle !== 'number') {
    const given = typeof cycle === 'string' ? `the string ${JSON.stringify(cycle)}` : `of type ${typeof cycle}`;
    throw new PlcError('INVALID_VALUE', `subscribe(): cycle must be a number (${range}), not ${given}`);
  }
  if (!Number.isInteger(cycle) || cycle < MIN_CYCLE_MS || cycle > MAX_CYCLE_MS)
    throw new PlcError('INVALID_VALUE', `subscribe(): cycle is ${cycle} ms; give ${range}`);
  return cycle;
}
