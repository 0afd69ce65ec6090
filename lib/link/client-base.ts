import { EventEmitter } from 'node:events';
import type { Duplex } from 'node:stream';
import { ConnectionError, PlcError, TagErrors, tagError, toPlcError, type TagResult } from '../errors';
import { LayoutMonitor } from '../symbols/layout-check';
import type { SymbolTable } from '../symbols/model';
import { addressOrSymbol, decodeShape, expandWrite, type SymbolShape } from '../symbols/resolve';
import type { LayoutCheck, LinkState, PlcClient, PlcData, PlcValue, PreparedRead, Protocol, RequestOptions } from '../types';

export type { PreparedRead } from '../types';
import type { BackoffOptions } from './backoff';
import type { Driver, DriverSession, DriverTag, ReadValues } from './driver';
import { LinkSupervisor } from './supervisor';

export type { Driver, DriverSession, DriverTag, ReadValues, TagSyntax } from './driver';

export interface ClientOptions {
  /** For messages, e.g. "s7://127.0.0.1:102". */
  name: string;
  /** Milliseconds, per request and for connecting. */
  timeout?: number;
  backoff?: BackoffOptions;
  /** Jobs waiting at most before QUEUE_FULL. */
  maxQueued?: number;
  /** Injected for tests (backoff jitter). */
  random?: () => number;
  /** Refuse every write before anything is sent (code WRITE_NOT_ALLOWED). */
  readOnly?: boolean;
  /** Only writes inside these areas ("DB10", "M", "ST5") or addresses ("DB1.DBW2") are allowed. */
  allow?: readonly string[];
  /**
   * A compiled symbol table (compileSymbols): tags may then be named as the
   * sources name them, `"Tank".Level`, beside absolute addresses
   * (docs/symbols.md, "Reading and writing by name").
   */
  symbols?: SymbolTable;
  /**
   * Refuse reads and writes by name (LAYOUT_MISMATCH) in a data block whose
   * length in the PLC differs from what the sources declare, instead of
   * returning values from shifted offsets (the URL's `strictSymbols=true`).
   */
  strictSymbols?: boolean;
}

export const DEFAULT_TIMEOUT = 5000;

/** What every endpoint carries for its client: the request timeout and the write safety. */
export interface EndpointOptions {
  timeout: number;
  readOnly?: boolean;
  allow?: readonly string[];
  strictSymbols?: boolean;
}

/** A client's options from its endpoint (`name` for messages), overridden by the caller's. */
export function endpointOptions(name: string, endpoint: EndpointOptions, options: Partial<ClientOptions>): ClientOptions {
  return {
    name,
    timeout: endpoint.timeout,
    ...(endpoint.readOnly ? { readOnly: true } : {}),
    ...(endpoint.allow ? { allow: endpoint.allow } : {}),
    ...(endpoint.strictSymbols ? { strictSymbols: true } : {}),
    ...options,
  };
}

