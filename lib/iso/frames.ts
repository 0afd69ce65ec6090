/**
 * Whole TPKT frames from a socket during a handshake, one answer at a time,
 * each wait with its own deadline (or none). A handshake step asks for the
 * next frame and learns, as a value, whether one came, the peer closed the
 * connection, nothing came in time, or the bytes are not TPKT. Not pure
 * (timers, socket events): the connect steps use it, the codecs do not.
 */
import type * as net from 'node:net';
import { abortError, type ProtocolError } from '../errors';
import { FrameReader } from '../link/framer';
import { MAX_FRAME } from './constants';
import { checkTpkt } from './tpkt';

/** How a wait for the peer's next frame ended. */
export type FrameResult =
  | { kind: 'frame'; frame: Buffer }
  /** The peer closed the connection (`error`: the socket's error, a reset, when there was one). */
  | { kind: 'closed'; error?: Error }
  /** Nothing within the wait's `ms`. */
  | { kind: 'silent'; ms: number }
  /** The bytes are not TPKT (a wrong version, a length shorter than a COTP header): another protocol. */
  | { kind: 'garbage'; error: ProtocolError };

type End = Exclude<FrameResult, { kind: 'frame' | 'silent' }>;

/**
 * Listens to `socket` from construction until `stop()`. `reader` is handed on
 * with the socket when the handshake ends, so bytes after the last answer
 * stay in it (by default a reader over socket chunks, which stay ours).
 */
export class IsoFrames {
  readonly reader: FrameReader;
  private readonly frames: Buffer[] = [];
  private end: End | undefined;
  private wake: (() => void) | undefined;
  private readonly onData = (chunk: Buffer) => {
    if (this.end) return;
    try {
      this.frames.push(...this.reader.push(chunk));
    } catch (err) {
      this.end = { kind: 'garbage', error: err as ProtocolError };
    }
    this.wake?.();
  };
  private readonly onError = (error: Error) => {
    this.end ??= { kind: 'closed', error };
    this.wake?.();
  };
  private readonly onClose = () => {
    this.end ??= { kind: 'closed' };
    this.wake?.();
  };

  /** `what` names the wait in the ABORTED error: `${what} was aborted`. */
  constructor(
    private readonly socket: net.Socket,
    private readonly signal: AbortSignal | undefined,
    private readonly what: string,
    reader?: FrameReader,
  ) {
    this.reader = reader ?? new FrameReader(checkTpkt, MAX_FRAME, { copy: false });
    socket.on('data', this.onData);
    socket.on('error', this.onError);
    socket.on('close', this.onClose);
    if (socket.destroyed) this.end = { kind: 'closed' };
  }

  /**
   * The next frame, or how the wait ended: frames that came first are
   * handed out before the end. Without `ms`, only the end of the connection
   * or the signal ends the wait. Rejects only with ABORTED.
   */
  next(ms?: number): Promise<FrameResult> {
    return new Promise((resolve, reject) => {
      let timer: NodeJS.Timeout | undefined;
      const done = () => {
        clearTimeout(timer);
        this.wake = undefined;
        this.signal?.removeEventListener('abort', onAbort);
      };
      const check = (): boolean => {
        const frame = this.frames.shift();
        if (frame) return (done(), resolve({ kind: 'frame', frame }), true);
        if (this.end) return (done(), resolve(this.end), true);
        return false;
      };
      const onAbort = () => (done(), reject(abortError(this.what, this.signal!)));
      if (check()) return;
      if (this.signal?.aborted) return onAbort();
      if (ms !== undefined) timer = setTimeout(() => (done(), resolve({ kind: 'silent', ms })), ms);
      this.signal?.addEventListener('abort', onAbort, { once: true });
      this.wake = () => void check();
    });
  }

  /** Takes this waiter's listeners off the socket (after the next owner put its own on). */
  stop(): void {
    this.socket.removeListener('data', this.onData);
    this.socket.removeListener('error', this.onError);
    this.socket.removeListener('close', this.onClose);
  }
}
