/**
 * Whom an S7CommPlus client trusts, and the TLS settings S7 PLCs accept.
 *
 * A PLC's certificate is self-signed or signed by the TIA project's CA, so the
 * usual web trust (public CAs, host names) does not apply. Trust is given in
 * the URL: `fingerprint=` pins the SHA-256 of the certificate's DER (64 hex
 * digits, colons and case ignored), `ca=` names a PEM file with the project's
 * CA, `insecure=true` accepts anything (for the bench) and says so on every
 * connect. Anything else is refused after the TLS handshake and before the
 * first S7CommPlus byte, with an error that shows the certificate and the URL
 * parameter that would pin it.
 */
import * as crypto from 'node:crypto';
import * as fs from 'node:fs';
import * as net from 'node:net';
import type * as tls from 'node:tls';
import { PlcError } from '../../errors';
import { fingerprint256 } from './cert';
import { fingerprintProblem, normalizeFingerprint } from './fingerprint';

/**
 * TLS 1.2 suites S7 PLCs accept, ECDHE first (forward secrecy), RSA key
 * exchange kept for older firmware: the list of the s7commplus package (MIT),
 * connection.py `_S7_CIPHERS`. TLS 1.3 keeps OpenSSL's default suites.
 */
export const S7_CIPHERS =
  'ECDHE-RSA-AES128-GCM-SHA256:ECDHE-RSA-AES256-GCM-SHA384:AES128-GCM-SHA256:AES256-GCM-SHA384:AES128-SHA256:AES256-SHA256';

/**
 * Key-exchange groups offered: X25519 (what an S7-1500 negotiates, and the
 * first key share) and P-256. Not x448 or the ffdhe groups: PLCs reset the
 * connection when they see groups they do not know (s7commplus (MIT),
 * connection.py `_S7_PREFERRED_GROUPS` and the comment above `_S7_CIPHERS`).
 */
export const S7_GROUPS = 'X25519:P-256';

/** OpenSSL 3's SSL_OP_NO_EXTENDED_MASTER_SECRET (not in crypto.constants). */
const SSL_OP_NO_EXTENDED_MASTER_SECRET = 0x1;

/**
 * No session tickets, no encrypt-then-MAC, no extended master secret: the
 * options the s7commplus package (MIT) sets for S7 PLCs (connection.py
 * `_setup_ssl_context`).
 */
export const S7_SECURE_OPTIONS =
  crypto.constants.SSL_OP_NO_TICKET | crypto.constants.SSL_OP_NO_ENCRYPT_THEN_MAC | SSL_OP_NO_EXTENDED_MASTER_SECRET;

/** What the URL says about trust. */
export interface TlsTrust {
  /** `fingerprint=`: SHA-256 of the PLC's DER certificate, 64 hex digits (colons and case ignored). */
  fingerprint?: string;
  /** `ca=`: a PEM file with the CA (the TIA project's) that signed the PLC's certificate. */
  ca?: string;
  /** `insecure=true`: accept any certificate, with a warning on every connect. */
  insecure?: boolean;
}

/** A certificate as the error and the warning show it. */
export interface CertificateInfo {
  /** SHA-256 of the DER, 64 upper-case hex digits. */
  fingerprint: string;
  subject: string;
  issuer: string;
  notBefore: Date;
  notAfter: Date;
  /** subjectAltName as Node prints it ("DNS:plc1, IP Address:192.168.0.1"), or undefined. */
  altNames?: string;
}

export type CertificateProblem = 'not-trusted' | 'wrong-pin' | 'expired' | 'not-yet-valid' | 'not-signed-by-ca' | 'wrong-name';

/** The PLC's certificate was refused; nothing of S7CommPlus was sent. */
export class CertificateError extends PlcError {
  readonly certificate: CertificateInfo;
  readonly problem: CertificateProblem;
  /** The URL parameter that would pin this certificate: `fingerprint=<64 hex digits>`. */
  readonly pin: string;

