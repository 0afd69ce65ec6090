/**
 * One live S7CommPlus connection: the stream it owns (the TLS socket over the
 * COTP tunnel, or the plain tunnel with tls=false), the sequence number and
 * the two IntegrityIds, one request in flight (lib/link/pending.ts, with its
 * deadline) and a FIFO of those waiting, and the loss of the link. Callers
 * ask (an Ask: function, body, the codec's encoder and decoder, see
 * asks.ts); the session stamps each request's header and IntegrityId and
 * decodes its answer.
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
import { abortError, ConnectionError, type PlcError, ProtocolError, toPlcError } from '../../errors';
import { Fifo } from '../../link/fifo';
import { PendingRequests } from '../../link/pending';
import { encodeFrames, S7pFrameReader, type S7pMessage } from '../codec/frame';
import { peekMessage, type DecodeOptions, type Request, type Response } from '../codec/header';
import { decodeDeleteObjectResponse, encodeDeleteObjectRequest } from '../codec/session';
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
 * A request as its caller asks it: the function, the body, and the codec's
 * encoder and decoder. The session stamps what the wire needs when the
 * request goes out (the sequence number, the session id, the IntegrityId of
 * the right counter) and decodes the answer as the session is (with or
 * without IntegrityIds): callers say what, not how.
 */
export interface Ask<B, R> {
  functionCode: number;
  body: B;
  encode(req: Request<B>): Buffer;
  decode(data: Buffer, opts: DecodeOptions): Response<R>;
  /** Default: TransportFlags.Normal. */
  transportFlags?: number;
}

/** A request the PLC does not answer (transport flags 0x74: a subscription's credits). */
export type Tell<B> = Omit<Ask<B, never>, 'decode'>;

export interface RequestOptions {
  signal?: AbortSignal | undefined;
  /** Frame version of this request (default: the session's). */
  version?: number;
  /** False: this request carries no IntegrityId and advances no counter (the session setup write). */
  integrity?: boolean;
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
  ask: Ask<unknown, unknown> | Tell<unknown>;
  options: RequestOptions;
  resolve(value: unknown): void;
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
  /** The request on the wire: its job, sequence number, and whether it carried an IntegrityId. */
  private current: { job: Job; seq: number; integrity: boolean } | undefined;
  /** Its answer, by sequence number, with its deadline (one at a time: the PLC answers in order). */
  private readonly inFlight = new PendingRequests<S7pMessage>();
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

  /** From now on every request carries an IntegrityId, both counters starting at 0 (after the session setup over TLS). */
  startIntegrity(): void {
    this.integrity = true;
    this.readId = 0;
    this.writeId = 0;
  }

  /**
   * Sends a request when the one before it is answered; resolves with the
   * answer's body. An answer of the wrong kind or sequence, or none within
   * the timeout, drops the link (a ProtocolError, a TimeoutError); an error
   * PDU or a body the decoder refuses fails this request alone.
   */
  request<B, R>(ask: Ask<B, R>, options: RequestOptions = {}): Promise<R> {
    return this.enqueue(ask as Ask<unknown, unknown>, options) as Promise<R>;
  }

  /** Sends a request the PLC does not answer; resolves once it is on the wire. */
  async tell<B>(message: Tell<B>, options: RequestOptions = {}): Promise<void> {
    await this.enqueue(message as Tell<unknown>, options);
  }

