/**
 * The pieces every driver's URL scheme parses with (lib/url.ts holds the
 * registry): query parameters checked against the scheme's list, hosts,
 * ports, and the INVALID_URL error.
 */
import { PlcError } from '../errors';

/** A URL's query parameters, checked against the names a scheme takes (case-insensitively; kept in the scheme's spelling). */
export class UrlParams {
  constructor(
    private readonly url: string,
    private readonly search: URLSearchParams,
    known: readonly string[],
  ) {
    const lower = new Map(known.map((k) => [k.toLowerCase(), k]));
    for (const key of search.keys()) {
      const canonical = lower.get(key.toLowerCase());
      if (!canonical) throw urlError(url, `unknown parameter "${key}" (known: ${known.join(', ')})`);
      if (canonical !== key) {
        const value = search.get(key)!;
        search.delete(key);
        search.set(canonical, value);
      }
    }
  }

  has(name: string): boolean {
    return this.search.has(name);
  }

  int(name: string, fallback: number, min: number, max: number): number {
    const raw = this.search.get(name);
    if (raw === null || raw === '') return fallback;
    if (!/^\d+$/.test(raw)) throw urlError(this.url, `${name}=${raw} is not a whole number`);
    const n = Number(raw);
    if (n < min || n > max) throw urlError(this.url, `${name}=${raw} is out of range (${min}–${max})`);
    return n;
  }

  hex(name: string, min: number, max: number): number | undefined {
    const raw = this.search.get(name);
    if (raw === null || raw === '') return undefined;
    const digits = raw.replace(/^0x/i, '');
    if (!/^[0-9a-f]{1,4}$/i.test(digits)) throw urlError(this.url, `${name}=${raw} is not a hex TSAP (e.g. 0100, 4D57)`);
    const n = parseInt(digits, 16);
    if (n < min || n > max) throw urlError(this.url, `${name}=${raw} is out of range`);
    return n;
  }

  choice<T extends string>(name: string, options: readonly T[], fallback: T): T {
    const raw = this.search.get(name);
    if (raw === null || raw === '') return fallback;
    const v = raw.toLowerCase() as T;
    if (!options.includes(v)) throw urlError(this.url, `${name}=${raw} must be one of ${options.join(', ')}`);
    return v;
  }

  bool(name: string): boolean {
    const raw = (this.search.get(name) ?? '').toLowerCase();
    if (raw === '' || raw === 'true' || raw === '1' || raw === 'yes') return true;
    if (raw === 'false' || raw === '0' || raw === 'no') return false;
    throw urlError(this.url, `${name}=${raw} must be true or false`);
  }

  list(name: string): string[] | undefined {
    const all = this.search.getAll(name);
    if (all.length === 0) return undefined;
    return all
      .flatMap((v) => v.split(','))
      .map((s) => s.trim())
      .filter(Boolean);
  }
}

export function requireHost(text: string, url: URL): string {
  const host = url.hostname.replace(/^\[|\]$/g, '');
  if (!host) throw urlError(text, 'no host (e.g. s7://192.168.0.2)');
  return host;
}

export function portOf(text: string, url: URL, fallback: number): number {
  if (!url.port) return fallback;
  const n = Number(url.port);
  if (!(n >= 1 && n <= 65535)) throw urlError(text, `port ${url.port} is out of range (1–65535)`);
  return n;
}

/** A host as it stands in a URL (an IPv6 address in brackets). */
export function hostPart(host: string): string {
  return host.includes(':') ? `[${host}]` : host;
}

export function urlError(url: string, problem: string): PlcError {
  return new PlcError('INVALID_URL', `invalid PLC URL "${redactUrl(url)}": ${problem}`);
}

/**
 * A URL as an error may show it: the value of any parameter that looks like a
 * secret (password, passwd, pwd, secret, token) and a "user:password@" part
 * replaced by ***, so a password typed into a URL never reaches a log.
 */
function redactUrl(url: string): string {
  return url.replace(/\/\/[^/@?#]*@/, '//***@').replace(/([?&;](?:[^=&#]*(?:pass|pwd|secret|token)[^=&#]*)=)[^&#]*/gi, '$1***');
}

/** What every endpoint carries, whatever its protocol (`readOnly`, `allow`, `strictSymbols`). */
export interface SafetyOptions {
  /** Refuse every write before anything is sent. */
  readOnly?: boolean;
  /** When set, only writes to these addresses or areas (e.g. "DB10", "M", "DB1.DBW2") are allowed. */
  allow?: string[];
  /** Reads and writes by name refused (LAYOUT_MISMATCH) in a data block whose length in the PLC differs from the sources'. */
  strictSymbols?: boolean;
}
