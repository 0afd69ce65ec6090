/**
 * The S7CommPlus handshake as steps (s7commplus (MIT), connection.py,
 * connect): TCP → COTP CR/CC with the S7CommPlus TSAPs → InitSSL → TLS
 * (unless tls=false) → CreateObject of a ServerSession → session setup (the
 * ServerSessionVersion echoed) → IntegrityIds on (over TLS) → the password
 * (legitimation.ts), only when one is given. Each step says in words what
 * failed; a failure leaves no socket behind.
 */
import type { Duplex } from 'node:stream';
import type { TLSSocket } from 'node:tls';
import { abortError, ConnectionError, PlcError, TimeoutError, toPlcError } from '../../errors';
import type { S7PlusEndpoint } from '../url';
import { encodeFrames, S7pFrameReader } from '../codec/frame';
import { decodeInitSslResponse, encodeInitSslRequest, sessionInfo } from '../codec/session';
import { Ids, ProtocolVersion } from '../constants';
import { S7PlusSession, type S7PlusWireCounters, type S7PlusWiring } from './session';
import { sessionCreateAsk, sessionSetupAsk } from './asks';
import { startTls } from '../transport/handshake';
import type { CertificateInfo } from '../transport/trust';
import { openTunnel } from './tunnel';
import { deviceString } from '../codec/identity';
import { legitimate, type Protection } from './legitimation';

/** The PLC's certificate of a TLS connection, as the client tells it (`client.certificate`, the `insecure` event). */
export interface PeerCertificate {
  /** SHA-256 of the DER certificate, 64 upper-case hex digits: the `fingerprint=` that pins it. */
  fingerprint: string;
  subject: string;
  validFrom: string;
  validTo: string;
}

export function peerCertificate(c: CertificateInfo): PeerCertificate {
  return { fingerprint: c.fingerprint, subject: c.subject, validFrom: c.notBefore.toISOString(), validTo: c.notAfter.toISOString() };
}

/** How the client names itself in the session's CreateObject (the PLC shows it among its connections). */
const CLIENT_NAME = 'plcwire';

export interface OpenOptions extends Omit<S7PlusWiring, 'timeout'> {
  timeout: number;
  signal: AbortSignal;
  stats: S7PlusWireCounters;
  /** Told the PLC's certificate of a connection that trusts any (`insecure=true`): the client warns. */
  insecure?(certificate: PeerCertificate): void;
  /** Told each handshake step as it passes (the connection doctor shows them); a failure is the step after the last one told. */
  onStep?(passed: HandshakeStep): void;
  /** The PLC's password: given in the "password" step, used there and nowhere else. */
  password?: string | undefined;
}

/** A handshake step that passed, with what it learnt. */
export type HandshakeStep =
  | { step: 'cotp'; maxPayload: number }
  | { step: 'InitSSL' }
  | { step: 'TLS'; certificate: PeerCertificate; protocol: string; trust: 'pinned' | 'ca' | 'insecure' }
  | { step: 'session'; sessionId: number; version: number; device: string | undefined }
  | { step: 'password'; protection: Protection };

/** What a connection was opened with: its session, the PLC's certificate over TLS, its device string (order code, firmware). */
export interface Opened {
  session: S7PlusSession;
  certificate: PeerCertificate | undefined;
  /** ServerSessionVersion's device string (codec/identity.ts); undefined when the PLC sends none. */
  device: string | undefined;
  /** What the password step found (only when a password was given). */
  protection?: Protection;
}

/** A closing session says goodbye (DeleteObject) for at most this long after a refused password. */
const GOODBYE_MS = 2000;

