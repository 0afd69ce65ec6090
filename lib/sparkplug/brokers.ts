/**
 * The edge node's brokers: their URLs checked when it is made, named without
 * a password wherever one is shown (status, errors, logs), and what a broker
 * refused turned into a typed error that says why. A list mixing TLS
 * (mqtts://, wss://) and plain (mqtt://, ws://) brokers is refused: moving to
 * the next broker would fall back to plain text on its own.
 */
import { PlcError } from '../errors';

const TLS = new Set(['mqtts:', 'wss:']);
const PLAIN = new Set(['mqtt:', 'ws:']);

/** A broker URL as it may be shown: its password replaced by `***`. */
export function brokerName(url: string): string {
  try {
    const u = new URL(url);
    if (u.password === '') return url;
    u.password = '***';
    return u.toString();
  } catch {
    return url.replace(/\/\/([^:/@]*):[^@/]*@/, '//$1:***@');
  }
}

/** The broker list, checked: at least one, each a URL of mqtt://, mqtts://, ws:// or wss://, all TLS or all plain. */
export function checkBrokers(urls: readonly string[]): void {
  const list: readonly unknown[] = (Array.isArray(urls) ? urls : []) as readonly unknown[];
  if (list.length === 0) throw new PlcError('INVALID_VALUE', 'a Sparkplug edge node needs at least one broker URL');
  const schemes = list.map((raw) => {
    const url = String(raw);
    let u: URL;
    try {
      u = new URL(url);
    } catch {
      throw new PlcError(
        'INVALID_URL',
        `broker ${JSON.stringify(brokerName(url))} is not a URL: give mqtt://host[:1883] or mqtts://host[:8883]`,
      );
    }
    if (!TLS.has(u.protocol) && !PLAIN.has(u.protocol))
      throw new PlcError('INVALID_URL', `broker ${brokerName(url)}: the scheme must be mqtt://, mqtts://, ws:// or wss://`);
    return u.protocol;
  });
  if (schemes.some((s) => TLS.has(s)) && schemes.some((s) => PLAIN.has(s))) {
    throw new PlcError(
      'INVALID_URL',
      `the brokers mix TLS and plain text (${list.map((u) => brokerName(String(u))).join(', ')}): moving to the next broker would fall back to plain text; give all mqtts:// (wss://) or all mqtt:// (ws://)`,
    );
  }
}

/** Node's codes for a TLS certificate it did not trust (tls.connect's verification, and the host name check). */
const UNTRUSTED = new Set([
  'SELF_SIGNED_CERT_IN_CHAIN',
  'DEPTH_ZERO_SELF_SIGNED_CERT',
  'UNABLE_TO_VERIFY_LEAF_SIGNATURE',
  'UNABLE_TO_GET_ISSUER_CERT',
  'UNABLE_TO_GET_ISSUER_CERT_LOCALLY',
  'CERT_HAS_EXPIRED',
  'CERT_NOT_YET_VALID',
  'CERT_UNTRUSTED',
  'CERT_SIGNATURE_FAILURE',
]);

/**
 * What a broker's connection failed with, typed: CERTIFICATE_UNTRUSTED (TLS refused the broker's certificate:
 * nothing was sent), ACCESS_DENIED (the broker refused the user or password: MQTT 3.1.1 CONNACK 4 and 5, MQTT 5
 * 0x86 and 0x87), else CONNECT_FAILED; each names the broker without its password.
 */
function brokerError(url: string, err: unknown): PlcError {
  if (err instanceof PlcError) return err;
  const e = err as { code?: unknown; message?: unknown };
  const message = String(e?.message ?? err);
  const name = brokerName(url);
  if (e?.code === 'ERR_TLS_CERT_ALTNAME_INVALID') {
    return new PlcError(
      'CERTIFICATE_UNTRUSTED',
      `broker ${name}: its TLS certificate was made for another name (${message}); nothing was sent. Reach the broker by a name its certificate holds`,
      { cause: err },
    );
  }
  if (typeof e?.code === 'string' && UNTRUSTED.has(e.code)) {
    return new PlcError(
      'CERTIFICATE_UNTRUSTED',
      `broker ${name}: its TLS certificate was refused (${message}); nothing was sent. Give the CA that signed it (mqtt.ca, --mqtt-ca)`,
      { cause: err },
    );
  }
  if (e?.code === 4 || e?.code === 5 || e?.code === 0x86 || e?.code === 0x87) {
    return new PlcError('ACCESS_DENIED', `broker ${name} refused the edge node's user or password (${message})`, { cause: err });
  }
  return new PlcError('CONNECT_FAILED', `broker ${name}: ${message}`, { cause: err });
}

/**
 * A broker's connection errors as they are told: the first of an outage, and then only one that says something
 * else (a broker that keeps refusing the certificate is one error, not one per reconnect); a session that
 * starts ends the outage.
 */
export class BrokerErrors {
  private last: string | undefined;

  constructor(private readonly tell: (error: PlcError) => void) {}

  /** Tells the typed error of `err`, unless it repeats the one told last. */
  take(url: string, err: unknown): void {
    const e = brokerError(url, err);
    const key = `${e.code} ${e.message}`;
    if (key === this.last) return;
    this.last = key;
    this.tell(e);
  }

  /** A session started: the next error is told again. */
  reset(): void {
    this.last = undefined;
  }
}
