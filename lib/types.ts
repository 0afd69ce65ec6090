/**
 * The shared model every driver speaks: data types, parsed tags, values,
 * per-tag results and the client interface returned by `connect(url)`.
 */
import type { TypedEvents } from './client/events';
import type { PlcError, TagResult } from './errors';

export type DataTypeName =
  | 'BOOL'
  | 'BYTE'
  | 'WORD'
  | 'DWORD'
  | 'LWORD'
  | 'SINT'
  | 'USINT'
  | 'INT'
  | 'UINT'
  | 'DINT'
  | 'UDINT'
  | 'LINT'
  | 'ULINT'
  | 'REAL'
  | 'LREAL'
  | 'CHAR'
  | 'WCHAR'
  | 'STRING'
  | 'WSTRING'
  | 'S5TIME'
  | 'TIME'
  | 'LTIME'
  | 'DATE'
  | 'TIME_OF_DAY'
  | 'DATE_AND_TIME'
  | 'DTL'
  | 'COUNTER'
  | 'TIMER';

/**
 * Memory areas. `V` (S7-200) is parsed to `DB` number 1. `PE`/`PA` are the
 * peripheral inputs/outputs. `C`/`T` are counters/timers: their offset is the
 * counter/timer number.
 */
export type AreaName = 'I' | 'Q' | 'M' | 'DB' | 'PE' | 'PA' | 'C' | 'T';

/** A parsed address: where a value lives in the PLC and how to read it. */
export interface Tag {
  /** The address exactly as the user wrote it (also the key of results). */
  readonly address: string;
  readonly area: AreaName;
  /** Data block number; 0 when the area is not DB. */
  readonly dbNumber: number;
  /** Byte offset in the area; for C and T the counter/timer number. */
  readonly byteOffset: number;
  /** Bit number 0–7; 0 unless type is BOOL. */
  readonly bitOffset: number;
  readonly type: DataTypeName;
  /** Number of elements; 1 for a scalar. */
  readonly count: number;
  /** True when the address names an array (the value is a JS array, even of length 1). */
  readonly isArray: boolean;
  /** Declared maximum characters of STRING/WSTRING (0 for other types). */
  readonly stringLength: number;
  /** Bytes the tag covers in the PLC, from byteOffset (for BOOL: bytes touched). */
  readonly byteLength: number;
}

/**
 * JavaScript values of PLC data types (see README, "Data types"):
 * BOOL → boolean; integers up to 32 bits, REAL, LREAL → number;
 * LWORD, LINT, ULINT, LTIME → bigint; CHAR/WCHAR/STRING/WSTRING → string;
 * S5TIME, TIME, TIME_OF_DAY → number (milliseconds); DATE, DATE_AND_TIME, DTL → Date (UTC fields);
 * COUNTER → number (0–999); TIMER → number (milliseconds); arrays → arrays of those.
 */
export type PlcScalar = boolean | number | bigint | string | Date;
export type PlcValue = PlcScalar | PlcScalar[];

/**
 * A whole STRUCT / UDT instance read by name (a client with `symbols`, see
 * docs/symbols.md): its members by name, nested structs as objects, arrays
 * of structs as arrays of objects.
 */
export interface PlcStruct {
  [member: string]: PlcData;
}

/** Any value a read can give: what an address gives (PlcValue), or a struct read by name. */
export type PlcData = PlcValue | PlcStruct | PlcStruct[];

export type LinkState = 'idle' | 'connecting' | 'connected' | 'reconnecting' | 'closed';

export type Protocol = 's7' | 'fetchwrite' | 'freeport' | 's7plus';

/**
 * A subscription a driver's PLC feeds (DriverEntry.subscribe; the S7CommPlus
 * client's S7PlusSubscription): `data` with every tag's latest result and the
 * ones that changed, `active` when (re)created, `lost` and `error`.
 */
