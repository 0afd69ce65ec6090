/**
 * The s7commplus package (PyPI, MIT; https://github.com/gijzelaerr/s7commplus)
 * as an independent S7CommPlus peer: its server emulator and its client, run
 * as Python processes by test/interop/s7commplus/server.py and client.py,
 * which talk JSON lines. `npm test`'s pretest installs the package into
 * test/interop/.venv-s7commplus (test/support/install-peers.js s7commplus);
 * without it a suite skips with the reason (requireS7CommPlus).
 *
 * Every process started here is tracked: stop it in `after`, and call
 * stopS7CommPlusPeers() there as well, so a failed test leaves none behind.
 */
import { type ChildProcess, spawn, spawnSync } from 'node:child_process';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import * as readline from 'node:readline';
import type { Context } from 'mocha';
import { skipBecause } from './skip';

/** The repository (this file runs as dist/test/support/s7commplus-peer.js). */
const ROOT = path.resolve(__dirname, '../../..');
const SCRIPTS = path.join(ROOT, 'test/interop/s7commplus');
const VENV = path.join(ROOT, 'test/interop/.venv-s7commplus');
const VENV_PYTHON = path.join(VENV, process.platform === 'win32' ? 'Scripts/python.exe' : 'bin/python');
/** The s7commplus version the scripts are written for: the one test/support/install-peers.js installs. */
export const { S7COMMPLUS_VERSION } = require(path.join(ROOT, 'test/support/install-peers.js')) as { S7COMMPLUS_VERSION: string };

/** A Python that imports s7commplus S7COMMPLUS_VERSION (the venv's, else python3's), or why there is none. */
export function findS7CommPlus(): { python: string } | { reason: string } {
  const tried: string[] = [];
  for (const python of [...(fs.existsSync(VENV_PYTHON) ? [VENV_PYTHON] : []), 'python3']) {
    const r = spawnSync(python, ['-c', 'import importlib.metadata as m, s7commplus; print(m.version("s7commplus"))'], {
      encoding: 'utf8',
      timeout: 30_000,
    });
    const version = r.status === 0 ? r.stdout.trim() : undefined;
    if (version === S7COMMPLUS_VERSION) return { python };
    tried.push(
      r.error
        ? `${python}: ${(r.error as NodeJS.ErrnoException).code ?? r.error.message}`
        : version === undefined
          ? `${python}: no s7commplus module`
          : `${python}: s7commplus ${version}`,
    );
  }
  return {
    reason:
      `s7commplus ${S7COMMPLUS_VERSION} is not installed (${tried.join('; ')}); ` +
      '`node test/support/install-peers.js s7commplus` installs it (npm test does), with python3 and PyPI',
  };
}

let found: { python: string } | { reason: string } | undefined;

/** The peer's Python, or skips the suite (from `before`) or test, saying why. Looked up once per run. */
export function requireS7CommPlus(ctx: Context): string {
  found ??= findS7CommPlus();
  if ('reason' in found) skipBecause(ctx, found.reason);
  return found.python;
}

// ---------------------------------------------------------------------------
// Processes

const live = new Set<ChildProcess>();

function track(child: ChildProcess): void {
  live.add(child);
  child.once('exit', () => live.delete(child));
  // A Python that cannot be started emits 'error' and no 'exit'.
  child.once('error', () => live.delete(child));
}

/** Resolves when `child` has exited; SIGKILL after `ms` if it has not. */
function awaitExit(child: ChildProcess, ms: number): Promise<void> {
  if (child.exitCode !== null || child.signalCode !== null) return Promise.resolve();
  return new Promise((resolve) => {
    const timer = setTimeout(() => child.kill('SIGKILL'), ms);
    child.once('exit', () => {
      clearTimeout(timer);
      resolve();
    });
  });
}

/** Kills every peer process still running and waits for each to exit: the safety net for `after`. */
export async function stopS7CommPlusPeers(): Promise<void> {
  await Promise.all(
    [...live].map((child) => {
      child.kill('SIGKILL');
      return awaitExit(child, 5000);
    }),
  );
}

/** How many peer processes are running (0 after every suite). */
export function liveS7CommPlusPeers(): number {
  return live.size;
}

