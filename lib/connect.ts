/**
 * `connect(url)`: one way to reach any PLC. The URL names the protocol
 * (see lib/url.ts); the same URLs serve the CLI and the Node-RED nodes.
 */
import type { BindingInterface } from '@serialport/bindings-interface';
import { PlcError } from './errors';
import { FetchWriteClient } from './fetchwrite/client';
import { FreeportClient } from './freeport/client';
import type { FreeportProfile } from './freeport/profile';
import type { ClientOptions } from './link/client-base';
import { S7Client } from './s7/client';
import type { PlcClient } from './types';
import { endpointName, parseUrl, type Endpoint, type FetchWriteEndpoint, type FreeportEndpoint, type S7Endpoint } from './url';

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
}

export type AnyClient = S7Client | FetchWriteClient | FreeportClient;

/**
 * The client a URL (or endpoint) gets, by its scheme: `s7://…` an S7Client
 * (whose services, info(), szl(), blocks…, are then there to call without a
 * cast), `fetchwrite://…` a FetchWriteClient, `freeport://…` and
 * `freeport+tcp://…` a FreeportClient; a string whose scheme TypeScript
 * cannot see, any of them (AnyClient).
 */
export type ClientFor<U extends string | Endpoint> = U extends `s7://${string}` | S7Endpoint
  ? S7Client
  : U extends `fetchwrite://${string}` | FetchWriteEndpoint
    ? FetchWriteClient
    : U extends `freeport://${string}` | `freeport+tcp://${string}` | FreeportEndpoint
      ? FreeportClient
      : AnyClient;

/** Creates the client for a URL (or parsed endpoint) without connecting: call `connect()` or `start()` on it. */
export function createClient<U extends string | Endpoint>(url: U, options?: ConnectOptions): ClientFor<U>;
export function createClient(url: string | Endpoint, options: ConnectOptions = {}): AnyClient {
  const endpoint = typeof url === 'string' ? parseUrl(url) : url;
  const { binding, profile, ...common } = options;
  switch (endpoint.protocol) {
    case 's7':
      return new S7Client(endpoint, common);
    case 'fetchwrite':
      return new FetchWriteClient(endpoint, common);
    case 'freeport':
      if (common.symbols) {
        throw new PlcError(
          'NOT_SUPPORTED',
          `${endpointName(endpoint)}: freeport cannot read or write by symbol: it reaches only each station's data area (ST<station>,…), a few bytes its PLC program fills, not V memory (DB1) by offset; reach the S7-200 over s7:// (a CP 243-1) to use its V memory symbols`,
        );
      }
      return new FreeportClient(endpoint, { ...common, ...(binding ? { binding } : {}), ...(profile ? { profile } : {}) });
  }
}

/**
 * Connects and resolves once the PLC answered the handshake; rejects with the
 * first attempt's error (a ConnectionError, TimeoutError or PlcError) and
 * leaves nothing open. After that the client reconnects by itself if the link drops.
 */
export async function connect<U extends string | Endpoint>(url: U, options?: ConnectOptions): Promise<ClientFor<U> & PlcClient>;
export async function connect(url: string | Endpoint, options: ConnectOptions = {}): Promise<AnyClient & PlcClient> {
  const client: AnyClient = createClient(url, options);
  await client.connect();
  return client;
}
