/**
 * One live S7 connection: the socket, its frame reader, the negotiated PDU
 * size and parallel jobs (AmQ), PDU references and the job queue. The
 * handshake (COTP CR/CC, setup communication) is `openS7Session`.
 */
import type * as net from 'node:net';
import { abortError, ConnectionError, PlcError, ProtocolError, TimeoutError, toPlcError } from '../../errors';
import { Fifo } from '../../link/fifo';
import { FrameReader } from '../../link/framer';
import { openTcp } from '../../link/tcp';
import type { S7Endpoint } from '../../url';
import { checkTpkt, decodeCotp, decodeS7, encodeConnectionRequest, encodeSetupCommunication } from '../codec';
import { headerError } from '../constants';
import { localTsapFor, remoteTsapFor } from '../tsap';

/** The largest TPKT frame we accept (the biggest S7 PDU is 65535 anyway; the PLC cannot make us buffer more). */
const MAX_FRAME = 0x10000 + 16;
/** What we ask for in setup communication; the PLC answers with what it grants. */
const REQUESTED_AMQ = 8;
/** TPDU size code asked in the COTP CR: 0x0A = 1024 bytes (S7-1500 offers PDU 960 only with it). */
const TPDU_SIZE_CODE = 0x0a;

/** Called once per job: with the PLC's answer frame (headers checked by the caller of answer()), or with the error that ended the wait. */
export type JobDone = (err: PlcError | undefined, answer: Buffer | undefined) => void;

interface InFlight {
  /** The job's PDU reference. */
  ref: number;
  done: JobDone | undefined;
  deadline: number;
  what: string;
  /** Called when the PLC answered or the session died: the request frame may be reused. */
  release: (() => void) | undefined;
}

interface Waiting {
  frame: Buffer;
  what: string;
  done: JobDone;
  release: (() => void) | undefined;
  signal: AbortSignal | undefined;
  onAbort: (() => void) | undefined;
}

const DEFAULT_MAX_QUEUED = 1000;

/**
 * One live S7 connection and its jobs. At most AmQ jobs are in flight; more
 * wait in a bounded FIFO. An AmQ slot is held until the PLC answers (an
 * aborted caller stops waiting, the PLC still works on the job). One timer
 * per session watches the oldest job: a job unanswered within the timeout
 * fails with TimeoutError and drops the link (the PLC still counts it).
 * No promise, closure or stack capture per job: this is the poll hot path.
 */
export class S7Session {
  /** Drops this session (set by the client when it attaches). */
  lose: ((err: PlcError) => void) | undefined;
  /** Counts each frame written (set by the client for its stats). */
  onSend: ((frame: Buffer) => void) | undefined;
  private nextRef = 0;
  /**
   * The jobs in flight, one slot per AmQ (at most 8), found by a scan. Not a
   * Map: a Map that jobs enter and leave rehashes every few jobs, and V8 links
   * each dropped table to its successor; once one of them is in the old
   * generation, the chain keeps every later table, with the answers and values
   * its jobs reached, alive through minor GCs (the figures: bench/README.md,
   * "Figures that used to be in comments").
   */
  private readonly slots: (InFlight | undefined)[];
  private running = 0;
  private readonly waiting = new Fifo<Waiting>();
  private timer: NodeJS.Timeout | undefined;
  private dead: PlcError | undefined;
  private readonly maxQueued: number;
  private corked = false;

  constructor(
    readonly socket: net.Socket,
    readonly reader: FrameReader,
    /** The PDU size the PLC negotiated. */
    readonly pduSize: number,
    /** The parallel jobs (AmQ) the PLC negotiated. */
    readonly maxJobs: number,
    maxQueued: number | undefined,
    private readonly timeout = 5000,
    private readonly name = 'S7',
  ) {
    this.maxQueued = maxQueued ?? DEFAULT_MAX_QUEUED;
    this.slots = new Array<InFlight | undefined>(Math.max(1, maxJobs)).fill(undefined);
  }

  private slotOf(ref: number): number {
    const { slots } = this;
    for (let i = 0; i < slots.length; i++) if (slots[i]?.ref === ref) return i;
    return -1;
  }

