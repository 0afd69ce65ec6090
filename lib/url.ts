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
 *
 * Every protocol also takes `readOnly=true` and `allow=<address or area>,…`
 * (a write allow-list). Unknown parameters are refused, so a typo never
 * silently falls back to a default.
 */
import { PlcError } from './errors';
import { DEFAULT_MAX_ITEMS, MAX_ITEMS, S7_PORT } from './s7/constants';

export type S7ConnectionType = 'pg' | 'op' | 'basic';
export type Parity = 'none' | 'even' | 'odd';

export interface SafetyOptions {
  /** Refuse every write before anything is sent. */
  readOnly?: boolean;
  /** When set, only writes to these addresses or areas (e.g. "DB10", "M", "DB1.DBW2") are allowed. */
  allow?: string[];
}

export interface S7Endpoint extends SafetyOptions {
  protocol: 's7';
  host: string;
  port: number;
  rack: number;
  slot: number;
  /** Explicit TSAPs (S7-200, LOGO, or a CP's own); override rack/slot. */
  localTsap?: number;
  remoteTsap?: number;
  connectionType: S7ConnectionType;
  /** Requested PDU size; the PLC's answer is what is used. */
  pduSize: number;
  timeout: number;
  /**
   * At most this many items per Read/Write Var job (the PDU size may allow
   * fewer); absent: DEFAULTS.maxItems (20, what snap7's server and VIPA CPUs
   * serve). A peer that answers fewer items than asked teaches the client a
   * lower limit (the `itemLimit` event).
   */
  maxItems?: number;
  /** `control=true`: allow stop(), hotStart() and coldStart() of the CPU (refused otherwise, and always with readOnly). */
  control?: boolean;
}

export interface FetchWriteEndpoint extends SafetyOptions {
  protocol: 'fetchwrite';
  host: string;
  fetchPort: number;
  writePort: number;
  /** How the device counts DB start addresses: words (Siemens CPs) or bytes (VIPA, some gateways). */
  dbUnit: 'word' | 'byte';
  timeout: number;
}

export type FreeportTransport =
  | { kind: 'serial'; path: string; baudRate: number; parity: Parity; dataBits: 7 | 8; stopBits: 1 | 2 }
  | { kind: 'tcp'; host: string; port: number };

export interface FreeportEndpoint extends SafetyOptions {
  protocol: 'freeport';
  transport: FreeportTransport;
  timeout: number;
  retries: number;
  /** Silence on the bus between a reply and the next request, ms. */
  interFrameGapMs: number;
}

export type Endpoint = S7Endpoint | FetchWriteEndpoint | FreeportEndpoint;

export const DEFAULTS = Object.freeze({
  s7Port: S7_PORT,
  rack: 0,
  slot: 1,
  pduSize: 960,
  timeout: 5000,
  /** Items per S7 job unless the URL says more (DEFAULT_MAX_ITEMS in lib/s7/constants.ts says why). */
  maxItems: DEFAULT_MAX_ITEMS,
  fetchPort: 2000,
  writePort: 2001,
  baudRate: 9600,
  freeportTimeout: 1000,
  retries: 2,
  interFrameGapMs: 10,
});

export type S7CpuPreset = 's7-1500' | 's7-1200' | 's7-400' | 's7-300' | 'logo' | 's7-200';

/** What a CPU preset puts into an s7:// URL: where the CPU answers, and how many items per job it serves. */
export interface S7CpuPresetParams {
  rack?: number;
  slot?: number;
  localTsap?: number;
  remoteTsap?: number;
  /** Absent: DEFAULTS.maxItems (20). 255: as many as the PDU allows. */
  maxItems?: number;
}

