/**
 * The client's TLS step inside the COTP tunnel: the handshake with a
 * deadline, the trust decision before anything else is sent, and TLS
 * failures in our words. There is no plain-text fallback: every failure
 * rejects, and the caller closes the connection.
 */
import type { Duplex } from 'node:stream';
import * as tls from 'node:tls';
import { abortError, ConnectionError, PlcError, ProtocolError, TimeoutError } from '../../errors';
import { clientTlsOptions, judgeCertificate, type CertificateInfo, type TlsTrust } from './trust';

export interface StartTlsOptions {
  trust: TlsTrust;
  /** The PLC's host as the user wrote it: for messages and, with `ca=`, the name the certificate must carry. */
  host: string;
  /** Milliseconds for the whole handshake. */
  timeout: number;
  signal?: AbortSignal;
}

export interface SecureChannel {
  socket: tls.TLSSocket;
  certificate: CertificateInfo;
  /** 'TLSv1.2' or 'TLSv1.3'. */
  protocol: string;
  /** Set with `insecure=true`: say it on every connect. */
  warning?: string;
}

/**
 * Runs TLS over `tunnel` (a CotpTunnel after InitSSL) and judges the PLC's
 * certificate. Resolves once the channel may carry S7CommPlus; on any
 * failure the TLS socket (and with it the tunnel and the TCP socket) is
 * destroyed and the promise rejects with a PlcError: CERTIFICATE_UNTRUSTED,
 * TIMEOUT, ABORTED, CONNECT_FAILED (TLS refused), PROTOCOL_ERROR (not TLS).
 */
export function startTls(tunnel: Duplex, options: StartTlsOptions): Promise<SecureChannel> {
  const { trust, host, timeout, signal } = options;
  return new Promise((resolve, reject) => {
    if (signal?.aborted) {
      tunnel.destroy();
      return reject(abortError(`the TLS handshake with ${host}`, signal));
    }
    let socket: tls.TLSSocket;
    try {
      socket = tls.connect({ ...clientTlsOptions(trust), socket: tunnel });
    } catch (err) {
      tunnel.destroy();
      return reject(err instanceof PlcError ? err : new ConnectionError('CONNECT_FAILED', `TLS with ${host}: ${(err as Error).message}`));
    }
    const timer = setTimeout(
      () =>
        fail(
          new TimeoutError(
            `the TLS handshake with ${host} did not complete within ${timeout} ms: the PLC stopped answering ` +
              `(is secure PG/HMI communication enabled, and is this the PLC's address?)`,
          ),
        ),
      timeout,
    );
    const onAbort = () => fail(abortError(`the TLS handshake with ${host}`, signal!));
    const onError = (err: Error) => fail(tlsFailure(err, host, 'handshake'));
    const onClose = () => fail(new ConnectionError('CONNECT_FAILED', `the PLC at ${host} closed the connection during the TLS handshake`));
    function cleanup() {
      clearTimeout(timer);
      signal?.removeEventListener('abort', onAbort);
      socket.removeListener('error', onError);
      socket.removeListener('close', onClose);
      socket.removeListener('secureConnect', onSecure);
    }
    function fail(err: PlcError) {
      cleanup();
      // The TLS socket may still report its own end; it is ours to silence now.
      socket.on('error', () => {});
      socket.destroy();
      tunnel.destroy();
      reject(err);
    }
    function onSecure() {
      let verdict;
      try {
        verdict = judgeCertificate(
          { certificate: socket.getPeerX509Certificate(), authorized: socket.authorized, authorizationError: socket.authorizationError },
          trust,
          host,
        );
      } catch (err) {
        return fail(err instanceof PlcError ? err : new ProtocolError(String(err)));
      }
      cleanup();
      resolve({
        socket,
        certificate: verdict.certificate,
        protocol: socket.getProtocol() ?? 'unknown',
        ...(verdict.warning ? { warning: verdict.warning } : {}),
      });
    }
    socket.once('secureConnect', onSecure);
    socket.on('error', onError);
    socket.once('close', onClose);
    signal?.addEventListener('abort', onAbort, { once: true });
  });
}

/**
 * A TLS socket's error as a PlcError. An alert the PLC sent ends the
 * session (CONNECT_FAILED during the handshake, CONNECTION_LOST after);
 * bytes that are not valid TLS are a PROTOCOL_ERROR; our own errors (the
 * tunnel's) are kept as they are.
 */
export function tlsFailure(err: Error, host: string, during: 'handshake' | 'session'): PlcError {
  if (err instanceof PlcError) return err;
  const code = (err as NodeJS.ErrnoException).code ?? '';
  const reason = (err as { reason?: string }).reason ?? err.message;
  const where = during === 'handshake' ? `the TLS handshake with ${host}` : `the TLS session with ${host}`;
  if (/ALERT/.test(code)) {
    const what = `${where} ended with an alert from the PLC (${reason})`;
    const hint =
      during === 'handshake' && /HANDSHAKE_FAILURE|PROTOCOL_VERSION|INSUFFICIENT_SECURITY/.test(code)
        ? ': the PLC accepts none of the TLS versions or suites offered (TLS 1.2 and 1.3, AES-GCM); check its firmware and its secure communication settings'
        : '';
    return new ConnectionError(during === 'handshake' ? 'CONNECT_FAILED' : 'CONNECTION_LOST', what + hint, { cause: err });
  }
  if (code.startsWith('ERR_SSL_')) {
    return new ProtocolError(`${where} failed: the PLC sent data that is not valid TLS (${reason})`, { cause: err });
  }
  return new ConnectionError(during === 'handshake' ? 'CONNECT_FAILED' : 'CONNECTION_LOST', `${where} failed: ${err.message}`, {
    cause: err,
  });
}
