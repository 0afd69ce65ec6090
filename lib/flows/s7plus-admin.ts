/**
 * The answers of the connection dialog's S7CommPlus questions (issue #25),
 * without Node-RED (nodes/shared/s7plus-admin.js serves them):
 *
 * certificateAnswer(url) → { ok, fingerprint, bytes, subject, validFrom, validTo }:
 *   the PLC's certificate taken without trusting it, closed before any
 *   session (lib/s7plus/client/certificate.ts); `bytes`: the fingerprint as
 *   TIA Portal shows it, byte by byte (the dialog joins them by colons).
 * browseAnswer(url, { password }) → { ok, blocks, entries, types, errors }:
 *   the PLC's table in the shape of the sources' compile (describe()).
 *
 * Either is { ok: false, code, message } when it fails (a URL that is not
 * s7plus:// is INVALID_URL); neither ever holds the password. Each ends at
 * `signal` (the caller's deadline, or its request going away).
 */
import { PlcError, toPlcError } from '../errors';
import { peekCertificate } from '../s7plus/client/certificate';
import { fingerprintBytes } from '../s7plus/transport/fingerprint';
import { isS7PlusEndpoint, type S7PlusEndpoint } from '../s7plus/url';
import { parseUrl } from '../url';
import { browsePlc } from './plc-tables';
import { describe, type SymbolsDescription } from './symbol-config';

type Failure = { ok: false; code: string; message: string };
export type CertificateAnswer =
  { ok: true; fingerprint: string; bytes: string[]; subject: string; validFrom: string; validTo: string } | Failure;
export type BrowseAnswer = ({ ok: true } & SymbolsDescription) | Failure;

/** An error as the dialog is told it. */
function failure(err: unknown): Failure {
  const e = toPlcError(err, 'PLC_ERROR');
  return { ok: false, code: e.code, message: e.message };
}

/** The s7plus:// endpoint of a request's URL; throws the parser's error or INVALID_URL for any other URL. */
function s7plusEndpoint(url: string): S7PlusEndpoint {
  const endpoint = parseUrl(url.trim());
  if (!isS7PlusEndpoint(endpoint)) {
    throw new PlcError('INVALID_URL', 'the PLC certificate and Browse PLC need an s7plus:// URL (S7CommPlus)');
  }
  return endpoint;
}

/** The PLC's certificate, trusting nothing: nothing after the TLS handshake goes on the wire. */
export async function certificateAnswer(url: string, signal: AbortSignal): Promise<CertificateAnswer> {
  try {
    const c = await peekCertificate(s7plusEndpoint(url), { signal });
    return {
      ok: true,
      fingerprint: c.fingerprint,
      bytes: fingerprintBytes(c.fingerprint),
      subject: c.subject,
      validFrom: c.validFrom,
      validTo: c.validTo,
    };
  } catch (err) {
    return failure(err);
  }
}

/** The PLC's table as the dialog lists a compile's, through a connection of its own (closed on every path). */
export async function browseAnswer(url: string, options: { password?: string | undefined; signal: AbortSignal }): Promise<BrowseAnswer> {
  try {
    s7plusEndpoint(url);
    const password = options.password;
    const table = await browsePlc(url.trim(), { signal: options.signal, ...(password === undefined ? {} : { password }) });
    return { ok: true, ...describe({ table }) };
  } catch (err) {
    return failure(err);
  }
}
