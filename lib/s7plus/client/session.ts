/**
 * One live S7CommPlus connection: the stream it owns (the TLS socket over the
 * COTP tunnel, or the plain tunnel with tls=false), the sequence number and
 * the two IntegrityIds, one request in flight and a FIFO of those waiting,
 * the deadline of the one in flight, and the loss of the link.
 *
 * What the PLC expects (s7commplus (MIT), connection.py, _send_request): every
 * request takes the next 16-bit sequence number, which the answer echoes;
 * once the session is set up, a read (READ_FUNCTIONS) carries the read
 * IntegrityId and every other request the write one, each counter advancing
 * by one per request sent. A PLC resets a connection whose counters jump, so
 * a request is numbered only when it goes on the wire, and one whose answer
 * never comes drops the link (its numbers are spent on the PLC's side too).
 */
import type { Duplex } from 'node:stream';
import { TLSSocket } from 'node:tls';
import { abortError, ConnectionError, type PlcError, ProtocolError, TimeoutError, toPlcError } from '../../errors';
import { Fifo } from '../../link/fifo';
import { encodeFrames, S7pFrameReader, type S7pMessage } from '../codec/frame';
import { peekMessage } from '../codec/header';
import { encodeDeleteObjectRequest } from '../codec/session';
import { FunctionCode, Opcode, ProtocolVersion, READ_FUNCTIONS, TransportFlags } from '../constants';
import { tlsFailure } from '../transport/handshake';

/** What a session is given by its client, and all it reports back. */
export interface S7PlusWiring {
  /** For messages: "s7plus://10.0.0.2:102". */
  name: string;
  /** Per request, ms: a request unanswered for this long drops the link. */
  timeout: number;
  maxQueued?: number | undefined;
  /** The error the requests fail with when the link goes for `cause` (CLOSED when the client was closed). */
  lossError(cause: PlcError): PlcError;
  /** Called once when the link is gone, after every request failed with `err`. */
  lost(session: S7PlusSession, err: PlcError): void;
  /** A notification's data (opcode 0x33 first), on a session that carries subscriptions; without it they are ignored. */
  notify?(data: Buffer): void;
}

/**
 * A request's message (its header included), made when it goes on the wire:
 * with the sequence number and the session id it gets then, and the
 * IntegrityId when the session sends one (the codec's encoders put it where
 * the PLC expects it).
 */
export type Encode = (sequence: number, sessionId: number, integrityId: number | undefined) => Buffer;

export interface RequestOptions {
  signal?: AbortSignal | undefined;
  /** Frame version of this request (default: the session's). */
  version?: number;
  /** False: this request carries no IntegrityId and advances no counter (the session setup write). */
  integrity?: boolean;
  /** The PLC does not answer it (transport flags 0x74: a subscription's credits): settled once it is on the wire. */
  noAnswer?: boolean;
}

/** Counters for diagnostics and the benchmark. */
export interface S7PlusWireCounters {
  requestsSent: number;
  bytesSent: number;
  bytesReceived: number;
  /** Answers to an earlier sequence number (a request given up on), and notifications nobody subscribed to. */
  ignored: number;
}

interface Job {
  fn: number;
  encode: Encode;
  options: RequestOptions;
  resolve(payload: Buffer): void;
  reject(err: PlcError): void;
  onAbort?: () => void;
}

const DEFAULT_MAX_QUEUED = 1000;
/** Stale answers (an earlier sequence number) tolerated per request before the stream counts as broken (connection.py allows 16). */
const MAX_STALE = 16;

export class S7PlusSession {
  /** The session's object id, from CreateObject (the null session until then). */
  sessionId: number;
  /** Where the session's subscriptions are created: the second object id of its CreateObject answer (0: the PLC named none). */
  subscriptionContainerId = 0;
  /** The frame version of data requests: V2 over TLS, V1 in plain text. */
  version: number;
  private nextSeq: number;
  private integrity = false;
  private readId = 0;
  private writeId = 0;
  private readonly cutter = new S7pFrameReader();
  private readonly waiting = new Fifo<Job>();
  private current: (Job & { seq: number }) | undefined;
  private timer: NodeJS.Timeout | undefined;
  private stale = 0;
  private dead: PlcError | undefined;
  private readonly maxQueued: number;
  /** The frame version of the last answer (the CreateObject answer's tells the protocol version the PLC speaks). */
  answerVersion = 0;

