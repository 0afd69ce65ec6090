/**
 * The connection dialog's fields and the URL parameters they write, per
 * protocol choice (each one a URL scheme): the one table both directions of
 * lib/flows/url-fields.ts and lib/flows/url-fields-read.ts read. Fields are
 * the dialog's inputs by their ids (nodes/connection.html).
 */

/** The dialog's fields by id: text as typed, a tick as a boolean. */
export type UrlFields = Record<string, string | boolean>;

/** One query parameter of a field: its text, or (`tick`) written as `param=<tick>` when the tick is so. */
export interface Part {
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
export const SCHEMES: Readonly<Record<string, { base: Base; parts: Part[]; covers?: string[] }>> = {
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
export const SAFETY: Part[] = [
  { field: 'readOnly', param: 'readOnly', tick: true },
  { field: 'allow', param: 'allow' },
];

export function textOf(value: unknown): string {
  return typeof value === 'string' ? value.trim() : typeof value === 'number' ? String(value) : '';
}

export function ticked(value: unknown): boolean | undefined {
  return value === true || value === 'true' ? true : value === false || value === 'false' ? false : undefined;
}
