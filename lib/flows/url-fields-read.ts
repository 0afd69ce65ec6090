/**
 * A URL (or a CPU preset) read into the connection dialog's fields: a valid
 * URL's endpoint (fieldsOf), an invalid one as it stands (looseFieldsOf), a
 * preset's fields, and what each empty field means (placeholdersOf). The
 * other direction is lib/flows/url-fields.ts.
 */
import type { Protocol } from '../types';
import { DEFAULTS, parseUrl, S7_CPU_PRESETS, type Endpoint } from '../url';
import { hex4 } from '../values/text';
import { SAFETY, SCHEMES, type UrlFields } from './url-field-table';

type EndpointOf<P extends Protocol> = Extract<Endpoint, { protocol: P }>;
const maxItemsField = (n: number | undefined) => (n === undefined ? '' : String(n));

/**
 * Each protocol's fields of its endpoint, one entry per protocol of the
 * registry (a protocol without one does not compile): the dialog's own
 * knowledge of which field shows which part of a URL.
 */
const FIELDS: { readonly [P in Protocol]: (e: EndpointOf<P>) => UrlFields } = {
  s7: (e) => ({
    protocol: 's7',
    host: e.host,
    port: String(e.port),
    addressing: e.localTsap === undefined ? 'rack' : 'tsap',
    rack: String(e.rack),
    slot: String(e.slot),
    ...(e.localTsap === undefined || e.remoteTsap === undefined
      ? {}
      : { localTsap: hex4(e.localTsap).toUpperCase(), remoteTsap: hex4(e.remoteTsap).toUpperCase() }),
    connectionType: e.connectionType,
    pduSize: String(e.pduSize),
    maxItems: maxItemsField(e.maxItems),
    control: !!e.control,
  }),
  s7plus: (e) => ({
    protocol: 's7plus',
    host: e.host,
    port: String(e.port),
    fingerprint: e.fingerprint ?? '',
    ca: e.ca ?? '',
    insecure: !!e.insecure,
    tls: e.tls,
    maxItems: maxItemsField(e.maxItems),
  }),
  fetchwrite: (e) => ({
    protocol: 'fetchwrite',
    host: e.host,
    fetchPort: String(e.fetchPort),
    writePort: String(e.writePort),
    dbUnit: e.dbUnit,
  }),
  freeport: (e) => {
    const line = { retries: String(e.retries), gap: String(e.interFrameGapMs) };
    const t = e.transport;
    if (t.kind === 'tcp') return { protocol: 'freeport+tcp', ...line, tcpHost: t.host, tcpPort: String(t.port) };
    return {
      protocol: 'freeport',
      ...line,
      serialPath: t.path,
      baudRate: String(t.baudRate),
      parity: t.parity,
      dataBits: String(t.dataBits),
      stopBits: String(t.stopBits),
    };
  },
};

/** The dialog's fields of an endpoint (the ones of its protocol, and the ones every protocol has). */
export function fieldsOf(e: Endpoint): UrlFields {
  const common = { timeout: String(e.timeout), readOnly: !!e.readOnly, allow: (e.allow ?? []).join(',') };
  const own = (FIELDS[e.protocol] as (e: Endpoint) => UrlFields)(e);
  return { protocol: own.protocol!, ...common, ...own };
}

/** A URL's flag as the parser reads it: `true`, `1`, `yes` or nothing. */
const flagOn = (value: string) => ['', 'true', '1', 'yes'].includes(value.toLowerCase());

/**
 * The fields of a URL as it stands, no value checked: a URL the parser
 * refuses still opens the dialog with its fields, the one to fix marked.
 * Undefined when it is no URL of a scheme the dialog offers.
 */
