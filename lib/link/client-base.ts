import { EventEmitter } from 'node:events';
import { ConnectionError, PlcError, TagErrors, toPlcError, type TagResult } from '../errors';
import type { LinkState, PlcClient, PlcValue, Protocol, RequestOptions } from '../types';
import type { BackoffOptions } from './backoff';
import { LinkSupervisor, type DriverSession } from './supervisor';

export type { DriverSession };

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
}

export const DEFAULT_TIMEOUT = 5000;
const MAX_CACHED_TAGS = 10_000;

/**
 * What every driver's client shares: the supervisor (connect, reconnect,
 * state events, close), address parsing with a cache, per-tag results and
 * TagErrors. A driver implements only its protocol.
 *
 * Requests made while not connected fail fast with NOT_CONNECTED: a stale
 * write executed minutes later, when the link comes back, is worse than an error.
 */
export abstract class BaseClient<S extends DriverSession, T extends { readonly address: string }>
  extends EventEmitter
  implements PlcClient
{
  abstract readonly protocol: Protocol;
  readonly name: string;
  protected readonly timeout: number;
  protected readonly maxQueued: number | undefined;
  private readonly supervisor: LinkSupervisor<S>;
  private readonly tags = new Map<string, T | PlcError>();

  constructor(options: ClientOptions) {
    super();
    this.name = options.name;
    this.timeout = options.timeout ?? DEFAULT_TIMEOUT;
    this.maxQueued = options.maxQueued;
    this.supervisor = new LinkSupervisor<S>({
      name: options.name,
      connectTimeout: this.timeout,
      open: (signal) => this.openSession(signal),
      events: this,
      ...(options.backoff ? { backoff: options.backoff } : {}),
      ...(options.random ? { random: options.random } : {}),
    });
  }

  /** Transport and handshakes. Honour `signal`; reject with a PlcError. */
  protected abstract openSession(signal: AbortSignal): Promise<S>;
  /** Parses an address; throws AddressError. Results are cached per address string. */
  protected abstract parseTag(address: string): T;
  /** One result per tag, in order. Throw only when the whole request failed. */
  protected abstract readTags(session: S, tags: readonly T[], signal?: AbortSignal): Promise<TagResult<PlcValue>[]>;
  /** One result per item, in order. Encode values here: a ValueError is that tag's result. */
  protected abstract writeTags(
    session: S,
    items: readonly { tag: T; value: unknown }[],
    signal?: AbortSignal,
  ): Promise<TagResult<void>[]>;

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

  /** Starts and waits for the first connection; rejects with the first attempt's error and stops. */
  async connect(): Promise<this> {
    await this.supervisor.connectOnce();
    return this;
  }

  /** Starts and keeps (re)connecting in the background until close(); never rejects. */
  start(): void {
    this.supervisor.start();
  }

  close(): Promise<void> {
    return this.supervisor.close();
  }

  /** Parses an address with this driver's syntax (cached); throws AddressError. */
  tag(address: string): T {
    const cached = this.parseCached(address);
    if (cached instanceof PlcError) throw cached;
    return cached;
  }

  async read(addresses: readonly string[], options?: RequestOptions): Promise<Record<string, PlcValue>> {
    const results = await this.readDetailed(addresses, options);
    const values: Record<string, PlcValue> = {};
    for (const key of Object.keys(results)) {
      const r = results[key]!;
      if (!r.ok) throw new TagErrors(results);
      values[key] = r.value;
    }
    return values;
  }

  async readDetailed(
    addresses: readonly string[],
    options: RequestOptions = {},
  ): Promise<Record<string, TagResult<PlcValue>>> {
    const session = this.liveSession();
    const results: Record<string, TagResult<PlcValue>> = {};
    const tags: T[] = [];
    for (const address of addresses) {
      const tag = this.parseCached(address);
      if (tag instanceof PlcError) results[address] = { ok: false, error: tag };
      else tags.push(tag);
    }
    if (tags.length > 0) {
      const read = await this.readTags(session, tags, options.signal);
      for (let i = 0; i < tags.length; i++) results[tags[i]!.address] = read[i]!;
    }
    return results;
  }

  async write(values: Readonly<Record<string, unknown>>, options?: RequestOptions): Promise<void> {
    const results = await this.writeDetailed(values, options);
    for (const key of Object.keys(results)) if (!results[key]!.ok) throw new TagErrors(results);
  }

  async writeDetailed(
    values: Readonly<Record<string, unknown>>,
    options: RequestOptions = {},
  ): Promise<Record<string, TagResult<void>>> {
    if (values === null || typeof values !== 'object') {
      throw new PlcError('INVALID_VALUE', 'write() takes an object of { address: value }');
    }
    const session = this.liveSession();
    const results: Record<string, TagResult<void>> = {};
    const items: { tag: T; value: unknown }[] = [];
    for (const address of Object.keys(values)) {
      const tag = this.parseCached(address);
      if (tag instanceof PlcError) results[address] = { ok: false, error: tag };
      else items.push({ tag, value: values[address] });
    }
    if (items.length > 0) {
      const written = await this.writeTags(session, items, options.signal);
      for (let i = 0; i < items.length; i++) results[items[i]!.tag.address] = written[i]!;
    }
    return results;
  }

  private liveSession(): S {
    const session = this.supervisor.session;
    if (session) return session;
    const why = this.state === 'closed' ? 'the client was closed' : `the link is ${this.state}`;
    throw new ConnectionError('NOT_CONNECTED', `not connected to ${this.name} (${why})`);
  }

  private parseCached(address: string): T | PlcError {
    let tag = this.tags.get(address);
    if (tag === undefined) {
      try {
        tag = this.parseTag(address);
      } catch (err) {
        tag = toPlcError(err, 'INVALID_ADDRESS');
      }
      if (this.tags.size >= MAX_CACHED_TAGS) this.tags.clear();
      this.tags.set(address, tag);
    }
    return tag;
  }
}
