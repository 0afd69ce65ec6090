import { ProtocolError } from '../errors';

/**
 * What a transport's framer says of the bytes buffered so far, which always
 * start at a frame boundary (or at garbage to skip).
 */
export type FrameCheck =
  | { kind: 'need' }
  | { kind: 'frame'; length: number }
  | { kind: 'skip'; length: number }
  | { kind: 'bad'; error: ProtocolError };

const DEFAULT_MAX_BUFFERED = 1 << 20;

/** Cuts a byte stream into frames with a framer function. Knows nothing of sockets. */
export class FrameReader {
  private pending: Buffer = Buffer.alloc(0);

  constructor(
    private readonly check: (buffered: Buffer) => FrameCheck,
    private readonly maxBuffered = DEFAULT_MAX_BUFFERED,
  ) {}

  get buffered(): number {
    return this.pending.length;
  }

  /** Adds a chunk and returns the complete frames it finished. Throws the framer's ProtocolError on 'bad'. */
  push(chunk: Buffer): Buffer[] {
    let buf = this.pending.length === 0 ? chunk : Buffer.concat([this.pending, chunk]);
    const frames: Buffer[] = [];
    while (buf.length > 0) {
      const verdict = this.check(buf);
      if (verdict.kind === 'need') break;
      if (verdict.kind === 'bad') {
        this.pending = Buffer.alloc(0);
        throw verdict.error;
      }
      const length = Math.max(1, Math.min(verdict.length, buf.length));
      if (verdict.kind === 'frame') {
        if (verdict.length > buf.length) break;
        frames.push(Buffer.from(buf.subarray(0, length)));
      }
      buf = buf.subarray(length);
    }
    if (buf.length > this.maxBuffered) {
      this.pending = Buffer.alloc(0);
      throw new ProtocolError(`peer sent ${buf.length} bytes without a complete frame (limit ${this.maxBuffered})`);
    }
    // Keep a private copy: the chunk's memory belongs to the socket.
    this.pending = buf.length === 0 ? Buffer.alloc(0) : Buffer.from(buf);
    return frames;
  }

  reset(): void {
    this.pending = Buffer.alloc(0);
  }
}
