/**
 * One open freeport line (serial port or TCP to a serial device server) with
 * half-duplex bus discipline: one request on the bus at a time, a reply or a
 * timeout before the next, a quiet gap between frames, retries on silence or
 * corruption. A silent station fails only its own request; the line stays up.
 */
import { abortError, ConnectionError, type PlcError, ProtocolError, TimeoutError, toPlcError } from '../errors';
import { JobQueue } from '../link/jobs';
import { PendingRequests } from '../link/pending';
import type { DriverSession } from '../link/supervisor';
import { encodeRequest, type FreeportReply, type FreeportRequest } from './codec';
import { FreeportParser } from './parser';
import type { FreeportProfile } from './profile';

/** The byte pipe under a session. */
export interface FreeportTransport {
  write(bytes: Buffer): void;
  /** Close now; must not throw. Resolves when the device or socket is released. */
  destroy(): Promise<void>;
}

export interface BusDiscipline {
  /** For messages: "freeport:///dev/ttyUSB0". */
  name: string;
  /** Milliseconds to wait for each reply. */
  timeout: number;
  /** Further attempts after a timeout or a corrupted reply. */
  retries: number;
  /** Quiet time on the bus between a reply (or timeout) and the next request, ms. */
  interFrameGapMs: number;
  maxQueued?: number;
}

/** Sends a request and resolves with the station's reply (retries included). */
export type Exchange = (request: FreeportRequest) => Promise<FreeportReply>;

export class FreeportSession implements DriverSession {
  private readonly parser: FreeportParser;
  private readonly pending = new PendingRequests<FreeportReply>();
  private readonly bus: JobQueue;
  private nextId = 1;
  private current: { id: number; station: number } | undefined;
  private quietSince = 0;
  /**
   * After a request timed out, no next request before this time: the reply
   * may still come, and with a profile whose replies do not echo the
   * station it would be taken for the next request's (another station's
   * data passed as good). Whatever arrives meanwhile is discarded.
   */
  private drainUntil = 0;
  private gapTimer: { timer: NodeJS.Timeout; done(): void } | undefined;
  private dead: PlcError | undefined;
  private released: Promise<void> | undefined;

  constructor(
    private readonly transport: FreeportTransport,
    private readonly profile: FreeportProfile,
    private readonly discipline: BusDiscipline,
  ) {
    this.parser = new FreeportParser(profile, 'reply');
    this.bus = new JobQueue({ concurrency: 1, ...(discipline.maxQueued ? { maxQueued: discipline.maxQueued } : {}) });
  }

  /** Bytes from the line. */
  receive(chunk: Buffer): void {
    for (const frame of this.parser.push(chunk)) {
      const current = this.current;
      if (!current) continue; // a late reply after a timeout: nobody asked
      if (frame.kind === 'corrupt') {
        this.pending.reject(current.id, new ProtocolError(`station ${current.station}: ${frame.error.message}`, { cause: frame.error }));
      } else if (frame.kind === 'reply') {
        if (frame.reply.station !== undefined && frame.reply.station !== current.station) continue; // another station's answer
        this.pending.resolve(current.id, frame.reply);
      }
    }
  }

  /** Runs `work` with the bus to itself: no other request goes out between its exchanges (read-modify-write). */
  transaction<T>(work: (exchange: Exchange) => Promise<T>, signal?: AbortSignal): Promise<T> {
    if (this.dead) return Promise.reject(this.dead);
    return this.bus.run(() => work((request) => this.withRetries(request, signal)), signal);
  }

  exchange(request: FreeportRequest, signal?: AbortSignal): Promise<FreeportReply> {
    return this.transaction((exchange) => exchange(request), signal);
  }

  destroy(err?: PlcError): void {
    if (this.dead) return;
    this.dead = err ?? new ConnectionError('CONNECTION_LOST', `the line to ${this.discipline.name} was closed`);
    if (this.gapTimer) {
      clearTimeout(this.gapTimer.timer);
      this.gapTimer.done();
      this.gapTimer = undefined;
    }
    this.pending.rejectAll(this.dead);
    this.bus.rejectAll(this.dead);
    this.released = this.transport.destroy().catch(() => {});
  }

  /** Resolves when the transport was released after destroy(). */
  closed(): Promise<void> {
    return this.released ?? Promise.resolve();
  }

  private async withRetries(request: FreeportRequest, signal?: AbortSignal): Promise<FreeportReply> {
    const { retries, timeout, name } = this.discipline;
    let last: PlcError | undefined;
    for (let attempt = 0; attempt <= retries; attempt++) {
      try {
        return await this.once(request, signal);
      } catch (err) {
        last = toPlcError(err);
        if (last.code !== 'TIMEOUT' && last.code !== 'PROTOCOL_ERROR') throw last;
      }
    }
    const attempts = `${retries + 1} attempt${retries === 0 ? '' : 's'} of ${timeout} ms`;
    if (last instanceof ProtocolError) {
      return Promise.reject(
        new ProtocolError(`station ${request.station} on ${name} sent no valid reply (${attempts}; last: ${last.message})`, {
          cause: last,
        }),
      );
    }
    throw new TimeoutError(`station ${request.station} on ${name} did not answer (${attempts})`, { cause: last });
  }

  private async once(request: FreeportRequest, signal?: AbortSignal): Promise<FreeportReply> {
    await this.quietGap();
    if (this.dead) throw this.dead;
    const id = this.nextId++;
    this.current = { id, station: request.station };
    this.parser.reset(); // a half reply from before must not join this one
    const what = `${request.command} of station ${request.station}`;
    const reply = this.pending.add(id, this.discipline.timeout, what, signal);
    reply.catch(() => {}); // settled below either way; a throw from write() must not leave it unhandled
    try {
      this.transport.write(encodeRequest(request, this.profile));
      return await reply;
    } catch (err) {
      if (err instanceof TimeoutError) this.drainUntil = Date.now() + this.discipline.timeout;
      throw err;
    } finally {
      if (this.pending.has(id)) this.pending.reject(id, abortError(what));
      this.current = undefined;
      this.quietSince = Date.now();
    }
  }

  private quietGap(): Promise<void> {
    const wait = Math.max(this.quietSince + this.discipline.interFrameGapMs, this.drainUntil) - Date.now();
    if (wait <= 0 || this.dead) return Promise.resolve();
    return new Promise((resolve) => {
      const done = () => {
        this.gapTimer = undefined;
        resolve();
      };
      this.gapTimer = { timer: setTimeout(done, wait), done };
    });
  }
}
