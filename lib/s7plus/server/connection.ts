/**
 * One S7CommPlus connection on the simulator's socket: the COTP CR it was
 * opened with, COTP data frames carrying S7CommPlus frames in plain text
 * until InitSSL, then TLS records carried in COTP data frames (the TPKT and
 * COTP headers stay in clear, as on a CPU: s7commplus (MIT) server.py and
 * connection.py `_activate_tls`), Node's TLS running over a Duplex of ours.
 */
import { Duplex } from 'node:stream';
import * as tls from 'node:tls';
import { ProtocolError } from '../../errors';
import { OMS_EXPORTER_LABEL, OMS_EXPORTER_LENGTH } from '../constants';
import { PlusSession, type SessionOptions } from './session';
import type { CpuSide } from './services';
import { connectionConfirm, connectionRequest, dataFrame } from './tsap';

/** The largest S7CommPlus frame put in one TLS write: the client reads a record at a time (connection.py `_recv_s7_data`). */
const MAX_FRAME_DATA = 16000;
/** Cleartext buffered while waiting for the rest of a frame. */
const MAX_PENDING = 1 << 20;

export interface ConnectionHost {
  readonly cpu: CpuSide;
  readonly secureContext: tls.SecureContext | undefined;
  readonly session: Omit<SessionOptions, 'tls' | 'push' | 'exporter'>;
  /** Writes bytes to the socket. */
  send(bytes: Buffer): void;
  /** Ends the connection (reset, or after DeleteObject). */
  close(reason?: Error): void;
}

export class PlusConnection {
  private readonly session: PlusSession;
  private pending: Buffer = Buffer.alloc(0);
  private unit: Buffer[] = [];
  private tunnel: Duplex | undefined;
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
    host.send(connectionConfirm(cr));
  }

  /** A TPKT frame from the socket. */
  onFrame(frame: Buffer): void {
    if (this.closed) return;
    if (frame.length < 7 || frame[5] !== 0xf0)
      throw new ProtocolError(`COTP ${frame.length < 6 ? 'frame too short' : `type 0x${frame[5]!.toString(16)}`} where data was expected`);
    this.unit.push(frame.subarray(7));
    if ((frame[6]! & 0x80) === 0) return;
    const payload = Buffer.concat(this.unit);
    this.unit = [];
    if (this.tunnel) this.tunnel.push(payload);
    else this.onClear(payload);
  }

  /** The socket closed: end TLS too. */
  dispose(): void {
    this.closed = true;
    this.session.close();
    this.secure?.destroy();
    this.tunnel?.destroy();
  }

  private onClear(bytes: Buffer): void {
    this.pending = this.pending.length === 0 ? bytes : Buffer.concat([this.pending, bytes]);
    if (this.pending.length > MAX_PENDING) throw new ProtocolError(`more than ${MAX_PENDING} bytes without a whole S7CommPlus frame`);
    while (this.pending.length >= 4 && !this.closed) {
      if (this.pending[0] !== 0x72) throw new ProtocolError(`S7CommPlus frame starts with 0x${this.pending[0]!.toString(16)}`);
      const total = 4 + this.pending.readUInt16BE(2) + 4;
      if (this.pending.length < total) return;
      const frame = this.pending.subarray(0, total);
      this.pending = this.pending.subarray(total);
      this.step(frame);
    }
  }

  private step(frame: Buffer): void {
    const step = this.session.handle(frame);
    if (step.reply) this.reply(step.reply);
    if (step.startTls) this.startTls();
    if (step.close) {
      this.closed = true;
      this.session.close();
      if (this.secure) this.secure.end(() => this.host.close());
      else this.host.close();
    }
  }

  /** Sends a response, split over several frames when long (the trailer after the last only, as a CPU splits). */
  private reply(frame: Buffer): void {
    const version = frame[1]!;
    const data = frame.subarray(4, frame.length - 4);
    const pieces: Buffer[] = [];
    for (let at = 0; at < data.length || pieces.length === 0; at += MAX_FRAME_DATA) pieces.push(data.subarray(at, at + MAX_FRAME_DATA));
    pieces.forEach((piece, i) => {
      const head = Buffer.from([0x72, version, 0, 0]);
      head.writeUInt16BE(piece.length, 2);
      const last = i === pieces.length - 1;
      const out = Buffer.concat([head, piece, ...(last ? [frame.subarray(frame.length - 4)] : [])]);
      if (this.secure) this.secure.write(out);
      else this.host.send(dataFrame(out));
    });
  }

  /** A notification: one frame, sent as a response is. */
  private push(frame: Buffer): void {
    if (this.closed) return;
    if (this.secure) this.secure.write(frame);
    else this.host.send(dataFrame(frame));
  }

  private startTls(): void {
    const host = this.host;
    const tunnel = new Duplex({
      read() {},
      write(chunk: Buffer, _enc, done) {
        // TLS records in COTP data frames no longer than a TPDU of 1024 bytes can carry.
        for (let at = 0; at < chunk.length; at += 1021) host.send(dataFrame(chunk.subarray(at, at + 1021)));
        done();
      },
    });
    this.tunnel = tunnel;
    const secure = new tls.TLSSocket(tunnel, {
      isServer: true,
      secureContext: this.host.secureContext,
      requestCert: false,
    });
    this.secure = secure;
    secure.on('data', (bytes: Buffer) => {
      try {
        this.onClear(bytes);
      } catch (err) {
        this.host.close(err as Error);
      }
    });
    secure.on('error', (err: Error) => this.host.close(err));
  }
}