  /** Jobs sent and not answered yet (each holds an AmQ slot). */
  get inFlight(): number {
    return this.running;
  }

  /** Jobs waiting for a free AmQ slot. */
  get queued(): number {
    return this.waiting.size;
  }

  /** The next PDU reference: 1..65535, skipping any still in flight, so a late answer never matches a new job. */
  ref(): number {
    do this.nextRef = this.nextRef >= 0xffff ? 1 : this.nextRef + 1;
    while (this.slotOf(this.nextRef) >= 0);
    return this.nextRef;
  }

  /**
   * Sends a job frame (its PDU reference, bytes 11–12, is set here) when an
   * AmQ slot is free; `done` is called exactly once. `release` is called
   * when the frame is no longer needed (answered, or the session died).
   */
  send(frame: Buffer, what: string, done: JobDone, signal?: AbortSignal, release?: () => void): void {
    if (this.dead) {
      release?.();
      return done(this.dead, undefined);
    }
    if (signal?.aborted) {
      release?.();
      return done(abortError(`${this.name} ${what}`, signal), undefined);
    }
    if (this.running < this.maxJobs && this.waiting.size === 0) {
      if (signal) done = this.abortable(done, signal, what, undefined);
      return this.start(frame, what, done, release);
    }
    if (this.queued >= this.maxQueued) {
      release?.();
      return done(new PlcError('QUEUE_FULL', `request queue is full (${this.maxQueued} waiting)`), undefined);
    }
    const item: Waiting = { frame, what, done, release, signal, onAbort: undefined };
    if (signal) item.done = this.abortable(done, signal, what, item);
    this.waiting.push(item);
  }

  /** Hands an answer frame to the job with that PDU reference; false when none waits for it. */
  answer(ref: number, frame: Buffer): boolean {
    const slot = this.slotOf(ref);
    if (slot < 0) return false;
    const job = this.slots[slot]!;
    this.slots[slot] = undefined;
    this.running--;
    job.release?.();
    // The timer stays armed: when it fires with nothing in flight it just
    // stops, so a poll does not create and clear a timer each time.
    this.drain();
    job.done?.(undefined, frame);
    return true;
  }

  /** Fails every job, running or waiting; later sends fail with `err` at once. */
  rejectAll(err: PlcError): void {
    this.dead ??= err;
    if (this.timer) clearTimeout(this.timer);
    this.timer = undefined;
    const running = this.slots.filter((job) => job !== undefined);
    this.slots.fill(undefined);
    this.running = 0;
    const waiting = this.waiting.takeAll();
    for (const job of running) {
      job.release?.();
      job.done?.(err, undefined);
    }
    for (const job of waiting) {
      job.release?.();
      job.done(err, undefined);
    }
  }

  destroy(): void {
    this.socket.destroy();
  }

  private start(frame: Buffer, what: string, done: JobDone, release: (() => void) | undefined, cork = true): void {
    const ref = this.ref();
    frame[11] = ref >> 8;
    frame[12] = ref & 0xff;
    this.slots[this.slots.indexOf(undefined)] = { ref, done, deadline: Date.now() + this.timeout, what, release };
    this.running++;
    this.timer ??= setTimeout(this.sweep, this.timeout);
    this.onSend?.(frame);
    // Jobs started together (a poll's PDUs, or several freed by one answer)
    // leave in one writev: one syscall instead of one per PDU. A single job
    // freed by an answer is not held back for the tick.
    if (!this.corked && cork) {
      this.corked = true;
      this.socket.cork();
      process.nextTick(this.uncork);
    }
    this.socket.write(frame);
  }

  private readonly uncork = (): void => {
    this.corked = false;
    this.socket.uncork();
  };

  private drain(): void {
    // One job started on an answer leaves at once; several leave in one writev.
    const cork = Math.min(this.maxJobs - this.running, this.waiting.size) > 1;
    while (this.running < this.maxJobs && this.waiting.size > 0) {
      const item = this.waiting.shift()!;
      if (item.onAbort) item.signal!.removeEventListener('abort', item.onAbort);
      // Still listening for an abort while in flight: abortable() wraps done.
      if (item.signal) item.done = this.abortable(item.done, item.signal, item.what, undefined);
      this.start(item.frame, item.what, item.done, item.release, cork);
    }
  }

