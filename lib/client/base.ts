import type { EventEmitter } from 'node:events';
import type { Duplex } from 'node:stream';
import { ConnectionError, PlcError, TagErrors, tagError, toPlcError, writeRefusal, type TagResult } from '../errors';
import type { Driver, DriverSession, DriverTag, ReadValues } from '../link/driver';
import { EventEmitterBase, type EventMap, type NoEvents, type TypedEvents } from './events';
import { LinkSupervisor } from '../link/supervisor';
import { expandWrite } from '../symbols/resolve';
import type { ClientEvents, LayoutCheck, LinkState, PlcClient, PlcData, PlcValue, PreparedRead, Protocol, RequestOptions } from '../types';
import { DEFAULT_TIMEOUT, type ClientOptions } from './options';
import { ReadLists, recordBuilder, toResults, type ReadList } from './lists';
import { ClientSymbols, shapeResults, shapeValues, type LayoutServices } from './symbols';
import { TagCache } from './tag-cache';
import { WriteGuard } from './write-guard';

export type { PreparedRead } from '../types';
export type { Driver, DriverSession, DriverTag, ReadValues, TagSyntax } from '../link/driver';
export { toResults } from './lists';
export { endpointOptions, type ClientOptions } from './options';

/**
 * Block infos the layout check asks at once: the S7 session queues beyond
 * the PLC's parallel jobs, and a few in flight hide the round trips without
 * crowding out the polls.
 */
const LAYOUT_PARALLEL = 4;

const NO_VALUES: ReadValues = Object.freeze({ values: [], errors: undefined }) as ReadValues;

// ClientEvents' and the driver's Own listener methods (lib/client/events.ts), merged into the class (the only merge here).
/* eslint-disable @typescript-eslint/no-unsafe-declaration-merging, @typescript-eslint/no-empty-object-type, @typescript-eslint/no-unused-vars */
export interface BaseClient<
  S extends DriverSession,
  T extends DriverTag,
  M = undefined,
  Own extends EventMap<Own> = NoEvents,
