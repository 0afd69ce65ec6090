import { ProtocolError } from '../errors';

/**
 * What a transport's framer says of the bytes buffered so far, which always
 * start at a frame boundary (or at garbage to skip).
 */
export type FrameCheck =
  { kind: 'need' } | { kind: 'frame'; length: number } | { kind: 'skip'; length: number } | { kind: 'bad'; error: ProtocolError };

const DEFAULT_MAX_BUFFERED = 1 << 20;
const EMPTY = Buffer.alloc(0);

export interface FrameReaderOptions {
  /**
   * false: frames and the bytes kept between chunks are subarrays of the
   * chunks pushed, not copies. Only for chunks that stay the caller's, as a
   * net.Socket's 'data' chunks do (each read gets its own memory); a stream
   * that reuses its buffers needs the default, true.
   */
  copy?: boolean;
}

/** Cuts a byte stream into frames with a framer function. Knows nothing of sockets. */
export class FrameReader {
  private pending: Buffer = Buffer.alloc(0);
  private readonly copy: boolean;

  constructor(
    private readonly check: (buffered: Buffer) => FrameCheck,
    private readonly maxBuffered = DEFAULT_MAX_BUFFERED,
    options: FrameReaderOptions = {},
  ) {
    this.copy = options.copy ?? true;
  }

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
        this.pending = EMPTY;
        throw verdict.error;
      }
      const length = Math.max(1, Math.min(verdict.length, buf.length));
      if (verdict.kind === 'frame') {
        if (verdict.length > buf.length) break;
        const frame = buf.subarray(0, length);
        frames.push(this.copy ? Buffer.from(frame) : frame);
      }
      buf = buf.subarray(length);
    }
    if (buf.length > this.maxBuffered) {
      this.pending = EMPTY;
      throw new ProtocolError(`peer sent ${buf.length} bytes without a complete frame (limit ${this.maxBuffered})`);
    }
    // Keep a private copy unless the chunks are ours to keep.
    this.pending = buf.length === 0 ? EMPTY : this.copy ? Buffer.from(buf) : buf;
    return frames;
  }

  reset(): void {
    this.pending = EMPTY;
  }
}
