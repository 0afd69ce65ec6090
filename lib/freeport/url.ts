/**
 * freeport:// (a serial port) and freeport+tcp:// (a serial device server)
 * URLs: the line, its settings, timeout, retries and the gap between frames
 * (lib/url.ts).
 */
import type { UrlScheme } from '../link/driver';
import { hostPart, portOf, requireHost, urlError, type UrlParams } from '../link/url-params';
import type { SafetyOptions } from '../link/url-params';
import type { Parity } from '../link/serial';

export type { Parity } from '../link/serial';

/** The line to the stations: a serial port, or TCP to a serial device server. */
export type FreeportLine =
  | { kind: 'serial'; path: string; baudRate: number; parity: Parity; dataBits: 7 | 8; stopBits: 1 | 2 }
  | { kind: 'tcp'; host: string; port: number };

export interface FreeportEndpoint extends SafetyOptions {
  protocol: 'freeport';
  transport: FreeportLine;
  timeout: number;
  retries: number;
  /** Silence on the bus between a reply and the next request, ms. */
  interFrameGapMs: number;
}

/** Baud rates an S7-200 port can run at (SMB30 / SMB130). */
export const FREEPORT_BAUD_RATES: readonly number[] = [1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200];

const DEFAULTS = Object.freeze({ baudRate: 9600, freeportTimeout: 1000, retries: 2, interFrameGapMs: 10 });
const LINE = ['timeout', 'retries', 'gap'];

function parseLine(scheme: string, text: string, url: URL, p: UrlParams): FreeportLine {
  if (scheme === 'freeport+tcp') {
    if (!url.port) throw urlError(text, 'a serial device server needs a port (freeport+tcp://host:4001)');
    return { kind: 'tcp', host: requireHost(text, url), port: portOf(text, url, 0) };
  }
  const path = decodeURIComponent(url.hostname && !url.pathname ? url.hostname : url.pathname);
  if (!path) throw urlError(text, 'no serial port (freeport:///dev/ttyUSB0 or freeport://COM3)');
  const baudRate = p.int('baud', DEFAULTS.baudRate, 1, 4_000_000);
  if (!FREEPORT_BAUD_RATES.includes(baudRate)) {
    throw urlError(text, `baud=${baudRate} is not a rate an S7-200 port runs at (${FREEPORT_BAUD_RATES.join(', ')})`);
  }
  return {
    kind: 'serial',
    path,
    baudRate,
    parity: p.choice('parity', ['none', 'even', 'odd'] as const, 'none'),
    dataBits: p.int('databits', 8, 7, 8) as 7 | 8,
    stopBits: p.int('stopbits', 1, 1, 2) as 1 | 2,
  };
}

const lineName = (e: FreeportEndpoint) =>
  e.transport.kind === 'tcp' ? `freeport+tcp://${hostPart(e.transport.host)}:${e.transport.port}` : `freeport://${e.transport.path}`;

export const FREEPORT_URLS: UrlScheme<FreeportEndpoint> = Object.freeze({
  protocol: 'freeport',
  schemes: { freeport: ['baud', 'parity', 'databits', 'stopbits', ...LINE], 'freeport+tcp': LINE },
  defaults: DEFAULTS,

  parse(scheme: string, text: string, url: URL, p: UrlParams): Omit<FreeportEndpoint, 'protocol' | 'readOnly' | 'allow'> {
    return {
      transport: parseLine(scheme, text, url, p),
      timeout: p.int('timeout', DEFAULTS.freeportTimeout, 1, 3_600_000),
      retries: p.int('retries', DEFAULTS.retries, 0, 100),
      interFrameGapMs: p.int('gap', DEFAULTS.interFrameGapMs, 0, 10_000),
    };
  },

  format(e: FreeportEndpoint, q: URLSearchParams): string {
    const t = e.transport;
    let base: string;
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
    return base;
  },

  key: (e: FreeportEndpoint) =>
    e.transport.kind === 'tcp' ? `freeport+tcp://${e.transport.host.toLowerCase()}:${e.transport.port}` : `freeport://${e.transport.path}`,
  name: lineName,
  host: (e: FreeportEndpoint) => (e.transport.kind === 'tcp' ? e.transport.host : ''),
});
