/**
 * Node-RED 4 in a child process with this package linked into its user
 * directory, for tests that drive the editor in a browser: a free port, the
 * local settings of `npm start` (demo/start.js) plus the caller's, `flow`
 * deployed. Resolves once the flows have started and the admin API answers
 * (waitForNodeRed).
 */
import { spawn, type ChildProcess } from 'node:child_process';
import * as fs from 'node:fs';
import * as http from 'node:http';
import * as os from 'node:os';
import * as path from 'node:path';
import type { Browser, BrowserContext, Page } from 'playwright-core';
import { freePort } from './net';

const ROOT = path.resolve(__dirname, '../../..');

export interface NodeRedProcess {
  /** The editor's base URL, ending in `/`. */
  url: string;
  /** Stops Node-RED (SIGINT, SIGKILL after 5 s) and removes its user directory. */
  stop(): Promise<void>;
}

export async function startNodeRedProcess(flow: object[], extraSettings: object = {}): Promise<NodeRedProcess> {
  // The port was free a moment before Node-RED binds it; another process may take it meanwhile: then a new port.
  for (let attempt = 1; ; attempt++) {
    try {
      return await startOnce(flow, extraSettings);
    } catch (err) {
      if (!(err instanceof NodeRedPortTaken) || attempt === 3) throw err;
    }
  }
}

async function startOnce(flow: object[], extraSettings: object): Promise<NodeRedProcess> {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-editor-'));
  const port = await freePort();
  fs.mkdirSync(path.join(dir, 'node_modules', '@plcwire'), { recursive: true });
  fs.symlinkSync(ROOT, path.join(dir, 'node_modules', '@plcwire', 'node-red-siemens'), 'dir');
  fs.writeFileSync(
    path.join(dir, 'package.json'),
    JSON.stringify({ name: 'editor-test', private: true, dependencies: { '@plcwire/node-red-siemens': '*' } }),
  );
  fs.writeFileSync(path.join(dir, 'flows.json'), JSON.stringify(flow));
  const { localSettings } = require(path.join(ROOT, 'demo/start.js')) as { localSettings(port: number): object };
  fs.writeFileSync(path.join(dir, 'settings.js'), `module.exports = ${JSON.stringify({ ...localSettings(port), ...extraSettings })};\n`);
  const red = require.resolve('node-red/red.js', { paths: [ROOT] });
  const child: ChildProcess = spawn(process.execPath, [red, '--userDir', dir, '--settings', path.join(dir, 'settings.js')], {
    cwd: dir,
    stdio: ['ignore', 'pipe', 'pipe'],
  });
  let output = '';
  child.stdout!.on('data', (d: Buffer) => (output += d.toString()));
  child.stderr!.on('data', (d: Buffer) => (output += d.toString()));
  const stop = async () => {
    if (child.exitCode === null && child.signalCode === null) {
      const exited = new Promise((r) => child.once('exit', r));
      child.kill('SIGINT');
      const force = setTimeout(() => child.kill('SIGKILL'), 5000);
      await exited;
      clearTimeout(force);
    }
    fs.rmSync(dir, { recursive: true, force: true });
  };
  const url = `http://127.0.0.1:${port}/`;
  try {
    await waitForNodeRed(child, `${url}flows`, () => output);
  } catch (err) {
    await stop();
    throw err;
  }
  return { url, stop };
}

/** Node-RED exited because another process had taken its port (red.js logs "port in use" and exits): a new port may do. */
export class NodeRedPortTaken extends Error {}

/**
 * Resolves once Node-RED in `child` is ready for clients: it logged "Started
 * flows" and `probe` (a URL of its admin API) answers 200. The log line alone
 * is not enough: red.js opens its HTTP port only after the runtime's start
 * resolves, so a request right after the line can be refused (seen on
 * Node-RED 5 under load). Rejects with the log when the process exits or
 * `ms` pass first, with a NodeRedPortTaken when it exited for want of its port.
 */
export async function waitForNodeRed(child: ChildProcess, probe: string, output: () => string, ms = 120_000): Promise<void> {
  const deadline = Date.now() + ms;
  // Exited, and its output read to the end (the last lines say why).
  const exited = () =>
    (child.exitCode !== null || child.signalCode !== null) &&
    [child.stdout, child.stderr].every((s) => !s || s.readableEnded || s.destroyed);
  const fail = (why: string) =>
    exited() && /EADDRINUSE|port in use/i.test(output())
      ? new NodeRedPortTaken(`Node-RED ${why}: its port was taken:\n${output()}`)
      : new Error(`Node-RED ${why}:\n${output()}`);
  // Wakes on the next chunk of output, the end of the process and its output, or the deadline, whichever comes first.
  const next = () =>
    new Promise<void>((resolve) => {
      const done = () => {
        clearTimeout(timer);
        child.stdout?.off('data', done);
        child.off('close', done);
        resolve();
      };
      const timer = setTimeout(done, Math.max(0, deadline - Date.now()));
      child.stdout?.on('data', done);
      child.once('close', done);
    });
  while (!/Started flows/.test(output())) {
    if (exited()) throw fail(`exited (${child.exitCode ?? child.signalCode}) before starting its flows`);
    if (Date.now() > deadline) throw fail(`did not start its flows within ${ms} ms`);
    await next();
  }
  let last = 'no answer yet';
  for (;;) {
    if (exited()) throw fail(`exited (${child.exitCode ?? child.signalCode}) before answering ${probe}`);
    if (Date.now() > deadline) throw fail(`did not answer ${probe} within ${ms} ms (last: ${last})`);
    const status = await new Promise<number | string>((resolve) => {
      const req = http.get(probe, { timeout: 10_000 }, (res) => {
        res.resume();
        resolve(res.statusCode ?? 0);
      });
      req.on('timeout', () => req.destroy(new Error('no response within 10 s')));
      req.on('error', (err: NodeJS.ErrnoException) => resolve(err.code ?? err.message));
    });
    if (status === 200) return;
    last = String(status);
    // Nothing announces the port opening: ask again shortly.
    await new Promise((r) => setTimeout(r, 100));
  }
}

/**
 * The editor of `red` in a new browser context of `locale` (a BCP 47 tag,
 * e.g. `de-DE`), once node `nodeId` of the deployed flow is loaded and drawn;
 * page errors are collected in `errors`.
 */
export async function openEditor(
  browser: Browser,
  red: NodeRedProcess,
  locale: string,
  nodeId: string,
): Promise<{ context: BrowserContext; page: Page; errors: Error[] }> {
  const context = await browser.newContext({ locale });
  const page = await context.newPage();
  const errors: Error[] = [];
  page.on('pageerror', (err) => errors.push(err));
  await page.goto(red.url, { waitUntil: 'domcontentloaded' });
  await page.waitForFunction((id) => (globalThis as any).RED?.nodes?.node(id) && (globalThis as any).document.getElementById(id), nodeId, {
    timeout: 30_000,
  });
  return { context, page, errors };
}
