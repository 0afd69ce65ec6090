/**
 * One URL model for all protocols: `connect(url)`, the CLI and the Node-RED
 * connection node all name a PLC the same way.
 *
 *   s7://host[:102]?rack=0&slot=1&type=pg|op|basic&pdu=960&timeout=5000&maxItems=20
 *   s7://host?localTsap=1000&remoteTsap=2000            (hex; S7-200/LOGO)
 *   s7://host?control=true                               (allow stop/start of the CPU)
 *   fetchwrite://host?fetchPort=2000&writePort=2001&dbUnit=word|byte&timeout=5000
 *   fetchwrite://host?port=2000                          (one port serves both)
 *   freeport:///dev/ttyUSB0?baud=9600&parity=none&databits=8&stopbits=1&timeout=1000&retries=2&gap=10
 *   freeport://COM3?baud=9600                            (Windows)
 *   freeport+tcp://host:4001?timeout=1000                (serial device server)
 *   s7plus://host[:102]?fingerprint=<SHA-256, 64 hex>&type=hmi|es|pg&timeout=5000&maxItems=20
 *   s7plus://host?ca=FILE | insecure=true | tls=false    (S7-1200/1500 over TLS: trust by CA, the bench, plain V1)
 *
 * An s7plus:// PLC's password never goes into a URL (ConnectOptions.password).
 * Every protocol also takes `readOnly=true` and `allow=<address or area>,…`
 * (a write allow-list), and `strictSymbols=true` (reads and writes by name
 * refused in a data block whose length differs from the sources',
 * docs/symbols.md). Unknown parameters are refused, so a typo never
 * silently falls back to a default.
 */
import { DRIVERS, driverOf, type Endpoint } from './drivers';
import type { UrlScheme } from './link/driver';
import { UrlParams, urlError, type SafetyOptions } from './link/url-params';

export type { S7ConnectionType, S7Endpoint } from './s7/url';
export { S7_CPU_PRESETS, type S7CpuPreset, type S7CpuPresetParams } from './s7/presets';
export type { FetchWriteEndpoint } from './fetchwrite/url';
export { FREEPORT_BAUD_RATES, type FreeportEndpoint, type FreeportLine, type Parity } from './freeport/url';

export type { SafetyOptions } from './link/url-params';

export type { Endpoint } from './drivers';

/** Every driver's URLs, from the registry (lib/drivers.ts): a protocol registered there is parsed here. */
const DRIVER_URLS: readonly UrlScheme<Endpoint>[] = Object.values(DRIVERS).map((d) => d.urls as UrlScheme<Endpoint>);

/** The URL schemes, each with its driver's entry. */
const SCHEMES: ReadonlyMap<string, UrlScheme<Endpoint>> = new Map(
  DRIVER_URLS.flatMap((entry) => Object.keys(entry.schemes).map((scheme) => [scheme, entry] as const)),
);

function urlsOf(e: Endpoint): UrlScheme<Endpoint> {
  return driverOf(e).urls;
}

/** What a URL that leaves a parameter out gets, for every protocol. */
export const DEFAULTS: Readonly<Record<string, number>> = Object.freeze(
  DRIVER_URLS.reduce<Record<string, number>>((all, u) => ({ ...all, ...u.defaults }), {}),
);

const SAFETY_PARAMS = ['readOnly', 'allow', 'strictSymbols'];

/** Parses a PLC URL; throws PlcError INVALID_URL naming the part that is wrong. */
export function parseUrl(text: string): Endpoint {
  if (typeof text !== 'string' || text.trim() === '') throw urlError(String(text), 'the URL is empty');
  let url: URL;
  try {
    url = new URL(text.trim());
  } catch {
    throw urlError(text, whyNotAUrl(text.trim()));
  }
  if (url.username || url.password) {
    // None of these protocols has credentials; refuse them rather than drop them, and never echo them.
    throw urlError(text.replace(/\/\/[^/@]*@/, '//***@'), 'PLC URLs take no user name or password; remove the "user:password@" part');
  }
  const scheme = url.protocol.slice(0, -1).toLowerCase();
  const entry = SCHEMES.get(scheme);
  if (!entry) throw urlError(text, `unknown protocol "${scheme}:" (use ${schemeList()})`);
  const params = new UrlParams(text, url.searchParams, [...entry.schemes[scheme]!, ...SAFETY_PARAMS]);
  const safety = parseSafety(params);
  return { protocol: entry.protocol, ...entry.parse(scheme, text, url, params), ...safety } as Endpoint;
}

/** "s7:, fetchwrite:, freeport: or freeport+tcp:" */
function schemeList(): string {
  const names = [...SCHEMES.keys()].map((s) => `${s}:`);
  return names.length > 1 ? `${names.slice(0, -1).join(', ')} or ${names.at(-1)}` : names.join('');
}

function parseSafety(p: UrlParams): SafetyOptions {
  const safety: SafetyOptions = {};
  if (p.has('readOnly')) safety.readOnly = p.bool('readOnly');
  const allow = p.list('allow');
  if (allow) safety.allow = allow;
  if (p.has('strictSymbols') && p.bool('strictSymbols')) safety.strictSymbols = true;
  return safety;
}

/** Formats an endpoint back to its URL, omitting defaults. */
export function formatUrl(e: Endpoint): string {
  const q = new URLSearchParams();
  const base = urlsOf(e).format(e, q);
  if (e.readOnly) q.set('readOnly', 'true');
  if (e.allow?.length) q.set('allow', e.allow.join(','));
  if (e.strictSymbols) q.set('strictSymbols', 'true');
  const query = q.toString().replace(/%2C/g, ',');
  return query ? `${base}?${query}` : base;
}

/**
 * Identity of the physical endpoint: two URLs with the same key reach the
 * same PLC connection(s) (the Node-RED nodes share one client per key).
 */
export function endpointKey(e: Endpoint): string {
  return urlsOf(e).key(e);
}

/** A short name for messages: "s7://10.0.0.2:102". */
export function endpointName(e: Endpoint): string {
  return urlsOf(e).name(e);
}

/** True when the endpoint is on this machine (the CLI asks before writing to anything else). */
export function isLoopback(e: Endpoint): boolean {
  const host = urlsOf(e).host(e);
  if (!host) return false;
  const h = host.replace(/^\[|\]$/g, '').toLowerCase();
  return h === 'localhost' || h === '::1' || /^127\.\d+\.\d+\.\d+$/.test(h);
}

/**
 * Why the URL parser refused `text`: it refuses a port above 65535 or one
 * that is not a number like any other malformed URL, so the port is looked
 * at here to say which part is wrong.
 */
function whyNotAUrl(text: string): string {
  const authority = /^([a-z][a-z0-9+.-]*):\/\/(\[[^\]]*\]|[^/?#:@]*)(?::([^/?#]*))?/i.exec(text);
  const port = authority?.[3];
  if (port !== undefined && port !== '') {
    const hint = SCHEMES.get(authority![1]!.toLowerCase())?.portHint;
    if (hint) return hint;
    if (!/^\d+$/.test(port)) return `port "${port}" is not a number`;
    return `port ${port} is out of range (1–65535)`;
  }
  return 'not a URL (expected e.g. s7://192.168.0.2?rack=0&slot=1)';
}
