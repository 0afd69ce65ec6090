/**
 * s7:// URLs: host, port 102, rack/slot or a TSAP pair, connection type,
 * PDU size, timeout, items per job, control of the CPU (lib/url.ts).
 */
import { DEFAULT_TIMEOUT } from '../client/options';
import type { UrlScheme } from '../link/driver';
import { hostPart, portOf, requireHost, urlError, type UrlParams } from '../link/url-params';
import type { SafetyOptions } from '../link/url-params';
import { DEFAULT_MAX_ITEMS, MAX_ITEMS, S7_PORT } from './constants';
import { hex4 } from '../values/text';

export type S7ConnectionType = 'pg' | 'op' | 'basic';

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

const DEFAULTS = Object.freeze({
  s7Port: S7_PORT,
  rack: 0,
  slot: 1,
  pduSize: 960,
  timeout: DEFAULT_TIMEOUT,
  /** Items per S7 job unless the URL says more (DEFAULT_MAX_ITEMS in lib/s7/constants.ts says why). */
  maxItems: DEFAULT_MAX_ITEMS,
});

/** True for an endpoint of an s7:// URL: the CPU services only S7Client has (SZL, diagnostic buffer, clock, RUN/STOP). */
export function isS7Endpoint(e: { readonly protocol: string }): e is S7Endpoint {
  return e.protocol === 's7';
}

export const S7_URLS: UrlScheme<S7Endpoint> = Object.freeze({
  protocol: 's7',
  schemes: { s7: ['rack', 'slot', 'localTsap', 'remoteTsap', 'type', 'pdu', 'timeout', 'maxItems', 'control'] },
  defaults: DEFAULTS,

  parse(_scheme: string, text: string, url: URL, p: UrlParams): Omit<S7Endpoint, 'protocol' | 'readOnly' | 'allow'> {
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
  },

  format(e: S7Endpoint, q: URLSearchParams): string {
    if (e.localTsap !== undefined && e.remoteTsap !== undefined) {
      q.set('localTsap', hex4(e.localTsap).toUpperCase());
      q.set('remoteTsap', hex4(e.remoteTsap).toUpperCase());
    } else {
      q.set('rack', String(e.rack));
      q.set('slot', String(e.slot));
    }
    if (e.connectionType !== 'pg') q.set('type', e.connectionType);
    if (e.pduSize !== DEFAULTS.pduSize) q.set('pdu', String(e.pduSize));
    if (e.timeout !== DEFAULTS.timeout) q.set('timeout', String(e.timeout));
    if (e.maxItems !== undefined) q.set('maxItems', String(e.maxItems));
    if (e.control) q.set('control', 'true');
    return `s7://${hostPart(e.host)}${e.port === DEFAULTS.s7Port ? '' : `:${e.port}`}`;
  },

  key: (e: S7Endpoint) =>
    `s7://${e.host.toLowerCase()}:${e.port}/${e.localTsap ?? `${e.connectionType}/${e.rack}/${e.slot}`}/${e.remoteTsap ?? ''}`,
  name: (e: S7Endpoint) => `s7://${hostPart(e.host)}:${e.port}`,
  host: (e: S7Endpoint) => e.host,
});
