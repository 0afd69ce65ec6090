/**
 * Eclipse Tahu 1.0.21's Java host (test/interop/tahu/TahuHost.java, built by
 * `node test/support/install-peers.js tahu`) as a child process: a Sparkplug B
 * primary host written by others. It publishes its STATE, decodes every message
 * under spBv1.0/# with Tahu's SparkplugBPayloadDecoder and prints one JSON line
 * each (TahuLine); rebirth, dcmd and state commands go to its stdin.
 */
import { spawn, spawnSync, type ChildProcess } from 'node:child_process';
import * as path from 'node:path';

const ROOT = path.resolve(__dirname, '../../..');
const DIR = path.join(ROOT, 'test/interop/tahu');
const { tahuBuilt, TAHU_VERSION } = require(path.join(ROOT, 'test/support/install-peers.js')) as {
  tahuBuilt: () => boolean;
  TAHU_VERSION: string;
};

/** One metric as Tahu decoded it: 64-bit integers as decimal strings, DateTime as ms since the epoch. */
export interface TahuMetric {
  name: string | null;
  /** Whether the message itself carried the name (data by alias carries none: the host took it from the birth). */
  named: boolean;
  alias?: number;
  datatype: string;
  value: unknown;
  timestamp?: number;
  is_historical: boolean;
  is_null: boolean;
}

/** One line of the host: a message it decoded (topic set), a command it sent, or an error. */
export interface TahuLine {
  topic?: string;
  type?: string;
  group?: string;
  edge?: string;
  device?: string;
  qos?: number;
  retained?: boolean;
  seq?: number;
  bdSeq?: string | number;
  timestamp?: number;
  metrics?: TahuMetric[];
  /** STATE's payload, as sent. */
  json?: string;
  ready?: boolean;
  sent?: string;
  error?: string;
}

/** Why the Tahu host cannot run here, or undefined. */
export function missingTahu(): string | undefined {
  const java = spawnSync('java', ['-version'], { encoding: 'utf8', timeout: 60_000 });
  if (java.status !== 0) return `no java (${java.error?.message ?? `exit ${java.status}`})`;
  if (!tahuBuilt())
    return `the Eclipse Tahu ${TAHU_VERSION} host is not built: run node test/support/install-peers.js tahu (needs javac and mvn)`;
  return undefined;
}

export class TahuHost {
  /** Every line so far, in order. */
  readonly lines: TahuLine[] = [];
  private readonly child: ChildProcess;
  private stderr = '';
  private readonly waiters = new Set<() => void>();

  /** Starts the host on `broker` (mqtt://host:port) as primary host `hostId`; `ready()` resolves once it is subscribed. */
  constructor(
    broker: string,
    readonly hostId: string,
  ) {
    const url = broker.replace(/^mqtt:/, 'tcp:');
    this.child = spawn(
      'java',
      ['-Dorg.slf4j.simpleLogger.defaultLogLevel=warn', '-cp', `build${path.delimiter}lib/*`, 'TahuHost', url, hostId],
      { cwd: DIR, stdio: ['pipe', 'pipe', 'pipe'] },
    );
    let rest = '';
    this.child.stdout!.on('data', (d: Buffer) => {
      const parts = (rest + d.toString('utf8')).split('\n');
      rest = parts.pop()!;
      for (const p of parts.filter((l) => l.startsWith('{'))) this.lines.push(JSON.parse(p) as TahuLine);
      this.waiters.forEach((w) => w());
    });
    this.child.stderr!.on('data', (d: Buffer) => (this.stderr = (this.stderr + d.toString('utf8')).slice(-8000)));
    this.child.on('exit', () => this.waiters.forEach((w) => w()));
  }

  /** Resolves with the first line from index `from` on that satisfies `match`, or rejects after `ms`. */
  waitFor(match: (l: TahuLine) => boolean, ms = 20_000, from = 0, what = 'a matching line'): Promise<TahuLine> {
    return new Promise((resolve, reject) => {
      const check = () => {
        const hit = this.lines.slice(from).find(match);
        if (hit) return done(() => resolve(hit));
        if (this.child.exitCode !== null || this.child.signalCode !== null)
          return done(() => reject(new Error(`the Tahu host exited before ${what}; stderr: ${this.stderr}`)));
      };
      const timer = setTimeout(
        () =>
          done(() =>
            reject(
              new Error(
                `the Tahu host printed no ${what} within ${ms} ms; last lines: ${JSON.stringify(this.lines.slice(-5))}; stderr: ${this.stderr}`,
              ),
            ),
          ),
        ms,
      );
      const done = (settle: () => void) => {
        clearTimeout(timer);
        this.waiters.delete(check);
        settle();
      };
      this.waiters.add(check);
      check();
    });
  }

  ready(ms = 60_000): Promise<TahuLine> {
    return this.waitFor((l) => l.ready === true, ms, 0, '{"ready":true} (connected and subscribed)');
  }

  /** Sends a command line and resolves once the host says it sent it. */
  async command(line: string, ms = 20_000): Promise<void> {
    const from = this.lines.length;
    this.child.stdin!.write(`${line}\n`);
    const r = await this.waitFor((l) => l.sent === line || (l.error ?? '').startsWith(`${line}:`), ms, from, `"sent" for ${line}`);
    if (r.error) throw new Error(`Tahu host: ${r.error}`);
  }

  /** The messages decoded so far (not STATE, not command echoes) of `type` (NBIRTH, DDATA, ...). */
  messages(type?: string): TahuLine[] {
    return this.lines.filter((l) => l.topic && l.type !== 'STATE' && (!type || l.type === type));
  }

  /** Ends the host: `quit` (STATE offline, clean disconnect), or SIGKILL after 10 s; `kill` skips the quit. */
  async close(kill = false): Promise<void> {
    const child = this.child;
    if (child.exitCode !== null || child.signalCode !== null) return;
    const gone = new Promise<void>((resolve) => child.once('exit', () => resolve()));
    if (kill) child.kill('SIGKILL');
    else child.stdin!.end('quit\n');
    const timer = setTimeout(() => child.kill('SIGKILL'), 10_000);
    await gone;
    clearTimeout(timer);
  }
}