/**
 * URL parameters per CPU family (the Node-RED connection dialog's presets).
 * Items per job: Siemens S7-1200, S7-1500 and S7-400 CPUs limit a job by
 * the PDU size only (more than 20 items in one job work on an S7-1200 and an
 * S7-1500, frangoteam/FUXA#694; 36 written to an S7-1500 in one job,
 * S7NetPlus/s7netplus#380; S7-400 as well, S7NetPlus/s7netplus#157), so
 * their presets allow 255 and the PDU decides (19 at PDU 240, 39 at 480, 79
 * at 960). The S7-300 preset keeps the default 20: S7-300 compatible CPUs
 * (VIPA, frangoteam/FUXA#694) serve 20, and a Siemens S7-300 at PDU 240
 * carries 19 anyway. LOGO! and S7-200 negotiate PDU 240 (19 items).
 * TSAPs: an S7-200's CP 243-1 is called at 10.xx, its connection number in
 * the low byte (CP 243-1 manual, section 4.2.3; S7NetPlus TsapPair.cs uses
 * 10.00 / 10.01); a LOGO! at the pair set in LOGO!Soft Comfort, 01.00 / 02.00
 * by default (the simulator's s7-200 and logo profiles accept these).
 */
export const S7_CPU_PRESETS: Readonly<Record<S7CpuPreset, Readonly<S7CpuPresetParams>>> = Object.freeze({
  's7-1500': Object.freeze({ rack: 0, slot: 1, maxItems: MAX_ITEMS }),
  's7-1200': Object.freeze({ rack: 0, slot: 1, maxItems: MAX_ITEMS }),
  's7-400': Object.freeze({ rack: 0, slot: 3, maxItems: MAX_ITEMS }),
  's7-300': Object.freeze({ rack: 0, slot: 2 }),
  logo: Object.freeze({ localTsap: 0x0100, remoteTsap: 0x0200 }),
  's7-200': Object.freeze({ localTsap: 0x1000, remoteTsap: 0x1001 }),
});

/** Baud rates an S7-200 port can run at (SMB30 / SMB130). */
export const FREEPORT_BAUD_RATES: readonly number[] = [1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200];

const SAFETY_PARAMS = ['readOnly', 'allow'];
const FETCHWRITE_PORTS = 'give the ports as ?fetchPort=…&writePort=… (or ?port=… when one port serves both)';
const KNOWN_PARAMS: Record<string, readonly string[]> = {
  s7: ['rack', 'slot', 'localTsap', 'remoteTsap', 'type', 'pdu', 'timeout', 'maxItems', 'control', ...SAFETY_PARAMS],
  fetchwrite: ['fetchPort', 'writePort', 'port', 'dbUnit', 'timeout', ...SAFETY_PARAMS],
  freeport: ['baud', 'parity', 'databits', 'stopbits', 'timeout', 'retries', 'gap', ...SAFETY_PARAMS],
  'freeport+tcp': ['timeout', 'retries', 'gap', ...SAFETY_PARAMS],
};

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
  const known = KNOWN_PARAMS[scheme];
  if (!known) throw urlError(text, `unknown protocol "${scheme}:" (use s7:, fetchwrite:, freeport: or freeport+tcp:)`);
  const params = new Params(text, url.searchParams, known);
  const safety = parseSafety(params);
  switch (scheme) {
    case 's7':
      return { protocol: 's7', ...parseS7(text, url, params), ...safety };
    case 'fetchwrite':
      return { protocol: 'fetchwrite', ...parseFetchWrite(text, url, params), ...safety };
    default:
      return { protocol: 'freeport', ...parseFreeport(text, url, params, scheme === 'freeport+tcp'), ...safety };
  }
}

function parseS7(text: string, url: URL, p: Params): Omit<S7Endpoint, 'protocol'> {
  const endpoint: Omit<S7Endpoint, 'protocol'> = {
    host: requireHost(text, url),
    port: portOf(text, url, DEFAULTS.s7Port),
    rack: p.int('rack', DEFAULTS.rack, 0, 7),
    slot: p.int('slot', DEFAULTS.slot, 0, 31),
    connectionType: p.choice('type', ['pg', 'op', 'basic'] as const, 'pg'),
    pduSize: p.int('pdu', DEFAULTS.pduSize, 240, 65535),
    timeout: p.int('timeout', DEFAULTS.timeout, 1, 3_600_000),
  };
  if (p.has('maxItems')) endpoint.maxItems = p.int('maxItems', DEFAULTS.maxItems, 1, MAX_ITEMS);
  const local = p.hex('localTsap', 0, 0xffff);
  const remote = p.hex('remoteTsap', 0, 0xffff);
  if ((local === undefined) !== (remote === undefined)) {
    throw urlError(text, 'localTsap and remoteTsap go together (e.g. localTsap=1000&remoteTsap=2000)');
  }
  if (local !== undefined && remote !== undefined) {
    endpoint.localTsap = local;
    endpoint.remoteTsap = remote;
  }
  if (p.has('control') && p.bool('control')) endpoint.control = true;
  return endpoint;
}