  constructor(
    private readonly stream: Duplex,
    start: { sessionId: number; version: number; nextSeq: number },
    private readonly wiring: S7PlusWiring,
    readonly stats: S7PlusWireCounters = { requestsSent: 0, bytesSent: 0, bytesReceived: 0, ignored: 0 },
  ) {
    this.sessionId = start.sessionId;
    this.version = start.version;
    this.nextSeq = start.nextSeq & 0xffff;
    this.maxQueued = wiring.maxQueued ?? DEFAULT_MAX_QUEUED;
    stream.on('data', this.receive);
    // Over TLS, the error says in words what the PLC's TLS did (an alert, records that are not TLS); OpenSSL's own text stays in `cause`.
    stream.on('error', (err: Error) =>
      this.lose(
        stream instanceof TLSSocket
          ? tlsFailure(err, wiring.name, 'session')
          : new ConnectionError('CONNECTION_LOST', `${wiring.name}: ${err.message}`, { cause: err }),
      ),
    );
    // A stream the PLC ended is as gone as a closed one (a half-open stream would leave requests to their timeout).
    const ended = () => this.lose(new ConnectionError('CONNECTION_LOST', `${wiring.name} closed the connection`));
    stream.on('end', ended);
    stream.on('close', ended);
  }

  /** True until the link is lost or destroyed. */
  get alive(): boolean {
    return this.dead === undefined;
  }

  /** The IntegrityIds the next read and the next write will carry (undefined while the session sends none). */
  get integrityIds(): { read: number; write: number } | undefined {
    return this.integrity ? { read: this.readId, write: this.writeId } : undefined;
  }

  /** Whether requests carry IntegrityIds (what the codec's decoders are told). */
  get integrityOn(): boolean {
    return this.integrity;
  }

  /** From now on every request carries an IntegrityId, both counters starting at 0 (after the session setup over TLS). */
  startIntegrity(): void {
    this.integrity = true;
    this.readId = 0;
    this.writeId = 0;
  }

  /**
   * Sends a request when the one before it is answered; resolves with the
   * answer's message (its response header included, for the codec's
   * decoder). An answer of the wrong kind or sequence, or none within the
   * timeout, drops the link (a ProtocolError, a TimeoutError).
   */
  request(fn: number, encode: Encode, options: RequestOptions = {}): Promise<Buffer> {
    if (this.dead) return Promise.reject(this.dead);
    if (options.signal?.aborted) return Promise.reject(abortError(`a request to ${this.wiring.name}`, options.signal));
    if (this.waiting.size >= this.maxQueued) {
      return Promise.reject(new ConnectionError('QUEUE_FULL', `${this.wiring.name}: ${this.maxQueued} requests are already waiting`));
    }
    return new Promise<Buffer>((resolve, reject) => {
      const job: Job = { fn, encode, options, resolve, reject };
      const signal = options.signal;
      if (signal) {
        // A request still waiting leaves the queue; one on the wire is answered (its numbers are spent) and its answer dropped.
        job.onAbort = () => {
          if (this.waiting.remove(job)) reject(abortError(`a request to ${this.wiring.name}`, signal));
        };
        signal.addEventListener('abort', job.onAbort, { once: true });
      }
      this.waiting.push(job);
      this.pump();
    });
  }

  /**
   * DeleteObject of the session, as a clean close asks (connection.py,
   * _delete_session): after the requests already queued, and at most
   * `deadline` ms; the link is then destroyed whatever the PLC answered.
   * It counts on the write IntegrityId as every other write of the session.
   */
  async goodbye(deadline: number): Promise<void> {
    if (this.dead) return this.destroy();
    const encode: Encode = (sequence, sessionId, integrityId) =>
      encodeDeleteObjectRequest({
        header: { functionCode: FunctionCode.DeleteObject, sequence, sessionId, transportFlags: TransportFlags.Normal },
        body: { objectId: sessionId },
        ...(integrityId === undefined ? {} : { integrityId }),
      });
    const ac = new AbortController();
    const timer = setTimeout(() => ac.abort(), deadline);
    try {
      await Promise.race([
        this.request(FunctionCode.DeleteObject, encode, { signal: ac.signal }),
        new Promise((_, reject) => ac.signal.addEventListener('abort', () => reject(new Error('deadline')), { once: true })),
      ]);
    } catch {
      // A PLC that does not answer a DeleteObject is closed all the same.
    } finally {
      clearTimeout(timer);
      this.destroy();
    }
  }

  /** Closes the stream now and fails every request with CLOSED (or the client's loss error). Never throws. */
  destroy(): void {
    this.lose(new ConnectionError('CLOSED', `connection to ${this.wiring.name} was closed`), false);
  }

