/**
 * The driver contract: what a protocol supplies so that the shared client
 * (BaseClient: supervisor, tag cache, per-tag results, write safety) can run
 * it. S7, FETCH/WRITE and freeport each implement it in their own folder;
 * nothing in lib/link/ knows which protocol it runs.
 *
 *   Driver          its protocol's address syntax (TagSyntax), its sessions
 *                   over a transport, its read and write planning, and which
 *                   of its errors end a whole request (isLinkError)
 *   UrlScheme       its URL scheme(s) and parameters (lib/url.ts registers them)
 */
import type { PlcError, TagResult } from '../errors';
import type { PlcValue, Protocol } from '../types';
import type { UrlParams } from './url-params';

/** A parsed address of any driver. */
export interface DriverTag {
  /** The address exactly as the user wrote it: the key of results and the name in errors. */
  readonly address: string;
}

/** A live connection of a driver (transport open, handshakes done). */
export interface DriverSession {
  /** Closes the transport now and rejects everything pending on it. Must not throw. */
  destroy(): void;
}

/**
 * What a read needs from a driver on the hot path: a value per tag and, only
 * when some tag failed, an error at its index (its value is then undefined).
 * No result object per tag: that is readDetailed's shape.
 */
export interface ReadValues {
  values: PlcValue[];
  errors: (PlcError | undefined)[] | undefined;
}

/** A driver's address syntax and what write allow-lists need to know about its tags. */
export interface TagSyntax<T extends DriverTag> {
  /**
   * Parses an address into this driver's tag. Throws an AddressError naming
   * the address and what is wrong; results are cached per address string by
   * the client, so this must give the same answer for the same string.
   */
  parse(address: string): T;

  /** The area a tag lies in, spelt as an allow-list names it ("DB10", "M", "ST5"). */
  areaOf(tag: T): string;

  /**
   * An allow-list entry that names a whole area, spelt as areaOf spells it
   * ("db010" → "DB10"); undefined when the entry is not an area name of this
   * driver, and so must be one of its addresses. The entry is trimmed,
   * upper-cased and without a leading "%".
   */
  allowArea(entry: string): string | undefined;

  /** True when `inner` lies wholly inside `outer` (an allow-list address admits the tags inside it). */
  contains(outer: T, inner: T): boolean;
}

/**
 * One protocol's part of a client. Every promise settles; none of these
 * is called while the client has no live session (requests then fail with
 * NOT_CONNECTED before reaching the driver).
 *
 * `M` is what the driver works out once per tag list that is read again and
 * again (prepareRead): the client keeps it with the list (a PreparedRead, or
 * the list behind an array read() sees again) and hands it back with that
 * list's tags.
 */
export interface Driver<S extends DriverSession, T extends DriverTag, M = undefined> {
  readonly syntax: TagSyntax<T>;

  /**
   * Optional: what this driver can compute once for a tag list (its grouping,
   * its plan, its request frames) so that polling the list does not compute
   * it again. Called once per list, before any session may exist: what
   * depends on the link (an S7 plan depends on the PDU size and the item
   * limit) the driver fills in at a read and checks at every read, so a
   * reconnect to another CPU re-plans. Must not throw; every read of the list
   * gets it as `prepared`.
   */
  prepareRead?(tags: readonly T[]): M;

  /**
   * Opens a session: transport, handshakes, and the handlers that report
   * its loss to the client. Honour `signal` (the connect deadline and
   * close()); reject with a PlcError and leave nothing open.
   */
  openSession(signal: AbortSignal): Promise<S>;

  /**
   * One result per tag, in order. A tag's own failure (refused by the PLC,
   * out of range, undecodable) is its result; throw only when the whole
   * request failed (isLinkError).
   */
  readTags(session: S, tags: readonly T[], signal?: AbortSignal, prepared?: M): Promise<TagResult<PlcValue>[]>;

  /**
   * read()'s path: the same outcome as readTags without a result object per
   * tag. Optional: without it the client derives it from readTags; a driver
   * whose poll is hot implements it (and derives readTags from it).
   */
  readValues?(session: S, tags: readonly T[], signal?: AbortSignal, prepared?: M): Promise<ReadValues>;

  /**
   * One result per item, in order. Encode values here: a ValueError is that
   * tag's result. A write whose outcome is unknown (the link dropped while
   * it was under way) is an error result, never a silent success.
   */
  writeTags(session: S, items: readonly { tag: T; value: unknown }[], signal?: AbortSignal): Promise<TagResult<void>[]>;

  /**
   * Optional: the length of data block `db` as the PLC reports it (null
   * when it has no such block), for the layout check of symbols
   * (lib/symbols/layout-check.ts). Rejects when the PLC cannot tell. Absent:
   * the protocol has no way to ask (`noBlockLength` says why, for the
   * `layoutUnknown` event).
   */
  blockLength?(session: S, db: number, signal?: AbortSignal): Promise<number | null>;
  /** Optional, with blockLength: the numbers of the data blocks the PLC has (the check asks only for those). */
  dbNumbers?(session: S, signal?: AbortSignal): Promise<number[]>;
  readonly noBlockLength?: string;

  /**
   * True when `err` ends the whole request rather than one tag's part of it:
   * the link is gone, or, on a protocol without request ids, a job timed out
   * and the link was dropped for it. The shared `isLinkError` (lib/errors.ts)
   * is the common part.
   */
  isLinkError(err: PlcError): boolean;
}

/**
 * A driver's URLs: its scheme(s) and parameters, parsed to its endpoint and
 * formatted back. lib/url.ts looks schemes up in a registry of these; the
 * parameters every scheme takes (readOnly, allow, strictSymbols) are parsed there.
 */
export interface UrlScheme<E extends { readonly protocol: Protocol }> {
  readonly protocol: E['protocol'];

  /** Each URL scheme of this driver ("freeport", "freeport+tcp") and the query parameters it takes. */
  readonly schemes: Readonly<Record<string, readonly string[]>>;

  /** What a URL that leaves a parameter out gets (part of the exported DEFAULTS). */
  readonly defaults: Readonly<Record<string, number>>;

  /** Said when the authority of a URL that does not parse has a port: for a scheme that takes its ports as parameters. */
  readonly portHint?: string;

  /**
   * The endpoint, without `protocol` and the common parameters, from a URL
   * of one of `schemes`. Throws INVALID_URL (urlError) naming the part that
   * is wrong.
   */
  parse(scheme: string, text: string, url: URL, params: UrlParams): Omit<E, 'protocol' | 'readOnly' | 'allow'>;

  /** The URL without its query; sets the query parameters that differ from the defaults on `query`. */
  format(endpoint: E, query: URLSearchParams): string;

  /** Identity of the physical endpoint: URLs with the same key reach the same connection(s). */
  key(endpoint: E): string;

  /** A short name for messages: "s7://10.0.0.2:102". */
  name(endpoint: E): string;

  /** The host the endpoint reaches over the network; '' when it reaches none (a serial port). */
  host(endpoint: E): string;
}