/** Lines of `child`'s stdout, each to `onLine`; stderr kept for error messages. */
function lines(child: ChildProcess, onLine: (line: string) => void): { stderr: () => string } {
  let stderr = '';
  child.stderr!.setEncoding('utf8');
  child.stderr!.on('data', (d: string) => (stderr = (stderr + d).slice(-4000)));
  readline.createInterface({ input: child.stdout! }).on('line', onLine);
  return { stderr: () => stderr.trim() };
}

// ---------------------------------------------------------------------------
// Server

/** A data block of the emulator: its variables are name -> [type ("Real", "Int", "Bool", ...), byte offset]. */
export interface PeerDb {
  readonly number: number;
  readonly size?: number;
  readonly variables?: Readonly<Record<string, readonly [type: string, offset: number]>>;
  /** Initial bytes from offset 0. */
  readonly data?: Buffer;
}

export interface PeerServerOptions {
  readonly dbs?: readonly PeerDb[];
  /** TLS after InitSSL: a certificate and key (PEM paths), or one the script makes (RSA 2048). Without it, plain V1. */
  readonly tls?: { readonly cert: string; readonly key: string } | 'self-signed';
  /** The highest TLS version the server accepts: '1.2' makes it refuse TLS 1.3, as some S7-1500 firmware is reported to. */
  readonly tlsMaxVersion?: '1.2' | '1.3';
  /** The protocol version the emulator announces: 1 without TLS, 2 with it by default. */
  readonly version?: number;
  /** The emulator drops a connection whose request frame is longer (PLCSIM Advanced's behaviour past about 1 kB). */
  readonly maxRequestBytes?: number;
  readonly host?: string;
  /** 0 (the default): a free port. */
  readonly port?: number;
}

/** A DB item write the emulator received; `ok` false: refused, nothing written. */
export interface PeerWrite {
  readonly db: number | null;
  readonly offset: number | null;
  readonly size: number | null;
  readonly data: Buffer;
  readonly ok: boolean;
}

interface ServerLine {
  event: string;
  [key: string]: unknown;
}

/** What the server reports as it happens (see server.py's docstring). */
export type PeerEvent =
  | { readonly event: 'connected' | 'disconnected'; readonly peer: string }
  | { readonly event: 'request'; readonly peer: string | null; readonly function: number | null; readonly bytes: number }
  | { readonly event: 'deleteObject'; readonly peer: string | null; readonly session: number }
  | ({ readonly event: 'write' } & PeerWrite);

const EVENTS = new Set(['connected', 'disconnected', 'request', 'deleteObject', 'write']);

export class S7CommPlusPeerServer {
  /** Every write received so far, in order. */
  readonly writes: PeerWrite[] = [];
  /** Every event so far, in order: connections, requests, DeleteObjects, writes. */
  readonly events: PeerEvent[] = [];
  port = 0;
  host = '127.0.0.1';
  /** SHA-256 of the DER certificate, lower-case hex; null without TLS. */
  fingerprint: string | null = null;
  /** The certificate's PEM path; null without TLS. */
  certPath: string | null = null;
  private readonly waiters: { match: (e: PeerEvent) => boolean; resolve: (e: PeerEvent) => void }[] = [];
  private readonly replies: { resolve: (l: ServerLine) => void; reject: (e: Error) => void }[] = [];
  private readonly output: { stderr: () => string };
  private exited = false;

  constructor(
    private readonly child: ChildProcess,
    private readonly tmp: string | undefined,
    onListening: (l: ServerLine) => void,
    onFail: (e: Error) => void,
  ) {
    let first = true;
    this.output = lines(child, (line) => {
      let msg: ServerLine;
      try {
        msg = JSON.parse(line) as ServerLine;
      } catch {
        return onFail(new Error(`s7commplus server.py printed a line that is not JSON: ${line}`));
      }
      if (first) {
        first = false;
        return msg.event === 'listening' ? onListening(msg) : onFail(new Error(`s7commplus server.py: ${String(msg.message ?? line)}`));
      }
      if (EVENTS.has(msg.event)) {
        let e: PeerEvent;
        if (msg.event === 'write') {
          const w: PeerWrite = {
            db: msg.db as number | null,
            offset: msg.offset as number | null,
            size: msg.size as number | null,
            data: Buffer.from(msg.data as string, 'hex'),
            ok: msg.ok as boolean,
          };
          this.writes.push(w);
          e = { event: 'write', ...w };
        } else {
          e = msg as unknown as PeerEvent;
        }
        this.events.push(e);
        for (let i = 0; i < this.waiters.length; i++) {
          if (this.waiters[i]!.match(e)) {
            this.waiters.splice(i, 1)[0]!.resolve(e);
            break;
          }
        }
        return;
      }
      const reply = this.replies.shift();
      if (reply) reply.resolve(msg);
    });
    child.once('exit', (code, signal) => {
      this.exited = true;
      const err = new Error(`s7commplus server.py exited (${code ?? signal}): ${this.output.stderr()}`);
      onFail(err);
      for (const r of this.replies.splice(0)) r.reject(err);
    });
  }

