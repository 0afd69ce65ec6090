/**
 * One live S7 connection: the socket and its read loop, the frame reader,
 * the negotiated PDU size and parallel jobs (AmQ), PDU references, the jobs
 * in flight and the job queue, the wire counters, and the loss of the link.
 * The handshake that opens it is `openS7Session` (handshake.ts).
 */
import type * as net from 'node:net';
import { abortError, ConnectionError, PlcError, ProtocolError, TimeoutError, toPlcError } from '../../errors';
import { Fifo } from '../../link/fifo';
import type { FrameReader } from '../../link/framer';
import { decodeS7, s7AnswerRef, type S7Message } from '../codec';
import { cotpTpduType, disconnectReason } from '../../iso/cotp';
import { setPduRef } from '../codec/pdu-decode';
import { decodeModeTransition } from '../codec/mode-transition';
import { isUserdataPush } from '../codec/userdata';
import { CotpType } from '../../iso/constants';

/** The counters a session adds to (the client's S7Stats, cumulative over reconnects). */
export interface WireCounters {
  /** S7 jobs sent. */
  pdusSent: number;
  /** Bytes written to and read from the socket, TPKT headers included. */
  bytesSent: number;
  bytesReceived: number;
  /** Replies that matched no pending job (wrong, duplicated or late PDU reference). */
  ignoredReplies: number;
}

/** What a session is given by its client when it is made, and all it reports back. */
export interface SessionWiring {
  /** For messages: "s7://10.0.0.2:102". */
  name: string;
  /** Per job, ms: a job unanswered for this long drops the link. */
  timeout: number;
  maxQueued: number | undefined;
  stats: WireCounters;
  /** The error the jobs fail with when the link goes for `cause` (the client says CLOSED when it was closed). */
  lossError(cause: PlcError): PlcError;
  /** Called once when the link is gone, after every job failed with `err`. */
  lost(session: S7Session, err: PlcError): void;
}

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
  /** The PDU size the PLC negotiated. */
  readonly pduSize: number;
  /** The parallel jobs (AmQ) the PLC negotiated. */
  readonly maxJobs: number;
  private readonly name: string;
  private readonly timeout: number;
  private readonly stats: WireCounters;
  private gone = false;
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
  private readonly pushListeners = new Set<(frame: Buffer) => void>();

  constructor(
    private readonly socket: net.Socket,
    private readonly reader: FrameReader,
    negotiated: { pduSize: number; maxJobs: number },
    private readonly wiring: SessionWiring,
  ) {
    this.pduSize = negotiated.pduSize;
    this.maxJobs = negotiated.maxJobs;
    this.name = wiring.name;
    this.timeout = wiring.timeout;
    this.stats = wiring.stats;
    this.maxQueued = wiring.maxQueued ?? DEFAULT_MAX_QUEUED;
    this.slots = new Array<InFlight | undefined>(Math.max(1, this.maxJobs)).fill(undefined);
    socket.on('data', this.receive);
    socket.on('error', (err) => this.lose(new ConnectionError('CONNECTION_LOST', `${this.name}: ${err.message}`, { cause: err })));
    socket.on('close', () => this.lose(new ConnectionError('CONNECTION_LOST', `${this.name} closed the connection`)));
  }

  /**
   * The read loop: each chunk is cut into frames. A COTP disconnect request
   * or a frame that is not S7 drops the link; an answer goes to the job with
   * its PDU reference (the headers are checked here, the job decodes the rest).
   */
  private readonly receive = (chunk: Buffer): void => {
    this.stats.bytesReceived += chunk.length;
    let frames: Buffer[];
    try {
      frames = this.reader.push(chunk);
    } catch (err) {
      return this.lose(linkError(this.name, err));
    }
    for (const frame of frames) {
      if (cotpTpduType(frame) === CotpType.DR) {
        return this.lose(
          new ConnectionError(
            'CONNECTION_LOST',
            `${this.name} disconnected (COTP disconnect request, reason 0x${disconnectReason(frame).toString(16)})`,
          ),
        );
      }
      if (isUserdataPush(frame) || decodeModeTransition(frame) !== undefined) {
        this.push(frame);
        continue;
      }
      let ref = s7AnswerRef(frame);
      if (ref < 0) {
        try {
          ref = decodeS7(frame).pduRef;
        } catch (err) {
          return this.lose(linkError(this.name, err));
        }
      }
      if (!this.answer(ref, frame)) this.stats.ignoredReplies++;
    }
  };

  /**
   * A PDU the CPU sent unasked (isUserdataPush: alarms, mode changes,
   * diagnostic messages, cyclic data) goes to every push listener; one that
   * throws loses the link as a malformed answer would. Without a listener it
   * is counted as an ignored reply.
   */
  private push(frame: Buffer): void {
    if (this.pushListeners.size === 0) {
      this.stats.ignoredReplies++;
      return;
    }
    for (const listener of this.pushListeners) {
      try {
        listener(frame);
      } catch (err) {
        this.lose(linkError(this.name, err));
        return;
      }
    }
  }

  /** Listens to the PDUs the CPU pushes on this session (see push()); returns the function that stops listening. */
  onPush(listener: (frame: Buffer) => void): () => void {
    this.pushListeners.add(listener);
    return () => this.pushListeners.delete(listener);
  }

  /** Drops the link, once: every job fails (with the client's word for it), the socket goes, the client is told. */
  lose(cause: PlcError): void {
    if (this.gone) return;
    this.gone = true;
    const err = this.wiring.lossError(cause);
    this.rejectAll(err);
    this.socket.destroy();
    this.wiring.lost(this, err);
  }

  /** Decodes an answer; a malformed one drops the link, as any frame the client cannot make sense of does. */
  decode(frame: Buffer): S7Message {
    try {
      return decodeS7(frame);
    } catch (err) {
      throw this.malformed(err);
    }
  }

  /** A malformed answer: the link drops (a ProtocolError), and this is the error to throw. */
  malformed(err: unknown): PlcError {
    const e = linkError(this.name, err);
    if (e.code === 'PROTOCOL_ERROR') this.lose(e);
    return e;
  }

  /** One request frame (its PDU reference is set when sent) as a job; resolves the raw answer frame. */
  exchange(frame: Buffer, what: string, signal?: AbortSignal): Promise<Buffer> {
    return new Promise((resolve, reject) => this.send(frame, what, (err, answer) => (err ? reject(err) : resolve(answer!)), signal));
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
  private answer(ref: number, frame: Buffer): boolean {
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
  private rejectAll(err: PlcError): void {
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
    setPduRef(frame, ref);
    this.slots[this.slots.indexOf(undefined)] = { ref, done, deadline: Date.now() + this.timeout, what, release };
    this.running++;
    this.timer ??= setTimeout(this.sweep, this.timeout);
    this.stats.pdusSent++;
    this.stats.bytesSent += frame.length;
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
    this.lose(new ConnectionError('CONNECTION_LOST', `${this.name} stopped answering: ${err.message}`, { cause: err }));
  };
}

/** A frame the session cannot make sense of, named after the link: a ProtocolError drops it. */
export function linkError(name: string, err: unknown): PlcError {
  const e = toPlcError(err, 'PROTOCOL_ERROR');
  return e instanceof ProtocolError ? new ProtocolError(`${name}: ${e.message}`, { cause: e }) : e;
}