> extends TypedEvents<ClientEvents, Own> {}
/* eslint-enable @typescript-eslint/no-empty-object-type, @typescript-eslint/no-unused-vars */

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
export abstract class BaseClient<S extends DriverSession, T extends DriverTag, M = undefined, Own extends EventMap<Own> = NoEvents>
  extends EventEmitterBase
  implements PlcClient
{
  abstract readonly protocol: Protocol;
  readonly name: string;
  protected readonly timeout: number;
  protected readonly maxQueued: number | undefined;
  private readonly supervisor: LinkSupervisor<S>;
  /** The parse cache (lib/client/tag-cache.ts). */
  private readonly tags: TagCache<T>;
  /** Prepared lists (lib/client/lists.ts). */
  private readonly lists: ReadLists<T, M>;
  /** Read-only and the allow-list (lib/client/write-guard.ts). */
  private readonly guard: WriteGuard<T>;
  /** The symbol table (ClientOptions.symbols), what its names resolved to and the layout check (lib/client/symbols.ts). */
  private readonly symbols: ClientSymbols<T> | undefined;
  /** ClientOptions.strictSymbols: names in a data block whose length differs from the sources' are refused. */
  private readonly strictSymbols: boolean;

  constructor(options: ClientOptions) {
    super();
    this.name = options.name;
    this.timeout = options.timeout ?? DEFAULT_TIMEOUT;
    this.maxQueued = options.maxQueued;
    this.strictSymbols = options.strictSymbols ?? false;
    this.symbols = options.symbols ? new ClientSymbols<T>(options.symbols, this.strictSymbols, () => this.layoutServices()) : undefined;
    this.tags = new TagCache<T>((address) => this.driver.syntax.parse(address), this.symbols);
    this.lists = new ReadLists<T, M>(this.tags, (tags) => this.driver.prepareRead?.(tags));
    this.guard = new WriteGuard<T>(
      options.readOnly ?? false,
      options.allow,
      () => this.driver.syntax,
      (address) => this.tag(address),
    );
    // The supervisor's events are the client's (by name: untyped); a new live session first starts its layout check.
    const self = this as unknown as EventEmitter;
    const events = {
      emit: (event: string, ...args: unknown[]) => {
        if (event === 'connected') this.symbols?.layout.linkUp();
        return self.emit(event, ...args);
      },
      listenerCount: (event: string) => self.listenerCount(event),
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
    this.guard.check();
    await this.supervisor.connectOnce();
    return this;
  }

  /** Starts and keeps (re)connecting in the background until close(); never rejects. */
  start(): void {
    this.guard.check();
    this.supervisor.start();
  }

  close(): Promise<void> {
    this.symbols?.stop();
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
    const layout = this.symbols?.layout;
    if (!layout) return Promise.resolve([]);
    try {
      this.liveSession();
    } catch (err) {
      return Promise.reject(err);
    }
    return layout.check(options.signal);
  }

  /** What the layout check of the symbol table's blocks asks of the driver (at its first use: the driver is a subclass field). */
  private layoutServices(): LayoutServices {
    const { driver } = this;
    return {
      events: this as unknown as EventEmitter,
      blockLength: driver.blockLength
        ? (db, signal) => {
            const session = this.liveSession();
            return driver.blockLength!(session, db, signal);
          }
        : undefined,
      dbNumbers: driver.dbNumbers ? (signal) => driver.dbNumbers!(this.liveSession(), signal) : undefined,
      unsupported: driver.noBlockLength ?? `${this.name}: the protocol has no service that tells the length of a data block`,
      parallel: () => LAYOUT_PARALLEL,
    };
  }

  /** Parses an address with this driver's syntax (cached); throws AddressError. */
  tag(address: string): T {
    const cached = this.tags.get(address);
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
    let list: ReadList<T, M> | undefined = this.lists.parse(addresses);
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
      list = this.lists.of(addresses);
    } catch (err) {
      return Promise.reject(err);
    }
    return this.readOf(list, options) as Promise<Record<string, V>>;
  }

  private async readOf(list: ReadList<T, M>, options?: RequestOptions): Promise<Record<string, PlcValue>> {
    const prepared = list.symbols && this.symbols?.layout.gating ? await this.gated(list, options?.signal) : list;
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
      list = this.lists.of(addresses);
    } catch (err) {
      return Promise.reject(err);
    }
    return this.readDetailedOf(list, options) as Promise<Record<string, TagResult<V>>>;
  }

  private async readDetailedOf(list: ReadList<T, M>, options: RequestOptions = {}): Promise<Record<string, TagResult<PlcValue>>> {
    const prepared = list.symbols && this.symbols?.layout.gating ? await this.gated(list, options.signal) : list;
    const session = this.liveSession();
    const read = prepared.tags.length > 0 ? await this.driver.readTags(session, prepared.tags, options.signal, prepared.prepared) : [];
    if (prepared.symbols && prepared.symbols.shaped.length > 0) shapeResults(prepared.symbols, prepared.tags, read);
    return this.byAddress(prepared, read);
  }

  /** strictSymbols: the list without the names in blocks the layout check refused (lib/client/symbols.ts). */
  private gated(list: ReadList<T, M>, signal: AbortSignal | undefined): Promise<ReadList<T, M>> {
    return this.symbols!.gated(list, signal, (addresses, tags, bad) => this.lists.ofTags(addresses, tags, bad));
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

  async write(values: Readonly<Record<string, unknown>>, options?: RequestOptions): Promise<void> {
    const results = await this.writeDetailed(values, options);
    for (const key of Object.keys(results)) if (!results[key]!.ok) throw new TagErrors(results);
  }

  async writeDetailed(values: Readonly<Record<string, unknown>>, options: RequestOptions = {}): Promise<Record<string, TagResult<void>>> {
    if (values === null || typeof values !== 'object') {
      throw new PlcError('INVALID_VALUE', 'write() takes an object of { address: value }');
    }
    try {
      return await this.writeEach(values, options);
    } catch (err) {
      throw writeRefusal(Object.keys(values), err);
    }
  }

  private async writeEach(values: Readonly<Record<string, unknown>>, options: RequestOptions): Promise<Record<string, TagResult<void>>> {
    let session = this.liveSession();
    const keys = Object.keys(values);
    const tags = keys.map((address) => this.tags.get(address));
    const symbols = this.symbols;
    const layout = symbols?.layout;
    if (layout?.gating && tags.some((t) => !(t instanceof PlcError) && symbols!.use(t) !== undefined)) {
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
      const use = symbols?.use(tag);
      let own: { tag: T; value: unknown }[];
      try {
        const refusal = use && layout?.refusal(use.db);
        if (refusal) throw tagError(address, refusal);
        own = use?.shape ? expandWrite(use.shape, values[address]) : [{ tag, value: values[address] }];
      } catch (err) {
        return void (results[address] = { ok: false, error: tagError(address, toPlcError(err, 'INVALID_VALUE')) });
      }
      for (const item of own) {
        const refusal = this.guard.refusal(item.tag);
        if (refusal) return void (results[address] = { ok: false, error: tagError(address, refusal) });
      }
      written.push({ key: address, from: items.length, count: own.length });
      items.push(...own);
    });
    const outcome = items.length > 0 ? await this.driver.writeTags(session, items, options.signal) : [];
    for (const { key, from, count } of written) {
      if (count === 1) {
        // Every driver's refusal names the tag it was for (a freeport station's failure names only the station).
        const r = outcome[from]!;
        results[key] = r.ok ? r : { ok: false, error: tagError(key, r.error) };
        continue;
      }
      // A struct: ok when every member written is; else its first member's error, naming the struct and the member.
      const failed = outcome.slice(from, from + count).find((r) => !r.ok);
      results[key] = failed && !failed.ok ? { ok: false, error: tagError(key, failed.error) } : { ok: true, value: undefined };
    }
    return results;
  }

  private liveSession(): S {
    const session = this.supervisor.session;
    if (session) return session;
    const why = this.state === 'closed' ? 'the client was closed' : `the link is ${this.state}`;
    throw new ConnectionError('NOT_CONNECTED', `not connected to ${this.name} (${why})`);
  }
}
