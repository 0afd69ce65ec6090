/**
 * s7plus:// URLs: S7CommPlus to an S7-1200/1500 on ISO-on-TCP port 102, over
 * TLS unless the URL says `tls=false` (lib/url.ts holds the registry).
 *
 *   s7plus://host[:102]?fingerprint=<SHA-256 of the PLC's DER certificate>
 *   s7plus://host?ca=/path/to/tia-project-ca.pem
 *   s7plus://host?insecure=true                  (the bench: any certificate, a warning on every connect)
 *   s7plus://host?tls=false                      (plain S7CommPlus V1, only when asked; never a fallback)
 *   s7plus://host?timeout=5000&maxItems=20&type=hmi|es|pg
 *
 * The password never goes into a URL: a `password=` parameter is refused,
 * without echoing it, with the ways that keep it secret (connect(url,
 * { password }), PLCWIRE_PASSWORD, --password-file).
 */
import { DEFAULT_TIMEOUT } from '../client/options';
import { PlcError } from '../errors';
import type { UrlScheme } from '../link/driver';
import { hostPart, portOf, requireHost, urlError, type SafetyOptions, type UrlParams } from '../link/url-params';
import { normalizeFingerprint } from './transport/fingerprint';

/** The called TSAP names of the S7CommPlus roles (s7commplus (MIT), protocol.py, ConnectionType). */
export type S7PlusRole = 'hmi' | 'es' | 'pg';

export interface S7PlusEndpoint extends SafetyOptions {
  protocol: 's7plus';
  host: string;
  port: number;
  /** False only when the URL says `tls=false`: plain S7CommPlus V1. */
  tls: boolean;
  /** The PLC certificate's SHA-256 over its DER bytes, 64 upper-case hex digits, no colons (normalizeFingerprint). */
  fingerprint?: string;
  /** A PEM file of the CA (the TIA project's) that signed the PLC's certificate. */
  ca?: string;
  /** Any certificate accepted (the bench): warned about on every connect. */
  insecure?: boolean;
  /** Which role the connection presents (the called TSAP); hmi unless the URL says otherwise. */
  role: S7PlusRole;
  timeout: number;
  /**
   * At most this many items per request, in place of the PLC's own
   * SystemLimits (an override); absent: what the PLC reports, read once per
   * session (DEFAULTS.s7plusMaxItems when it reports none). A PLC that
   * refuses a request as too large (or resets on it) teaches the client a
   * lower limit.
   */
  maxItems?: number;
}

/**
 * Items per request unless the URL says more: public reports say a CPU 1215C
 * refuses more than 50 items in one GetMultiVariables (issue #25 of this
 * project cites them); 20 keeps the requests of a large poll far below the
 * frame sizes PLCSIM is reported to drop.
 */
export const S7PLUS_DEFAULT_MAX_ITEMS = 20;
const S7PLUS_MAX_ITEMS = 1000;

const DEFAULTS = Object.freeze({
  s7plusPort: 102,
  s7plusMaxItems: S7PLUS_DEFAULT_MAX_ITEMS,
});

const PARAMS = ['fingerprint', 'ca', 'insecure', 'tls', 'timeout', 'maxItems', 'type', 'password'];

/** Where the password goes instead of the URL (the refusal says it, and the docs). */
const PASSWORD_HINT = 'give it as connect(url, { password }), in PLCWIRE_PASSWORD or with --password-file';

/** True for an endpoint of an s7plus:// URL (the PLC certificate of the connection dialog is S7CommPlus's alone). */
export function isS7PlusEndpoint(e: { readonly protocol: string }): e is S7PlusEndpoint {
  return e.protocol === 's7plus';
}

export const S7PLUS_URLS: UrlScheme<S7PlusEndpoint> = Object.freeze({
  protocol: 's7plus',
  schemes: { s7plus: PARAMS },
  defaults: DEFAULTS,

  parse(_scheme: string, text: string, url: URL, p: UrlParams): Omit<S7PlusEndpoint, 'protocol' | 'readOnly' | 'allow'> {
    if (p.has('password')) {
      // Never echo the URL (nor the password in it, however it is spelt or escaped): it lands in flows, logs and shell histories.
      const where = `s7plus://${hostPart(url.hostname.replace(/^\[|\]$/g, ''))}${url.port ? `:${url.port}` : ''}`;
      throw new PlcError('INVALID_URL', `invalid PLC URL "${where}?…": a PLC password never goes into a URL; ${PASSWORD_HINT}`);
    }
    const endpoint: Omit<S7PlusEndpoint, 'protocol'> = {
      host: requireHost(text, url),
      port: portOf(text, url, DEFAULTS.s7plusPort),
      tls: p.has('tls') ? p.bool('tls') : true,
      role: p.choice('type', ['hmi', 'es', 'pg'] as const, 'hmi'),
      timeout: p.int('timeout', DEFAULT_TIMEOUT, 1, 3_600_000),
    };
    if (p.has('maxItems')) endpoint.maxItems = p.int('maxItems', DEFAULTS.s7plusMaxItems, 1, S7PLUS_MAX_ITEMS);
    const pin = url.searchParams.get('fingerprint');
    if (pin !== null) {
      const fingerprint = normalizeFingerprint(pin);
      if (!fingerprint) {
        throw urlError(text, `fingerprint=${pin} is not a SHA-256 fingerprint (64 hex digits; colons and case do not matter)`);
      }
      endpoint.fingerprint = fingerprint;
    }
    const ca = url.searchParams.get('ca');
    if (ca !== null) {
      if (ca.trim() === '') throw urlError(text, 'ca= names no file (the PEM file of the CA that signed the PLC certificate)');
      endpoint.ca = ca;
    }
    if (p.has('insecure') && p.bool('insecure')) endpoint.insecure = true;
    const trust = [endpoint.fingerprint && 'fingerprint', endpoint.ca && 'ca', endpoint.insecure && 'insecure'].filter(Boolean);
    if (!endpoint.tls && trust.length > 0) {
      throw urlError(text, `tls=false has no certificate to check; drop ${trust.join(' and ')}= or tls=false`);
    }
    if (endpoint.insecure && trust.length > 1) {
      throw urlError(text, 'insecure=true accepts any certificate: it goes with neither fingerprint= nor ca=');
    }
    return endpoint;
  },

  format(e: S7PlusEndpoint, q: URLSearchParams): string {
    if (e.fingerprint) q.set('fingerprint', e.fingerprint);
    if (e.ca) q.set('ca', e.ca);
    if (e.insecure) q.set('insecure', 'true');
    if (!e.tls) q.set('tls', 'false');
    if (e.role !== 'hmi') q.set('type', e.role);
    if (e.timeout !== DEFAULT_TIMEOUT) q.set('timeout', String(e.timeout));
    if (e.maxItems !== undefined) q.set('maxItems', String(e.maxItems));
    return `s7plus://${hostPart(e.host)}${e.port === DEFAULTS.s7plusPort ? '' : `:${e.port}`}`;
  },

  key: (e: S7PlusEndpoint) => `s7plus://${e.host.toLowerCase()}:${e.port}/${e.role}`,
  name: (e: S7PlusEndpoint) => `s7plus://${hostPart(e.host)}:${e.port}`,
  host: (e: S7PlusEndpoint) => e.host,
});
