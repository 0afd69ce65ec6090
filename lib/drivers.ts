/**
 * The protocols, one entry each: its URLs (schemes, parameters, defaults),
 * how to make its client, and what it can do (its capability ports:
 * diagnose, browse, subscribe). lib/url.ts, createClient(), connect(), the
 * doctor (lib/doctor/), the CLI and the Node-RED nodes read this registry and
 * test no scheme: a new protocol is its own folder (docs/architecture.md,
 * "How to add a protocol") and one line in DRIVERS; a capability of a driver
 * is its folder's part and one field of its entry.
 */
import type { BindingInterface } from '@serialport/bindings-interface';
import type { AlarmPort } from './alarms/model';
import { S7_ALARMS } from './s7/alarm-port';
import type { ClientOptions } from './client/options';
import type { DiagnosePort } from './doctor-steps';
import { PlcError } from './errors';
import { FetchWriteClient } from './fetchwrite/client';
import { serveFetchWrite } from './fetchwrite/serve';
import { FETCHWRITE_URLS } from './fetchwrite/url';
import { FreeportClient } from './freeport/client';
import type { FreeportProfile } from './freeport/profile';
import { serveFreeport } from './freeport/serve';
import { FREEPORT_URLS } from './freeport/url';
import type { UrlScheme } from './link/driver';
import { S7Client } from './s7/client';
import { serveS7 } from './cpu/serve';
import { S7_DOCTOR } from './s7/doctor';
import { S7_URLS } from './s7/url';
import { S7PlusClient } from './s7plus/client';
import { S7PLUS_DOCTOR } from './s7plus/doctor';
import { S7PLUS_URLS } from './s7plus/url';
import type { Served, ServeFlags } from './sim/serve';
import type { SymbolTable } from './symbols/model';
import type { PlcClient, Protocol, RequestOptions, TagSubscription } from './types';

/**
 * `symbols` (a compiled SymbolTable) lets reads and writes name tags as the
 * PLC's sources do, beside absolute addresses; `strictSymbols` (also the
 * URL's `strictSymbols=true`) refuses names in a data block whose length in
 * the PLC differs from the sources' (docs/symbols.md, "Reading and writing
 * by name"). Freeport refuses `symbols`: it reaches a few bytes per station
 * that the station's program fills, not V memory by offset.
 */
export interface ConnectOptions extends Partial<Omit<ClientOptions, 'name'>> {
  /** Serial binding for freeport (tests inject `@serialport/binding-mock`). */
  binding?: BindingInterface;
  /** Freeport frame profile of your PLC program; unnamed fields keep the default profile's (docs/protocols.md, "S7-200 freeport"). */
  profile?: Partial<FreeportProfile>;
  /** s7plus: the PLC's password (legitimation); never in a URL, never in a log, an error or JSON. */
  password?: string;
}

/**
 * What a driver offers beyond reads and writes, each an optional port of its
 * entry: a caller asks the entry (`driverOf(endpoint).browse`), never the
 * URL's scheme. What several drivers share of a capability lives in a folder
 * above the protocols (the doctor's walk and URL handling in lib/doctor/),
 * each driver's part in its own folder (the alarm model in lib/alarms/).
 */
interface DriverPorts<E, C> {
  /** The connection doctor's steps of this protocol (`plcwire doctor`, diagnose(), Test connection in Node-RED). */
  readonly diagnose?: DiagnosePort<E>;
  /** The PLC's own tag table, names and types as its program declares them (`plcwire browse`, Browse PLC). */
  browse?(client: C, options?: RequestOptions): Promise<SymbolTable>;
  /** The PLC reports changes of `tags`, sampled every `cycle` ms (`plcwire watch`, the read node's push mode). */
  subscribe?(client: C, tags: readonly string[], options?: { cycle?: number }): Promise<TagSubscription>;
  /** What the PLC pushes: its alarms, mode changes, diagnostic messages (`plcwire alarms`, `plcwire ack`, the alarms node). */
  readonly alarms?: AlarmPort<C>;
}

