/**
 * `connect(url)`: one way to reach any PLC. The URL names the protocol
 * (see lib/url.ts); the same URLs serve the CLI and the Node-RED nodes.
 */
import { createDriverClient, type AnyClient, type ClientFor, type ConnectOptions } from './drivers';
import type { PlcClient } from './types';
import { parseUrl, type Endpoint } from './url';

export type { AnyClient, ClientFor, ConnectOptions } from './drivers';

/**
 * Creates the client for a URL (or parsed endpoint) without connecting: call `connect()` or `start()` on it.
 * The protocol's entry in lib/drivers.ts makes it; `symbols` given to a protocol without them is refused (NOT_SUPPORTED).
 * Typed by the URL's scheme: `createClient('s7://…')` is an S7Client.
 */
export function createClient<U extends string | Endpoint>(url: U, options?: ConnectOptions): ClientFor<U>;
export function createClient(url: string | Endpoint, options: ConnectOptions = {}): AnyClient {
  const endpoint = typeof url === 'string' ? parseUrl(url) : url;
  return createDriverClient(endpoint, options);
}

/**
 * Connects and resolves once the PLC answered the handshake; rejects with the
 * first attempt's error (a ConnectionError, TimeoutError or PlcError) and
 * leaves nothing open. After that the client reconnects by itself if the link drops.
 * Typed by the URL's scheme: `(await connect('s7://…')).info()` compiles without a cast.
 */
export async function connect<U extends string | Endpoint>(url: U, options?: ConnectOptions): Promise<ClientFor<U> & PlcClient>;
export async function connect(url: string | Endpoint, options: ConnectOptions = {}): Promise<AnyClient & PlcClient> {
  const client: AnyClient = createClient(url, options);
  await client.connect();
  return client;
}
