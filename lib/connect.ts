/**
 * `connect(url)`: one way to reach any PLC. The URL names the protocol
 * (see lib/url.ts); the same URLs serve the CLI and the Node-RED nodes.
 */
import { createDriverClient, type AnyClient, type ConnectOptions } from './drivers';
import type { PlcClient } from './types';
import { parseUrl, type Endpoint } from './url';

export type { AnyClient, ConnectOptions } from './drivers';

/**
 * Creates the client for a URL (or parsed endpoint) without connecting: call `connect()` or `start()` on it.
 * The protocol's entry in lib/drivers.ts makes it; `symbols` given to a protocol without them is refused (NOT_SUPPORTED).
 */
export function createClient(url: string | Endpoint, options: ConnectOptions = {}): AnyClient {
  const endpoint = typeof url === 'string' ? parseUrl(url) : url;
  return createDriverClient(endpoint, options);
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
