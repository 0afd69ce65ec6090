/**
 * A real mosquitto broker (the Debian package) for the Sparkplug B tests: one
 * process on 127.0.0.1 with a port of its own, which can be stopped and
 * started again on that port (a broker outage). Without mosquitto the tests
 * that need it skip and say why (test/support/sparkplug-peers.ts).
 */
import { spawn, type ChildProcess } from 'node:child_process';
import { missingMosquitto, mosquittoPath } from './sparkplug-peers';
import * as fs from 'node:fs';
import * as net from 'node:net';
import * as os from 'node:os';
import * as path from 'node:path';
import { freePort } from './net';

export class Mosquitto {
  port = 0;
  private child: ChildProcess | undefined;
  private dir: string | undefined;
  /** What the broker wrote, for a failing test's message. */
  log = '';

  get url(): string {
    return `mqtt://127.0.0.1:${this.port}`;
  }

  /** Starts the broker (on its previous port after a stop) and resolves once it accepts connections. */
  async start(ms = 10_000): Promise<void> {
    const bin = mosquittoPath();
    if (!bin) throw new Error(missingMosquitto());
    if (!this.port) this.port = await freePort();
    this.dir ??= fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-mosquitto-'));
    const conf = path.join(this.dir, 'mosquitto.conf');
    fs.writeFileSync(conf, `listener ${this.port} 127.0.0.1\nallow_anonymous true\npersistence false\nmax_queued_messages 0\n`);
    const child = spawn(bin, ['-c', conf], { stdio: ['ignore', 'pipe', 'pipe'] });
    this.child = child;
    const keep = (d: Buffer) => (this.log = (this.log + d.toString('utf8')).slice(-8000));
    child.stdout!.on('data', keep);
    child.stderr!.on('data', keep);
    const exited = new Promise<never>((_, reject) =>
      child.once('exit', (code) => reject(new Error(`mosquitto exited (${code}) on port ${this.port}: ${this.log}`))),
    );
    // A later exit (a stop) rejects it with nobody racing it: handled here.
    exited.catch(() => undefined);
    const deadline = Date.now() + ms;
    for (;;) {
      const up = await Promise.race([this.accepts(), exited]);
      if (up) return;
      if (Date.now() > deadline) {
        await this.stop();
        throw new Error(`mosquitto did not accept connections on ${this.port} within ${ms} ms: ${this.log}`);
      }
      await new Promise((r) => setTimeout(r, 20));
    }
  }

  /** Stops the broker (SIGTERM, then SIGKILL after 5 s) and resolves once it exited; the port stays ours. */
  async stop(): Promise<void> {
    const child = this.child;
    this.child = undefined;
    if (!child || child.exitCode !== null || child.signalCode !== null) return;
    const gone = new Promise<void>((resolve) => child.once('exit', () => resolve()));
    child.kill('SIGTERM');
    const timer = setTimeout(() => child.kill('SIGKILL'), 5000);
    await gone;
    clearTimeout(timer);
  }

  /** Stops the broker and removes its directory. */
  async dispose(): Promise<void> {
    await this.stop();
    if (this.dir) fs.rmSync(this.dir, { recursive: true, force: true });
    this.dir = undefined;
  }

  private accepts(): Promise<boolean> {
    return new Promise((resolve) => {
      const s = net.connect(this.port, '127.0.0.1');
      s.once('connect', () => (s.destroy(), resolve(true)));
      s.once('error', () => (s.destroy(), resolve(false)));
    });
  }
}
