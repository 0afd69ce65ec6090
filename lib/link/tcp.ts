import * as net from 'node:net';
import { ConnectionError, PlcError, TimeoutError } from '../errors';

export interface TcpConnectOptions {
  host: string;
  port: number;
  /** Milliseconds to wait for the TCP handshake. */
  timeout: number;
  signal?: AbortSignal;
  /** TCP keep-alive probe delay; 0 disables. */
  keepAliveMs?: number;
}

const DEFAULT_KEEPALIVE_MS = 10_000;

/**
 * Connects with no-delay and keep-alive on. Rejects with a PlcError
 * (CONNECT_FAILED, TIMEOUT or ABORTED); on failure no socket or listener is left.
 */
export function openTcp(options: TcpConnectOptions): Promise<net.Socket> {
  const { host, port, timeout, signal } = options;
  const where = `${host}:${port}`;
  return new Promise((resolve, reject) => {
    if (signal?.aborted) return reject(abortError(where, signal));
    const socket = net.connect({ host, port, noDelay: true });
    const timer = setTimeout(() => fail(new TimeoutError(`connecting to ${where} timed out after ${timeout} ms`)), timeout);
    const onAbort = () => fail(abortError(where, signal!));
    const onError = (err: NodeJS.ErrnoException) =>
      fail(new ConnectionError('CONNECT_FAILED', `cannot connect to ${where}: ${err.code ?? err.message}`, { cause: err }));
    const cleanup = () => {
      clearTimeout(timer);
      signal?.removeEventListener('abort', onAbort);
      socket.removeListener('error', onError);
      socket.removeListener('connect', onConnect);
    };
    function fail(err: PlcError) {
      cleanup();
      socket.on('error', () => {}); // a late error from the destroyed socket must not go unhandled
      socket.destroy();
      reject(err);
    }
    function onConnect() {
      cleanup();
      const keepAlive = options.keepAliveMs ?? DEFAULT_KEEPALIVE_MS;
      if (keepAlive > 0) socket.setKeepAlive(true, keepAlive);
      resolve(socket);
    }
    socket.once('connect', onConnect);
    socket.once('error', onError);
    signal?.addEventListener('abort', onAbort, { once: true });
  });
}

function abortError(where: string, signal: AbortSignal): PlcError {
  return new PlcError('ABORTED', `connecting to ${where} was aborted`, { cause: signal.reason });
}