  /** The first event that satisfies `match` (one already reported counts), or rejects after `ms`. */
  waitForEvent<E extends PeerEvent = PeerEvent>(match: (e: PeerEvent) => boolean, ms = 10_000, what = 'matching event'): Promise<E> {
    const done = this.events.find(match);
    if (done) return Promise.resolve(done as E);
    return new Promise((resolve, reject) => {
      const entry = {
        match,
        resolve: (e: PeerEvent) => {
          clearTimeout(timer);
          resolve(e as E);
        },
      };
      const timer = setTimeout(() => {
        this.waiters.splice(this.waiters.indexOf(entry), 1);
        reject(new Error(`no ${what} from the s7commplus server within ${ms} ms (${this.events.length} events so far)`));
      }, ms);
      this.waiters.push(entry);
    });
  }

  /** The first write that satisfies `match` (one already received counts), or rejects after `ms`. */
  async waitForWrite(match: (w: PeerWrite) => boolean = () => true, ms = 10_000): Promise<PeerWrite> {
    const e = await this.waitForEvent((x) => x.event === 'write' && match(x), ms, 'matching write');
    const { event: _event, ...w } = e as { event: 'write' } & PeerWrite;
    return w;
  }

  /** Resolves once every client connection the server accepted has closed its socket; rejects after `ms`. */
  async waitForNoClients(ms = 10_000): Promise<void> {
    const deadline = Date.now() + ms;
    for (;;) {
      const open = this.openClients();
      if (open.length === 0) return;
      await this.waitForEvent(
        (e) => e.event === 'disconnected' && e.peer === open[0],
        Math.max(1, deadline - Date.now()),
        `close of ${open[0]}`,
      );
    }
  }

  /** The peers ("host:port") connected now. */
  openClients(): string[] {
    const open = new Set<string>();
    for (const e of this.events) {
      if (e.event === 'connected') open.add(e.peer);
      else if (e.event === 'disconnected') open.delete(e.peer);
    }
    return [...open];
  }

  private command(cmd: object, ms = 10_000): Promise<ServerLine> {
    if (this.exited) return Promise.reject(new Error('the s7commplus server has exited'));
    return new Promise((resolve, reject) => {
      const timer = setTimeout(() => reject(new Error(`s7commplus server.py did not answer ${JSON.stringify(cmd)} within ${ms} ms`)), ms);
      this.replies.push({
        resolve: (l) => {
          clearTimeout(timer);
          if (l.event === 'error') reject(new Error(`s7commplus server.py: ${String(l.message)}`));
          else resolve(l);
        },
        reject: (e) => {
          clearTimeout(timer);
          reject(e);
        },
      });
      this.child.stdin!.write(JSON.stringify(cmd) + '\n');
    });
  }

  /** Sets the emulated CPU's operating state; resolves once the emulator has it. */
  async setCpuState(state: 'RUN' | 'STOP'): Promise<void> {
    await this.command({ cmd: 'cpu', state });
  }

  /** Bytes of a DB straight from the emulator's memory (not over the network). */
  async read(db: number, offset: number, size: number): Promise<Buffer> {
    const l = await this.command({ cmd: 'read', db, offset, size });
    return Buffer.from(l.data as string, 'hex');
  }

  /** Writes a DB's memory in the emulator (not over the network), as the PLC program would. */
  async write(db: number, offset: number, data: Buffer): Promise<void> {
    await this.command({ cmd: 'write', db, offset, data: data.toString('hex') });
  }