export async function openS7PlusSession(e: S7PlusEndpoint, o: OpenOptions): Promise<Opened> {
  const tunnel = await openTunnel(e, o);
  o.onStep?.({ step: 'cotp', maxPayload: tunnel.maxPayload });
  let stream: Duplex = tunnel;
  let secure: TLSSocket | undefined;
  let session: S7PlusSession | undefined;
  let step: Step = 'InitSSL';
  // close() or the connect deadline during a step ends it at once, whatever that step waits for.
  const abandon = () => {
    session?.destroy();
    stream.destroy();
    tunnel.destroy();
  };
  o.signal.addEventListener('abort', abandon, { once: true });
  try {
    // InitSSL goes in plain text with sequence number 0, before TLS.
    await initSsl(tunnel, o);
    o.onStep?.({ step: 'InitSSL' });
    let certificate: PeerCertificate | undefined;
    if (e.tls) {
      step = 'TLS';
      // The transport's TLS step: the trust decision before any S7CommPlus byte, never a plain-text fallback.
      const trust = {
        ...(e.fingerprint ? { fingerprint: e.fingerprint } : {}),
        ...(e.ca ? { ca: e.ca } : {}),
        ...(e.insecure ? { insecure: true } : {}),
      };
      const started = await startTls(tunnel, { trust, host: e.host, timeout: o.timeout, signal: o.signal });
      stream = started.socket;
      secure = started.socket;
      certificate = peerCertificate(started.certificate);
      if (started.warning !== undefined) o.insecure?.(certificate);
      const trusted = e.fingerprint ? 'pinned' : e.ca ? 'ca' : 'insecure';
      o.onStep?.({ step: 'TLS', certificate, protocol: started.protocol, trust: trusted });
    }
    session = new S7PlusSession(
      stream,
      { sessionId: Ids.ObjectNullServerSession, version: ProtocolVersion.V1, nextSeq: 1 },
      { name: o.name, timeout: o.timeout, maxQueued: o.maxQueued, lossError: o.lossError, lost: o.lost, notify: o.notify },
      o.stats,
    );
    const signal = o.signal;
    step = 'CreateObject';
    const created = sessionInfo(await session.request(sessionCreateAsk({ name: CLIENT_NAME }), { integrity: false, signal }));
    const spoken = session.answerVersion;
    if (!e.tls && spoken !== ProtocolVersion.V1) {
      throw new ConnectionError(
        'CONNECT_FAILED',
        `${o.name} speaks S7CommPlus V${spoken} and wants it over TLS (tls=false asks for plain V1): drop tls=false` +
          ' (the PLC needs "secure PG/HMI communication" on), or use s7:// with standard-access data blocks',
      );
    }
    if (created.serverSessionVersion === undefined) {
      throw new ConnectionError(
        'CONNECT_FAILED',
        `${o.name} gave no ServerSessionVersion when the session was created: the session cannot be set up`,
      );
    }
    session.sessionId = created.sessionId;
    session.subscriptionContainerId = created.subscriptionContainerId;
    if (e.tls) session.version = ProtocolVersion.V2;
    const version = created.serverSessionVersion;
    step = 'session setup';
    const setup = await session.request(sessionSetupAsk(session.sessionId, version), {
      version: ProtocolVersion.V2,
      integrity: false,
      signal,
    });
    if (setup.returnValue !== 0n) {
      throw new ConnectionError('CONNECT_FAILED', `${o.name} refused the session setup (0x${setup.returnValue.toString(16)})`, {
        plcCode: Number(setup.returnValue & 0xffffn),
      });
    }
    if (e.tls) session.startIntegrity();
    const device = deviceString(version);
    o.onStep?.({ step: 'session', sessionId: session.sessionId, version: session.version, device });
    let protection: Protection | undefined;
    if (o.password !== undefined) {
      step = 'password';
      protection = await legitimate(session, {
        name: o.name,
        password: o.password,
        version: created.serverSessionVersion,
        tls: secure,
        signal,
      });
      o.onStep?.({ step: 'password', protection });
    }
    if (o.signal.aborted) throw abortError(`connecting to ${o.name}`, o.signal);
    return { session, certificate, device, ...(protection ? { protection } : {}) };
  } catch (err) {
    // A session the PLC set up is ended with a DeleteObject (a refused password leaves nothing open on the PLC).
    if (session?.alive && step === 'password' && !o.signal.aborted) await session.goodbye(Math.min(o.timeout, GOODBYE_MS));
    if (session) session.destroy();
    stream.destroy();
    tunnel.destroy();
    if (o.signal.aborted) throw abortError(`connecting to ${o.name}`, o.signal);
    const e2 = toPlcError(err, 'CONNECT_FAILED');
    if (e2 instanceof TimeoutError) throw new TimeoutError(`${step} failed: ${e2.message}`, { cause: e2 });
    if (e2.code !== 'PROTOCOL_ERROR' && e2.code !== 'CLOSED' && e2.code !== 'CONNECTION_LOST' && e2.code !== 'CONNECT_FAILED') throw e2;
    if (e2.code === 'CONNECT_FAILED' && step !== 'TLS' && step !== 'CreateObject') throw e2;
    const what = e2.message.startsWith(o.name) ? e2.message.slice(o.name.length).replace(/^:?\s*/, '') : e2.message;
    throw new ConnectionError('CONNECT_FAILED', `${o.name}: ${step} failed: ${what}${hint(e, step)}`, { cause: e2 });
  } finally {
    o.signal.removeEventListener('abort', abandon);
  }
}

/** The handshake's steps after the COTP connection, for messages. */
type Step = 'InitSSL' | 'TLS' | 'CreateObject' | 'session setup' | 'password';

/** What a failure at `step` most likely means, for the URL it used. */
function hint(e: S7PlusEndpoint, step: Step): string {
  if (step === 'TLS' && e.tls) {
    return ' (a PLC without secure PG/HMI communication speaks plain S7CommPlus: tls=false reaches it, without encryption)';
  }
  if (step === 'CreateObject' && !e.tls) return ' (a PLC with secure PG/HMI communication on wants TLS after InitSSL: drop tls=false)';
  return '';
}

/** InitSSL → its answer, on the plain tunnel (connection.py, _init_ssl); the deadline is the connect's. */
export function initSsl(tunnel: Duplex, o: { name: string; signal: AbortSignal }): Promise<void> {
  const cutter = new S7pFrameReader();
  return new Promise<void>((resolve, reject) => {
    const done = (err?: PlcError) => {
      tunnel.off('data', onData);
      tunnel.off('error', onError);
      tunnel.off('close', onClose);
      o.signal.removeEventListener('abort', onAbort);
      if (err) reject(err);
      else resolve();
    };
    const onData = (chunk: Buffer) => {
      try {
        const [m] = cutter.push(chunk);
        if (!m) return;
        const answer = decodeInitSslResponse(m.data);
        if (answer.header.sequence !== 0) {
          return done(new PlcError('PROTOCOL_ERROR', `${o.name} answered InitSSL with sequence ${answer.header.sequence}`));
        }
        done();
      } catch (err) {
        done(toPlcError(err, 'PROTOCOL_ERROR'));
      }
    };
    const onError = (err: Error) => done(new ConnectionError('CONNECT_FAILED', `${o.name}: ${err.message}`, { cause: err }));
    const onClose = () =>
      done(
        new ConnectionError(
          'CONNECT_FAILED',
          `${o.name} closed the connection at InitSSL: the CPU may not speak S7CommPlus (an S7-300/400: use s7://)`,
        ),
      );
    const onAbort = () => done(abortError(`connecting to ${o.name}`, o.signal));
    tunnel.on('data', onData);
    tunnel.on('error', onError);
    tunnel.on('close', onClose);
    o.signal.addEventListener('abort', onAbort, { once: true });
    tunnel.write(encodeFrames(ProtocolVersion.V1, encodeInitSslRequest(0)));
  });
}