/** The names of the capability ports. */
export type Capability = keyof DriverPorts<unknown, unknown>;

/** One protocol in the registry. */
export interface DriverEntry<E extends { readonly protocol: Protocol }, C extends PlcClient> extends DriverPorts<E, C> {
  /** Its URL schemes and parameters, parsed to its endpoint and formatted back (lib/url.ts). */
  readonly urls: UrlScheme<E>;
  /**
   * Its client for an endpoint, not connected. `options` are the caller's;
   * an entry passes on what its client takes.
   */
  createClient(endpoint: E, options: ConnectOptions): C;
  /** Reads and writes by name (ConnectOptions.symbols); false: createClient refuses a symbol table (NOT_SUPPORTED). */
  readonly symbols: boolean;
  /** Why it has no symbols, after the endpoint's name in the refusal. */
  readonly noSymbols?: string;
  /** Its client can ask a data block's length, so strictSymbols can check a symbol table's layout against the PLC. */
  readonly blockLength: boolean;
  /** Why the protocol itself cannot tell a block's length, when that is so for every PLC it reaches (the CLI's layout note). */
  readonly noBlockLength?: string;
  /** Its client takes the PLC's password (ConnectOptions.password: the CLI's PLCWIRE_PASSWORD and --password-file, a node's credential). */
  readonly password: boolean;
  /** `plcwire serve <protocol>`: starts its simulator from the command line's flags. */
  serve(flags: ServeFlags): Promise<Served>;
}

/** The options every client takes: ConnectOptions without freeport's serial binding and frame profile. */
function common(options: ConnectOptions): Partial<ClientOptions> {
  const { binding: _binding, profile: _profile, password: _password, ...rest } = options;
  return rest;
}

function entry<E extends { readonly protocol: Protocol }, C extends PlcClient>(e: DriverEntry<E, C>): DriverEntry<E, C> {
  return Object.freeze(e);
}

/** Every protocol, by name: adding a protocol is one line here (its entry from its own folder). */
export const DRIVERS = Object.freeze({
  s7: entry({
    urls: S7_URLS,
    createClient: (e, o) => new S7Client(e, common(o)),
    symbols: true,
    blockLength: true,
    password: false,
    serve: serveS7,
    diagnose: S7_DOCTOR,
    alarms: S7_ALARMS,
  }),
  fetchwrite: entry({
    urls: FETCHWRITE_URLS,
    createClient: (e, o) => new FetchWriteClient(e, common(o)),
    symbols: true,
    blockLength: false,
    noBlockLength: 'FETCH/WRITE does not report the length of data blocks',
    password: false,
    serve: serveFetchWrite,
  }),
  freeport: entry({
    urls: FREEPORT_URLS,
    createClient: (e, { binding, profile, ...o }) =>
      new FreeportClient(e, { ...o, ...(binding ? { binding } : {}), ...(profile ? { profile } : {}) }),
    symbols: false,
    noSymbols:
      "freeport cannot read or write by symbol: it reaches only each station's data area (ST<station>,…), a few bytes its PLC program fills, not V memory (DB1) by offset; reach the S7-200 over s7:// (a CP 243-1) to use its V memory symbols",
    blockLength: false,
    password: false,
    serve: serveFreeport,
  }),
  s7plus: entry({
    urls: S7PLUS_URLS,
    createClient: (e, o) => new S7PlusClient(e, { ...common(o), ...(o.password !== undefined ? { password: o.password } : {}) }),
    symbols: true,
    blockLength: false,
    password: true,
    diagnose: S7PLUS_DOCTOR,
    browse: (client, options) => client.browse(options),
    subscribe: (client, tags, options) => client.subscribe(tags, options),
    // Program_Alarms (issue #33): the active-alarm list, the alarm subscription; acknowledge refuses (docs/alarms.md).
    alarms: {
      list: (client, options) => client.alarms(options),
      subscribe: (client, options, listener) => client.subscribeAlarms(options, listener),
      acknowledge: (client, id, options) => client.acknowledge(id, options),
    },
    // Its simulator is the S7 one's (S7CommPlus on the same port as PUT/GET, as a CPU serves it) once that serves it.
    // As on a CPU, S7CommPlus is served by the S7 simulator of an S7-1200/1500 on the PUT/GET port (the called TSAP decides).
    serve: (flags) =>
      Promise.reject(
        flags.usage('S7CommPlus is served on the PUT/GET port by `plcwire serve s7 --profile s7-1500` (or s7-1200) with --source'),
      ),
  }),
}) satisfies { readonly [P in Protocol]: DriverEntry<{ readonly protocol: P }, PlcClient> };