export interface TagSubscription {
  on(event: 'data', listener: (d: SubscriptionNotice) => void): unknown;
  on(event: 'lost' | 'error', listener: (err: PlcError) => void): unknown;
  on(event: 'active', listener: () => void): unknown;
  close(): Promise<void>;
}

/** One notification of a TagSubscription. */
export interface SubscriptionNotice {
  /** Every tag's latest result, by the address or name as given. */
  results: Record<string, TagResult<PlcValue>>;
  /** The tags whose value or quality changed with this notification. */
  changed: string[];
  /** The first notification after the subscription was (re)created: it carries every value. */
  initial: boolean;
}

export interface RequestOptions {
  /** Abort the request (it rejects with code ABORTED). */
  signal?: AbortSignal;
}

/** The layout check of one data block of a symbol table's sources (client.checkLayout(), docs/symbols.md). */
export interface LayoutCheck {
  /** The block's name in the sources (`Tank`; `DB10` for a STEP 7 block without symbol). */
  block: string;
  db: number;
  /** Bytes the sources declare (standard access). */
  declared: number;
  /** Bytes the PLC reports; null when the PLC has no such DB; undefined when it could not tell (status 'unknown'). */
  actual: number | null | undefined;
  status: 'ok' | 'mismatch' | 'unknown';
  /** Why the PLC could not tell (status 'unknown'). */
  error?: PlcError;
}

/** The `layoutMismatch` event: a block of the PLC is not as long as the sources declare (`actual` null: the PLC has no such DB). */
export interface LayoutMismatchEvent {
  block: string;
  db: number;
  declared: number;
  actual: number | null;
}

/** The `layoutUnknown` event: the PLC could not tell the length of these blocks; `error` says why (the first block's). */
export interface LayoutUnknownEvent {
  checks: LayoutCheck[];
  error: PlcError;
}

/** The `layoutOk` event: every block of the sources has the length they declare. */
export interface LayoutOkEvent {
  checks: LayoutCheck[];
}

/** The `reconnecting` event: the next attempt in `delay` ms, the `attempt`-th since the link went, and why the last one failed. */
export interface ReconnectingEvent {
  delay: number;
  attempt: number;
  error: PlcError;
}

/**
 * The events every client emits and their arguments (see PlcClient): a
 * listener of a misspelt event (`client.on('conected', …)`) or of another
 * event's argument does not compile. A driver's client adds its own
 * (S7ClientEvents, S7PlusClientEvents).
 */
export interface ClientEvents {
  state: [state: LinkState];
  connecting: [];
  connected: [];
  disconnected: [error: PlcError];
  reconnecting: [event: ReconnectingEvent];
  /** Only emitted when someone listens. */
  error: [error: PlcError];
  closed: [];
  layoutMismatch: [event: LayoutMismatchEvent];
  layoutUnknown: [event: LayoutUnknownEvent];
  layoutOk: [event: LayoutOkEvent];
}

/**
 * What `connect(url)` returns, whatever the protocol.
 *
 * Events (state changes only; typed by ClientEvents): `connecting`, `connected`,
 * `disconnected` (err), `reconnecting` (ReconnectingEvent `{ delay, attempt, error }`),
 * `error` (err), `state` (LinkState), `closed`.
 * S7Client also emits `itemLimit` (ItemLimitEvent `{ limit, was }`) once when
 * the PLC answers fewer items than a job asked for: from then on it plans jobs
 * of at most `limit` items (see S7Endpoint.maxItems).
 *
 * A client with a symbol table (`symbols`) checks after each connect (and
 * on checkLayout()) that the PLC's data blocks are as long as the sources
 * declare, and emits, at most once per connection and block for the same
 * finding:
 * - `layoutMismatch` (LayoutMismatchEvent `{ block, db, declared, actual }`):
 *   a block differs (`actual` null: the PLC has no such DB); reads by name in
 *   it return shifted values, or fail with LAYOUT_MISMATCH with `strictSymbols`;
 * - `layoutUnknown` (LayoutUnknownEvent `{ checks, error }`): the PLC could not
 *   tell (no block functions, e.g. S7-1200/1500 over PUT/GET; FETCH/WRITE has
 *   no such service); nothing is refused;
 * - `layoutOk` (LayoutOkEvent `{ checks }`): every block matches (again).
 */
