/**
 * The PLC's certificate without trusting it (the connection dialog's "Get
 * certificate", issue #25): TCP, COTP with the S7CommPlus TSAPs, InitSSL,
 * then a TLS handshake that takes any certificate; the connection is closed
 * right after it, before any S7CommPlus request (no session, nothing read or
 * written). The steps are the client's own (tunnel.ts, handshake.ts).
 */
import { PlcError } from '../../errors';
import type { S7PlusEndpoint } from '../url';
import { startTls } from '../transport/handshake';
import { initSsl, peerCertificate, type PeerCertificate } from './handshake';
import { openTunnel } from './tunnel';

export async function peekCertificate(endpoint: S7PlusEndpoint, options: { signal: AbortSignal }): Promise<PeerCertificate> {
  if (!endpoint.tls) throw new PlcError('INVALID_URL', 'tls=false: the PLC is asked for plain S7CommPlus, without a certificate');
  const { signal } = options;
  const name = `s7plus://${endpoint.host}:${endpoint.port}`;
  const tunnel = await openTunnel(endpoint, { name, timeout: endpoint.timeout, signal });
  try {
    await initSsl(tunnel, { name, signal });
    // insecure: take any certificate, to show it; the socket is closed at once, the session never starts.
    const { socket, certificate } = await startTls(tunnel, {
      trust: { insecure: true },
      host: endpoint.host,
      timeout: endpoint.timeout,
      signal,
    });
    socket.destroy();
    return peerCertificate(certificate);
  } finally {
    tunnel.destroy();
  }
}