function parseFetchWrite(text: string, url: URL, p: Params): Omit<FetchWriteEndpoint, 'protocol'> {
  const host = requireHost(text, url);
  if (url.port) throw urlError(text, FETCHWRITE_PORTS);
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
}

function parseFreeport(text: string, url: URL, p: Params, overTcp: boolean): Omit<FreeportEndpoint, 'protocol'> {
  let transport: FreeportTransport;
  if (overTcp) {
    if (!url.port) throw urlError(text, 'a serial device server needs a port (freeport+tcp://host:4001)');
    transport = { kind: 'tcp', host: requireHost(text, url), port: portOf(text, url, 0) };
  } else {
    const path = decodeURIComponent(url.hostname && !url.pathname ? url.hostname : url.pathname);
    if (!path) throw urlError(text, 'no serial port (freeport:///dev/ttyUSB0 or freeport://COM3)');
    const baudRate = p.int('baud', DEFAULTS.baudRate, 1, 4_000_000);
    if (!FREEPORT_BAUD_RATES.includes(baudRate)) {
      throw urlError(text, `baud=${baudRate} is not a rate an S7-200 port runs at (${FREEPORT_BAUD_RATES.join(', ')})`);
    }
    transport = {
      kind: 'serial',
      path,
      baudRate,
      parity: p.choice('parity', ['none', 'even', 'odd'] as const, 'none'),
      dataBits: p.int('databits', 8, 7, 8) as 7 | 8,
      stopBits: p.int('stopbits', 1, 1, 2) as 1 | 2,
    };
  }
  return {
    transport,
    timeout: p.int('timeout', DEFAULTS.freeportTimeout, 1, 3_600_000),
    retries: p.int('retries', DEFAULTS.retries, 0, 100),
    interFrameGapMs: p.int('gap', DEFAULTS.interFrameGapMs, 0, 10_000),
  };
}

function parseSafety(p: Params): SafetyOptions {
  const safety: SafetyOptions = {};
  if (p.has('readOnly')) safety.readOnly = p.bool('readOnly');
  const allow = p.list('allow');
  if (allow) safety.allow = allow;
  return safety;
}

/** Formats an endpoint back to its URL, omitting defaults. */
export function formatUrl(e: Endpoint): string {
  const q = new URLSearchParams();
  let base: string;
  if (e.protocol === 's7') {
    base = `s7://${hostPart(e.host)}${e.port === DEFAULTS.s7Port ? '' : `:${e.port}`}`;
    if (e.localTsap !== undefined && e.remoteTsap !== undefined) {
      q.set('localTsap', hex4(e.localTsap));
      q.set('remoteTsap', hex4(e.remoteTsap));
    } else {
      q.set('rack', String(e.rack));
      q.set('slot', String(e.slot));
    }
    if (e.connectionType !== 'pg') q.set('type', e.connectionType);
    if (e.pduSize !== DEFAULTS.pduSize) q.set('pdu', String(e.pduSize));
    if (e.timeout !== DEFAULTS.timeout) q.set('timeout', String(e.timeout));
    if (e.maxItems !== undefined) q.set('maxItems', String(e.maxItems));
    if (e.control) q.set('control', 'true');
  } else if (e.protocol === 'fetchwrite') {
    base = `fetchwrite://${hostPart(e.host)}`;
    if (e.fetchPort === e.writePort) q.set('port', String(e.fetchPort));
    else {
      q.set('fetchPort', String(e.fetchPort));
      q.set('writePort', String(e.writePort));
    }
    if (e.dbUnit !== 'word') q.set('dbUnit', e.dbUnit);
    if (e.timeout !== DEFAULTS.timeout) q.set('timeout', String(e.timeout));
  } else {
    const t = e.transport;
    if (t.kind === 'tcp') base = `freeport+tcp://${hostPart(t.host)}:${t.port}`;
    else {
      base = t.path.startsWith('/') ? `freeport://${encodeURI(t.path)}` : `freeport://${encodeURIComponent(t.path)}`;
      q.set('baud', String(t.baudRate));
      if (t.parity !== 'none') q.set('parity', t.parity);
      if (t.dataBits !== 8) q.set('databits', String(t.dataBits));
      if (t.stopBits !== 1) q.set('stopbits', String(t.stopBits));
    }
    if (e.timeout !== DEFAULTS.freeportTimeout) q.set('timeout', String(e.timeout));
    if (e.retries !== DEFAULTS.retries) q.set('retries', String(e.retries));
    if (e.interFrameGapMs !== DEFAULTS.interFrameGapMs) q.set('gap', String(e.interFrameGapMs));
  }
  if (e.readOnly) q.set('readOnly', 'true');
  if (e.allow?.length) q.set('allow', e.allow.join(','));
  const query = q.toString().replace(/%2C/g, ',');
  return query ? `${base}?${query}` : base;
}

