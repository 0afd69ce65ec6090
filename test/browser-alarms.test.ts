/**
 * The demo dashboard's alarm list in headless Chromium (issue #33): the tank's high level, raised by the demo plant
 * on the classic S7-300 (ALARM_SQ) and the S7-1200 (Program_Alarm), appears in the list with its time, text, value,
 * state and acknowledgement; at 412 px the Acknowledge buttons are on screen and clickable; a click acknowledges the
 * classic alarm in the simulated CPU, and on the S7-1200 the alarms node's refusal is shown under the list.
 */
import { expect } from 'chai';
import * as path from 'node:path';
import type { Browser, Page } from 'playwright-core';
import type { PlcAlarm } from '../lib/alarms/model';
import { DEMO_ALARM_IDS, DEMO_HIGH_LEVEL } from '../lib/plant/alarms';
import type { Plant } from '../lib/plant/plant';
import { S7Client } from '../lib/s7/client';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { launchChromium } from './support/browser';
import { freePort } from './support/net';

const ROOT = path.resolve(__dirname, '../..');

interface Demo {
  dashboard: string;
  plant: Plant;
  stop(): Promise<void>;
}

const CLASSIC = `.plcwire-alarm[data-alarm="s7classic:${DEMO_ALARM_IDS.classic}"]`;
const PROGRAM = `.plcwire-alarm[data-alarm="s7plus:${DEMO_ALARM_IDS.program}"]`;

/** Whether every part of the alarm list lies inside the page's width and nothing in it overflows sideways. */
async function fitsWidth(page: Page): Promise<string[]> {
  return page.evaluate(() => {
    const doc = (globalThis as any).document;
    const right = doc.documentElement.clientWidth;
    const problems: string[] = [];
    // Vuetify's ripple (a click's passing effect) is drawn past its button on purpose: not part of the layout.
    for (const el of doc.querySelectorAll('.plcwire-alarms, .plcwire-alarms *:not(.v-ripple__container):not(.v-ripple__animation)')) {
      const r = el.getBoundingClientRect();
      if (r.width > 0 && (r.left < -0.5 || r.right > right + 0.5)) problems.push(`${el.className} ${r.left}..${r.right} of ${right}`);
      if (el.scrollWidth > el.clientWidth + 1 && (globalThis as any).getComputedStyle(el).overflowX !== 'visible')
        problems.push(`${el.className} overflows (${el.scrollWidth} > ${el.clientWidth})`);
    }
    return problems;
  });
}

describe('browser: the demo dashboard alarm list (issue #33)', function () {
  this.timeout(120_000);
  let demo: Demo;
  let browser: Browser;
  let page: Page;
  let client: S7Client | undefined;

  before(async () => {
    const { startDemo } = require(path.join(ROOT, 'demo/start.js')) as { startDemo(o: object): Promise<Demo> };
    const [port, s7, fetch, write, freeport, s7classic] = await Promise.all([
      freePort(),
      freePort(),
      freePort(),
      freePort(),
      freePort(),
      freePort(),
    ]);
    demo = await startDemo({ port, plantPorts: { s7, fetch, write, freeport, s7classic }, quiet: true, log: () => undefined });
    browser = await launchChromium();
    page = await browser.newPage({ viewport: { width: 412, height: 915 } });
  });

  after(async () => {
    await client?.close();
    await browser?.close();
    await demo?.stop();
  });

  it('the high level comes on both CPUs and shows in the list: time, text, value, state, unacknowledged, a button each', async () => {
    await page.goto(demo.dashboard, { waitUntil: 'domcontentloaded' });
    await page.waitForSelector('.plcwire-alarms', { timeout: 30_000 });
    // The tank above its limit (the program raises the flag in its next cycle); then the program stands still, so the
    // alarm stays coming while the test looks at it.
    demo.plant.memory.area('DB', 1)!.writeFloatBE(DEMO_HIGH_LEVEL.above + 5, 0);
    await page.waitForSelector(`${CLASSIC} .plcwire-alarm-ack`, { timeout: 20_000 });
    await page.waitForSelector(`${PROGRAM} .plcwire-alarm-ack`, { timeout: 20_000 });
    demo.plant.process.stop();
    const classic = await page.locator(CLASSIC).innerText();
    expect(classic)
      .to.match(/S7-300/)
      .and.match(/Tank level high/)
      .and.match(/\b9\d\.\d %/)
      .and.match(/coming/)
      .and.match(/unacknowledged/);
    expect(classic).to.match(/\d{4}-\d\d-\d\d \d\d:\d\d:\d\d/);
    const program = await page.locator(PROGRAM).innerText();
    expect(program)
      .to.match(/S7-1200/)
      .and.match(/Tank level high: 9\d\.\d %/)
      .and.match(/coming/)
      .and.match(/unacknowledged/);
    expect(await fitsWidth(page), 'at 412 px').to.deep.equal([]);
    // Nothing was refused before anyone clicked: the start's "list" request reached both alarms nodes as one.
    expect(await page.locator('.plcwire-alarms-note').count(), 'a refusal note before any click').to.equal(0);
  });

  it("at 412 px the classic alarm's Acknowledge button is on screen; a click acknowledges it in the S7-300", async () => {
    const button = page.locator(`${CLASSIC} .plcwire-alarm-ack`);
    await button.scrollIntoViewIfNeeded();
    const box = (await button.boundingBox())!;
    expect(box.x).to.be.at.least(0);
    expect(box.x + box.width).to.be.at.most(412);
    expect(box.height).to.be.at.least(36);
    await button.click();
    await page.waitForSelector(`${CLASSIC}[data-ack="acknowledged"]`, { timeout: 20_000 });
    expect(await page.locator(`${CLASSIC} .plcwire-alarm-ack`).count()).to.equal(0);
    // The CPU's own answer: the alarm query lists it acknowledged.
    client = new S7Client(parseUrl(`${demo.plant.urls.s7classic}&timeout=5000`) as S7Endpoint);
    await client.connect();
    const active: PlcAlarm[] = await client.alarms();
    expect(active.find((a) => a.id === DEMO_ALARM_IDS.classic)).to.include({ state: 'coming', acknowledged: true });
  });

  it("on the S7-1200 the click's refusal is shown under the list, and the alarm stays unacknowledged", async () => {
    await page.locator(`${PROGRAM} .plcwire-alarm-ack`).click();
    const note = page.locator('.plcwire-alarms-note');
    await note.waitFor({ timeout: 20_000 });
    // The client's own words, as the operator reads them (not "PlcError: …"): why the S7-1200 cannot be acknowledged here.
    expect(await note.innerText()).to.match(/^S7-1200: acknowledging alarm 1 refused: (?!\w*Error:).*S7CommPlus/s);
    if (process.env.PLCWIRE_SCREENSHOT) await page.locator('.plcwire-alarms').screenshot({ path: process.env.PLCWIRE_SCREENSHOT });
    expect(await page.locator(PROGRAM).getAttribute('data-ack')).to.equal('unacknowledged');
    expect(await fitsWidth(page), 'at 412 px').to.deep.equal([]);
  });

  it('at 1280 px the list fits its group', async () => {
    await page.setViewportSize({ width: 1280, height: 900 });
    await page.waitForFunction(() => (globalThis as any).document.documentElement.clientWidth > 1000, undefined, { timeout: 5000 });
    expect(await fitsWidth(page), 'at 1280 px').to.deep.equal([]);
    expect(await page.locator(PROGRAM).isVisible()).to.equal(true);
  });
});