export function looseFieldsOf(text: string): UrlFields | undefined {
  let url: URL;
  try {
    url = new URL(text.trim());
  } catch {
    return undefined;
  }
  const scheme = url.protocol.slice(0, -1).toLowerCase();
  const entry = SCHEMES[scheme];
  if (!entry) return undefined;
  const { base, parts } = entry;
  const fields: UrlFields = { protocol: scheme };
  if (base.host) fields[base.host] = url.hostname.replace(/^\[(.*)\]$/, '$1');
  if (base.port) fields[base.port] = url.port;
  if (base.path) {
    try {
      fields[base.path] = decodeURIComponent(`${url.hostname}${url.pathname}`);
    } catch {
      fields[base.path] = `${url.hostname}${url.pathname}`;
    }
  }
  const params = new Map([...url.searchParams].map(([name, value]) => [name.toLowerCase(), value]));
  for (const part of [...parts, ...SAFETY]) {
    // A field the URL leaves out is empty (a tick as the parser takes its absence): none keeps a value from before.
    const value = params.get(part.param.toLowerCase());
    if (value !== undefined) fields[part.field] = part.tick === undefined ? value : flagOn(value);
    else fields[part.field] = part.tick === undefined ? '' : !part.tick;
  }
  if (parts.some((p) => p.field === 'localTsap')) fields.addressing = params.has('localtsap') || params.has('remotetsap') ? 'tsap' : 'rack';
  // One port for both (fetchwrite://cp?port=2000).
  const both = parts.some((p) => p.param === 'fetchPort') ? params.get('port') : undefined;
  if (both !== undefined) fields.fetchPort = fields.writePort = both;
  return fields;
}

/**
 * Per scheme the dialog offers: the URL that names a place and nothing else,
 * whose parse shows what every other field means when empty; whether its
 * port is part of the place (not a default to show); items per job as the
 * driver assumes them when the URL says nothing.
 */
const BARE: Readonly<Record<string, { url: string; portIsPlace?: boolean; maxItems?: number }>> = {
  s7: { url: 's7://localhost', maxItems: DEFAULTS.maxItems },
  s7plus: { url: 's7plus://localhost', maxItems: DEFAULTS.s7plusMaxItems },
  fetchwrite: { url: 'fetchwrite://localhost' },
  freeport: { url: 'freeport://COM1' },
  'freeport+tcp': { url: 'freeport+tcp://localhost:1', portIsPlace: true },
};

/**
 * What each text field of a protocol means when left empty (its placeholder):
 * the library's defaults, read from a URL that names a place and nothing
 * else; items per job as the driver assumes them. Empty for a protocol the
 * dialog does not offer.
 */
export function placeholdersOf(protocol: string): UrlFields {
  const bare = Object.hasOwn(BARE, protocol) ? BARE[protocol] : undefined;
  if (!bare) return {};
  const { base } = SCHEMES[protocol]!;
  const own = new Set([base.host, base.path, bare.portIsPlace ? base.port : undefined]);
  const out: UrlFields = {};
  for (const [name, value] of Object.entries(fieldsOf(parseUrl(bare.url)))) {
    if (typeof value === 'string' && value !== '' && !own.has(name)) out[name] = value;
  }
  if (bare.maxItems !== undefined) out.maxItems = String(bare.maxItems);
  return out;
}

/**
 * The fields a CPU preset sets (S7_CPU_PRESETS): rack and slot or the TSAP
 * pair, and items per job (empty: the library's default); undefined for a
 * name that is no preset.
 */
export function presetFields(cpu: string): UrlFields | undefined {
  const preset = Object.hasOwn(S7_CPU_PRESETS, cpu) ? S7_CPU_PRESETS[cpu as keyof typeof S7_CPU_PRESETS] : undefined;
  if (!preset) return undefined;
  const where: UrlFields =
    preset.localTsap !== undefined && preset.remoteTsap !== undefined
      ? { addressing: 'tsap', localTsap: hex4(preset.localTsap).toUpperCase(), remoteTsap: hex4(preset.remoteTsap).toUpperCase() }
      : { addressing: 'rack', rack: String(preset.rack ?? ''), slot: String(preset.slot ?? '') };
  return { ...where, maxItems: preset.maxItems === undefined ? '' : String(preset.maxItems) };
}