  private enqueue(ask: Ask<unknown, unknown> | Tell<unknown>, options: RequestOptions): Promise<unknown> {
    if (this.dead) return Promise.reject(this.dead);
    if (options.signal?.aborted) return Promise.reject(abortError(`a request to ${this.wiring.name}`, options.signal));
    if (this.waiting.size >= this.maxQueued) {
      return Promise.reject(new ConnectionError('QUEUE_FULL', `${this.wiring.name}: ${this.maxQueued} requests are already waiting`));
    }
    return new Promise<unknown>((resolve, reject) => {
      const job: Job = { ask, options, resolve, reject };
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
    const ac = new AbortController();
    const timer = setTimeout(() => ac.abort(), deadline);
    try {
      await Promise.race([
        this.request(
          {
            functionCode: FunctionCode.DeleteObject,
            body: { objectId: this.sessionId },
            encode: encodeDeleteObjectRequest,
            decode: decodeDeleteObjectResponse,
          },
          { signal: ac.signal },
        ),
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

  /** A request's message: its header (this session's id, sequence `seq`) and body, with `integrityId` where the codec puts it. */
  private stamp(ask: Ask<unknown, unknown> | Tell<unknown>, seq: number, integrityId: number | undefined): Buffer {
    const header = {
      functionCode: ask.functionCode,
      sequence: seq,
      sessionId: this.sessionId,
      transportFlags: ask.transportFlags ?? TransportFlags.Normal,
    };
    return ask.encode(integrityId === undefined ? { header, body: ask.body } : { header, body: ask.body, integrityId });
  }

  private pump(): void {
    if (this.current || this.dead) return;
    const job = this.waiting.shift();
    if (!job) return;
    const seq = this.nextSeq;
    this.nextSeq = (this.nextSeq + 1) & 0xffff;
    const o = job.options;
    const fn = job.ask.functionCode;
    const counted = this.integrity && o.integrity !== false;
    const isRead = READ_FUNCTIONS.has(fn);
    let frame: Buffer;
    try {
      frame = encodeFrames(
        o.version ?? this.version,
        this.stamp(job.ask, seq, counted ? (isRead ? this.readId : this.writeId) : undefined),
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
    this.stale = 0;
    this.stats.requestsSent++;
    this.stats.bytesSent += frame.length;
    this.stream.write(frame);
    if (!('decode' in job.ask)) {
      this.settle(job, undefined, undefined);
      return this.pump();
    }
    this.current = { job, seq, integrity: counted };
    const what = `${this.wiring.name} did not answer request 0x${fn.toString(16)} (sequence ${seq}) within ${this.wiring.timeout} ms`;
    this.inFlight.add(seq, this.wiring.timeout, `request 0x${fn.toString(16)} to ${this.wiring.name}`, undefined, what).then(
      (m) => this.answered(job, m, counted),
      // Its deadline (a TimeoutError: the link drops), or the link already lost (then a no-op).
      (err: PlcError) => this.lose(err),
    );
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
    const current = this.current;
    if (!current) throw new ProtocolError(`${this.wiring.name}: an answer (sequence ${r.seq}) to no request`);
    if (r.seq !== current.seq) {
      const behind = (current.seq - r.seq) & 0xffff;
      if (behind > 0 && behind < 0x8000 && ++this.stale <= MAX_STALE) {
        this.stats.ignored++;
        return;
      }
      throw new ProtocolError(`${this.wiring.name}: an answer with sequence ${r.seq} while waiting for ${current.seq}`);
    }
    const fn = current.job.ask.functionCode;
    if (r.fn !== fn && r.fn !== FunctionCode.Error) {
      throw new ProtocolError(`${this.wiring.name}: the answer to request 0x${fn.toString(16)} is for function 0x${r.fn.toString(16)}`);
    }
    this.current = undefined;
    this.answerVersion = m.version;
    this.inFlight.resolve(r.seq, m);
    this.pump();
  }

  /** The answer of `job`'s request: its body as the session decodes it (`integrity`: the request carried an IntegrityId). */
  private answered(job: Job, m: S7pMessage, integrity: boolean): void {
    const fn = job.ask.functionCode;
    if (m.data.readUInt16BE(3) === FunctionCode.Error) {
      return this.settle(job, new ProtocolError(`${this.wiring.name} answered request 0x${fn.toString(16)} with an error PDU`));
    }
    let body: unknown;
    try {
      body = (job.ask as Ask<unknown, unknown>).decode(m.data, { integrity }).body;
    } catch (err) {
      return this.settle(job, toPlcError(err, 'PROTOCOL_ERROR'));
    }
    this.settle(job, undefined, body);
  }

  /**
   * A SystemEvent: 16 bytes or more (connection.py, _system_event_return_value).
   * The PLC sends one before it ends a session it disagrees with (a counter
   * jump among them): anything shorter is malformed, and the link then drops.
   */
  private systemEvent(data: Buffer): void {
    if (data.length < 16) throw new ProtocolError(`${this.wiring.name}: a SystemEvent of ${data.length} bytes`);
  }

  private settle(job: Job, err: PlcError | undefined, value?: unknown): void {
    if (job.onAbort) job.options.signal?.removeEventListener('abort', job.onAbort);
    if (err) job.reject(err);
    else job.resolve(value);
  }

  /** The link is gone: every request fails, the stream is destroyed, the client told (unless it destroyed the session itself). */
  private lose(cause: PlcError, report = true): void {
    if (this.dead) return;
    const err = this.wiring.lossError(cause);
    this.dead = err;
    this.stream.off('data', this.receive);
    // Late 'error' events of the dying stream have a listener still (the one in the constructor), so they never crash the process.
    this.stream.destroy();
    const current = this.current;
    this.current = undefined;
    this.inFlight.rejectAll(err);
    if (current) this.settle(current.job, err);
    for (let w = this.waiting.shift(); w; w = this.waiting.shift()) this.settle(w, err);
    if (report) this.wiring.lost(this, err);
  }
}
