/**
 * The COTP tunnel of an S7CommPlus connection as a Duplex: TCP to port 102,
 * COTP CR with the S7CommPlus TSAPs (calling 0x0600, called the ASCII name of
 * the role) → CC, then every write one COTP DT (TPKT framed) and the payload
 * of every DT read. TLS runs over this stream, not over the raw socket, so the
 * TPKT and COTP headers stay plain as the PLC expects (s7commplus (MIT),
 * transport.py _build_cotp_cr, connection.py _activate_tls).
 *
 * The client's own until lib/s7plus/transport/ (the COTP tunnel of the
 * transport layer) is merged; it then takes this one's place.
 */
import type * as net from 'node:net';
import { Duplex } from 'node:stream';
import { abortError, ConnectionError, type PlcError, ProtocolError, toPlcError } from '../../errors';
import { FrameReader } from '../../link/framer';
import { openTcp } from '../../link/tcp';
import { checkTpkt } from '../../s7/codec/tpkt';
import { LOCAL_TSAP, RemoteTsap as REMOTE_TSAP } from '../constants';
import type { S7PlusRole } from '../url';

const COTP_CR = 0xe0;
const COTP_CC = 0xd0;
const COTP_DR = 0x80;
const COTP_DT = 0xf0;
const EOT = 0x80;
/** TPDU size code 0x0A: 1024 bytes (what s7commplus asks for). */
const TPDU_SIZE_CODE = 0x0a;
/** Largest TPKT packet: the longest DT payload is this less TPKT (4) and DT (3) headers. */
const MAX_TPKT = 0xffff;

/** TPKT + COTP CR with the S7CommPlus TSAPs: calling 0x0600, called the role's name, TPDU size. */
function connectionRequest(role: S7PlusRole): Buffer {
  const called = Buffer.from(REMOTE_TSAP[role], 'latin1');
  const params = Buffer.concat([
    Buffer.from([0xc1, 2, LOCAL_TSAP >> 8, LOCAL_TSAP & 0xff]),
    Buffer.from([0xc2, called.length]),
    called,
    Buffer.from([0xc0, 1, TPDU_SIZE_CODE]),
  ]);
  const cotp = Buffer.concat([Buffer.from([6 + params.length, COTP_CR, 0, 0, 0, 1, 0]), params]);
  return Buffer.concat([Buffer.from([3, 0, (cotp.length + 4) >> 8, (cotp.length + 4) & 0xff]), cotp]);
}

function dataFrame(payload: Buffer): Buffer {
  const frame = Buffer.allocUnsafe(7 + payload.length);
  frame.writeUInt32BE(0x03000000 | frame.length, 0);
  frame[4] = 2;
  frame[5] = COTP_DT;
  frame[6] = EOT;
  payload.copy(frame, 7);
  return frame;
}

/** A live tunnel: a Duplex of the DT payloads over its socket. */
export class CotpTunnel extends Duplex {
  private readonly reader = new FrameReader(checkTpkt, MAX_TPKT);

  constructor(
    private readonly socket: net.Socket,
    private readonly name: string,
  ) {
    super();
    socket.on('data', (chunk: Buffer) => {
      try {
        for (const frame of this.reader.push(chunk)) this.frame(frame);
      } catch (err) {
        this.destroy(toPlcError(err, 'PROTOCOL_ERROR'));
      }
    });
    socket.on('error', (err) => this.destroy(new ConnectionError('CONNECTION_LOST', `${name}: ${err.message}`, { cause: err })));
    socket.on('close', () => this.destroy());
  }

  private frame(frame: Buffer): void {
    const type = frame[5]! & 0xf0;
    if (type === COTP_DT) {
      this.push(frame.subarray(4 + 1 + frame[4]!));
      return;
    }
    if (type === COTP_DR) throw new ConnectionError('CONNECTION_LOST', `${this.name} ended the connection (COTP disconnect request)`);
    throw new ProtocolError(`${this.name}: a COTP frame of type 0x${type.toString(16)} inside the connection`);
  }

  override _read(): void {
    // Frames are pushed as they arrive; a PLC answers only what was asked.
  }

  override _write(chunk: Buffer, _encoding: BufferEncoding, done: (err?: Error | null) => void): void {
    const room = MAX_TPKT - 7;
    for (let at = 0; at < chunk.length; at += room) this.socket.write(dataFrame(chunk.subarray(at, at + room)));
    done();
  }

  override _destroy(err: Error | null, done: (err: Error | null) => void): void {
    this.socket.destroy();
    done(err);
  }
}

/**
 * TCP and COTP CR → CC. Rejects with a PlcError (CONNECT_FAILED when the PLC
 * refuses the TSAPs) and leaves no socket behind.
 */
export async function openTunnel(
  e: { host: string; port: number; role: S7PlusRole },
  o: { name: string; timeout: number; signal: AbortSignal },
): Promise<CotpTunnel> {
  const socket = await openTcp({ host: e.host, port: e.port, timeout: o.timeout, signal: o.signal });
  try {
    const cc = await firstFrame(socket, o, e.role);
    if ((cc[5]! & 0xf0) !== COTP_CC) {
      throw new ConnectionError(
        'CONNECT_FAILED',
        `${o.name} refused the S7CommPlus connection (called TSAP "${REMOTE_TSAP[e.role]}"): the CPU does not speak S7CommPlus on this port, or its connection limit is reached`,
      );
    }
    return new CotpTunnel(socket, o.name);
  } catch (err) {
    socket.destroy();
    throw err;
  }
}

/** Sends the CR and waits for one whole TPKT frame (the CC), the connect signal and the socket's end honoured. */
function firstFrame(socket: net.Socket, o: { name: string; signal: AbortSignal }, role: S7PlusRole): Promise<Buffer> {
  const reader = new FrameReader(checkTpkt, MAX_TPKT);
  return new Promise<Buffer>((resolve, reject) => {
    const done = (err: PlcError | undefined, frame?: Buffer) => {
      socket.off('data', onData);
      socket.off('error', onError);
      socket.off('close', onClose);
      o.signal.removeEventListener('abort', onAbort);
      if (err) reject(err);
      else resolve(frame!);
    };
    const onData = (chunk: Buffer) => {
      try {
        const [frame] = reader.push(chunk);
        if (frame) done(undefined, frame);
      } catch (err) {
        done(toPlcError(err, 'PROTOCOL_ERROR'));
      }
    };
    const onError = (err: Error) => done(new ConnectionError('CONNECT_FAILED', `${o.name}: ${err.message}`, { cause: err }));
    const onClose = () => done(new ConnectionError('CONNECT_FAILED', `${o.name} closed the connection before confirming it (COTP)`));
    const onAbort = () => done(abortError(`connecting to ${o.name}`, o.signal));
    socket.on('data', onData);
    socket.on('error', onError);
    socket.on('close', onClose);
    o.signal.addEventListener('abort', onAbort, { once: true });
    socket.write(connectionRequest(role));
  });
}