  /** Stops the server (closing its stdin), waits for the process to exit (SIGKILL after `ms`), removes its temp files. */
  async stop(ms = 10_000): Promise<void> {
    this.child.stdin!.end();
    await awaitExit(this.child, ms);
    if (this.tmp) fs.rmSync(this.tmp, { recursive: true, force: true });
  }
}

/** Starts server.py with `python`; resolves once it listens (its port and fingerprint are then set), rejects after `ms`. */
export async function startS7CommPlusServer(python: string, options: PeerServerOptions = {}, ms = 30_000): Promise<S7CommPlusPeerServer> {
  const tmp = options.tls === 'self-signed' ? fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-s7cp-')) : undefined;
  const config = {
    host: options.host ?? '127.0.0.1',
    port: options.port ?? 0,
    ...(options.version !== undefined ? { version: options.version } : {}),
    ...(options.maxRequestBytes !== undefined ? { maxRequestBytes: options.maxRequestBytes } : {}),
    ...(options.tls
      ? {
          tls: {
            ...(options.tls === 'self-signed' ? { selfSigned: tmp } : options.tls),
            ...(options.tlsMaxVersion ? { maxVersion: options.tlsMaxVersion } : {}),
          },
        }
      : {}),
    dbs: (options.dbs ?? []).map((db) => ({
      number: db.number,
      size: db.size ?? 1024,
      variables: db.variables ?? {},
      data: db.data?.toString('hex') ?? '',
    })),
  };
  const child = spawn(python, [path.join(SCRIPTS, 'server.py'), JSON.stringify(config)], { stdio: ['pipe', 'pipe', 'pipe'] });
  track(child);
  let server!: S7CommPlusPeerServer;
  try {
    await new Promise<void>((resolve, reject) => {
      const timer = setTimeout(() => reject(new Error(`s7commplus server.py did not report its port within ${ms} ms`)), ms);
      child.once('error', reject);
      server = new S7CommPlusPeerServer(
        child,
        tmp,
        (l) => {
          clearTimeout(timer);
          server.port = l.port as number;
          server.host = l.host as string;
          server.fingerprint = l.fingerprint as string | null;
          server.certPath = l.cert as string | null;
          resolve();
        },
        (e) => {
          clearTimeout(timer);
          reject(e);
        },
      );
    });
  } catch (e) {
    child.kill('SIGKILL');
    await awaitExit(child, 5000);
    if (tmp) fs.rmSync(tmp, { recursive: true, force: true });
    throw e;
  }
  return server;
}

// ---------------------------------------------------------------------------
// Client

/** One operation of client.py (see its docstring for what each returns). */
export type PeerOp =
  | {
      op: 'connect';
      host?: string;
      port: number;
      tls?: boolean;
      fingerprint?: string;
      ca?: string;
      password?: string;
      connectionType?: 'hmi' | 'es' | 'pg';
    }
  | { op: 'list_datablocks' | 'browse' | 'get_cpu_state' | 'refresh_if_changed' | 'disconnect' }
  | { op: 'read_tags'; names: readonly string[] }
  | { op: 'write_tag'; name: string; value: string }
  | { op: 'write_tags'; values: Readonly<Record<string, string>> }
  | { op: 'write_values'; values: Readonly<Record<string, unknown>> }
  | { op: 'db_read'; db: number; offset: number; size: number }
  | { op: 'db_write'; db: number; offset: number; data: string }
  | { op: 'subscribe'; items: readonly string[]; cycleMs?: number }
  | { op: 'notification'; subscription?: number; timeoutMs?: number }
  // Alarms (issue #33): languages are Windows LCIDs (1033 en-US, 1031 de-DE).
  | { op: 'alarm_subscribe'; languages?: readonly number[] }
  | { op: 'alarm_notification'; languages?: readonly number[]; timeoutMs?: number }
  | { op: 'read_alarms'; languages?: readonly number[] };

export interface PeerError {
  readonly type: string;
  readonly message: string;
}

export type PeerBatchResult =
  | { readonly ok: true; readonly results: unknown[] }
  | { readonly ok: false; readonly failed: number | null; readonly error: PeerError; readonly results: unknown[] };