  constructor(problem: CertificateProblem, certificate: CertificateInfo, message: string) {
    super('CERTIFICATE_UNTRUSTED', message);
    this.certificate = certificate;
    this.problem = problem;
    this.pin = `fingerprint=${certificate.fingerprint}`;
  }
}

/**
 * The `fingerprint=` value as 64 upper-case hex digits. Colons, spaces and
 * case are ignored; anything else is an INVALID_URL error saying what the
 * value should be.
 */
export function parseFingerprint(text: string): string {
  const hex = normalizeFingerprint(text);
  if (hex) return hex;
  const shown = text.length > 80 ? `${text.slice(0, 77)}...` : text;
  return badUrl(
    `fingerprint=${shown}: ${fingerprintProblem(text)}; give the SHA-256 of the PLC's certificate as 64 hex digits (colons and case are ignored)`,
  );
}

function badUrl(problem: string): never {
  throw new PlcError('INVALID_URL', `invalid PLC URL parameter ${problem}`);
}

/** Reads the `ca=` file; an INVALID_URL error names the file and what is wrong with it. */
function readCa(file: string): Buffer {
  let pem: Buffer;
  try {
    pem = fs.readFileSync(file);
  } catch (err) {
    return badUrl(`ca=${file}: cannot read the file (${(err as NodeJS.ErrnoException).code ?? (err as Error).message})`);
  }
  try {
    new crypto.X509Certificate(pem);
  } catch {
    return badUrl(`ca=${file}: the file holds no PEM certificate (-----BEGIN CERTIFICATE-----)`);
  }
  return pem;
}

/**
 * Options for `tls.connect` over a tunnel: TLS 1.2 and 1.3 both offered
 * (S7-1500 firmware before V3.0 refuses a client that offers only 1.3), the
 * S7 suites, groups and options. The certificate is not judged by Node
 * (rejectUnauthorized false) but by `judgeCertificate` once the handshake is
 * done, so every refusal has our words; with `ca=` Node's chain check result
 * (`authorized`) is one of its inputs.
 */
export function clientTlsOptions(trust: TlsTrust): tls.ConnectionOptions {
  if (trust.fingerprint !== undefined) parseFingerprint(trust.fingerprint);
  return {
    minVersion: 'TLSv1.2',
    maxVersion: 'TLSv1.3',
    ciphers: S7_CIPHERS,
    ecdhCurve: S7_GROUPS,
    secureOptions: S7_SECURE_OPTIONS,
    rejectUnauthorized: false,
    checkServerIdentity: () => undefined,
    ...(trust.ca !== undefined ? { ca: readCa(trust.ca) } : {}),
  };
}

function describeCertificate(cert: crypto.X509Certificate): CertificateInfo {
  return {
    fingerprint: fingerprint256(cert.raw),
    subject: oneLine(cert.subject),
    issuer: oneLine(cert.issuer),
    notBefore: new Date(cert.validFrom),
    notAfter: new Date(cert.validTo),
    ...(cert.subjectAltName ? { altNames: cert.subjectAltName } : {}),
  };
}

const oneLine = (dn: string) => dn.split('\n').filter(Boolean).join(', ');
const day = (d: Date) => d.toISOString().replace(/\.\d{3}Z$/, 'Z');

/** "SHA-256 AB…, subject CN=…, issuer …, valid from … to …" */
function shown(c: CertificateInfo): string {
  const issuer = c.issuer === c.subject ? 'self-signed' : `issuer ${c.issuer}`;
  return `SHA-256 ${c.fingerprint}, subject ${c.subject}, ${issuer}, valid from ${day(c.notBefore)} to ${day(c.notAfter)}`;
}

/** What the TLS socket says about the peer, for `judgeCertificate`. */
export interface PeerView {
  certificate: crypto.X509Certificate | undefined;
  /** Node's chain check against `ca=` (only meaningful with a CA). */
  authorized: boolean;
  authorizationError?: string | Error;
}

