/**
 * The S7 handshake as steps: TCP, COTP connection request → confirm, setup
 * communication → its ack. `openS7Session` runs them and hands the socket,
 * its frame reader and what was negotiated to a new S7Session, which owns
 * them from then on.
 */
import type * as net from 'node:net';
import { abortError, ConnectionError, ProtocolError, toPlcError } from '../../errors';
import { FrameReader } from '../../link/framer';
import { openTcp } from '../../link/tcp';
import type { S7Endpoint } from '../url';
import { checkTpkt, decodeCotp, decodeS7, encodeConnectionRequest, encodeSetupCommunication } from '../codec';
import { headerError, REQUESTED_AMQ, TPDU_SIZE_CODE } from '../constants';
import { MAX_FRAME } from '../../iso/constants';
import { localTsapFor, remoteTsapFor } from '../tsap';
import { S7Session, type SessionWiring } from './session';
import { hex4 } from '../../values/text';

export interface OpenOptions extends Omit<SessionWiring, 'timeout'> {
  /** For the TCP connect; the supervisor aborts `signal` when the whole handshake takes longer. */
  timeout: number;
  /** Per job; defaults to `timeout`. */
  requestTimeout?: number;
  signal: AbortSignal;
}

/**
 * TCP, COTP CR → CC, setup communication → its ack. Resolves a session with
 * the negotiated PDU size and AmQ; rejects with a PlcError (CONNECT_FAILED,
 * TIMEOUT, ABORTED, ACCESS_DENIED …) and leaves no socket behind.
 */
export async function openS7Session(e: S7Endpoint, o: OpenOptions): Promise<S7Session> {
  const socket = await openTcp({ host: e.host, port: e.port, timeout: o.timeout, signal: o.signal });
  // The socket's chunks are ours: frames are cut from them without a copy.
  const reader = new FrameReader(checkTpkt, MAX_FRAME, { copy: false });
  const next = frameWaiter(socket, reader, o.signal, o.name);
  try {
    await requestConnection(socket, next, e, o.name);
    const negotiated = await setupCommunication(socket, next, e, o.name);
    // The session's listeners go on before the handshake's come off, so no socket event is ever unheard.
    const session = new S7Session(socket, reader, negotiated, {
      name: o.name,
      timeout: o.requestTimeout ?? o.timeout,
      maxQueued: o.maxQueued,
      stats: o.stats,
      lossError: o.lossError,
      lost: o.lost,
    });
    next.stop();
    return session;
  } catch (err) {
    next.stop();
    socket.destroy();
    if (o.signal.aborted) throw abortError(`connecting to ${o.name}`, o.signal);
    const e2 = toPlcError(err, 'CONNECT_FAILED');
    throw e2.code === 'PROTOCOL_ERROR' ? new ConnectionError('CONNECT_FAILED', `${o.name}: ${e2.message}`, { cause: e2 }) : e2;
  }
}

/** COTP CR → CC: the PLC takes the connection at the TSAPs the endpoint names (rack/slot, or configured TSAPs). */
async function requestConnection(socket: net.Socket, next: FrameWaiter, e: S7Endpoint, name: string): Promise<void> {
  const calledTsap = e.remoteTsap ?? remoteTsapFor(e.connectionType, e.rack, e.slot);
  const callingTsap = e.localTsap ?? localTsapFor(e.connectionType);
  socket.write(encodeConnectionRequest({ sourceRef: 0x0001, callingTsap, calledTsap, tpduSize: TPDU_SIZE_CODE }));
  const cc = decodeCotp(await next());
  if (cc.type !== 'CC') {
    const where = e.remoteTsap !== undefined ? `TSAP 0x${hex4(calledTsap)}` : `rack ${e.rack}, slot ${e.slot}`;
    throw new ConnectionError(
      'CONNECT_FAILED',
      `${name} refused the connection (${where}): wrong rack/slot or TSAP, or the PLC's connection limit is reached`,
    );
  }
}

/** Setup communication → its ack: the PDU size and parallel jobs (AmQ) the PLC grants. */
async function setupCommunication(
  socket: net.Socket,
  next: FrameWaiter,
  e: S7Endpoint,
  name: string,
): Promise<{ pduSize: number; maxJobs: number }> {
  socket.write(encodeSetupCommunication(0, { maxAmqCalling: REQUESTED_AMQ, maxAmqCalled: REQUESTED_AMQ, pduSize: e.pduSize }));
  const ack = decodeS7(await next());
  if (ack.kind === 'error') throw headerError(ack.errorClass, ack.errorCode, `${name} setup communication`);
  if (ack.kind !== 'setup-ack') throw new ProtocolError(`${name}: expected the answer to setup communication, got ${ack.kind}`);
  const { pduSize, maxAmqCalling, maxAmqCalled } = ack.params;
  if (pduSize < 64) throw new ProtocolError(`${name} negotiated an unusable PDU size of ${pduSize}`);
  // The PLC answers with what it grants; a 0 would mean "none", which no CPU sends: treat as 1.
  // More than we asked for is not ours to use.
  return { pduSize, maxJobs: Math.max(1, Math.min(maxAmqCalling, maxAmqCalled, REQUESTED_AMQ)) };
}

interface FrameWaiter {
  (): Promise<Buffer>;
  stop(): void;
}

/** Whole frames from the socket during the handshake; each call resolves the next one, or rejects on close/error/abort. */
function frameWaiter(socket: net.Socket, reader: FrameReader, signal: AbortSignal, name: string): FrameWaiter {
  const frames: Buffer[] = [];
  let waiting: { resolve: (b: Buffer) => void; reject: (e: Error) => void } | undefined;
  let failure: Error | undefined;
  const flush = () => {
    if (!waiting) return;
    const w = waiting;
    if (frames.length > 0) {
      waiting = undefined;
      w.resolve(frames.shift()!);
    } else if (failure) {
      waiting = undefined;
      w.reject(failure);
    }
  };
  const fail = (err: Error) => {
    failure ??= err;
    flush();
  };
  const onData = (chunk: Buffer) => {
    try {
      frames.push(...reader.push(chunk));
    } catch (err) {
      failure ??= toPlcError(err, 'PROTOCOL_ERROR');
    }
    flush();
  };
  const onClose = () =>
    fail(
      new ConnectionError(
        'CONNECT_FAILED',
        `${name} closed the connection during the handshake (wrong rack/slot or TSAP, or the connection limit is reached)`,
      ),
    );
  const onError = (err: Error) => fail(new ConnectionError('CONNECT_FAILED', `${name}: ${err.message}`, { cause: err }));
  const onAbort = () => fail(abortError(`connecting to ${name}`, signal));
  socket.on('data', onData);
  socket.on('close', onClose);
  socket.on('error', onError);
  signal.addEventListener('abort', onAbort, { once: true });
  const next = () =>
    new Promise<Buffer>((resolve, reject) => {
      waiting = { resolve, reject };
      flush();
    });
  return Object.assign(next, {
    stop() {
      socket.removeListener('data', onData);
      socket.removeListener('close', onClose);
      socket.removeListener('error', onError);
      signal.removeEventListener('abort', onAbort);
    },
  });
}