/** Runs `ops` in one client.py process (one connection); resolves with its one result line; kills it after `ms`. */
export async function runS7CommPlusClient(python: string, ops: readonly PeerOp[], ms = 30_000): Promise<PeerBatchResult> {
  const child = spawn(python, [path.join(SCRIPTS, 'client.py')], { stdio: ['pipe', 'pipe', 'pipe'] });
  track(child);
  const out: string[] = [];
  const { stderr } = lines(child, (l) => out.push(l));
  const exited = new Promise<number | null>((resolve, reject) => {
    child.once('error', reject);
    child.once('exit', (code) => resolve(code));
  });
  child.stdin!.end(JSON.stringify(ops) + '\n');
  const timer = setTimeout(() => child.kill('SIGKILL'), ms);
  const code = await exited.finally(() => clearTimeout(timer));
  // readline may still hold the last line for a tick after 'exit'.
  await new Promise((r) => setImmediate(r));
  const last = out.at(-1);
  if (last === undefined) throw new Error(`s7commplus client.py printed nothing (exit ${code ?? 'killed'} after ${ms} ms?): ${stderr()}`);
  const result = JSON.parse(last) as PeerBatchResult;
  if (result.ok !== (code === 0)) throw new Error(`s7commplus client.py exited ${code} with ${last}`);
  return result;
}

/** The results of `ops`, or throws with the peer's error and the operation it failed at. */
export async function s7CommPlusClientOk(python: string, ops: readonly PeerOp[], ms = 30_000): Promise<unknown[]> {
  const r = await runS7CommPlusClient(python, ops, ms);
  if (!r.ok)
    throw new Error(
      `s7commplus client failed at operation ${r.failed} (${JSON.stringify(ops[r.failed ?? 0])}): ${r.error.type}: ${r.error.message}`,
    );
  return r.results;
}

/** One client.py process kept open: operations one at a time, so a test can act between them (e.g. after subscribing). */
export class S7CommPlusPeerClient {
  private readonly pending: ((l: string) => void)[] = [];
  private readonly output: { stderr: () => string };
  private readonly exited: Promise<void>;

  constructor(private readonly child: ChildProcess) {
    this.output = lines(child, (l) => this.pending.shift()?.(l));
    this.exited = new Promise((resolve) => child.once('exit', () => resolve()));
  }

  /** Runs one operation; resolves with `{ ok, result }` or `{ ok: false, error }`; rejects after `ms`. */
  op(o: PeerOp, ms = 30_000): Promise<{ ok: true; result: unknown } | { ok: false; error: PeerError }> {
    return new Promise((resolve, reject) => {
      if (this.child.exitCode !== null || this.child.signalCode !== null)
        return reject(new Error(`s7commplus client.py has exited: ${this.output.stderr()}`));
      const timer = setTimeout(() => reject(new Error(`s7commplus client.py did not answer ${o.op} within ${ms} ms`)), ms);
      const onExit = () => {
        clearTimeout(timer);
        reject(new Error(`s7commplus client.py exited during ${o.op}: ${this.output.stderr()}`));
      };
      this.child.once('exit', onExit);
      this.pending.push((l) => {
        clearTimeout(timer);
        this.child.removeListener('exit', onExit);
        resolve(JSON.parse(l) as { ok: true; result: unknown } | { ok: false; error: PeerError });
      });
      this.child.stdin!.write(JSON.stringify(o) + '\n');
    });
  }

  /** The operation's result, or throws with the peer's error. */
  async ok(o: PeerOp, ms = 30_000): Promise<unknown> {
    const r = await this.op(o, ms);
    if (!r.ok) throw new Error(`s7commplus client ${o.op} failed: ${r.error.type}: ${r.error.message}`);
    return r.result;
  }

  /** Ends the session (the script disconnects) and waits for the process to exit (SIGKILL after `ms`). */
  async close(ms = 10_000): Promise<void> {
    this.child.stdin!.end();
    await awaitExit(this.child, ms);
    await this.exited;
  }
}

/** Starts client.py in interactive mode. */
export function openS7CommPlusClient(python: string): S7CommPlusPeerClient {
  const child = spawn(python, [path.join(SCRIPTS, 'client.py')], { stdio: ['pipe', 'pipe', 'pipe'] });
  track(child);
  return new S7CommPlusPeerClient(child);
}