  private pump(): void {
    if (this.current || this.dead) return;
    const job = this.waiting.shift();
    if (!job) return;
    const seq = this.nextSeq;
    this.nextSeq = (this.nextSeq + 1) & 0xffff;
    const o = job.options;
    const counted = this.integrity && o.integrity !== false;
    const isRead = READ_FUNCTIONS.has(job.fn);
    let frame: Buffer;
    try {
      frame = encodeFrames(
        o.version ?? this.version,
        job.encode(seq, this.sessionId, counted ? (isRead ? this.readId : this.writeId) : undefined),
      );
    } catch (err) {
      // Nothing went out: the numbers are not spent.
      this.nextSeq = seq;
      this.settle(job, toPlcError(err, 'PROTOCOL_ERROR'));
      return this.pump();
    }
    if (counted) {
      if (isRead) this.readId = (this.readId + 1) >>> 0;
      else this.writeId = (this.writeId + 1) >>> 0;
    }
    this.current = { ...job, seq };
    this.stale = 0;
    this.stats.requestsSent++;
    this.stats.bytesSent += frame.length;
    this.stream.write(frame);
    if (o.noAnswer) {
      this.current = undefined;
      this.settle(job, undefined, Buffer.alloc(0));
      return this.pump();
    }
    this.timer = setTimeout(() => {
      const what = `${this.wiring.name} did not answer request 0x${job.fn.toString(16)} (sequence ${seq}) within ${this.wiring.timeout} ms`;
      this.lose(new TimeoutError(what));
    }, this.wiring.timeout);
  }

  private readonly receive = (chunk: Buffer): void => {
    if (this.dead) return;
    this.stats.bytesReceived += chunk.length;
    try {
      for (const m of this.cutter.push(chunk)) this.answer(m);
    } catch (err) {
      this.lose(toPlcError(err, 'PROTOCOL_ERROR'));
    }
  };

  /** One message: the answer of the request in flight, a stale answer, a notification, a SystemEvent. */
  private answer(m: S7pMessage): void {
    if (this.dead) return;
    if (m.version === ProtocolVersion.SystemEvent) return this.systemEvent(m.data);
    if (m.data[0] === Opcode.Notification) {
      if (this.wiring.notify) this.wiring.notify(m.data);
      else this.stats.ignored++;
      return;
    }
    const peek = peekMessage(m.data);
    if (peek.opcode !== Opcode.Response && peek.opcode !== Opcode.Response2) {
      throw new ProtocolError(`${this.wiring.name}: an answer with opcode 0x${peek.opcode.toString(16)}`);
    }
    if (peek.sequence === undefined || peek.functionCode === undefined) {
      throw new ProtocolError(`${this.wiring.name}: an answer of ${m.data.length} bytes has no response header`);
    }
    const r = { seq: peek.sequence, fn: peek.functionCode };
    const job = this.current;
    if (!job) throw new ProtocolError(`${this.wiring.name}: an answer (sequence ${r.seq}) to no request`);
    if (r.seq !== job.seq) {
      const behind = (job.seq - r.seq) & 0xffff;
      if (behind > 0 && behind < 0x8000 && ++this.stale <= MAX_STALE) {
        this.stats.ignored++;
        return;
      }
      throw new ProtocolError(`${this.wiring.name}: an answer with sequence ${r.seq} while waiting for ${job.seq}`);
    }
    if (r.fn !== job.fn && r.fn !== FunctionCode.Error) {
      throw new ProtocolError(`${this.wiring.name}: the answer to request 0x${job.fn.toString(16)} is for function 0x${r.fn.toString(16)}`);
    }
    clearTimeout(this.timer);
    this.current = undefined;
    this.answerVersion = m.version;
    if (r.fn === FunctionCode.Error) {
      this.settle(job, new ProtocolError(`${this.wiring.name} answered request 0x${job.fn.toString(16)} with an error PDU`));
    } else {
      this.settle(job, undefined, m.data);
    }
    this.pump();
  }

  /**
   * A SystemEvent: 16 bytes or more (connection.py, _system_event_return_value).
   * The PLC sends one before it ends a session it disagrees with (a counter
   * jump among them): anything shorter is malformed, and the link then drops.
   */
  private systemEvent(data: Buffer): void {
    if (data.length < 16) throw new ProtocolError(`${this.wiring.name}: a SystemEvent of ${data.length} bytes`);
  }

  private settle(job: Job, err: PlcError | undefined, payload?: Buffer): void {
    if (job.onAbort) job.options.signal?.removeEventListener('abort', job.onAbort);
    if (err) job.reject(err);
    else job.resolve(payload!);
  }

  /** The link is gone: every request fails, the stream is destroyed, the client told (unless it destroyed the session itself). */
  private lose(cause: PlcError, report = true): void {
    if (this.dead) return;
    clearTimeout(this.timer);
    const err = this.wiring.lossError(cause);
    this.dead = err;
    this.stream.off('data', this.receive);
    // Late 'error' events of the dying stream have a listener still (the one in the constructor), so they never crash the process.
    this.stream.destroy();
    const job = this.current;
    this.current = undefined;
    if (job) this.settle(job, err);
    for (let w = this.waiting.shift(); w; w = this.waiting.shift()) this.settle(w, err);
    if (report) this.wiring.lost(this, err);
  }
}
