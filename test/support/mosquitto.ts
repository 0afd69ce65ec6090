/**
 * A real Mosquitto broker for the Sparkplug tests (Debian's /usr/sbin/mosquitto,
 * or MOSQUITTO): its own config in a temporary directory, listening on a
 * loopback port that was free a moment ago; start() resolves when the log
 * says it is listening (deadline: it rejects with the log), stop() ends the
 * process and waits for its exit. A stopped broker can be started again on
 * the same port (a broker restart). No persistence: a restart forgets
 * sessions and retained messages, as a broker without `persistence true` does.
 */
import { spawn, type ChildProcess } from 'node:child_process';
import * as crypto from 'node:crypto';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { generateCertificate, type GeneratedCertificate } from '../../lib/s7plus/transport/cert';
import { freePort } from './net';

export const MOSQUITTO = process.env['MOSQUITTO'] ?? '/usr/sbin/mosquitto';

/** Whether the broker binary is here (tests skip with a reason when not). */
export function haveMosquitto(): boolean {
  return fs.existsSync(MOSQUITTO);
}

/** What a broker asks of its clients: TLS with this certificate and key (PEM), and a user and password. */
export interface MosquittoOptions {
  tls?: { cert: string; key: string };
  users?: Readonly<Record<string, string>>;
}

/**
 * A password file line as mosquitto 2 reads it (`$7$`: PBKDF2-SHA512, its iterations, base64 salt and hash;
 * the format mosquitto_passwd writes, see mosquitto's password_file documentation).
 */
function passwordLine(user: string, password: string): string {
  const salt = crypto.randomBytes(12);
  const hash = crypto.pbkdf2Sync(password, salt, 101, 64, 'sha512');
  return `${user}:$7$101$${salt.toString('base64')}$${hash.toString('base64')}`;
}

export class Mosquitto {
  port = 0;
  log = '';
  private child: ChildProcess | undefined;
  private dir: string | undefined;

  constructor(private readonly options: MosquittoOptions = {}) {}

  get url(): string {
    return `${this.options.tls ? 'mqtts' : 'mqtt'}://127.0.0.1:${this.port}`;
  }

  async start(deadline = 10_000): Promise<void> {
    if (this.port === 0) this.port = await freePort();
    this.dir ??= fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-mosquitto-'));
    const config = path.join(this.dir, 'mosquitto.conf');
    const lines = [`listener ${this.port} 127.0.0.1`, 'persistence false', 'log_dest stderr', 'log_type all'];
    // Started as root, mosquitto drops to the user "mosquitto", which cannot read this 0700 directory's files.
    if (process.getuid?.() === 0) lines.push('user root');
    const { tls, users } = this.options;
    if (tls) {
      fs.writeFileSync(path.join(this.dir, 'server.pem'), tls.cert);
      fs.writeFileSync(path.join(this.dir, 'server.key'), tls.key, { mode: 0o600 });
      lines.push(`certfile ${path.join(this.dir, 'server.pem')}`, `keyfile ${path.join(this.dir, 'server.key')}`);
    }
    if (users) {
      const file = path.join(this.dir, 'passwords');
      fs.writeFileSync(
        file,
        Object.entries(users)
          .map(([u, p]) => `${passwordLine(u, p)}\n`)
          .join(''),
        { mode: 0o600 },
      );
      lines.push('allow_anonymous false', `password_file ${file}`);
    } else lines.push('allow_anonymous true');
    fs.writeFileSync(config, [...lines, ''].join('\n'));
    const child = spawn(MOSQUITTO, ['-c', config], { stdio: ['ignore', 'pipe', 'pipe'] });
    this.child = child;
    this.log = '';
    await new Promise<void>((resolve, reject) => {
      const timer = setTimeout(
        () => fail(new Error(`mosquitto did not listen on ${this.port} within ${deadline} ms:\n${this.log}`)),
        deadline,
      );
      const onData = (chunk: Buffer): void => {
        this.log += chunk.toString();
        if (/Opening ipv4 listen socket on port \d+/.test(this.log) && /mosquitto version .* running/.test(this.log)) done();
      };
      const onExit = (code: number | null): void => fail(new Error(`mosquitto exited (${code}) before listening:\n${this.log}`));
      const cleanup = (): void => {
        clearTimeout(timer);
        child.off('exit', onExit);
      };
      const done = (): void => {
        cleanup();
        resolve();
      };
      const fail = (err: Error): void => {
        cleanup();
        child.kill('SIGKILL');
        reject(err);
      };
      child.stderr!.on('data', onData);
      child.stdout!.on('data', onData);
      child.once('exit', onExit);
    });
  }

  /** Ends the broker (SIGTERM, SIGKILL after 5 s) and waits for its exit. */
  async stop(): Promise<void> {
    const child = this.child;
    this.child = undefined;
    if (!child || child.exitCode !== null || child.signalCode !== null) return;
    await new Promise<void>((resolve) => {
      const timer = setTimeout(() => child.kill('SIGKILL'), 5000);
      child.once('exit', () => {
        clearTimeout(timer);
        resolve();
      });
      child.kill('SIGTERM');
    });
  }

  /** Stops it and removes its directory. */
  async dispose(): Promise<void> {
    await this.stop();
    if (this.dir) fs.rmSync(this.dir, { recursive: true, force: true });
    this.dir = undefined;
  }
}

/** A CA of its own, for the TLS tests (EC: quick to make). */
export function testCa(commonName: string): Promise<GeneratedCertificate> {
  return generateCertificate({ commonName, ca: true, keyType: 'ec' });
}

/** A broker (not started) with a TLS listener whose certificate `ca` signed for `hosts`, and these users. */
export async function tlsMosquitto(
  ca: GeneratedCertificate,
  users: Readonly<Record<string, string>>,
  hosts: readonly string[] = ['127.0.0.1'],
): Promise<Mosquitto> {
  const leaf = await generateCertificate({ commonName: 'broker', hosts: [...hosts], issuer: ca, keyType: 'ec' });
  return new Mosquitto({ tls: { cert: leaf.cert, key: leaf.key }, users });
}
