/**
 * The connection dialog's fields ⇄ a PLC URL, both ways through the library's
 * own parser and formatter (lib/url.ts), so the editor (nodes/connection.html)
 * holds no scheme's format, default or fingerprint rule: it sends what the
 * fields hold, as typed, and shows and saves the URL it gets back.
 *
 * Fields are the dialog's inputs by their ids: text as typed, ticks as
 * booleans. An empty text field is a parameter left out (the library's
 * default); a field the dialog does not send is an empty one.
 */
import { PlcError, toPlcError } from '../errors';
import { hostPart } from '../link/url-params';
import { DEFAULTS, endpointKey, formatUrl, parseUrl, S7_CPU_PRESETS, type Endpoint } from '../url';
import { hex4 } from '../values/text';

/** The dialog's fields by id: text as typed, a tick as a boolean. */
export type UrlFields = Record<string, string | boolean>;

/** A URL the fields make, with what the dialog shows of it. */
export interface FieldsUrl {
  ok: true;
  /** The URL as the library writes it (defaults left out, a fingerprint in its one form). */
  url: string;
  endpoint: Endpoint;
  /** Identity of the PLC it reaches (endpointKey). */
  key: string;
  /** What a text field left empty means, for its placeholder (placeholdersOf). */
  placeholders: UrlFields;
}

/** Fields that make no valid URL: the parser's error, the field it is about, and the URL as composed. */
export interface FieldsProblem {
  ok: false;
  code: string;
  message: string;
  /** The field whose value the parser refused, when one alone is to blame. */
  field?: string;
  /** The URL the fields make, not valid: what the dialog saves, so the node is marked invalid with this message. */
  url: string;
  placeholders: UrlFields;
}

/** One query parameter of a field: its text, or (`tick`) written as `param=<tick>` when the tick is so. */
interface Part {
  field: string;
  param: string;
  tick?: boolean;
  /** Sent only when the other fields say so (rack/slot or the TSAP pair). */
  when?: (f: UrlFields) => boolean;
}

/** Where the URL's authority (or a serial port's path) comes from, and what a parser accepts in place of each. */
interface Base {
  host?: string;
  port?: string;
  path?: string;
}

/** Values the parser accepts in a base field: a field is to blame when its own value, replaced by one of these, makes the URL parse. */
const NEUTRAL = { host: 'localhost', port: '1', path: 'COM1' } as const;

const byRack = (f: UrlFields) => textOf(f.addressing) !== 'tsap';
const byTsap = (f: UrlFields) => textOf(f.addressing) === 'tsap';

const LINE: Part[] = [
  { field: 'timeout', param: 'timeout' },
  { field: 'retries', param: 'retries' },
  { field: 'gap', param: 'gap' },
];

/**
 * The dialog's protocol choices (each one a URL scheme): its base fields, the
 * fields of its parameters, and (`covers`) parameters its fields stand for
 * without writing them.
 */
const SCHEMES: Readonly<Record<string, { base: Base; parts: Part[]; covers?: string[] }>> = {
  s7: {
    base: { host: 'host', port: 'port' },
    parts: [
      { field: 'rack', param: 'rack', when: byRack },
      { field: 'slot', param: 'slot', when: byRack },
      { field: 'localTsap', param: 'localTsap', when: byTsap },
      { field: 'remoteTsap', param: 'remoteTsap', when: byTsap },
      { field: 'connectionType', param: 'type' },
      { field: 'pduSize', param: 'pdu' },
      { field: 'timeout', param: 'timeout' },
      { field: 'maxItems', param: 'maxItems' },
      { field: 'control', param: 'control', tick: true },
    ],
  },
  s7plus: {
    base: { host: 'host', port: 'port' },
    parts: [
      { field: 'fingerprint', param: 'fingerprint' },
      { field: 'ca', param: 'ca' },
      { field: 'insecure', param: 'insecure', tick: true },
      { field: 'tls', param: 'tls', tick: false },
      { field: 'timeout', param: 'timeout' },
      { field: 'maxItems', param: 'maxItems' },
    ],
  },
  fetchwrite: {
    base: { host: 'host' },
    parts: [
      { field: 'fetchPort', param: 'fetchPort' },
      { field: 'writePort', param: 'writePort' },
      { field: 'dbUnit', param: 'dbUnit' },
      { field: 'timeout', param: 'timeout' },
    ],
    // One port for both is written as port= (lib/fetchwrite/url.ts): the two port fields stand for it.
    covers: ['port'],
  },
  freeport: {
    base: { path: 'serialPath' },
    parts: [
      { field: 'baudRate', param: 'baud' },
      { field: 'parity', param: 'parity' },
      { field: 'dataBits', param: 'databits' },
      { field: 'stopBits', param: 'stopbits' },
      ...LINE,
    ],
  },
  'freeport+tcp': { base: { host: 'tcpHost', port: 'tcpPort' }, parts: LINE },
};

/** What every protocol takes (lib/url.ts). */
const SAFETY: Part[] = [
  { field: 'readOnly', param: 'readOnly', tick: true },
  { field: 'allow', param: 'allow' },
];