  /** `done` that also settles (once) when `signal` aborts; a queued job then leaves the queue. */
  private abortable(done: JobDone, signal: AbortSignal, what: string, queued: Waiting | undefined): JobDone {
    let settled = false;
    const onAbort = () => {
      if (settled) return;
      settled = true;
      if (queued) {
        this.waiting.remove(queued);
        queued.release?.();
      }
      done(abortError(`${this.name} ${what}`, signal), undefined);
    };
    signal.addEventListener('abort', onAbort, { once: true });
    if (queued) queued.onAbort = onAbort;
    return (err, answer) => {
      signal.removeEventListener('abort', onAbort);
      if (settled) return;
      settled = true;
      done(err, answer);
    };
  }

  /** The oldest job in flight decides: past its deadline, it times out and the link goes. */
  private readonly sweep = (): void => {
    this.timer = undefined;
    const now = Date.now();
    // Every job has the same timeout: the earliest deadline is the oldest job.
    let oldest = -1;
    for (let i = 0; i < this.slots.length; i++) {
      const job = this.slots[i];
      if (job && (oldest < 0 || job.deadline < this.slots[oldest]!.deadline)) oldest = i;
    }
    if (oldest < 0) return;
    const job = this.slots[oldest]!;
    if (job.deadline > now) {
      this.timer = setTimeout(this.sweep, job.deadline - now);
      return;
    }
    this.slots[oldest] = undefined;
    this.running--;
    const err = new TimeoutError(`${this.name} ${job.what} timed out after ${this.timeout} ms`);
    job.done?.(err, undefined);
    this.lose?.(new ConnectionError('CONNECTION_LOST', `${this.name} stopped answering: ${err.message}`, { cause: err }));
  };
}

export interface OpenOptions {
  name: string;
  /** For the TCP connect; the supervisor aborts `signal` when the whole handshake takes longer. */
  timeout: number;
  maxQueued: number | undefined;
  /** Per job; defaults to `timeout`. */
  requestTimeout?: number;
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
  // The socket's chunks are ours: frames are cut from them without a copy.
  const reader = new FrameReader(checkTpkt, MAX_FRAME, { copy: false });
  const next = frameWaiter(socket, reader, o.signal, o.name);
  try {
    const calledTsap = e.remoteTsap ?? remoteTsapFor(e.connectionType, e.rack, e.slot);
    const callingTsap = e.localTsap ?? localTsapFor(e.connectionType);
    socket.write(encodeConnectionRequest({ sourceRef: 0x0001, callingTsap, calledTsap, tpduSize: TPDU_SIZE_CODE }));
    const cc = decodeCotp(await next());
    if (cc.type !== 'CC') {
      const where = e.remoteTsap !== undefined ? `TSAP 0x${calledTsap.toString(16).padStart(4, '0')}` : `rack ${e.rack}, slot ${e.slot}`;
      throw new ConnectionError(
        'CONNECT_FAILED',
        `${o.name} refused the connection (${where}): wrong rack/slot or TSAP, or the PLC's connection limit is reached`,
      );
    }
    socket.write(encodeSetupCommunication(0, { maxAmqCalling: REQUESTED_AMQ, maxAmqCalled: REQUESTED_AMQ, pduSize: e.pduSize }));
    const ack = decodeS7(await next());
    if (ack.kind === 'error') throw headerError(ack.errorClass, ack.errorCode, `${o.name} setup communication`);
    if (ack.kind !== 'setup-ack') throw new ProtocolError(`${o.name}: expected the answer to setup communication, got ${ack.kind}`);
    const { pduSize, maxAmqCalling, maxAmqCalled } = ack.params;
    if (pduSize < 64) throw new ProtocolError(`${o.name} negotiated an unusable PDU size of ${pduSize}`);
    // The PLC answers with what it grants; a 0 would mean "none", which no CPU sends: treat as 1.
    // More than we asked for is not ours to use.
    const maxJobs = Math.max(1, Math.min(maxAmqCalling, maxAmqCalled, REQUESTED_AMQ));
    const session = new S7Session(socket, reader, pduSize, maxJobs, o.maxQueued, o.requestTimeout ?? o.timeout, o.name);
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