/**
 * Identity of the physical endpoint: two URLs with the same key reach the
 * same PLC connection(s) (the Node-RED nodes share one client per key).
 */
export function endpointKey(e: Endpoint): string {
  switch (e.protocol) {
    case 's7':
      return `s7://${e.host.toLowerCase()}:${e.port}/${e.localTsap ?? `${e.connectionType}/${e.rack}/${e.slot}`}/${e.remoteTsap ?? ''}`;
    case 'fetchwrite':
      return `fetchwrite://${e.host.toLowerCase()}:${e.fetchPort}/${e.writePort}`;
    case 'freeport':
      return e.transport.kind === 'tcp'
        ? `freeport+tcp://${e.transport.host.toLowerCase()}:${e.transport.port}`
        : `freeport://${e.transport.path}`;
  }
}

/** A short name for messages: "s7://10.0.0.2:102". */
export function endpointName(e: Endpoint): string {
  switch (e.protocol) {
    case 's7':
      return `s7://${hostPart(e.host)}:${e.port}`;
    case 'fetchwrite':
      return `fetchwrite://${hostPart(e.host)}:${e.fetchPort}${e.writePort === e.fetchPort ? '' : `+${e.writePort}`}`;
    case 'freeport':
      return e.transport.kind === 'tcp'
        ? `freeport+tcp://${hostPart(e.transport.host)}:${e.transport.port}`
        : `freeport://${e.transport.path}`;
  }
}

/** True when the endpoint is on this machine (the CLI asks before writing to anything else). */
export function isLoopback(e: Endpoint): boolean {
  const host = e.protocol === 'freeport' ? (e.transport.kind === 'tcp' ? e.transport.host : '') : e.host;
  if (!host) return false;
  const h = host.replace(/^\[|\]$/g, '').toLowerCase();
  return h === 'localhost' || h === '::1' || /^127\.\d+\.\d+\.\d+$/.test(h);
}

class Params {
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
    return all.flatMap((v) => v.split(',')).map((s) => s.trim()).filter(Boolean);
  }
}

function requireHost(text: string, url: URL): string {
  const host = url.hostname.replace(/^\[|\]$/g, '');
  if (!host) throw urlError(text, 'no host (e.g. s7://192.168.0.2)');
  return host;
}

function portOf(text: string, url: URL, fallback: number): number {
  if (!url.port) return fallback;
  const n = Number(url.port);
  if (!(n >= 1 && n <= 65535)) throw urlError(text, `port ${url.port} is out of range (1–65535)`);
  return n;
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
    if (authority![1]!.toLowerCase() === 'fetchwrite') return FETCHWRITE_PORTS;
    if (!/^\d+$/.test(port)) return `port "${port}" is not a number`;
    return `port ${port} is out of range (1–65535)`;
  }
  return 'not a URL (expected e.g. s7://192.168.0.2?rack=0&slot=1)';
}

function hostPart(host: string): string {
  return host.includes(':') ? `[${host}]` : host;
}

function hex4(n: number): string {
  return n.toString(16).toUpperCase().padStart(4, '0');
}

function urlError(url: string, problem: string): PlcError {
  return new PlcError('INVALID_URL', `invalid PLC URL "${url}": ${problem}`);
}