export interface PlcClient extends TypedEvents<ClientEvents> {
  readonly protocol: Protocol;
  readonly state: LinkState;
  /**
   * Reads tags; resolves `{ address: value }`, or rejects with TagErrors (whose `results` has the good ones).
   * Polling the same list: pass the same array object each time, or use prepare(); a new array is parsed and planned again.
   * `V` is a type assertion, as PlcValue (the default) is: addresses and elementary symbols give PlcValues; a whole
   * struct read by name gives a PlcStruct (`read<PlcData>([...])`).
   */
  read<V extends PlcData = PlcValue>(addresses: readonly string[], options?: RequestOptions): Promise<Record<string, V>>;
  /** Reads tags; always resolves with a result per tag (rejects only when nothing could be attempted). */
  readDetailed<V extends PlcData = PlcValue>(addresses: readonly string[], options?: RequestOptions): Promise<Record<string, TagResult<V>>>;
  /** Parses `addresses` once and keeps what the driver computes for them: the fast way to poll the same tags (see PreparedRead). */
  prepare(addresses: readonly string[]): PreparedRead;
  /** Writes `{ address: value }`; resolves when the PLC acknowledged every tag, else rejects with TagErrors. */
  write(values: Readonly<Record<string, unknown>>, options?: RequestOptions): Promise<void>;
  /** Writes; always resolves with a result per tag. */
  writeDetailed(values: Readonly<Record<string, unknown>>, options?: RequestOptions): Promise<Record<string, TagResult<void>>>;
  /** Checks the symbol table's data blocks against the PLC now (see the layout events above); [] without a symbol table. */
  checkLayout(options?: RequestOptions): Promise<LayoutCheck[]>;
  /** Stops reconnecting, fails what is pending with CLOSED, closes the socket. Always resolves. */
  close(): Promise<void>;
}

/**
 * A tag list prepared for polling, from `client.prepare(addresses)`. It owns
 * what a poll of the list needs and would otherwise work out again: the
 * parsed tags, and what the driver computes once for them (S7: the read
 * plan for the negotiated PDU size and the PLC's item limit, and the
 * request frames, kept and reused; FETCH/WRITE: the merged fetch ranges;
 * freeport: the tags grouped by station). A reconnect to a CPU with another
 * PDU size, or a PLC that turns out to serve fewer items per job, re-plans
 * it at the next read. Nothing of it holds the link: reads made while the
 * client is not connected fail fast with NOT_CONNECTED, and the handle
 * works again once the link is back.
 *
 * `client.read(array)` gets the same benefit only as long as it is given
 * the same array object every time (the list is recognised by identity);
 * a new array, even with the same addresses, is parsed and grouped again
 * (an S7 client still finds the plan in its bounded plan cache).
 */
export interface PreparedRead {
  /** The addresses, in the order given to prepare() (a frozen copy). */
  readonly addresses: readonly string[];
  /** Same result as `client.read(addresses)`: `{ address: value }`, or rejects with TagErrors (its `results` keeps the good values). */
  read<V extends PlcData = PlcValue>(options?: RequestOptions): Promise<Record<string, V>>;
  /** Same result as `client.readDetailed(addresses)`: a result per tag. */
  readDetailed<V extends PlcData = PlcValue>(options?: RequestOptions): Promise<Record<string, TagResult<V>>>;
  /** Drops the plan and frames it holds; reads then reject with CLOSED. Nothing else needs releasing. */
  close(): void;
}

export type { PlcError, TagResult };
