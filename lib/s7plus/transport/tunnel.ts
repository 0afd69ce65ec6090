/**
 * The COTP tunnel: a Duplex whose bytes travel as the payload of COTP data
 * (DT) frames over an ISO-on-TCP connection that is already connected (CR/CC
 * done). S7CommPlus carries its TLS records this way: TPKT and COTP headers
 * stay in clear and only the DT payload is TLS (the s7commplus package (MIT),
 * connection.py `_activate_tls` and server.py `_server_tls_handshake`,
 * `_send_cotp_dt_raw`). Node's TLS runs on top: `tls.connect({ socket })` on
 * the client, `new tls.TLSSocket(tunnel, { isServer: true })` on a server.
 *
 * Out: each write is cut into DT frames of at most the negotiated TPDU size
 * (header included, ISO 8073 §14.6), the last with EOT set.
 * In: the payloads of the DT frames, in order, as one byte stream (a TLS
 * record may span frames, a frame may hold several records). A DT larger
 * than the TPDU size is taken as it comes: the s7commplus emulator sends a
 * whole TLS flight in one DT frame, and TPKT caps it at 64 KiB anyway.
 * A COTP disconnect request ends the stream; a malformed TPKT/COTP frame, an
 * error TPDU or an unexpected one destroys it with a ProtocolError.
 */
import { Duplex } from 'node:stream';
import { ConnectionError, ProtocolError, ValueError } from '../../errors';
import { FrameReader } from '../../link/framer';
import { COTP_DT_HEADER, CotpType, TPKT_HEADER, TPKT_VERSION } from '../../s7/constants';
import { decodeCotp } from '../../s7/codec/cotp';
import { checkTpkt } from '../../s7/codec/tpkt';

/** The byte stream below the tunnel: a net.Socket, or any Duplex (tests). */
type Carrier = Duplex & { remoteAddress?: string; remotePort?: number };

export interface CotpTunnelOptions {
  /** The TPDU size the CC confirmed, in bytes (1 << the size code: 1024 for 0x0A). */
  tpduSize: number;
  /** Bytes already read from the carrier after the CC, handed over in order. */
  head?: Buffer;
  /** Who is at the other end, for messages; default the carrier's remote address. */
  peer?: string;
}

/** Smallest and largest TPDU a DT frame may be cut to: ISO 8073 size codes 7..13 are 128..8192, TPKT allows up to 65531. */
const MIN_TPDU = 128;
const MAX_TPDU = 0xffff - TPKT_HEADER;

export class CotpTunnel extends Duplex {
  readonly peer: string;
  /** Largest DT payload sent in one frame. */
  readonly maxPayload: number;
  private readonly carrier: Carrier;
  private readonly reader = new FrameReader(checkTpkt);
  /** A write waiting for the carrier's 'drain'. */
  private waitingDrain: (() => void) | undefined;
  private readonly onData = (chunk: Buffer) => this.receive(chunk);
  /** The carrier's read side ended (FIN) or the peer disconnected (DR). */
  private ended = false;
  private readonly onEnd = () => {
    this.ended = true;
    this.push(null);
  };
  private readonly onDrain = () => {
    const resume = this.waitingDrain;
    this.waitingDrain = undefined;
    resume?.();
  };
  private readonly onError = (err: Error) => {
    this.destroy(new ConnectionError('CONNECTION_LOST', `connection to ${this.peer} failed: ${err.message}`, { cause: err }));
  };
  private readonly onClose = () => {
    // Closed after its end: the stream ends as usual once read. Closed without one: the connection was lost.
    if (!this.ended && !this.destroyed) this.destroy(this.lostError());
  };

