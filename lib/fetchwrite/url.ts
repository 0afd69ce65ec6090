/**
 * fetchwrite:// URLs: host, the two ports (or one for both) as parameters,
 * the unit DB addresses count in, timeout (lib/url.ts).
 */
import { DEFAULT_TIMEOUT } from '../client/options';
import type { UrlScheme } from '../link/driver';
import { hostPart, requireHost, urlError, type UrlParams } from '../link/url-params';
import type { SafetyOptions } from '../link/url-params';

export interface FetchWriteEndpoint extends SafetyOptions {
  protocol: 'fetchwrite';
  host: string;
  fetchPort: number;
  writePort: number;
  /** How the device counts DB start addresses: words (Siemens CPs) or bytes (VIPA, some gateways). */
  dbUnit: 'word' | 'byte';
  timeout: number;
}

const DEFAULTS = Object.freeze({ fetchPort: 2000, writePort: 2001, timeout: DEFAULT_TIMEOUT });
const PORTS = 'give the ports as ?fetchPort=…&writePort=… (or ?port=… when one port serves both)';

export const FETCHWRITE_URLS: UrlScheme<FetchWriteEndpoint> = Object.freeze({
  protocol: 'fetchwrite',
  schemes: { fetchwrite: ['fetchPort', 'writePort', 'port', 'dbUnit', 'timeout'] },
  defaults: DEFAULTS,
  portHint: PORTS,

  parse(_scheme: string, text: string, url: URL, p: UrlParams): Omit<FetchWriteEndpoint, 'protocol' | 'readOnly' | 'allow'> {
    const host = requireHost(text, url);
    if (url.port) throw urlError(text, PORTS);
    const single = p.int('port', 0, 1, 65535);
    if (single && (p.has('fetchPort') || p.has('writePort'))) {
      throw urlError(text, 'use either port, or fetchPort and writePort');
    }
    return {
      host,
      fetchPort: single || p.int('fetchPort', DEFAULTS.fetchPort, 1, 65535),
      writePort: single || p.int('writePort', DEFAULTS.writePort, 1, 65535),
      dbUnit: p.choice('dbUnit', ['word', 'byte'] as const, 'word'),
      timeout: p.int('timeout', DEFAULTS.timeout, 1, 3_600_000),
    };
  },

  format(e: FetchWriteEndpoint, q: URLSearchParams): string {
    if (e.fetchPort === e.writePort) q.set('port', String(e.fetchPort));
    else {
      q.set('fetchPort', String(e.fetchPort));
      q.set('writePort', String(e.writePort));
    }
    if (e.dbUnit !== 'word') q.set('dbUnit', e.dbUnit);
    if (e.timeout !== DEFAULTS.timeout) q.set('timeout', String(e.timeout));
    return `fetchwrite://${hostPart(e.host)}`;
  },

  key: (e: FetchWriteEndpoint) => `fetchwrite://${e.host.toLowerCase()}:${e.fetchPort}/${e.writePort}`,
  name: (e: FetchWriteEndpoint) => `fetchwrite://${hostPart(e.host)}:${e.fetchPort}${e.writePort === e.fetchPort ? '' : `+${e.writePort}`}`,
  host: (e: FetchWriteEndpoint) => e.host,
});