/** The outcome of a trusted handshake: the certificate, and the warning to emit when trust was not checked. */
export interface TrustVerdict {
  certificate: CertificateInfo;
  warning?: string;
}

/**
 * Decides whether the PLC at `host` may be talked to. Throws a
 * CertificateError (CERTIFICATE_UNTRUSTED) in our words; with
 * `insecure=true` returns a warning instead (but a `fingerprint=` given
 * beside it must still match).
 */
export function judgeCertificate(peer: PeerView, trust: TlsTrust, host: string, now = new Date()): TrustVerdict {
  if (!peer.certificate) throw new PlcError('PROTOCOL_ERROR', `the PLC at ${host} completed the TLS handshake without a certificate`);
  const c = describeCertificate(peer.certificate);
  const pinIt = `fingerprint=${c.fingerprint}`;
  const pin = trust.fingerprint === undefined ? undefined : parseFingerprint(trust.fingerprint);
  if (pin !== undefined && pin !== c.fingerprint) {
    throw new CertificateError(
      'wrong-pin',
      c,
      `the TLS certificate of ${host} is not the pinned one: fingerprint= says ${pin}, the PLC shows ${shown(c)}. ` +
        `If the PLC's certificate was renewed on purpose, pin the new one with ${pinIt}; otherwise something else answers at this address.`,
    );
  }
  // insecure=true accepts anything else; a pin given beside it is still honoured (above).
  if (trust.insecure) {
    return {
      certificate: c,
      warning:
        pin !== undefined
          ? `insecure=true: the pinned TLS certificate of ${host} is used without checking its validity (${shown(c)}).`
          : `insecure=true: the TLS certificate of ${host} is not checked (${shown(c)}); anyone on the network path could ` +
            `read and change this connection. To trust this certificate, use ${pinIt} instead.`,
    };
  }
  if (now.getTime() > c.notAfter.getTime()) {
    throw new CertificateError(
      'expired',
      c,
      `the TLS certificate of ${host} expired on ${day(c.notAfter)} (this computer's clock says ${day(now)}): ${shown(c)}. ` +
        `Renew the PLC's certificate in TIA Portal and download it, or correct this computer's clock.`,
    );
  }
  if (now.getTime() < c.notBefore.getTime()) {
    throw new CertificateError(
      'not-yet-valid',
      c,
      `the TLS certificate of ${host} is not valid before ${day(c.notBefore)} (this computer's clock says ${day(now)}): ${shown(c)}. ` +
        `Check the clocks of this computer and of the PLC.`,
    );
  }
  if (pin !== undefined && trust.ca === undefined) return { certificate: c };
  if (trust.ca !== undefined) {
    if (!peer.authorized) {
      const why = String(peer.authorizationError ?? 'not verified');
      throw new CertificateError(
        'not-signed-by-ca',
        c,
        `the TLS certificate of ${host} is not signed by the CA in ca=${trust.ca} (${why}): ${shown(c)}. ` +
          `If this is your PLC's certificate (compare the fingerprint with TIA Portal), pin it with ${pinIt}.`,
      );
    }
    if (pin === undefined && !matchesHost(peer.certificate, host)) {
      throw new CertificateError(
        'wrong-name',
        c,
        `the TLS certificate of ${host} is signed by the CA in ca=${trust.ca} but issued for ${c.altNames ?? c.subject}, not ${host}: ` +
          `${shown(c)}. Connect by a name or address the certificate names, or pin this certificate with ${pinIt}.`,
      );
    }
    return { certificate: c };
  }
  throw new CertificateError(
    'not-trusted',
    c,
    `the TLS certificate of ${host} is not trusted: nothing in the URL pins it (fingerprint=) or names its CA (ca=): ${shown(c)}. ` +
      `If this is your PLC's certificate (compare the fingerprint with TIA Portal), add ${pinIt} to the URL.`,
  );
}

function matchesHost(cert: crypto.X509Certificate, host: string): boolean {
  return net.isIP(host) ? cert.checkIP(host) !== undefined : cert.checkHost(host) !== undefined;
}