/** A parsed address list and what the driver prepared for it (behind a PreparedRead, or an array read() sees again). */
interface ReadList<T, M> {
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

/** What the client keeps of a tag resolved from a symbol: its data block (null outside DBs) and, for a struct, its shape. */
interface SymbolUse<T> {
  db: number | null;
  shape: SymbolShape<T> | undefined;
}

interface ListSymbols<T> {
  dbs: Set<number>;
  /** Tags (by index) whose bytes are decoded into an object. */
  shaped: { index: number; shape: SymbolShape<T> }[];
}

/**
 * Block infos the layout check asks at once: the S7 session queues beyond
 * the PLC's parallel jobs, and a few in flight hide the round trips without
 * crowding out the polls.
 */
const LAYOUT_PARALLEL = 4;

const NO_VALUES: ReadValues = Object.freeze({ values: [], errors: undefined }) as ReadValues;

/**
 * A function returning `{ "DB1,INT2": read[0], … }` for a polled list.
 * Adding hundreds of string keys to an object one by one turns it into a
 * hash table, slower to build and to read than this literal, which is built
 * in one step (the figure: bench/README.md, "Figures that used to be in comments"). Keys are JSON-quoted
 * address strings. Falls back to the loop (null) where code generation is
 * disabled or a key would be special in a literal.
 */
function recordBuilder(prepared: ReadList<{ readonly address: string }, unknown>, kind: 'values' | 'results'): RecordBuilder | undefined {
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
const MAX_CACHED_TAGS = 10_000;

/**
 * What every driver's client shares: the supervisor (connect, reconnect,
 * state events, close), address parsing with a cache, prepared reads
 * (prepare(), and the same for an array read() is given again), per-tag results,
 * TagErrors and the write safety (read-only, allow-list). It knows no
 * protocol: a client supplies its `driver` (lib/link/driver.ts).
 *
 * Requests made while not connected fail fast with NOT_CONNECTED: a stale
 * write executed minutes later, when the link comes back, is worse than an error.
 */
export abstract class BaseClient<S extends DriverSession, T extends DriverTag, M = undefined> extends EventEmitter implements PlcClient {
  abstract readonly protocol: Protocol;
  readonly name: string;
  protected readonly timeout: number;
  protected readonly maxQueued: number | undefined;
  private readonly supervisor: LinkSupervisor<S>;
  private readonly tags = new Map<string, T | PlcError>();
  /** The lists behind arrays read() was given, by identity (see PreparedRead). */
  private readonly lists = new WeakMap<readonly string[], ReadList<T, M>>();
  private readonly readOnly: boolean;
  private readonly allow: readonly string[] | undefined;
  private allowed: { areas: Set<string>; tags: T[] } | undefined;
  /** The symbol table (ClientOptions.symbols) and what its names resolved to (the tags of the parse cache). */
  private readonly symbols: SymbolTable | undefined;
  private readonly strictSymbols: boolean;
  private readonly symbolUses = new WeakMap<T, SymbolUse<T>>();
  private layoutMonitor: LayoutMonitor | undefined;

  constructor(options: ClientOptions) {
    super();
    this.name = options.name;
    this.timeout = options.timeout ?? DEFAULT_TIMEOUT;
    this.maxQueued = options.maxQueued;
    this.readOnly = options.readOnly ?? false;
    this.allow = options.allow && options.allow.length > 0 ? options.allow : undefined;
    this.symbols = options.symbols;
    this.strictSymbols = options.strictSymbols ?? false;
    // The supervisor's events are the client's; a new live session first starts its layout check.
    const events = {
      emit: (event: string, ...args: unknown[]) => {
        if (event === 'connected') this.layout?.linkUp();
        return this.emit(event, ...args);
      },
      listenerCount: (event: string) => this.listenerCount(event),
    };
    this.supervisor = new LinkSupervisor<S>({
      name: options.name,
      connectTimeout: this.timeout,
      open: (signal) => this.driver.openSession(signal),
      // The supervisor uses emit and listenerCount only.
      events: events as unknown as EventEmitter,
      ...(options.backoff ? { backoff: options.backoff } : {}),
      ...(options.random ? { random: options.random } : {}),
    });
  }

  /** The protocol's part (lib/link/driver.ts); used from connect() on, so a field initialiser may set it. */
  protected abstract readonly driver: Driver<S, T, M>;

  get state(): LinkState {
    return this.supervisor.state;
  }

  /** The live session, if any (for drivers and diagnostics). */
  protected get session(): S | undefined {
    return this.supervisor.session;
  }

  /** A driver calls this when a live session dies; the supervisor reconnects. */
  protected sessionLost(session: S, err: PlcError): void {
    this.supervisor.lost(session, err);
  }

  /** The error a session's requests fail with when its link goes for `cause`: CLOSED, with the cause, when close() ended it. */
  protected lossError(cause: PlcError): PlcError {
    return this.state === 'closed' ? new ConnectionError('CLOSED', `${this.name}: the client was closed`, { cause }) : cause;
  }

  /**
   * How a session over a stream dies, once: the returned `fail(cause)` on
   * its first call runs `teardown` with the error (CLOSED, with the cause,
   * when close() ended it) and tells the supervisor; later calls do nothing.
   * The stream's 'error' and 'close' call it.
   */
  protected attachStream(session: S, stream: Duplex, teardown: (err: PlcError) => void): (cause: PlcError) => void {
    let lost = false;
    const fail = (cause: PlcError) => {
      if (lost) return;
      lost = true;
      const err = this.lossError(cause);
      teardown(err);
      this.sessionLost(session, err);
    };
    stream.on('error', (err) => fail(new ConnectionError('CONNECTION_LOST', `${this.name}: ${err.message}`, { cause: err })));
    stream.on('close', () => fail(new ConnectionError('CONNECTION_LOST', `${this.name} closed the connection`)));
    return fail;
  }

  /** Starts and waits for the first connection; rejects with the first attempt's error and stops. */
  async connect(): Promise<this> {
    this.checkAllowList();
    await this.supervisor.connectOnce();
    return this;
  }

  /** Starts and keeps (re)connecting in the background until close(); never rejects. */
  start(): void {
    this.checkAllowList();
    this.supervisor.start();
  }

  close(): Promise<void> {
    this.layoutMonitor?.stop();
    return this.supervisor.close();
  }

  /**
   * Compares the length of every data block of the symbol table's sources
   * with the PLC's block (S7: block info), as on each connect, and reports
   * as on connect (`layoutMismatch`, `layoutUnknown`, `layoutOk`: PlcClient).
   * Resolves [] without a symbol table; rejects NOT_CONNECTED while not
   * connected, and with the link's error when it drops during the check.
   */
  checkLayout(options: RequestOptions = {}): Promise<LayoutCheck[]> {
    const layout = this.layout;
    if (!layout) return Promise.resolve([]);
    try {
      this.liveSession();
    } catch (err) {
      return Promise.reject(err);
    }
    return layout.check(options.signal);
  }

  /** The layout check of the symbol table's blocks (made at first use: the driver is a subclass field). */
  private get layout(): LayoutMonitor | undefined {
    if (!this.symbols) return undefined;
    const { driver } = this;
    return (this.layoutMonitor ??= new LayoutMonitor({
      table: this.symbols,
      strict: this.strictSymbols,
      events: this,
      blockLength: driver.blockLength
        ? (db, signal) => {
            const session = this.liveSession();
            return driver.blockLength!(session, db, signal);
          }
        : undefined,
      dbNumbers: driver.dbNumbers ? (signal) => driver.dbNumbers!(this.liveSession(), signal) : undefined,
      unsupported: driver.noBlockLength ?? `${this.name}: the protocol has no service that tells the length of a data block`,
      parallel: () => LAYOUT_PARALLEL,
    }));
  }

  /** Parses an address with this driver's syntax (cached); throws AddressError. */
  tag(address: string): T {
    const cached = this.parseCached(address);
    if (cached instanceof PlcError) throw cached;
    return cached;
  }

  /**
   * Parses the addresses once and keeps what this client's driver can
   * compute ahead for them (see PreparedRead): the fast way to poll the same
   * tags. Throws the AddressError (INVALID_ADDRESS, naming the address) of
   * the first address that does not parse; nothing is sent. Needs no link:
   * a list may be prepared before connect().
   */
  prepare(addresses: readonly string[]): PreparedRead {
    if (!Array.isArray(addresses) || !addresses.every((a) => typeof a === 'string')) {
      throw new PlcError('INVALID_ADDRESS', 'prepare() takes an array of address strings');
    }
    let list: ReadList<T, M> | undefined = this.readList(addresses);
    const [bad] = list.bad;
    if (bad) throw bad.error;
    const closed = () => new PlcError('CLOSED', `a prepared read of ${this.name} was used after its close()`);
    return {
      addresses: Object.freeze(list.addresses.slice()),
      read: <V extends PlcData>(options?: RequestOptions) =>
        (list ? this.readOf(list, options) : Promise.reject(closed())) as Promise<Record<string, V>>,
      readDetailed: <V extends PlcData>(options?: RequestOptions) =>
        (list ? this.readDetailedOf(list, options) : Promise.reject(closed())) as Promise<Record<string, TagResult<V>>>,
      close: () => void (list = undefined),
    };
  }

  /**
   * Reads tags. Polling the same list? Prefer prepare(). Given the same
   * array object again (unchanged), read() recognises it and skips what
   * prepare() saves as well; a new array each time is parsed and prepared
   * again (an S7 client finds the plan in its bounded plan cache).
   */
  read<V extends PlcData = PlcValue>(addresses: readonly string[], options?: RequestOptions): Promise<Record<string, V>> {
    let list: ReadList<T, M>;
    try {
      list = this.listOf(addresses);
    } catch (err) {
      return Promise.reject(err);
    }
    return this.readOf(list, options) as Promise<Record<string, V>>;
  }

  private async readOf(list: ReadList<T, M>, options?: RequestOptions): Promise<Record<string, PlcValue>> {
    const prepared = list.symbols && this.layout?.gating ? await this.layoutGated(list, options?.signal) : list;
    if (prepared.bad.length > 0) {
      const results = await this.readDetailedOf(prepared, options);
      throw new TagErrors(results);
    }
    const session = this.liveSession();
    const { tags } = prepared;
    const read = tags.length > 0 ? await this.valuesOf(session, tags, options?.signal, prepared.prepared) : NO_VALUES;
    const { values } = read;
    let { errors } = read;
    if (prepared.symbols && prepared.symbols.shaped.length > 0) errors = shapeValues(prepared.symbols, tags, values, errors);
    if (errors) return this.valuesOrThrow(this.byAddress(prepared, toResults(values, errors)));
    const build = recordBuilder(prepared, 'values');
    if (build) return build(values) as Record<string, PlcValue>;
    const record: Record<string, PlcValue> = {};
    for (let i = 0; i < tags.length; i++) record[tags[i]!.address] = values[i]!;
    return record;
  }

  /** The driver's readValues, or the same outcome derived from its readTags. */
  private async valuesOf(session: S, tags: readonly T[], signal: AbortSignal | undefined, prepared: M | undefined): Promise<ReadValues> {
    const { driver } = this;
    if (driver.readValues) return driver.readValues(session, tags, signal, prepared);
    const results = await driver.readTags(session, tags, signal, prepared);
    const values = new Array<PlcValue>(results.length);
    let errors: (PlcError | undefined)[] | undefined;
    for (let i = 0; i < results.length; i++) {
      const r = results[i]!;
      if (r.ok) values[i] = r.value;
      else (errors ??= new Array<PlcError | undefined>(results.length))[i] = r.error;
    }
    return { values, errors };
  }

  private valuesOrThrow(results: Record<string, TagResult<PlcValue>>): Record<string, PlcValue> {
    const values: Record<string, PlcValue> = {};
    for (const key of Object.keys(results)) {
      const r = results[key]!;
      if (!r.ok) throw new TagErrors(results);
      values[key] = r.value;
    }
    return values;
  }

  /** A result per tag; like read(), fastest for a prepared list (prepare()) or the same array again. */
  readDetailed<V extends PlcData = PlcValue>(
    addresses: readonly string[],
    options: RequestOptions = {},
  ): Promise<Record<string, TagResult<V>>> {
    let list: ReadList<T, M>;
    try {
      list = this.listOf(addresses);
    } catch (err) {
      return Promise.reject(err);
    }
    return this.readDetailedOf(list, options) as Promise<Record<string, TagResult<V>>>;
  }

  private async readDetailedOf(list: ReadList<T, M>, options: RequestOptions = {}): Promise<Record<string, TagResult<PlcValue>>> {
    const prepared = list.symbols && this.layout?.gating ? await this.layoutGated(list, options.signal) : list;
    const session = this.liveSession();
    const read = prepared.tags.length > 0 ? await this.driver.readTags(session, prepared.tags, options.signal, prepared.prepared) : [];
    if (prepared.symbols && prepared.symbols.shaped.length > 0) shapeResults(prepared.symbols, prepared.tags, read);
    return this.byAddress(prepared, read);
  }

  /**
   * strictSymbols: waits for a layout check under way, then the list
   * without the symbols of blocks that do not match (their LAYOUT_MISMATCH
   * among the unparsable ones); the list itself when none is refused.
   */
  private async layoutGated(list: ReadList<T, M>, signal: AbortSignal | undefined): Promise<ReadList<T, M>> {
    const layout = this.layout!;
    await layout.settled(signal);
    let kept: T[] | undefined;
    const refused: { address: string; error: PlcError }[] = [];
    list.tags.forEach((tag, i) => {
      const refusal = layout.refusal(this.symbolUses.get(tag)?.db ?? null);
      if (refusal) {
        kept ??= list.tags.slice(0, i);
        refused.push({ address: tag.address, error: tagError(tag.address, refusal) });
      } else kept?.push(tag);
    });
    if (!kept) return list;
    return this.listOfTags(list.addresses, kept, [...list.bad, ...refused]);
  }

  /** Results keyed by address: unparsable addresses first, then the tags read (a tag given twice: its last result). */
  private byAddress(prepared: ReadList<T, M>, read: readonly TagResult<PlcValue>[]): Record<string, TagResult<PlcValue>> {
    const build = prepared.bad.length === 0 ? recordBuilder(prepared, 'results') : undefined;
    if (build) return build(read) as Record<string, TagResult<PlcValue>>;
    const results: Record<string, TagResult<PlcValue>> = {};
    for (const { address, error } of prepared.bad) results[address] = { ok: false, error };
    const { tags } = prepared;
    for (let i = 0; i < tags.length; i++) results[tags[i]!.address] = read[i]!;
    return results;
  }

  /**
   * The list behind an array read() is given: polls that pass the same
   * array again are recognised by identity (and checked element by element,
   * in case the caller changed it), and get what a PreparedRead keeps.
   */
  private listOf(addresses: readonly string[]): ReadList<T, M> {
    const known = this.lists.get(addresses);
    if (known && sameStrings(known.addresses, addresses)) return known;
    const list = this.readList(addresses);
    this.lists.set(addresses, list);
    return list;
  }

  /** Parses an address list and has the driver prepare its tags. */
  private readList(addresses: readonly string[]): ReadList<T, M> {
    const tags: T[] = [];
    const bad: { address: string; error: PlcError }[] = [];
    for (const address of addresses) {
      const tag = this.parseCached(address);
      if (tag instanceof PlcError) bad.push({ address, error: tag });
      else tags.push(tag);
    }
    return this.listOfTags(addresses.slice(), tags, bad);
  }

  private listOfTags(addresses: readonly string[], tags: T[], bad: { address: string; error: PlcError }[]): ReadList<T, M> {
    const prepared = tags.length > 0 ? this.driver.prepareRead?.(tags) : undefined;
    const list: ReadList<T, M> = { addresses, tags, bad, prepared, uses: 0 };
    if (this.symbols) {
      tags.forEach((tag, index) => {
        const use = this.symbolUses.get(tag);
        if (!use) return;
        const symbols = (list.symbols ??= { dbs: new Set(), shaped: [] });
        if (use.db !== null) symbols.dbs.add(use.db);
        if (use.shape) symbols.shaped.push({ index, shape: use.shape });
      });
    }
    return list;
  }

  async write(values: Readonly<Record<string, unknown>>, options?: RequestOptions): Promise<void> {
    const results = await this.writeDetailed(values, options);
    for (const key of Object.keys(results)) if (!results[key]!.ok) throw new TagErrors(results);
  }

  async writeDetailed(values: Readonly<Record<string, unknown>>, options: RequestOptions = {}): Promise<Record<string, TagResult<void>>> {
    if (values === null || typeof values !== 'object') {
      throw new PlcError('INVALID_VALUE', 'write() takes an object of { address: value }');
    }
    let session = this.liveSession();
    const keys = Object.keys(values);
    const tags = keys.map((address) => this.parseCached(address));
    const layout = this.layout;
    if (layout?.gating && tags.some((t) => !(t instanceof PlcError) && this.symbolUses.has(t))) {
      await layout.settled(options.signal);
      session = this.liveSession();
    }
    const results: Record<string, TagResult<void>> = {};
    const items: { tag: T; value: unknown }[] = [];
    /** Per key written: its first item and how many (a struct: one per member given). */
    const written: { key: string; from: number; count: number }[] = [];
    keys.forEach((address, k) => {
      const tag = tags[k]!;
      if (tag instanceof PlcError) return void (results[address] = { ok: false, error: tag });
      const use = this.symbols ? this.symbolUses.get(tag) : undefined;
      let own: { tag: T; value: unknown }[];
      try {
        const refusal = use && layout?.refusal(use.db);
        if (refusal) throw tagError(address, refusal);
        own = use?.shape ? expandWrite(use.shape, values[address]) : [{ tag, value: values[address] }];
      } catch (err) {
        return void (results[address] = { ok: false, error: tagError(address, toPlcError(err, 'INVALID_VALUE')) });
      }
      for (const item of own) {
        const refusal = this.writeRefusal(item.tag);
        if (refusal) return void (results[address] = { ok: false, error: tagError(address, refusal) });
      }
      written.push({ key: address, from: items.length, count: own.length });
      items.push(...own);
    });
    const outcome = items.length > 0 ? await this.driver.writeTags(session, items, options.signal) : [];
    for (const { key, from, count } of written) {
      if (count === 1) {
        results[key] = outcome[from]!;
        continue;
      }
      // A struct: ok when every member written is; else its first member's error, naming the struct and the member.
      const failed = outcome.slice(from, from + count).find((r) => !r.ok);
      results[key] = failed && !failed.ok ? { ok: false, error: tagError(key, failed.error) } : { ok: true, value: undefined };
    }
    return results;
  }

  private writeRefusal(tag: T): PlcError | undefined {
    if (this.readOnly) {
      return new PlcError('WRITE_NOT_ALLOWED', `write to "${tag.address}" refused: the connection is read-only`, { tag: tag.address });
    }
    if (!this.allow) return undefined;
    this.allowed ??= this.compileAllowList(this.allow);
    const { areas, tags } = this.allowed;
    const { syntax } = this.driver;
    if (areas.has(syntax.areaOf(tag)) || tags.some((outer) => syntax.contains(outer, tag))) return undefined;
    return new PlcError(
      'WRITE_NOT_ALLOWED',
      `write to "${tag.address}" refused: not in the connection's write allow-list (${this.allow.join(', ')})`,
      { tag: tag.address },
    );
  }

  /** A bad allow-list entry is a configuration error: say so at start, not at the first write. */
  private checkAllowList(): void {
    if (this.allow) this.allowed ??= this.compileAllowList(this.allow);
  }

  private compileAllowList(entries: readonly string[]): { areas: Set<string>; tags: T[] } {
    const areas = new Set<string>();
    const tags: T[] = [];
    for (const entry of entries) {
      const area = this.driver.syntax.allowArea(entry.trim().toUpperCase().replace(/^%/, ''));
      if (area !== undefined) areas.add(area);
      else tags.push(this.tag(entry));
    }
    return { areas, tags };
  }

  private liveSession(): S {
    const session = this.supervisor.session;
    if (session) return session;
    const why = this.state === 'closed' ? 'the client was closed' : `the link is ${this.state}`;
    throw new ConnectionError('NOT_CONNECTED', `not connected to ${this.name} (${why})`);
  }

  /**
   * The tag of an address or, with a symbol table, of a name (cached: a
   * symbol is resolved once), by addressOrSymbol. Absolute addresses come first: text that
   * parses as an address is that address (`M1`, `DB1.DBW2`, with or without
   * %), so a symbol table never changes what an address means; a symbol whose
   * name reads as an address is written quoted, as TIA writes it (`"M1"`).
   */
  private parseCached(address: string): T | PlcError {
    let tag = this.tags.get(address);
    if (tag === undefined) {
      try {
        const { tag: found, symbol } = addressOrSymbol(address, (a) => this.driver.syntax.parse(a), this.symbols);
        if (symbol) this.symbolUses.set(found, { db: symbol.entry.area === 'DB' ? symbol.entry.db : null, shape: symbol.shape });
        tag = found;
      } catch (err) {
        tag = toPlcError(err, 'INVALID_ADDRESS');
      }
      if (this.tags.size >= MAX_CACHED_TAGS) this.tags.clear();
      this.tags.set(address, tag);
    }
    return tag;
  }
}

/** Struct values from their bytes, in place (tags that failed keep their error); the errors, with any of decoding. */
function shapeValues<T>(
  symbols: ListSymbols<T>,
  tags: readonly DriverTag[],
  values: unknown[],
  errors: (PlcError | undefined)[] | undefined,
): (PlcError | undefined)[] | undefined {
  for (const { index, shape } of symbols.shaped) {
    if (errors?.[index]) continue;
    try {
      values[index] = decodeShape(shape, values[index] as PlcValue);
    } catch (err) {
      (errors ??= new Array<PlcError | undefined>(values.length))[index] = tagError(
        tags[index]!.address,
        toPlcError(err, 'PROTOCOL_ERROR'),
      );
    }
  }
  return errors;
}

function shapeResults<T>(symbols: ListSymbols<T>, tags: readonly DriverTag[], results: TagResult<PlcValue>[]): void {
  for (const { index, shape } of symbols.shaped) {
    const r = results[index]!;
    if (!r.ok) continue;
    try {
      results[index] = { ok: true, value: decodeShape(shape, r.value) as PlcValue };
    } catch (err) {
      results[index] = { ok: false, error: tagError(tags[index]!.address, toPlcError(err, 'PROTOCOL_ERROR')) };
    }
  }
}