  constructor(carrier: Carrier, options: CotpTunnelOptions) {
    super({ allowHalfOpen: false });
    const size = options.tpduSize;
    if (!Number.isInteger(size) || size < MIN_TPDU || size > MAX_TPDU) {
      throw new ValueError('COTP TPDU size', `${size} is not a whole number of bytes between ${MIN_TPDU} and ${MAX_TPDU}`);
    }
    this.carrier = carrier;
    this.maxPayload = size - COTP_DT_HEADER;
    this.peer = options.peer ?? (carrier.remoteAddress ? `${carrier.remoteAddress}:${carrier.remotePort}` : 'the peer');
    carrier.on('data', this.onData);
    carrier.on('end', this.onEnd);
    carrier.on('drain', this.onDrain);
    carrier.on('error', this.onError);
    carrier.on('close', this.onClose);
    if (options.head && options.head.length > 0) {
      const head = options.head;
      // After the constructor, so that a malformed head reaches an 'error' listener.
      process.nextTick(() => this.receive(head));
    }
  }

  private lostError(): ConnectionError {
    return new ConnectionError('CONNECTION_LOST', `connection to ${this.peer} was closed`);
  }

  private receive(chunk: Buffer): void {
    if (this.destroyed || this.ended) return;
    let frames: Buffer[];
    try {
      frames = this.reader.push(chunk);
    } catch (err) {
      this.destroy(new ProtocolError(`COTP tunnel from ${this.peer}: ${(err as Error).message}`, { cause: err }));
      return;
    }
    for (const frame of frames) {
      let message;
      try {
        message = decodeCotp(frame);
      } catch (err) {
        this.destroy(new ProtocolError(`COTP tunnel from ${this.peer}: ${(err as Error).message}`, { cause: err }));
        return;
      }
      if (message.type === 'DT') {
        if (message.payload.length > 0 && !this.push(message.payload)) this.carrier.pause();
      } else if (message.type === 'DR' || message.type === 'DC') {
        // The peer disconnects: no more data comes; answer by closing our side.
        this.onEnd();
        this.carrier.end();
        return;
      } else if (message.type === 'ER') {
        this.destroy(new ProtocolError(`COTP tunnel from ${this.peer}: the peer sent a TPDU error (cause ${message.cause})`));
        return;
      } else {
        this.destroy(new ProtocolError(`COTP tunnel from ${this.peer}: unexpected COTP ${message.type} on a connected link`));
        return;
      }
    }
  }

  override _read(): void {
    if (this.carrier.isPaused()) this.carrier.resume();
  }

  override _write(chunk: Buffer, _encoding: BufferEncoding, callback: (error?: Error | null) => void): void {
    const frames = this.frame(chunk);
    if (this.carrier.write(frames)) callback();
    else this.waitingDrain = () => callback();
  }

  /** DT frames for one write: fragments of at most maxPayload bytes, EOT on the last. */
  private frame(data: Buffer): Buffer {
    const overhead = TPKT_HEADER + COTP_DT_HEADER;
    const count = Math.max(1, Math.ceil(data.length / this.maxPayload));
    const out = Buffer.allocUnsafe(data.length + count * overhead);
    let at = 0;
    for (let i = 0; i < count; i++) {
      const part = data.subarray(i * this.maxPayload, (i + 1) * this.maxPayload);
      const length = overhead + part.length;
      out[at] = TPKT_VERSION;
      out[at + 1] = 0;
      out.writeUInt16BE(length, at + 2);
      out[at + 4] = 2; // length indicator: the two header bytes after it
      out[at + 5] = CotpType.DT;
      out[at + 6] = i === count - 1 ? 0x80 : 0x00; // EOT on the last fragment; TPDU number 0 (class 0)
      part.copy(out, at + overhead);
      at += length;
    }
    return out;
  }

  override _final(callback: (error?: Error | null) => void): void {
    // Everything written is with the carrier: end it (a FIN after its queued bytes) and be done.
    if (!this.carrier.destroyed && !this.carrier.writableEnded) this.carrier.end();
    callback();
  }

  override _destroy(error: Error | null, callback: (error?: Error | null) => void): void {
    this.carrier.removeListener('data', this.onData);
    this.carrier.removeListener('end', this.onEnd);
    this.carrier.removeListener('drain', this.onDrain);
    this.carrier.removeListener('error', this.onError);
    this.carrier.removeListener('close', this.onClose);
    this.carrier.destroy();
    this.reader.reset();
    const resume = this.waitingDrain;
    this.waitingDrain = undefined;
    resume?.();
    callback(error);
  }
}