type Drivers = typeof DRIVERS;

/** Any protocol's endpoint: what parseUrl gives. */
export type Endpoint = { [P in Protocol]: Drivers[P] extends DriverEntry<infer E, PlcClient> ? E : never }[Protocol];

/** Any protocol's client: what createClient gives. */
export type AnyClient = { [P in Protocol]: ReturnType<Drivers[P]['createClient']> }[Protocol];

/**
 * Each protocol's URL schemes, for the types (ClientFor): the same as the
 * keys of its entry's `urls.schemes`, which test/drivers.test.ts holds equal.
 */
export const URL_SCHEMES = Object.freeze({
  s7: ['s7'],
  fetchwrite: ['fetchwrite'],
  freeport: ['freeport', 'freeport+tcp'],
  s7plus: ['s7plus'],
} as const) satisfies {
  readonly [P in Protocol]: readonly string[];
};
type SchemesOf<P extends Protocol> = (typeof URL_SCHEMES)[P][number];

/**
 * The client a URL (or endpoint) gets, by its scheme: `s7://…` an S7Client
 * (whose services, info(), szl(), blocks…, are then there to call without a
 * cast), `fetchwrite://…` a FetchWriteClient, `freeport://…` and
 * `freeport+tcp://…` a FreeportClient; a string whose scheme TypeScript
 * cannot see, any of them (AnyClient). Derived from the registry: an
 * endpoint's protocol, or the schemes each entry's URLs declare.
 */
export type ClientFor<U extends string | Endpoint> = U extends Endpoint
  ? ReturnType<Drivers[U['protocol']]['createClient']>
  : { [P in Protocol]: U extends `${SchemesOf<P>}://${string}` ? ReturnType<Drivers[P]['createClient']> : never }[Protocol] extends infer C
    ? [C] extends [never]
      ? AnyClient
      : C
    : never;

/** The registry's entry of an endpoint's (or a client's) protocol. */
export function driverOf(of: { readonly protocol: Protocol }): DriverEntry<Endpoint, AnyClient> {
  return DRIVERS[of.protocol] as DriverEntry<Endpoint, AnyClient>;
}

/** The URL schemes of the drivers offering `what`, as a user writes them: "s7:// or s7plus://" (for messages). */
export function schemesOffering(what: Capability | 'password'): string {
  const names = Object.values(DRIVERS)
    .filter((d) => (what === 'password' ? d.password : (d as DriverPorts<unknown, unknown>)[what] !== undefined))
    .flatMap((d) => Object.keys(d.urls.schemes))
    .map((s) => `${s}://`);
  return names.length > 1 ? `${names.slice(0, -1).join(', ')} or ${names.at(-1)}` : names.join('');
}

/** The client of an endpoint, by its protocol's entry; a symbol table given to a protocol without symbols is refused (NOT_SUPPORTED). */
export function createDriverClient(endpoint: Endpoint, options: ConnectOptions): AnyClient {
  const driver = driverOf(endpoint);
  if (options.symbols && !driver.symbols) {
    throw new PlcError(
      'NOT_SUPPORTED',
      `${driver.urls.name(endpoint)}: ${driver.noSymbols ?? 'this protocol cannot read or write by symbol'}`,
    );
  }
  return driver.createClient(endpoint, options);
}
