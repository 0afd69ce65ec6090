/**
 * Our S7 simulator of an S7-1500 serving S7CommPlus over TLS with a certificate made for the test, and the pinned
 * s7plus:// URL of it: what the S7CommPlus tests against our own simulator start with.
 */
import { S7Server } from '../../lib/s7/server';
import { S7PlusService, type S7PlusOptions } from '../../lib/s7plus/server';
import { generateCertificate } from '../../lib/s7plus/transport/cert';

export interface PlusSimulator {
  server: S7Server;
  service: S7PlusService;
  /** `s7plus://127.0.0.1:<port>?fingerprint=…&timeout=10000`. */
  url: string;
}

export async function startPlusSimulator(options: Omit<S7PlusOptions, 'tls'>): Promise<PlusSimulator> {
  const cert = await generateCertificate();
  const service = new S7PlusService({ ...options, tls: { cert: cert.cert, key: cert.key } });
  const server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
  await server.listen();
  return { server, service, url: `s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=10000` };
}
