/**
 * One S7CommPlus connection on the simulator's socket, through the transport
 * the client uses (lib/s7plus/transport): the COTP tunnel (`CotpTunnel`: DT
 * frames cut to the confirmed TPDU size, their payloads as one stream)
 * carries S7CommPlus frames in plain text until InitSSL, then TLS records
 * (`acceptTls`), the TPKT and COTP headers staying in clear as on a CPU
 * (s7commplus (MIT) server.py and connection.py `_activate_tls`). Frames are
 * cut by the codec's `S7pFrameReader`.
 */
import type { Socket } from 'node:net';
import type * as tls from 'node:tls';
import { ConnectionError, ProtocolError } from '../../errors';
import { OMS_EXPORTER_LABEL, OMS_EXPORTER_LENGTH, S7P_PROTOCOL_ID } from '../constants';
import { S7pFrameReader, type S7pMessage } from '../codec/frame';
import { acceptTls } from '../transport/server-tls';
import { CotpTunnel } from '../transport/tunnel';
import { PlusSession, type SessionOptions } from './session';
import { ResetConnection, type CpuSide } from './services';
import { connectionConfirm, connectionRequest } from './tsap';

/** The largest S7CommPlus frame put in one TLS write: the client reads a record at a time (connection.py `_recv_s7_data`). */
const MAX_FRAME_DATA = 16000;
/** How long a client may take for its TLS handshake after InitSSL. */
const TLS_HANDSHAKE_MS = 10_000;

export interface ConnectionHost {
  readonly cpu: CpuSide;
  readonly secureContext: tls.SecureContext | undefined;
  readonly session: Omit<SessionOptions, 'tls' | 'push' | 'exporter'>;
  /** The accepted socket, which this connection reads and writes from the CR's confirm on. */
  readonly socket: Socket;
  /** Ends the connection: `reason` is a frame that broke the protocol (the simulator reports it and drops the socket). */
  close(reason?: Error): void;
}

export class PlusConnection {
  private readonly session: PlusSession;
  private readonly tunnel: CotpTunnel;
  private readonly frames = new S7pFrameReader();
  private readonly onPlain = (bytes: Buffer) => this.receive(bytes);
  private secure: tls.TLSSocket | undefined;
  private closed = false;

  constructor(
    private readonly host: ConnectionHost,
    crFrame: Buffer,
  ) {
    const cr = connectionRequest(crFrame);
    if (!cr) throw new ProtocolError('not a COTP connection request');
    this.session = new PlusSession(host.cpu, {
      ...host.session,
      tls: host.secureContext !== undefined,
      push: (frame) => this.push(frame),
      exporter: () => this.secure?.exportKeyingMaterial(OMS_EXPORTER_LENGTH, OMS_EXPORTER_LABEL, Buffer.alloc(0)),
    });
    const confirm = connectionConfirm(cr);
    host.socket.write(confirm.frame);
    this.tunnel = new CotpTunnel(host.socket, { tpduSize: confirm.tpduBytes });
    this.tunnel.on('data', this.onPlain);
    this.tunnel.on('error', (err: Error) => this.fail(err));
  }

  /** A frame the S7 simulator cut before the tunnel took the socket over: nothing may come before the confirm. */
  onFrame(): void {
    throw new ProtocolError('S7CommPlus: data before the COTP connection confirm');
  }

  /** The socket closed: end TLS and the tunnel too. */
  dispose(): void {
    this.closed = true;
    this.session.close();
    this.secure?.destroy();
    this.tunnel.destroy();
  }

  /**
   * A link error: a frame that broke the protocol (or TLS) is reported; a peer that left, and our write racing its
   * close (the stream's ERR_STREAM_WRITE_AFTER_END, a reset), just end the connection.
   */
  private fail(err: Error): void {
    if (this.closed) return;
    this.closed = true;
    this.session.close();
    const code = (err as NodeJS.ErrnoException).code ?? '';
    const left = err instanceof ConnectionError || /^(ERR_STREAM_|ECONNRESET$|EPIPE$)/.test(code);
    this.host.close(left ? undefined : err);
  }

  private receive(bytes: Buffer): void {
    let messages: S7pMessage[];
    try {
      messages = this.frames.push(bytes);
    } catch (err) {
      return this.fail(err as Error);
    }
    for (const message of messages) {
      if (this.closed) return;
      try {
        this.step(message);
      } catch (err) {
        return this.fail(err as Error);
      }
    }
  }

  private step(message: S7pMessage): void {
    const { version, data } = message;
    if (data.length > 0xffff) throw new ResetConnection(`a request of ${data.length} bytes of data, more than one frame takes`);
    const frame = Buffer.concat([Buffer.of(S7P_PROTOCOL_ID, version, data.length >> 8, data.length & 0xff), data]);
    const step = this.session.handle(Buffer.concat([frame, Buffer.of(S7P_PROTOCOL_ID, version, 0, 0)]));
    if (step.reply) this.reply(step.reply);
    if (step.startTls) this.startTls();
    if (step.close) {
      this.closed = true;
      this.session.close();
      if (this.secure) this.secure.end(() => this.host.close());
      else this.tunnel.end(() => this.host.close());
    }
  }

  /** Writes to the peer: through TLS once it runs, else into the tunnel (DT frames of the confirmed TPDU size). */
  private write(bytes: Buffer): void {
    if (this.secure) this.secure.write(bytes);
    else this.tunnel.write(bytes);
  }

  /** Sends a response, split over several frames when long (the trailer after the last only, as a CPU splits). */
  private reply(frame: Buffer): void {
    const version = frame[1]!;
    const data = frame.subarray(4, frame.length - 4);
    const pieces: Buffer[] = [];
    for (let at = 0; at < data.length || pieces.length === 0; at += MAX_FRAME_DATA) pieces.push(data.subarray(at, at + MAX_FRAME_DATA));
    pieces.forEach((piece, i) => {
      const head = Buffer.from([S7P_PROTOCOL_ID, version, 0, 0]);
      head.writeUInt16BE(piece.length, 2);
      const last = i === pieces.length - 1;
      this.write(Buffer.concat([head, piece, ...(last ? [frame.subarray(frame.length - 4)] : [])]));
    });
  }

  /** A notification: one frame, sent as a response is. */
  private push(frame: Buffer): void {
    if (!this.closed) this.write(frame);
  }

  /** After the InitSSL answer: the tunnel's bytes are TLS records from now on, the frames inside them S7CommPlus. */
  private startTls(): void {
    if (this.frames.buffered > 0) throw new ProtocolError('S7CommPlus: data after InitSSL before the TLS handshake');
    this.tunnel.off('data', this.onPlain);
    const peer = `${this.host.socket.remoteAddress ?? 'a client'}:${this.host.socket.remotePort ?? 0}`;
    acceptTls(this.tunnel, this.host.secureContext!, { timeout: TLS_HANDSHAKE_MS, peer }).then(
      (secure) => {
        if (this.closed) return void secure.destroy();
        this.secure = secure;
        secure.on('data', (bytes: Buffer) => this.receive(bytes));
        secure.on('error', (err: Error) => this.fail(err));
      },
      (err: Error) => this.fail(err),
    );
  }
}
