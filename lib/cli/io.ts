/**
 * What every command shares with the process it runs in: the streams and the
 * Ctrl-C signal (CliIo), the exit codes, the one-line failure report, the
 * confirmation prompt and the connect-work-close frame around a client.
 */
import { createInterface } from 'node:readline';
import type { AnyClient } from '../connect';
import { abortError, isLinkError, PlcError, SourceError, TagErrors } from '../errors';
import { UsageError } from './args';

export const EXIT = Object.freeze({
  OK: 0,
  /** The PLC refused or could not serve one or more tags. */
  TAG_ERROR: 1,
  /** Bad command line, URL, address, value or source file: nothing was sent. */
  USAGE: 2,
  /** Could not connect (also: the PLC refused the password, or its certificate is not trusted), or the connection was lost. */
  CONNECTION: 3,
  /** A write or a control command was refused for safety (read-only, allow-list, no control=true, or no --yes). */
  REFUSED: 4,
  /** Stopped by Ctrl-C before it finished. */
  INTERRUPTED: 130,
});

export interface CliIo {
  stdout: NodeJS.WritableStream;
  stderr: NodeJS.WritableStream;
  stdin: NodeJS.ReadableStream & { isTTY?: boolean };
  /** Aborted on SIGINT/SIGTERM. */
  signal: AbortSignal;
}

/**
 * One line on stderr, and the exit code for the kind of failure. A source
 * that does not compile is reported as compilers do, `file:line:column: problem`
 * at the start of the line, which editors and CI annotations jump to.
 */
export function fail(io: CliIo, err: unknown, debug: boolean): number {
  const code = exitCode(err);
  const message = err instanceof Error ? err.message : String(err);
  const prefix = err instanceof SourceError ? '' : 'plcwire: ';
  io.stderr.write(`${prefix}${message}${code === EXIT.USAGE && err instanceof UsageError ? ' (plcwire --help)' : ''}\n`);
  if (debug && err instanceof Error && err.stack) io.stderr.write(`${err.stack}\n`);
  return code;
}

/**
 * Errors `client.connect()` rejected with (withClient): whatever their code, the command could not connect, as
 * the doctor's failed connection steps say (a refused password is ACCESS_DENIED, which for a tag is a tag error).
 */
const CONNECT_FAILURES = new WeakSet<object>();

export function exitCode(err: unknown): number {
  const code = exitCodeOf(err);
  return code === EXIT.TAG_ERROR && typeof err === 'object' && err !== null && CONNECT_FAILURES.has(err) ? EXIT.CONNECTION : code;
}

function exitCodeOf(err: unknown): number {
  if (err instanceof UsageError) return EXIT.USAGE;
  if (err instanceof TagErrors) {
    // The tag errors' most telling code: bad input, then a refusal, then the link, else the tags themselves.
    const codes = new Set(Object.values(err.errors).map((e) => exitCode(e)));
    return [EXIT.USAGE, EXIT.REFUSED, EXIT.CONNECTION].find((c) => codes.has(c)) ?? EXIT.TAG_ERROR;
  }
  if (!(err instanceof PlcError)) return EXIT.TAG_ERROR;
  if (isLinkError(err)) return EXIT.CONNECTION;
  switch (err.code) {
    case 'INVALID_ADDRESS':
    case 'INVALID_VALUE':
    case 'INVALID_URL':
    case 'INVALID_SOURCE':
    case 'OPTIMIZED_BLOCK': // a name in an optimized block over a protocol that reads by address: nothing was sent
      return EXIT.USAGE;
    case 'WRITE_NOT_ALLOWED':
      return EXIT.REFUSED;
    case 'ABORTED':
      return EXIT.INTERRUPTED;
    case 'TIMEOUT':
    case 'PROTOCOL_ERROR':
    case 'CERTIFICATE_UNTRUSTED': // the PLC's TLS certificate refused before any data: the connection failed
      return EXIT.CONNECTION;
    default:
      return EXIT.TAG_ERROR;
  }
}

/** Connects `client`, runs `work`, always closes; Ctrl-C aborts the connect or the request. */
export async function withClient<R>(client: AnyClient, io: CliIo, work: (client: AnyClient) => Promise<R>): Promise<R> {
  const onAbort = () => void client.close();
  io.signal.addEventListener('abort', onAbort, { once: true });
  try {
    await client.connect().catch((err: unknown) => {
      if (typeof err === 'object' && err !== null) CONNECT_FAILURES.add(err);
      throw err;
    });
    return await work(client);
  } catch (err) {
    if (io.signal.aborted) throw abortError('the command', io.signal);
    throw err;
  } finally {
    io.signal.removeEventListener('abort', onAbort);
    await client.close();
  }
}

export function confirm(io: CliIo, question: string): Promise<boolean> {
  const rl = createInterface({ input: io.stdin, output: io.stderr });
  return new Promise((resolve) => {
    const onAbort = () => rl.close();
    io.signal.addEventListener('abort', onAbort, { once: true });
    rl.on('close', () => resolve(false));
    rl.question(question, (answer) => {
      io.signal.removeEventListener('abort', onAbort);
      resolve(/^y(es)?$/i.test(answer.trim()));
      rl.close();
    });
  });
}

/** Resolves when Ctrl-C (or SIGTERM) aborts `io.signal`: how `serve` and `demo` run until stopped. */
export function untilInterrupted(io: CliIo): Promise<void> {
  return new Promise<void>((resolve) => {
    if (io.signal.aborted) resolve();
    else io.signal.addEventListener('abort', () => resolve(), { once: true });
  });
}
