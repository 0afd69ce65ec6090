/**
 * The first five minutes of a new user, in a real browser: `npm start`'s
 * Node-RED with the demo flow, the editor's palette, and the Dashboard 2.0
 * page showing live values and writing back to the simulated PLC.
 * Headless Chromium driven by playwright-core (test/support/browser.ts).
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import type { Browser, Page } from 'playwright-core';
import { launchChromium } from './support/browser';
import { freePort } from './support/net';
import { until } from './support/wait';

const ROOT = path.resolve(__dirname, '../..');

interface Demo {
  editor: string;
  dashboard: string;
  plant: { memory: { area(a: string, db?: number): Buffer | undefined } };
  stop(): Promise<void>;
}

describe('browser: the npm start demo in headless Chromium', function () {
  this.timeout(120_000);
  let demo: Demo;
  let browser: Browser;
  let page: Page;
  let profile: string;

  before(async () => {
    const { startDemo } = require(path.join(ROOT, 'demo/start.js')) as { startDemo(o: object): Promise<Demo> };
    const [port, s7, fetch, write, freeport] = await Promise.all([freePort(), freePort(), freePort(), freePort(), freePort()]);
    demo = await startDemo({ port, plantPorts: { s7, fetch, write, freeport }, quiet: true, log: () => undefined });
    profile = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-chromium-'));
    browser = await launchChromium();
    page = await browser.newPage();
  });

  after(async () => {
    await browser?.close();
    await demo?.stop();
    if (profile) fs.rmSync(profile, { recursive: true, force: true });
  });

  it('the editor lists our four nodes in the palette', async () => {
    await page.goto(demo.editor, { waitUntil: 'domcontentloaded' });
    for (const type of ['plcwire-connection', 'plcwire-read', 'plcwire-write', 'plcwire-heartbeat']) {
      if (type === 'plcwire-connection') continue; // config nodes are not in the palette
      await page.waitForSelector(`.red-ui-palette-node[data-palette-type="${type}"]`, { timeout: 30_000 });
    }
    const registered = await page.evaluate(() => (globalThis as any).RED.nodes.getType('plcwire-connection') !== undefined);
    expect(registered).to.equal(true);
  });

  it('the dashboard shows the tank level changing live', async () => {
    await page.goto(demo.dashboard, { waitUntil: 'domcontentloaded' });
    const selector = '.plcwire-ui-fw-level';
    await page.waitForFunction((sel) => /\d/.test((globalThis as any).document.querySelector(sel)?.textContent ?? ''), selector, { timeout: 30_000 });
    const first = await page.locator(selector).innerText();
    // The simulated tank fills at 4 %/s: the shown level must change within seconds.
    await page.waitForFunction(
      ([sel, before]) => {
        const now = (globalThis as any).document.querySelector(sel!)?.textContent ?? '';
        return /\d/.test(now) && now.replace(/\s+/g, ' ') !== before!.replace(/\s+/g, ' ');
      },
      [selector, first],
      { timeout: 15_000 },
    );
  });

  it('clicking the motor switch writes the run command to the simulated PLC', async () => {
    const db1 = demo.plant.memory.area('DB', 1)!;
    expect(db1[4]! & 0x01).to.equal(0);
    // The switch's own control (Vuetify draws the thumb over a hidden checkbox).
    await page.locator('.plcwire-motor .v-selection-control__input').click();
    await until(() => (db1[4]! & 0x01) === 1, 10_000, 'DB1.DBX4.0 set by the dashboard');
    // The process reacts: the motor ramps up and the dashboard shows its speed.
    await until(() => db1.readInt16BE(6) > 0, 10_000, 'motor speed rising');
    await page.waitForFunction(() => /[1-9]/.test((globalThis as any).document.querySelector('.plcwire-ui-speed')?.textContent ?? ''), undefined, { timeout: 15_000 });
    if (process.env.PLCWIRE_SCREENSHOT) await page.screenshot({ path: process.env.PLCWIRE_SCREENSHOT, fullPage: true });
  });
});
