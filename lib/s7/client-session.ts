/**
 * One live S7 connection: the socket, its frame reader, the negotiated PDU
 * size and parallel jobs (AmQ), PDU references and the job queue. The
 * handshake (COTP CR/CC, setup communication) is `openS7Session`.
 */
import type * as net from 'node:net';
import { ConnectionError, PlcError, ProtocolError, toPlcError } from '../errors';
import { FrameReader } from '../link/framer';
import { JobQueue } from '../link/jobs';
import { PendingRequests, abortError } from '../link/pending';
import { openTcp } from '../link/tcp';
import type { S7Endpoint } from '../url';
import { checkTpkt, decodeCotp, decodeS7, encodeConnectionRequest, encodeSetupCommunication, type S7Message } from './codec';
import { headerError, remoteTsapFor } from './constants';

/** The largest TPKT frame we accept (the biggest S7 PDU is 65535 anyway; the PLC cannot make us buffer more). */
const MAX_FRAME = 0x10000 + 16;
/** What we ask for in setup communication; the PLC answers with what it grants. */
const REQUESTED_AMQ = 8;
/** TPDU size code asked in the COTP CR: 0x0A = 1024 bytes (S7-1500 offers PDU 960 only with it). */
const TPDU_SIZE_CODE = 0x0a;
const CONNECTION_TYPES = { pg: 1, op: 2, basic: 3 } as const;

export class S7Session {
  readonly pending = new PendingRequests<S7Message>();
  readonly jobs: JobQueue;
  /** Drops this session (set by the client when it attaches). */
  lose: ((err: PlcError) => void) | undefined;
  private nextRef = 0;

  constructor(
    readonly socket: net.Socket,
    readonly reader: FrameReader,
    /** The PDU size the PLC negotiated. */
    readonly pduSize: number,
    /** The parallel jobs (AmQ) the PLC negotiated. */
    readonly maxJobs: number,
    maxQueued: number | undefined,
  ) {
    this.jobs = new JobQueue({ concurrency: maxJobs, ...(maxQueued === undefined ? {} : { maxQueued }) });
  }

  /** The next PDU reference: 1..65535, skipping any still pending, so a late answer never matches a new job. */
  ref(): number {
    do this.nextRef = this.nextRef >= 0xffff ? 1 : this.nextRef + 1;
    while (this.pending.has(this.nextRef));
    return this.nextRef;
  }

  destroy(): void {
    this.socket.destroy();
  }
}

/** Local TSAP for rack/slot addressing: the connection type in the high byte (PG 0x0100, OP 0x0200, basic 0x0300). */
export function localTsapFor(type: S7Endpoint['connectionType']): number {
  return CONNECTION_TYPES[type] << 8;
}

export interface OpenOptions {
  name: string;
  /** For the TCP connect; the supervisor aborts `signal` when the whole handshake takes longer. */
  timeout: number;
  maxQueued: number | undefined;
  signal: AbortSignal;
  /** Installs the live listeners; called before the handshake's listeners go, so no socket event is ever unheard. */
  attach(session: S7Session): void;
}

/**
 * TCP, COTP CR → CC, setup communication → its ack. Resolves a session with
 * the negotiated PDU size and AmQ; rejects with a PlcError (CONNECT_FAILED,
 * TIMEOUT, ABORTED, ACCESS_DENIED …) and leaves no socket behind.
 */
export async function openS7Session(e: S7Endpoint, o: OpenOptions): Promise<S7Session> {
  const socket = await openTcp({ host: e.host, port: e.port, timeout: o.timeout, signal: o.signal });
  const reader = new FrameReader(checkTpkt, MAX_FRAME);
  const next = frameWaiter(socket, reader, o.signal, o.name);
  try {
    const calledTsap = e.remoteTsap ?? remoteTsapFor(e.connectionType, e.rack, e.slot);
    const callingTsap = e.localTsap ?? localTsapFor(e.connectionType);
    socket.write(encodeConnectionRequest({ sourceRef: 0x0001, callingTsap, calledTsap, tpduSize: TPDU_SIZE_CODE }));
    const cc = decodeCotp(await next());
    if (cc.type !== 'CC') {
      const where = e.remoteTsap !== undefined ? `TSAP 0x${calledTsap.toString(16).padStart(4, '0')}` : `rack ${e.rack}, slot ${e.slot}`;
      throw new ConnectionError('CONNECT_FAILED', `${o.name} refused the connection (${where}): wrong rack/slot or TSAP, or the PLC's connection limit is reached`);
    }
    socket.write(encodeSetupCommunication(0, { maxAmqCalling: REQUESTED_AMQ, maxAmqCalled: REQUESTED_AMQ, pduSize: e.pduSize }));
    const ack = decodeS7(await next());
    if (ack.kind === 'error') throw headerError(ack.errorClass, ack.errorCode, `${o.name} setup communication`);
    if (ack.kind !== 'setup-ack') throw new ProtocolError(`${o.name}: expected the answer to setup communication, got ${ack.kind}`);
    const { pduSize, maxAmqCalling, maxAmqCalled } = ack.params;
    if (pduSize < 64) throw new ProtocolError(`${o.name} negotiated an unusable PDU size of ${pduSize}`);
    // The PLC answers with what it grants; a 0 would mean "none", which no CPU sends: treat as 1.
    const maxJobs = Math.max(1, Math.min(maxAmqCalling, maxAmqCalled));
    const session = new S7Session(socket, reader, pduSize, maxJobs, o.maxQueued);
    o.attach(session);
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
    fail(new ConnectionError('CONNECT_FAILED', `${name} closed the connection during the handshake (wrong rack/slot or TSAP, or the connection limit is reached)`));
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