function textOf(value: unknown): string {
  return typeof value === 'string' ? value.trim() : typeof value === 'number' ? String(value) : '';
}

function ticked(value: unknown): boolean | undefined {
  return value === true || value === 'true' ? true : value === false || value === 'false' ? false : undefined;
}

/** A host as typed (an IPv6 address with or without its brackets), refused when it would change the URL's shape. */
function authority(host: string, port: string): string {
  const bare = host.replace(/^\[(.*)\]$/, '$1');
  if (/[\s/?#@[\]\\]/.test(bare)) throw new PlcError('INVALID_URL', `invalid PLC URL: "${host}" is no host name or IP address`);
  return `${hostPart(bare)}${port ? `:${port}` : ''}`;
}

/** A serial port's path as a URL writes it (freeport:///dev/ttyUSB0, freeport://COM3). */
function serialPart(path: string): string {
  return path.startsWith('/') ? encodeURI(path) : encodeURIComponent(path);
}

/**
 * The parameters of `kept` (the URL the fields were filled from) that no
 * field of `scheme` writes: a role (`type=es` on s7plus://) or
 * `strictSymbols=true` typed into the URL stays when a field changes. None
 * when `kept` is of another scheme or no URL.
 */
function keptParams(scheme: string, kept: string): [string, string][] {
  let url: URL;
  try {
    url = new URL(kept.trim());
  } catch {
    return [];
  }
  if (url.protocol !== `${scheme}:`) return [];
  const { parts, covers = [] } = SCHEMES[scheme]!;
  const written = new Set([...parts, ...SAFETY].map((p) => p.param.toLowerCase()).concat(covers));
  return [...url.searchParams].filter(([name]) => !written.has(name.toLowerCase()));
}

/** The URL text of `fields` for `scheme`, with field `swap` (if any) given `value` instead of its own. */
function compose(scheme: string, fields: UrlFields, kept: string, swap?: { field: string; value: string | boolean }): string {
  const { base, parts } = SCHEMES[scheme]!;
  const get = (name: string): unknown => (swap && swap.field === name ? swap.value : fields[name]);
  const head = base.path ? serialPart(textOf(get(base.path))) : authority(textOf(get(base.host!)), base.port ? textOf(get(base.port)) : '');
  const query = new URLSearchParams();
  for (const part of [...parts, ...SAFETY]) {
    if (part.when && !part.when(fields)) continue;
    const value = get(part.field);
    if (part.tick !== undefined) {
      if (ticked(value) === part.tick) query.set(part.param, String(part.tick));
    } else if (part.param === 'allow') {
      const list = textOf(value)
        .split(',')
        .map((s) => s.trim())
        .filter(Boolean);
      if (list.length) query.set('allow', list.join(','));
    } else if (textOf(value) !== '') query.set(part.param, textOf(value));
  }
  for (const [name, value] of keptParams(scheme, kept)) query.append(name, value);
  const q = query.toString().replace(/%2C/g, ',');
  return `${scheme}://${head}${q ? `?${q}` : ''}`;
}

/** Why the parser refuses `text` (its problem, without the URL it quotes), or undefined when it parses. */
function refusal(text: () => string): string | undefined {
  try {
    parseUrl(text());
    return undefined;
  } catch (err) {
    return toPlcError(err, 'INVALID_URL').message.replace(/^invalid PLC URL( "[^"]*")?: /, '');
  }
}

/**
 * The field to blame for fields that make no valid URL: the first whose own
 * value, replaced by one the parser accepts (a parameter left out, a tick
 * undone, a placeholder host), makes the URL parse; else the first parameter
 * that, alone with the host, is refused for the same reason; undefined when
 * no one field is (then the URL as a whole is wrong).
 */
function blamed(scheme: string, fields: UrlFields, kept: string, problem: string): string | undefined {
  const { base, parts } = SCHEMES[scheme]!;
  const swaps: { field: string; value: string | boolean }[] = [];
  if (base.host) swaps.push({ field: base.host, value: NEUTRAL.host });
  if (base.port) swaps.push({ field: base.port, value: textOf(fields[base.port]) === '' ? NEUTRAL.port : '' });
  if (base.path) swaps.push({ field: base.path, value: NEUTRAL.path });
  const params: Part[] = [];
  for (const part of [...parts, ...SAFETY]) {
    if (part.when && !part.when(fields)) continue;
    if (part.tick !== undefined) {
      if (ticked(fields[part.field]) !== part.tick) continue;
      swaps.push({ field: part.field, value: !part.tick });
    } else if (textOf(fields[part.field]) !== '') swaps.push({ field: part.field, value: '' });
    else continue;
    params.push(part);
  }
  const fixed = swaps.find((swap) => refusal(() => compose(scheme, fields, kept, swap)) === undefined);
  if (fixed) return fixed.field;
  // Two fields wrong at once (a TSAP pair with a bad half): the one refused on its own for this very reason.
  const place: UrlFields = { protocol: scheme, addressing: fields.addressing ?? '' };
  for (const name of [base.host, base.port, base.path]) if (name) place[name] = fields[name] ?? '';
  return params.find((part) => refusal(() => compose(scheme, { ...place, [part.field]: fields[part.field]! }, '')) === problem)?.field;
}

/**
 * `fields` without the values that are their protocol's defaults (they change
 * nothing the parser says), composed, with the parser's refusal; undefined
 * when that URL cannot be composed or is not refused.
 */
function leanText(scheme: string, fields: UrlFields, kept: string): { code: string; message: string; url: string } | undefined {
  const lean: UrlFields = { ...fields };
  for (const [name, value] of Object.entries(placeholdersOf(scheme)))
    if (name !== 'protocol' && textOf(fields[name]) === value) lean[name] = '';
  let url: string;
  try {
    url = compose(scheme, lean, kept);
  } catch {
    return undefined;
  }
  try {
    parseUrl(url);
    return undefined;
  } catch (err) {
    const e = toPlcError(err, 'INVALID_URL');
    return { code: e.code, message: e.message, url };
  }
}

/**
 * The URL the dialog's fields make, in the library's form; or why they make
 * none, and which field says so. `kept`: the URL the fields were filled from,
 * whose parameters no field writes are kept (keptParams).
 */
export function urlOfFields(fields: UrlFields, kept = ''): FieldsUrl | FieldsProblem {
  const scheme = textOf(fields.protocol) || 's7';
  if (!SCHEMES[scheme]) {
    return { ok: false, code: 'INVALID_URL', message: `unknown protocol "${scheme}"`, field: 'protocol', url: '', placeholders: {} };
  }
  let text = '';
  try {
    text = compose(scheme, fields, kept);
    const endpoint = parseUrl(text);
    return { ok: true, url: formatUrl(endpoint), endpoint, key: endpointKey(endpoint), placeholders: placeholdersOf(scheme) };
  } catch (err) {
    const e = toPlcError(err, 'INVALID_URL');
    const field = blamed(scheme, fields, kept, refusal(() => text) ?? '');
    // Shown and saved without the defaults typed (as the library writes a valid URL): they change nothing the parser says.
    const lean = leanText(scheme, fields, kept);
    if (lean !== undefined) return { ok: false, ...lean, ...(field ? { field } : {}), placeholders: placeholdersOf(scheme) };
    const url = text || `${scheme}://`;
    return { ok: false, code: e.code, message: e.message, ...(field ? { field } : {}), url, placeholders: placeholdersOf(scheme) };
  }
}

/** The dialog's fields of an endpoint (the ones of its protocol, and the ones every protocol has). */
export function fieldsOf(e: Endpoint): UrlFields {
  const common = { timeout: String(e.timeout), readOnly: !!e.readOnly, allow: (e.allow ?? []).join(',') };
  const maxItems = (n: number | undefined) => (n === undefined ? '' : String(n));
  switch (e.protocol) {
    case 's7':
      return {
        protocol: 's7',
        ...common,
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
        maxItems: maxItems(e.maxItems),
        control: !!e.control,
      };
    case 's7plus':
      return {
        protocol: 's7plus',
        ...common,
        host: e.host,
        port: String(e.port),
        fingerprint: e.fingerprint ?? '',
        ca: e.ca ?? '',
        insecure: !!e.insecure,
        tls: e.tls,
        maxItems: maxItems(e.maxItems),
      };
    case 'fetchwrite':
      return {
        protocol: 'fetchwrite',
        ...common,
        host: e.host,
        fetchPort: String(e.fetchPort),
        writePort: String(e.writePort),
        dbUnit: e.dbUnit,
      };
    case 'freeport': {
      const line = { ...common, retries: String(e.retries), gap: String(e.interFrameGapMs) };
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
    }
  }
}

/** The URLs that name a place and nothing else, whose parse shows what every other field of the scheme means when empty. */
const BARE: Readonly<Record<string, string>> = {
  s7: 's7://localhost',
  s7plus: 's7plus://localhost',
  fetchwrite: 'fetchwrite://localhost',
  freeport: 'freeport://COM1',
  'freeport+tcp': 'freeport+tcp://localhost:1',
};

/**
 * What each text field of a protocol means when left empty (its placeholder):
 * the library's defaults, read from a URL that names a place and nothing
 * else; items per job as the driver assumes them. Empty for a protocol the
 * dialog does not offer.
 */
export function placeholdersOf(protocol: string): UrlFields {
  const bare = BARE[protocol];
  if (!bare) return {};
  const { base } = SCHEMES[protocol]!;
  const own = new Set([base.host, base.path, protocol === 'freeport+tcp' ? base.port : undefined]);
  const out: UrlFields = {};
  for (const [name, value] of Object.entries(fieldsOf(parseUrl(bare)))) {
    if (typeof value === 'string' && value !== '' && !own.has(name)) out[name] = value;
  }
  if (protocol === 's7') out.maxItems = String(DEFAULTS.maxItems);
  if (protocol === 's7plus') out.maxItems = String(DEFAULTS.s7plusMaxItems);
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
