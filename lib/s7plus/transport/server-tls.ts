/**
 * The simulator's side of S7CommPlus TLS: its certificate (made at start, or
 * read from the `--tls-cert`/`--tls-key` files) and the server handshake
 * over an accepted COTP tunnel, with the suites and groups a PLC uses.
 */
import * as crypto from 'node:crypto';
import * as fs from 'node:fs';
import type { Duplex } from 'node:stream';
import * as tls from 'node:tls';
import { ConnectionError, PlcError, TimeoutError, ValueError } from '../../errors';
import { fingerprint256, generateCertificate, type CertificateOptions } from './cert';
import { S7_CIPHERS, S7_GROUPS, S7_SECURE_OPTIONS } from './trust';
import { tlsFailure } from './handshake';

export interface ServerCertificate {
  /** PEM certificate (chain). */
  cert: string;
  /** PEM private key. Never printed. */
  key: string;
  /** SHA-256 of the (first) certificate: what a client pins with `fingerprint=`. */
  fingerprint: string;
  /** Where it came from, for the start-up line: "generated at start" or the file. */
  source: string;
}

/**
 * The certificate the simulator serves: from `certFile` and `keyFile` when
 * given (both or neither; a typed error names the file and what is wrong),
 * else a fresh self-signed one.
 */
export async function loadServerCertificate(
  files: { certFile?: string; keyFile?: string } = {},
  generate: CertificateOptions = {},
): Promise<ServerCertificate> {
  const { certFile, keyFile } = files;
  if (certFile === undefined && keyFile === undefined) {
    const made = await generateCertificate(generate);
    return { cert: made.cert, key: made.key, fingerprint: made.fingerprint, source: 'generated at start' };
  }
  if (certFile === undefined || keyFile === undefined) {
    throw new ValueError('--tls-cert/--tls-key', `give both files (only ${certFile === undefined ? '--tls-key' : '--tls-cert'} was given)`);
  }
  const cert = readText(certFile, '--tls-cert');
  const key = readText(keyFile, '--tls-key');
  let x509: crypto.X509Certificate;
  try {
    x509 = new crypto.X509Certificate(cert);
  } catch {
    throw new ValueError('--tls-cert', `${certFile} holds no PEM certificate (-----BEGIN CERTIFICATE-----)`);
  }
  let privateKey: crypto.KeyObject;
  try {
    privateKey = crypto.createPrivateKey(key);
  } catch {
    // The key's contents never go into a message.
    throw new ValueError('--tls-key', `${keyFile} holds no PEM private key (or one protected by a passphrase)`);
  }
  if (!x509.checkPrivateKey(privateKey)) {
    throw new ValueError('--tls-key', `${keyFile} is not the private key of the certificate in ${certFile}`);
  }
  return { cert, key, fingerprint: fingerprint256(x509.raw), source: certFile };
}

function readText(file: string, flag: string): string {
  try {
    return fs.readFileSync(file, 'utf8');
  } catch (err) {
    throw new ValueError(flag, `cannot read ${file} (${(err as NodeJS.ErrnoException).code ?? (err as Error).message})`);
  }
}

/**
 * The simulator's TLS settings with its certificate and key, made once (a CPU's: TLS 1.2 and 1.3, the S7 suites and
 * groups, no tickets): what acceptTls() serves every connection with.
 */
export function serverSecureContext(certificate: { readonly cert: string | Buffer; readonly key: string | Buffer }): tls.SecureContext {
  return tls.createSecureContext({
    cert: certificate.cert,
    key: certificate.key,
    minVersion: 'TLSv1.2',
    maxVersion: 'TLSv1.3',
    ciphers: S7_CIPHERS,
    ecdhCurve: S7_GROUPS,
    secureOptions: S7_SECURE_OPTIONS,
  });
}

/**
 * Runs the server side of TLS over an accepted tunnel, with `certificate` (or its serverSecureContext(), made once
 * for many connections). Resolves the TLS socket once the handshake is done; on failure, a deadline or a client
 * that leaves, everything is destroyed and the promise rejects.
 */
export function acceptTls(
  tunnel: Duplex,
  certificate: Pick<ServerCertificate, 'cert' | 'key'> | tls.SecureContext,
  options: { timeout: number; peer: string },
): Promise<tls.TLSSocket> {
  const { timeout, peer } = options;
  const secureContext = 'context' in certificate ? certificate : serverSecureContext(certificate);
  return new Promise((resolve, reject) => {
    const socket = new tls.TLSSocket(tunnel, { isServer: true, secureContext, requestCert: false });
    const timer = setTimeout(() => fail(new TimeoutError(`the TLS handshake with ${peer} did not complete within ${timeout} ms`)), timeout);
    const onError = (err: Error) => fail(tlsFailure(err, peer, 'handshake'));
    const onClose = () => fail(new ConnectionError('CONNECTION_LOST', `${peer} left during the TLS handshake`));
    function cleanup() {
      clearTimeout(timer);
      socket.removeListener('secure', onSecure);
      socket.removeListener('error', onError);
      socket.removeListener('close', onClose);
    }
    function fail(err: PlcError) {
      cleanup();
      socket.on('error', () => {});
      socket.destroy();
      tunnel.destroy();
      reject(err);
    }
    function onSecure() {
      cleanup();
      resolve(socket);
    }
    socket.once('secure', onSecure);
    socket.on('error', onError);
    socket.once('close', onClose);
  });
}
