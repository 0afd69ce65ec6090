import * as net from 'node:net';
import { abortError, ConnectionError, PlcError, TimeoutError } from '../errors';

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
    if (signal?.aborted) return reject(abortError(`connecting to ${where}`, signal));
    const socket = net.connect({ host, port, noDelay: true });
    const timer = setTimeout(() => fail(new TimeoutError(`connecting to ${where} timed out after ${timeout} ms`)), timeout);
    const onAbort = () => fail(abortError(`connecting to ${where}`, signal!));
    const onError = (err: NodeJS.ErrnoException) =>
      fail(new ConnectionError('CONNECT_FAILED', connectFailure(host, port, err), { cause: err }));
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

/**
 * A failed connect in words that say what to check, with the system's code
 * kept (it is what people search for). A name that does not resolve is about
 * the host, not the port.
 */
function connectFailure(host: string, port: number, err: NodeJS.ErrnoException): string {
  const where = `${host}:${port}`;
  switch (err.code) {
    case 'ENOTFOUND':
      return `cannot connect to ${where}: the host name "${host}" does not resolve (ENOTFOUND): check the name, or use the PLC's IP address`;
    case 'EAI_AGAIN':
      return `cannot connect to ${where}: the host name "${host}" could not be looked up (EAI_AGAIN: no DNS server answered): check the network's DNS, or use the PLC's IP address`;
    case 'ECONNREFUSED':
      return `cannot connect to ${where}: the connection was refused (ECONNREFUSED): nothing listens on port ${port} at ${host}`;
    case 'EHOSTUNREACH':
    case 'ENETUNREACH':
      return `cannot connect to ${where}: no route to ${host} (${err.code}): check the IP address, the subnet and the cable`;
    default:
      return `cannot connect to ${where}: ${err.code ?? err.message}`;
  }
}
