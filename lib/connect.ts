/**
 * `connect(url)`: one way to reach any PLC. The URL names the protocol
 * (see lib/url.ts); the same URLs serve the CLI and the Node-RED nodes.
 */
import type { BindingInterface } from '@serialport/bindings-interface';
import { FetchWriteClient } from './fetchwrite/client';
import { FreeportClient } from './freeport/client';
import type { FreeportProfile } from './freeport/profile';
import type { ClientOptions } from './link/client-base';
import { S7Client } from './s7/client';
import type { PlcClient } from './types';
import { parseUrl, type Endpoint } from './url';

export interface ConnectOptions extends Partial<Omit<ClientOptions, 'name'>> {
  /** Serial binding for freeport (tests inject `@serialport/binding-mock`). */
  binding?: BindingInterface;
  /** Freeport frame profile of your PLC program; unnamed fields keep the default profile's (docs/protocols.md, "S7-200 freeport"). */
  profile?: Partial<FreeportProfile>;
}

export type AnyClient = S7Client | FetchWriteClient | FreeportClient;

/** Creates the client for a URL (or parsed endpoint) without connecting: call `connect()` or `start()` on it. */
export function createClient(url: string | Endpoint, options: ConnectOptions = {}): AnyClient {
  const endpoint = typeof url === 'string' ? parseUrl(url) : url;
  const { binding, profile, ...common } = options;
  switch (endpoint.protocol) {
    case 's7':
      return new S7Client(endpoint, common);
    case 'fetchwrite':
      return new FetchWriteClient(endpoint, common);
    case 'freeport':
      return new FreeportClient(endpoint, { ...common, ...(binding ? { binding } : {}), ...(profile ? { profile } : {}) });
  }
}

/**
 * Connects and resolves once the PLC answered the handshake; rejects with the
 * first attempt's error (a ConnectionError, TimeoutError or PlcError) and
 * leaves nothing open. After that the client reconnects by itself if the link drops.
 */
export async function connect(url: string | Endpoint, options: ConnectOptions = {}): Promise<AnyClient & PlcClient> {
  const client = createClient(url, options);
  await client.connect();
  return client;
}
