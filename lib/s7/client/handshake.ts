/**
 * The S7 handshake as steps: TCP and COTP connection request → confirm (the
 * ISO connect step, lib/iso/connect.ts, with S7's TSAPs), setup
 * communication → its ack (`exchangeSetup`). `openS7Session` runs them and
 * hands the socket, its frame reader and what was negotiated to a new
 * S7Session, which owns them from then on. The connection doctor runs the
 * same steps and reads their answers in its own words.
 */
import type * as net from 'node:net';
import { abortError, ConnectionError, ProtocolError, toPlcError } from '../../errors';
import { IsoConnectError, isoConnect, type IsoConnection, type IsoConnectionRequest } from '../../iso/connect';
import type { FrameResult, IsoFrames } from '../../iso/frames';
import type { S7Endpoint } from '../url';
import { decodeS7, encodeSetupCommunication } from '../codec';
import { headerError, REQUESTED_AMQ, TPDU_SIZE_CODE } from '../constants';
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
  const { socket, frames } = await requestConnection(e, o);
  try {
    const negotiated = await setupCommunication(socket, frames, e, o.name);
    // The session's listeners go on before the handshake's come off, so no socket event is ever unheard.
    const session = new S7Session(socket, frames.reader, negotiated, {
      name: o.name,
      timeout: o.requestTimeout ?? o.timeout,
      maxQueued: o.maxQueued,
      stats: o.stats,
      lossError: o.lossError,
      lost: o.lost,
    });
    frames.stop();
    return session;
  } catch (err) {
    frames.stop();
    socket.destroy();
    if (o.signal.aborted) throw abortError(`connecting to ${o.name}`, o.signal);
    const e2 = toPlcError(err, 'CONNECT_FAILED');
    throw e2.code === 'PROTOCOL_ERROR' ? new ConnectionError('CONNECT_FAILED', `${o.name}: ${e2.message}`, { cause: e2 }) : e2;
  }
}

/** The COTP connection request of an endpoint: the TSAPs it names (rack/slot, or configured TSAPs) and our TPDU size. */
function s7ConnectionRequest(e: S7Endpoint, name: string): IsoConnectionRequest & { callingTsap: number; calledTsap: number } {
  return {
    name,
    calledTsap: e.remoteTsap ?? remoteTsapFor(e.connectionType, e.rack, e.slot),
    callingTsap: e.localTsap ?? localTsapFor(e.connectionType),
    tpduSize: TPDU_SIZE_CODE,
  };
}

/** TCP, then COTP CR → CC (lib/iso/connect.ts): the PLC takes the connection at the endpoint's TSAPs; a refusal in S7's words. */
async function requestConnection(e: S7Endpoint, o: OpenOptions): Promise<IsoConnection> {
  const request = s7ConnectionRequest(e, o.name);
  try {
    return await isoConnect({ ...request, host: e.host, port: e.port, timeout: o.timeout, signal: o.signal });
  } catch (err) {
    if (!(err instanceof IsoConnectError)) throw err;
    const r = err.refusal;
    if (r.kind === 'garbage') throw new ConnectionError('CONNECT_FAILED', `${o.name}: ${r.message}`, { cause: err.cause });
    if (r.kind === 'closed') {
      if (r.error) throw new ConnectionError('CONNECT_FAILED', `${o.name}: ${r.error.message}`, { cause: r.error });
      throw new ConnectionError(
        'CONNECT_FAILED',
        `${o.name} closed the connection during the handshake (wrong rack/slot or TSAP, or the connection limit is reached)`,
      );
    }
    const where = e.remoteTsap !== undefined ? `TSAP 0x${hex4(request.calledTsap)}` : `rack ${e.rack}, slot ${e.slot}`;
    throw new ConnectionError(
      'CONNECT_FAILED',
      `${o.name} refused the connection (${where}): wrong rack/slot or TSAP, or the PLC's connection limit is reached`,
    );
  }
}

/** How a PLC answered setup communication: what it granted, or what came instead. */
export type SetupAnswer =
  | { kind: 'granted'; pduSize: number; maxJobs: number }
  /** An ack with a header error: class and code (headerError puts them in words). */
  | { kind: 'refused'; errorClass: number; errorCode: number }
  /** An S7 PDU of another kind (decodeS7's `kind`). */
  | { kind: 'other'; what: string }
  /** A PDU size below 64 bytes, which no job fits. */
  | { kind: 'unusable'; pduSize: number }
  | Exclude<FrameResult, { kind: 'frame' }>;

/**
 * Setup communication → its ack, on a socket whose COTP connection stands: the
 * PDU size and parallel jobs (AmQ) the PLC grants, or what came instead.
 * `ms`: how long to wait for the answer (none: until the signal of `frames`).
 * Throws ProtocolError for an answer that is not an S7 PDU, ABORTED on abort.
 */
export async function exchangeSetup(socket: net.Socket, frames: IsoFrames, pduSize: number, ms?: number): Promise<SetupAnswer> {
  socket.write(encodeSetupCommunication(0, { maxAmqCalling: REQUESTED_AMQ, maxAmqCalled: REQUESTED_AMQ, pduSize }));
  const answer = await frames.next(ms);
  if (answer.kind !== 'frame') return answer;
  const ack = decodeS7(answer.frame);
  if (ack.kind === 'error') return { kind: 'refused', errorClass: ack.errorClass, errorCode: ack.errorCode };
  if (ack.kind !== 'setup-ack') return { kind: 'other', what: ack.kind };
  const { maxAmqCalling, maxAmqCalled } = ack.params;
  if (ack.params.pduSize < 64) return { kind: 'unusable', pduSize: ack.params.pduSize };
  // The PLC answers with what it grants; a 0 would mean "none", which no CPU sends: treat as 1.
  // More than we asked for is not ours to use.
  return { kind: 'granted', pduSize: ack.params.pduSize, maxJobs: Math.max(1, Math.min(maxAmqCalling, maxAmqCalled, REQUESTED_AMQ)) };
}

/** Setup communication → its ack, as the client needs it: the grant, or an error. */
async function setupCommunication(
  socket: net.Socket,
  frames: IsoFrames,
  e: S7Endpoint,
  name: string,
): Promise<{ pduSize: number; maxJobs: number }> {
  const answer = await exchangeSetup(socket, frames, e.pduSize);
  switch (answer.kind) {
    case 'granted':
      return { pduSize: answer.pduSize, maxJobs: answer.maxJobs };
    case 'refused':
      throw headerError(answer.errorClass, answer.errorCode, `${name} setup communication`);
    case 'other':
      throw new ProtocolError(`${name}: expected the answer to setup communication, got ${answer.what}`);
    case 'unusable':
      throw new ProtocolError(`${name} negotiated an unusable PDU size of ${answer.pduSize}`);
    case 'garbage':
      throw answer.error;
    case 'closed':
      if (answer.error) throw new ConnectionError('CONNECT_FAILED', `${name}: ${answer.error.message}`, { cause: answer.error });
      throw new ConnectionError(
        'CONNECT_FAILED',
        `${name} closed the connection during the handshake (wrong rack/slot or TSAP, or the connection limit is reached)`,
      );
    case 'silent': // no wait of its own: the supervisor's signal ends it
      throw new ProtocolError(`${name}: no answer to setup communication within ${answer.ms} ms`);
  }
}
