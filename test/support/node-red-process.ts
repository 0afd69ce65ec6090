/**
 * Node-RED 4 in a child process with this package linked into its user
 * directory, for tests that drive the editor in a browser: a free port, the
 * local settings of `npm start` (demo/start.js) plus the caller's, `flow`
 * deployed. Resolves once the flows have started and the admin API answers.
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
    await new Promise<void>((resolve, reject) => {
      const deadline = Date.now() + 60_000;
      const attempt = () => {
        if (child.exitCode !== null) return reject(new Error(`Node-RED exited (${child.exitCode}):\n${output}`));
        if (Date.now() > deadline) return reject(new Error(`Node-RED did not start within 60 s:\n${output}`));
        if (!/Started flows/.test(output)) return void setTimeout(attempt, 100);
        http
          .get(`${url}flows`, (res) => {
            res.resume();
            if (res.statusCode === 200) resolve();
            else setTimeout(attempt, 100);
          })
          .on('error', () => setTimeout(attempt, 100));
      };
      attempt();
    });
  } catch (err) {
    await stop();
    throw err;
  }
  return { url, stop };
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
