/**
 * Test connection in a real browser with tag names (issue #23): the demo's
 * kind of connection (demo/Plant.db as its symbol source, DB numbers, read
 * nodes by name) against an S7 simulator holding that DB. The name steps
 * pass, and every step row is in view, in the dialog's visible area, right
 * after the result arrives: at a large and at a small window.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import type { Browser } from 'playwright-core';
import { launchChromium } from './support/browser';
import { openEditor, startNodeRedProcess, type NodeRedProcess } from './support/node-red-process';

const ROOT = path.resolve(__dirname, '../..');
const lib = require(path.join(ROOT, 'dist/lib/index.js'));
const PLANT_DB = fs.readFileSync(path.join(ROOT, 'demo/Plant.db'), 'utf8');
const CATALOG = JSON.parse(fs.readFileSync(path.join(ROOT, 'nodes/locales/en-US/connection.json'), 'utf8'))['plcwire-connection'];

function plantFlow(port: number): object[] {
  const at = (y: number) => ({ z: 'tab', x: 200, y, wires: [[]] });
  return [
    { id: 'tab', type: 'tab', label: 'doctor by name' },
    {
      id: 'conn-plant',
      type: 'plcwire-connection',
      name: 'plant',
      url: `s7://127.0.0.1:${port}?rack=0&slot=2&timeout=2000`,
      symbolSources: [{ name: 'Plant.db', content: PLANT_DB }],
      dbNumbers: [{ block: 'Plant', db: 1 }],
    },
    {
      id: 'read-plant',
      type: 'plcwire-read',
      name: 'plant',
      ...at(40),
      connection: 'conn-plant',
      interval: 0,
      output: 'object',
      deadband: 0,
      tags: [
        { name: 'level', address: '"Plant".Level' },
        { name: 'speed', address: 'Plant.MotorSpeed' },
        { name: 'raw', address: 'DB1,INT4' },
      ],
    },
  ];
}

describe('editor in Chromium: Test connection with tag names', function () {
  this.timeout(120_000);
  let sim: any;
  let red: NodeRedProcess;
  let browser: Browser;

  before(async () => {
    const table = lib.compileSymbols([{ name: 'Plant.db', content: PLANT_DB }], { db: { Plant: 1 } });
    sim = new lib.S7Server({ port: 0, profile: 's7-300', symbols: table });
    red = await startNodeRedProcess(plantFlow(await sim.listen()));
    browser = await launchChromium();
  });

  after(async () => {
    await browser?.close();
    await red?.stop();
    await sim?.close();
  });

  for (const [width, height] of [
    [1600, 1000],
    [1024, 700],
  ] as const) {
    it(`at ${width}x${height}: the name steps pass and every step row is in the dialog's visible area`, async () => {
      const { context, page, errors } = await openEditor(browser, red, 'en-US', 'read-plant');
      try {
        await page.setViewportSize({ width, height });
        await page.evaluate(() => (globalThis as any).RED.editor.editConfig('', 'plcwire-connection', 'conn-plant'));
        await page.waitForSelector('#node-config-plcwire-test', { state: 'visible', timeout: 10_000 });
        await page.click('#node-config-plcwire-test');
        await page.waitForFunction(
          (texts) => texts.includes((globalThis as any).document.querySelector('#node-config-plcwire-test-summary').textContent),
          [CATALOG.editor.testOk, CATALOG.editor.testFailed],
          { timeout: 30_000 },
        );
        const seen = await page.evaluate(() => {
          const doc = (globalThis as any).document;
          const win = globalThis as any;
          const rect = (e: any) => {
            const r = e.getBoundingClientRect();
            return { top: r.top, bottom: r.bottom, left: r.left, right: r.right };
          };
          const list = doc.querySelector('#node-config-plcwire-test-steps');
          let scroller = list.parentElement;
          while (scroller && scroller !== doc.body && !/auto|scroll/.test(win.getComputedStyle(scroller).overflowY))
            scroller = scroller.parentElement;
          const s = rect(scroller);
          const l = rect(list);
          // What the user sees: the dialog's scrolling body, the window, and the list's own box, intersected.
          const area = {
            top: Math.max(s.top, l.top, 0),
            bottom: Math.min(s.bottom, l.bottom, win.innerHeight),
            left: Math.max(s.left, 0),
            right: Math.min(s.right, win.innerWidth),
          };
          return {
            area,
            summary: {
              text: doc.querySelector('#node-config-plcwire-test-summary').textContent,
              ...rect(doc.querySelector('#node-config-plcwire-test-summary')),
            },
            rows: [...list.querySelectorAll('li')].map((li: any) => ({
              step: li.getAttribute('data-step'),
              ok: li.classList.contains('plcwire-step-ok'),
              visible: li.offsetParent !== null,
              ...rect(li),
            })),
          };
        });
        expect(seen.summary.text, JSON.stringify(seen.rows)).to.equal(CATALOG.editor.testOk);
        expect(seen.rows.map((r) => r.step)).to.deep.equal([
          'resolve',
          'tcp',
          'cotp',
          'setup',
          'identity',
          'protection',
          'putget',
          'symbol "Plant".Level',
          'symbol Plant.MotorSpeed',
          'address DB1,INT4',
        ]);
        expect(seen.rows.every((r) => r.ok)).to.equal(true);
        expect(seen.summary.top, 'the summary is in view').to.be.at.least(seen.area.top - 40);
        for (const r of seen.rows) {
          expect(r.visible, r.step).to.equal(true);
          expect(r.top, `${r.step} top in view ${JSON.stringify(seen.area)}`).to.be.at.least(seen.area.top - 0.5);
          expect(r.bottom, `${r.step} bottom in view ${JSON.stringify(seen.area)}`).to.be.at.most(seen.area.bottom + 0.5);
          expect(r.left).to.be.at.least(seen.area.left - 0.5);
        }
        expect(errors.map((e) => e.message)).to.deep.equal([]);
      } finally {
        await context.close();
      }
    });
  }
});
