/**
 * The client's way into the COTP tunnel of an S7CommPlus connection: TCP to
 * port 102, COTP CR with the S7CommPlus TSAPs (calling 0x0600, called the
 * ASCII name of the role) → CC, then the transport's CotpTunnel
 * (lib/s7plus/transport/tunnel.ts) over the socket, at the TPDU size the CC
 * confirmed. TLS runs over the tunnel, not over the raw socket, so TPKT and
 * COTP stay plain as the PLC expects (s7commplus (MIT), transport.py
 * _build_cotp_cr, connection.py _activate_tls).
 */
import type * as net from 'node:net';
import { abortError, ConnectionError, type PlcError, toPlcError } from '../../errors';
import { openTcp } from '../../link/tcp';
import { decodeCotp } from '../../iso/cotp';
import { checkTpkt } from '../../iso/tpkt';
import { CotpTunnel } from '../transport/tunnel';
import { LOCAL_TSAP, RemoteTsap as REMOTE_TSAP } from '../constants';
import type { S7PlusRole } from '../url';

const COTP_CR = 0xe0;
/** TPDU size code 0x0A: 1024 bytes (what s7commplus asks for, and what a CC without the parameter leaves). */
const TPDU_SIZE_CODE = 0x0a;

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
    const { frame, head } = await firstFrame(socket, o, e.role);
    const cc = decodeCotp(frame);
    if (cc.type !== 'CC') {
      throw new ConnectionError(
        'CONNECT_FAILED',
        `${o.name} refused the S7CommPlus connection (called TSAP "${REMOTE_TSAP[e.role]}"): the CPU does not speak S7CommPlus on this port, or its connection limit is reached`,
      );
    }
    return new CotpTunnel(socket, { tpduSize: 1 << (cc.tpduSize || TPDU_SIZE_CODE), head, peer: o.name });
  } catch (err) {
    socket.destroy();
    throw err;
  }
}

/** Sends the CR and waits for one whole TPKT frame (the CC) and what came after it, the connect signal and the socket's end honoured. */
function firstFrame(
  socket: net.Socket,
  o: { name: string; signal: AbortSignal },
  role: S7PlusRole,
): Promise<{ frame: Buffer; head: Buffer }> {
  let buffered = Buffer.alloc(0);
  return new Promise((resolve, reject) => {
    const done = (err: PlcError | undefined, got?: { frame: Buffer; head: Buffer }) => {
      socket.off('data', onData);
      socket.off('error', onError);
      socket.off('close', onClose);
      o.signal.removeEventListener('abort', onAbort);
      if (err) reject(err);
      else resolve(got!);
    };
    const onData = (chunk: Buffer) => {
      buffered = Buffer.concat([buffered, chunk]);
      const check = checkTpkt(buffered);
      if (check.kind === 'bad') return done(toPlcError(check.error, 'PROTOCOL_ERROR'));
      if (check.kind === 'frame') done(undefined, { frame: buffered.subarray(0, check.length), head: buffered.subarray(check.length) });
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
