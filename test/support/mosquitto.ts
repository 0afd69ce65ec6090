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
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { freePort } from './net';

export const MOSQUITTO = process.env['MOSQUITTO'] ?? '/usr/sbin/mosquitto';

/** Whether the broker binary is here (tests skip with a reason when not). */
export function haveMosquitto(): boolean {
  return fs.existsSync(MOSQUITTO);
}

export class Mosquitto {
  port = 0;
  log = '';
  private child: ChildProcess | undefined;
  private dir: string | undefined;

  get url(): string {
    return `mqtt://127.0.0.1:${this.port}`;
  }

  async start(deadline = 10_000): Promise<void> {
    if (this.port === 0) this.port = await freePort();
    this.dir ??= fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-mosquitto-'));
    const config = path.join(this.dir, 'mosquitto.conf');
    fs.writeFileSync(
      config,
      [`listener ${this.port} 127.0.0.1`, 'allow_anonymous true', 'persistence false', 'log_dest stderr', 'log_type all', ''].join('\n'),
    );
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
