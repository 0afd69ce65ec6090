/**
 * TLS over the COTP tunnel, and the trust decision before any S7CommPlus
 * data: the PLC's certificate pinned by its SHA-256 (`fingerprint=`), or
 * signed by the CA of `ca=`, or anything with `insecure=true` (the bench).
 * Otherwise refused, with the certificate's fingerprint, subject and validity
 * and the URL parameter that would pin it. TLS 1.2 and 1.3 both offered
 * (S7-1500 firmware before V3.0 is reported to refuse a 1.3-only client).
 *
 * The client's own until lib/s7plus/transport/ (TLS options and pinning of
 * the transport layer) is merged; it then takes this one's place.
 */
import { createHash } from 'node:crypto';
import * as fs from 'node:fs';
import type { Duplex } from 'node:stream';
import * as tls from 'node:tls';
import { abortError, ConnectionError, type PlcError } from '../../errors';
import type { S7PlusEndpoint } from '../url';

/** What the client learns of the PLC's certificate (also for the `insecure` warning). */
export interface PeerCertificate {
  fingerprint: string;
  subject: string;
  validFrom: string;
  validTo: string;
}

function describe(cert: tls.PeerCertificate): PeerCertificate {
  const subject = Object.entries(cert.subject ?? {})
    .map(([k, v]) => `${k}=${Array.isArray(v) ? v.join('+') : v}`)
    .join(', ');
  return {
    fingerprint: createHash('sha256').update(cert.raw).digest('hex'),
    subject: subject || '(none)',
    validFrom: cert.valid_from,
    validTo: cert.valid_to,
  };
}

/** "AB:CD:…" as TIA and browsers show a fingerprint. */
function colons(hex: string): string {
  return hex.toUpperCase().replace(/(..)(?!$)/g, '$1:');
}

/** The PLC's certificate refused by the URL's trust settings (not a failed handshake). */
export class TrustRefusal extends ConnectionError {}

function refusal(name: string, why: string, c: PeerCertificate): PlcError {
  return new TrustRefusal(
    'CONNECT_FAILED',
    `${name}: ${why}. Its certificate: SHA-256 ${colons(c.fingerprint)}, subject ${c.subject}, valid ${c.validFrom} to ${c.validTo}. ` +
      `If it is your PLC's, pin it with fingerprint=${c.fingerprint} in the URL`,
  );
}

/**
 * The TLS handshake over `tunnel`; resolves the TLS socket once the PLC's
 * certificate is trusted (and its description). Rejects with a PlcError and
 * destroys the socket otherwise: no S7CommPlus byte goes to an untrusted peer.
 */
export function startTls(
  tunnel: Duplex,
  e: S7PlusEndpoint,
  o: { name: string; signal: AbortSignal },
): Promise<{ socket: tls.TLSSocket; certificate: PeerCertificate }> {
  let ca: Buffer | undefined;
  if (e.ca) {
    try {
      ca = fs.readFileSync(e.ca);
    } catch (err) {
      const reason = (err as NodeJS.ErrnoException).code ?? String(err);
      return Promise.reject(new ConnectionError('CONNECT_FAILED', `${o.name}: cannot read the CA file of ca= (${e.ca}): ${reason}`));
    }
  }
  return new Promise((resolve, reject) => {
    const socket = tls.connect({
      socket: tunnel,
      // The decision is ours, below: a PLC certificate names no host name we could check, and a pin needs no chain.
      rejectUnauthorized: false,
      minVersion: 'TLSv1.2',
      maxVersion: 'TLSv1.3',
      ...(ca ? { ca } : {}),
    });
    const finish = (err: PlcError | undefined, certificate?: PeerCertificate) => {
      socket.off('secureConnect', onSecure);
      socket.off('error', onError);
      socket.off('close', onClose);
      o.signal.removeEventListener('abort', onAbort);
      if (err) {
        socket.on('error', () => {});
        socket.destroy();
        tunnel.destroy();
        reject(err);
      } else resolve({ socket, certificate: certificate! });
    };
    const onSecure = () => {
      const c = describe(socket.getPeerCertificate());
      if (e.fingerprint) {
        if (c.fingerprint === e.fingerprint) return finish(undefined, c);
        return finish(refusal(o.name, `the PLC's certificate is not the one fingerprint= pins (${colons(e.fingerprint)})`, c));
      }
      if (ca) {
        if (socket.authorized) return finish(undefined, c);
        return finish(refusal(o.name, `the PLC's certificate is not signed by the CA of ca= (${String(socket.authorizationError)})`, c));
      }
      if (e.insecure) return finish(undefined, c);
      finish(refusal(o.name, 'the PLC presented a certificate nothing in the URL trusts (fingerprint=, ca= or insecure=true)', c));
    };
    const onError = (err: Error) =>
      finish(new ConnectionError('CONNECT_FAILED', `${o.name}: the TLS handshake failed: ${err.message}`, { cause: err }));
    const onClose = () => finish(new ConnectionError('CONNECT_FAILED', `${o.name} closed the connection during the TLS handshake`));
    const onAbort = () => finish(abortError(`connecting to ${o.name}`, o.signal));
    socket.once('secureConnect', onSecure);
    socket.on('error', onError);
    socket.once('close', onClose);
    o.signal.addEventListener('abort', onAbort, { once: true });
  });
}
