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
import { endpointKey, formatUrl, parseUrl, type Endpoint } from '../url';
import { SAFETY, SCHEMES, textOf, ticked, type Part, type UrlFields } from './url-field-table';
import { placeholdersOf } from './url-fields-read';

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

/** Values the parser accepts in a base field: a field is to blame when its own value, replaced by one of these, makes the URL parse. */
const NEUTRAL = { host: 'localhost', port: '1', path: 'COM1' } as const;

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
