/**
 * The ISO connect step, for any driver over ISO-on-TCP: a TCP connection,
 * then COTP CR → CC with the driver's TSAPs and TPDU size. Every answer other
 * than a confirm is an IsoConnectError that says which it was (a disconnect
 * and its reason, a TPDU error and its cause, another TPDU, bytes that are not
 * TPKT, the connection closed, silence), so a driver puts it in its own words
 * and a diagnosis can tell them apart. Not pure (sockets, timers).
 */
import type * as net from 'node:net';
import { ConnectionError } from '../errors';
import { openTcp } from '../link/tcp';
import { DR_ADDRESS_UNKNOWN, DR_CONGESTION, tpduBytes } from './constants';
import { decodeCotp, encodeConnectionRequest, type CotpConnection, type CotpTsap } from './cotp';
import { IsoFrames } from './frames';

/** What the peer did instead of confirming a connection request. */
export type IsoRefusal =
  /** A COTP disconnect request (DR) with its reason (DR_CONGESTION, DR_ADDRESS_UNKNOWN …). */
  | { kind: 'disconnect'; reason: number }
  /** A COTP TPDU error (ER) with its reject cause. */
  | { kind: 'error'; cause: number }
  /** Another COTP TPDU (DC, DT, CR) where a confirm belongs. */
  | { kind: 'unexpected'; type: 'CR' | 'DC' | 'DT' }
  /** Bytes that are not TPKT and COTP: another protocol on the port. */
  | { kind: 'garbage'; message: string }
  /** The peer closed the connection without an answer (`error`: the socket's, a reset, when there was one). */
  | { kind: 'closed'; error?: Error }
  /** No answer within `answerTimeout` ms. */
  | { kind: 'silent'; ms: number };

/** The connection request was not confirmed: code TIMEOUT for silence, else CONNECT_FAILED; `refusal` says what came instead. */
export class IsoConnectError extends ConnectionError {
  readonly refusal: IsoRefusal;

  constructor(name: string, refusal: IsoRefusal, cause?: Error) {
    super(refusal.kind === 'silent' ? 'TIMEOUT' : 'CONNECT_FAILED', `${name}: ${describeRefusal(refusal)}`, cause ? { cause } : {});
    this.refusal = refusal;
  }
}

const DR_REASONS: Readonly<Record<number, string>> = {
  [DR_CONGESTION]: 'congestion at the TSAP: all connections in use',
  [DR_ADDRESS_UNKNOWN]: 'the called TSAP is unknown',
};

function describeRefusal(r: IsoRefusal): string {
  switch (r.kind) {
    case 'disconnect':
      return `the connection request was refused (COTP disconnect, reason ${r.reason}${DR_REASONS[r.reason] ? `: ${DR_REASONS[r.reason]}` : ''})`;
    case 'error':
      return `the connection request was rejected (COTP TPDU error, cause ${r.cause})`;
    case 'unexpected':
      return `a COTP ${r.type} instead of a connection confirm`;
    case 'garbage':
      return `the answer to the connection request is not ISO-on-TCP: ${r.message}`;
    case 'closed':
      return r.error ? r.error.message : 'the peer closed the connection without answering the connection request';
    case 'silent':
      return `no answer to the connection request within ${r.ms} ms`;
  }
}

/** A COTP connection request: the driver's TSAPs and TPDU size. */
export interface IsoConnectionRequest {
  /** Names the peer in errors ("s7://10.0.0.2:102"). */
  name: string;
  callingTsap: CotpTsap;
  calledTsap: CotpTsap;
  /** TPDU size code asked for (0x0A = 1024 bytes). */
  tpduSize: number;
  /** Our source reference (default 1). */
  sourceRef?: number;
  /** Ms to wait for the answer; without it only the signal or the end of the connection ends the wait. */
  answerTimeout?: number;
  signal?: AbortSignal;
}

/** What the peer confirmed. */
export interface IsoConfirm {
  /** The decoded CC: the peer's reference (`sourceRef`), the TSAPs and TPDU size code as it echoed them (-1, 0 when absent). */
  confirm: CotpConnection;
  /** The TPDU size in bytes the CC names (0 when it names none or an invalid code). */
  tpduBytes: number;
}

/**
 * CR → CC on an open socket, reading answers through `frames`. Resolves what
 * the peer confirmed; rejects with an IsoConnectError for any other answer, or
 * ABORTED (frames' own error) when the signal aborts. Leaves the socket open.
 */
export async function requestIsoConnection(socket: net.Socket, frames: IsoFrames, r: IsoConnectionRequest): Promise<IsoConfirm> {
  socket.write(
    encodeConnectionRequest({
      sourceRef: r.sourceRef ?? 0x0001,
      callingTsap: r.callingTsap,
      calledTsap: r.calledTsap,
      tpduSize: r.tpduSize,
    }),
  );
  const answer = await frames.next(r.answerTimeout);
  if (answer.kind === 'silent' || answer.kind === 'closed')
    throw new IsoConnectError(r.name, answer, answer.kind === 'closed' ? answer.error : undefined);
  if (answer.kind === 'garbage') throw new IsoConnectError(r.name, { kind: 'garbage', message: answer.error.message }, answer.error);
  let m;
  try {
    m = decodeCotp(answer.frame);
  } catch (err) {
    throw new IsoConnectError(r.name, { kind: 'garbage', message: (err as Error).message }, err as Error);
  }
  if (m.type === 'CC') return { confirm: m, tpduBytes: tpduBytes(m.tpduSize) };
  if (m.type === 'DR') throw new IsoConnectError(r.name, { kind: 'disconnect', reason: m.reason });
  if (m.type === 'ER') throw new IsoConnectError(r.name, { kind: 'error', cause: m.cause });
  throw new IsoConnectError(r.name, { kind: 'unexpected', type: m.type });
}

export interface IsoConnectOptions extends IsoConnectionRequest {
  host: string;
  port: number;
  /** Ms for the TCP connect. */
  timeout: number;
  /** TCP keep-alive probe delay (openTcp's default when absent; 0 disables). */
  keepAliveMs?: number;
}

/** An ISO connection: the socket, its frames from now on, and what the peer confirmed. */
export interface IsoConnection extends IsoConfirm {
  socket: net.Socket;
  /**
   * Still listening: the driver reads its own handshake's answers here, then
   * hands `frames.reader` and the socket to its session and calls
   * `frames.stop()` once the session's listeners are on.
   */
  frames: IsoFrames;
}

/**
 * TCP, then CR → CC. Rejects with openTcp's errors (CONNECT_FAILED, TIMEOUT,
 * ABORTED), an IsoConnectError, or ABORTED (`connecting to ${name} was
 * aborted`); on failure no socket or listener is left.
 */
export async function isoConnect(o: IsoConnectOptions): Promise<IsoConnection> {
  const socket = await openTcp({
    host: o.host,
    port: o.port,
    timeout: o.timeout,
    ...(o.signal ? { signal: o.signal } : {}),
    ...(o.keepAliveMs !== undefined ? { keepAliveMs: o.keepAliveMs } : {}),
  });
  const frames = new IsoFrames(socket, o.signal, `connecting to ${o.name}`);
  try {
    return { socket, frames, ...(await requestIsoConnection(socket, frames, o)) };
  } catch (err) {
    frames.stop();
    socket.destroy();
    throw err;
  }
}
