/**
 * One PLC client per endpoint (endpointKey of the URL), shared by every
 * owner that names it: in Node-RED, every connection config node for one
 * PLC. Owners share a client only when they agree on what it may do to the
 * PLC (the write-safety settings readOnly, allow, control) and on the symbol
 * sources it resolves names with; otherwise the later one is refused with
 * SETTINGS_CONFLICT, since one client has one set of them and a node would
 * write (or resolve a name) under the other owner's rules.
 */
import { createHmac, randomBytes } from 'node:crypto';
import { EventEmitter } from 'node:events';
import { createClient, type AnyClient, type ConnectOptions } from '../connect';
import { PlcError } from '../errors';
import type { SymbolTable } from '../symbols';
import type { LinkState, PlcClient } from '../types';
import { endpointKey, endpointName, parseUrl, type Endpoint } from '../url';

/** Parameters that change what a client may do to the PLC: two owners must agree on them to share a client. */
const SAFETY = ['readOnly', 'allow', 'control'] as const;

/** What a pooled link's client must do (an AnyClient; tests may give a stand-in). */
export interface PoolClient extends Pick<PlcClient, 'on'> {
  /** The link's state: the client's supervisor's (LinkSupervisor.state), the one source of it. */
  readonly state: LinkState;
  start(): void;
  close(): Promise<void>;
}

/** The symbols a link's client resolves names with: `key` what they were compiled from ('' for none). */
export interface PoolSymbols {
  key: string;
  table?: SymbolTable;
  strict?: boolean;
  /** s7plus: the PLC's password (a Node-RED credential), handed to the client only. */
  password?: string;
}

/** How the link is doing, as its owners show it. */
export interface LinkStatus {
  state: string;
  delay?: number;
  error?: unknown;
}

/** Who holds a link: anything with an optional name (a connection node). */
export interface PoolOwner {
  name?: string;
}

/**
 * One open client and its owners. Events: 'status' (LinkStatus), 'link-error'
 * (the client's errors, which never throw), 'layout-mismatch' and 'layout-ok'
 * (the symbol table's layout check on each connect, docs/symbols.md, "Stale layouts").
 */
export class PooledLink<C extends PoolClient = AnyClient> extends EventEmitter {
  readonly name: string;
  readonly owners = new Set<PoolOwner>();
  /** The delay and error of the retry the client announced last; cleared by every state change. */
  private retry: { delay: number; error: unknown } | undefined;

  constructor(
    private readonly pool: ClientPool<C>,
    readonly key: string,
    readonly url: string,
    readonly endpoint: Endpoint,
    readonly symbolsKey: string,
    readonly client: C,
  ) {
    super();
    this.name = endpointName(endpoint);
    client.on('state', (state: string) => {
      this.retry = undefined;
      // 'reconnecting' is told by the event that follows, with its delay.
      if (state !== 'reconnecting' && state !== 'idle') this.emit('status', this.status);
    });
    client.on('reconnecting', ({ delay, error }: { delay: number; error: unknown }) => {
      this.retry = { delay, error };
      this.emit('status', this.status);
    });
    // A listener on 'error' keeps an error event from ever throwing; errors reach users via 'status'.
    client.on('error', (error: unknown) => this.emit('link-error', error));
    client.on('layoutMismatch', (event: unknown) => this.emit('layout-mismatch', event));
    client.on('layoutOk', (event: unknown) => this.emit('layout-ok', event));
    client.start();
  }

  /**
   * How the link is doing, read from the client's state (its supervisor's,
   * LinkSupervisor.state in lib/link/supervisor.ts: the one source of a
   * link's state; nothing here keeps a copy of it), with the announced
   * retry's delay and error while reconnecting. 'idle' (not yet started) shows as 'connecting'.
   */
  get status(): LinkStatus {
    const state = this.client.state;
    if (state === 'reconnecting' && this.retry) return { state, ...this.retry };
    return { state: state === 'idle' ? 'connecting' : state };
  }

  /** Closes the client (the pool forgets the link). Always resolves. */
  close(): Promise<void> {
    this.pool.forget(this);
    return this.client.close().catch(() => undefined);
  }
}

/** The client for an endpoint with the pool's symbols; the default opens the library's own. */
type ClientFactory<C> = (endpoint: Endpoint, options: ConnectOptions) => C;

const safetyOf = (endpoint: Endpoint): string => JSON.stringify(SAFETY.map((k) => settingOf(endpoint, k) ?? null));

function settingOf(endpoint: Endpoint, key: (typeof SAFETY)[number]): unknown {
  return (endpoint as unknown as Record<string, unknown>)[key];
}

/** The URL without a user:password@ part: conflict messages reach logs and Catch nodes. */
export function withoutCredentials(url: string): string {
  return String(url).replace(/^([a-z0-9+.-]+:\/\/)[^/?#@]*@/i, '$1');
}

/** A setting as a conflict message shows it. */
function shownSetting(value: unknown): string {
  if (value === undefined || value === null) return 'not set';
  return Array.isArray(value) ? value.join(',') : String(value as string | number | boolean);
}

/** "control is true there, not set here; …": the write-safety settings of `here` that differ from `there`'s. */
function safetyDifferences(there: Endpoint, here: Endpoint): string {
  return SAFETY.filter((k) => JSON.stringify(settingOf(there, k) ?? null) !== JSON.stringify(settingOf(here, k) ?? null))
    .map((k) => `${k} is ${shownSetting(settingOf(there, k))} there, ${shownSetting(settingOf(here, k))} here`)
    .join('; ');
}

/** Which way two owners' symbol sources differ (by their keys, '' for none). */
function sourcesDifference(there: string, here: string): string {
  if (!here) return 'no symbol sources (it has some)';
  if (!there) return 'symbol sources (it has none)';
  return 'other symbol sources (or block numbers, or strictness)';
}

/** How a message names a connection: its name and URL, or the URL alone. */
function connectionName(owner: PoolOwner | undefined, url: string): string {
  const name = owner && owner.name ? `"${owner.name}" ` : '';
  return `${name}(${withoutCredentials(url)})`;
}

export class ClientPool<C extends PoolClient = AnyClient> {
  private readonly links = new Map<string, PooledLink<C>>();
  /** Which password each link's client was given, as a keyed digest (never the password): a second owner must give the same. */
  private readonly passwords = new WeakMap<PooledLink<C>, string>();
  /** The digest's key, random per pool, so the digest is no password hash that could be tried offline. */
  private readonly digestKey = randomBytes(32);

  constructor(private readonly create: ClientFactory<C> = createClient as unknown as ClientFactory<C>) {}

  /**
   * Takes (or opens) the link for `url` on behalf of `owner`, with the symbols
   * its client resolves names with. Throws PlcError INVALID_URL for a bad URL;
   * SETTINGS_CONFLICT when another owner already holds the link to the same
   * PLC with other write-safety settings (readOnly, allow, control) or other
   * symbol sources.
   */
  acquire(url: string, owner: PoolOwner, symbols: PoolSymbols = { key: '' }): PooledLink<C> {
    const endpoint = parseUrl(url);
    const key = endpointKey(endpoint);
    let link = this.links.get(key);
    const other = link && connectionName(link.owners.values().next().value, link.url);
    if (link && safetyOf(link.endpoint) !== safetyOf(endpoint)) {
      throw new PlcError(
        'SETTINGS_CONFLICT',
        `${withoutCredentials(url)} is a valid URL, but it reaches the same PLC as connection ${other}, whose link is already open, with other settings (${safetyDifferences(link.endpoint, endpoint)}); connections to one PLC share one link: give both the same readOnly, allow and control, or use one connection node`,
      );
    }
    if (link && link.symbolsKey !== symbols.key) {
      throw new PlcError(
        'SETTINGS_CONFLICT',
        `${withoutCredentials(url)} is a valid URL, but it reaches the same PLC as connection ${other}, whose link is already open, with ${sourcesDifference(link.symbolsKey, symbols.key)}; connections to one PLC share one link: give both the same sources, block numbers and strictness, or use one connection node`,
      );
    }
    const password = symbols.password === undefined ? '' : createHmac('sha256', this.digestKey).update(symbols.password).digest('hex');
    if (link && (this.passwords.get(link) ?? '') !== password) {
      throw new PlcError(
        'SETTINGS_CONFLICT',
        `${withoutCredentials(url)} is a valid URL, but it reaches the same PLC as connection ${other}, whose link is already open, with ${password === '' ? 'no password here and one there' : (this.passwords.get(link) ?? '') === '' ? 'a password here and none there' : 'another password'}; connections to one PLC share one link (and its login): give both the same password, or use one connection node`,
      );
    }
    if (!link) {
      const client = this.create(endpoint, {
        ...(symbols.table ? { symbols: symbols.table, strictSymbols: !!symbols.strict } : {}),
        ...(symbols.password !== undefined ? { password: symbols.password } : {}),
      });
      link = new PooledLink(this, key, url, endpoint, symbols.key, client);
      this.links.set(key, link);
      if (password !== '') this.passwords.set(link, password);
    }
    link.owners.add(owner);
    return link;
  }

  /** Gives the link back; the last owner closes it. Always resolves. */
  release(link: PooledLink<C>, owner: PoolOwner): Promise<void> {
    link.owners.delete(owner);
    return link.owners.size === 0 ? link.close() : Promise.resolve();
  }

  /** The open link to the PLC `url` names (by endpointKey), if any; undefined for an invalid URL too. */
  linkOf(url: string): PooledLink<C> | undefined {
    try {
      return this.links.get(endpointKey(parseUrl(url)));
    } catch {
      return undefined;
    }
  }

  /** How many links are open. */
  get size(): number {
    return this.links.size;
  }

  /** Drops a closing link (only PooledLink.close calls this). */
  forget(link: PooledLink<C>): void {
    if (this.links.get(link.key) === link) this.links.delete(link.key);
  }
}
