/**
 * The read node's tag table as a user sees it, in headless Chromium: the
 * demo's read node (its seven tags by name, from the demo plant's source)
 * plus a name that does not resolve, at several window sizes and after the
 * window is resized. Every row is drawn inside the list (rows beyond its
 * height scroll, never over the "add" button), the add button can be
 * clicked and adds a row, a name's absolute address is shown in full, and a
 * name that does not resolve shows why in the row.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import type { Browser, Page } from 'playwright-core';
import { launchChromium } from './support/browser';
import { freePort } from './support/net';
import { openEditor, startNodeRedProcess, type NodeRedProcess } from './support/node-red-process';

const ROOT = path.resolve(__dirname, '../..');
const { demoFlow } = require(path.join(ROOT, 'demo/flows.js')) as { demoFlow(urls: object): any[] };

/** A name one letter short of the plant's "Plant".MotorRunning: no such member. */
const UNRESOLVED = '"Plant".MotorRunnin';
const EN = JSON.parse(fs.readFileSync(path.join(ROOT, 'nodes/locales/en-US/read.json'), 'utf8'));

/** The demo's S7 connection and read node (no other node), the PLC on a port where nothing listens, plus a row that does not resolve. */
function flowOf(port: number): { flow: object[]; tags: { name: string; address: string }[] } {
  const demo = demoFlow({ s7: `s7://127.0.0.1:${port}?rack=0&slot=1`, fetchwrite: '', freeport: '' });
  const conn = demo.find((n) => n.id === 'conn.s7');
  const read = demo.find((n) => n.id === 's7.read');
  const tags = [...read.tags, { name: 'typo', address: UNRESOLVED }];
  return {
    tags,
    flow: [{ id: 'tab', type: 'tab', label: 'tag table' }, conn, { ...read, tags, z: 'tab', x: 200, y: 100, interval: 0, wires: [[]] }],
  };
}

/** What the dialog shows: every row's box, the list's and the add button's, and the texts of the rows. */
interface Layout {
  list: Box;
  add: Box;
  /** The add button is what a click at its centre reaches (no row drawn over it). */
  addOnTop: boolean;
  rows: {
    box: Box;
    name: string;
    address: string;
    addressFits: boolean;
    type: string;
    resolved: string;
    resolvedFits: boolean;
    problem: string;
    problemShown: boolean;
  }[];
}
interface Box {
  top: number;
  bottom: number;
  left: number;
  right: number;
}

/** Scrolls each row into the list's view in turn and measures it there (a row beyond the list's height is reached by scrolling it). */
function layoutOf(page: Page): Promise<Layout> {
  return page.evaluate(() => {
    const doc = (globalThis as any).document;
    const box = (el: any): Box => {
      const r = el.getBoundingClientRect();
      return { top: r.top, bottom: r.bottom, left: r.left, right: r.right };
    };
    const list = doc.querySelector('#node-input-plcwire-tags');
    const container = list.closest('.red-ui-editableList-container');
    const add = list.closest('.red-ui-editableList').querySelector('.red-ui-editableList-addButton');
    add.scrollIntoView({ block: 'nearest' });
    const a = box(add);
    const hit = doc.elementFromPoint((a.left + a.right) / 2, (a.top + a.bottom) / 2);
    const addOnTop = !!hit && (hit === add || add.contains(hit));
    const rows = [...doc.querySelectorAll('#node-input-plcwire-tags > li')].map((li: any) => {
      li.scrollIntoView({ block: 'nearest' });
      const input = li.querySelector('.plcwire-tag-address');
      const resolved = li.querySelector('.plcwire-tag-resolved');
      const problem = li.querySelector('.plcwire-tag-problem');
      const pr = problem ? problem.getBoundingClientRect() : { width: 0, height: 0 };
      return {
        box: box(li),
        name: li.querySelector('.plcwire-tag-name').value,
        address: input.value,
        addressFits: input.scrollWidth <= input.clientWidth,
        type: li.querySelector('.plcwire-tag-type').textContent,
        resolved: resolved.textContent,
        resolvedFits: resolved.scrollWidth <= resolved.clientWidth,
        problem: problem ? problem.textContent : '',
        problemShown:
          !!problem &&
          pr.width > 0 &&
          pr.height > 0 &&
          problem.scrollWidth <= problem.clientWidth &&
          problem.scrollHeight <= problem.clientHeight,
      };
    });
    container.scrollTop = 0;
    return { list: box(container), add: a, addOnTop, rows };
  });
}

describe('editor: the tag table inside its dialog, at every window size', function () {
  this.timeout(180_000);
  let red: NodeRedProcess;
  let browser: Browser;
  let tags: { name: string; address: string }[];

  before(async () => {
    const { flow, tags: t } = flowOf(await freePort());
    tags = t;
    red = await startNodeRedProcess(flow);
    browser = await launchChromium();
  });
  after(async () => {
    await browser?.close();
    await red?.stop();
  });

  /** The demo's read node opened in the editor, in a window of `width` × `height`, once every row shows what the runtime said. */
  async function openReadDialog(width: number, height: number) {
    const opened = await openEditor(browser, red, 'en-US', 's7.read');
    await opened.page.setViewportSize({ width, height });
    await opened.page.evaluate(() => (globalThis as any).RED.editor.edit((globalThis as any).RED.nodes.node('s7.read')));
    await opened.page.waitForSelector('.node-input-plcwire-tags-row .red-ui-editableList-addButton', { state: 'visible', timeout: 20_000 });
    await settled(opened.page, tags.length);
    return opened;
  }

  /** Every one of `n` rows shows a type (the runtime's answer has arrived), and the tray has finished sliding in. */
  async function settled(page: Page, n: number): Promise<void> {
    await page.waitForFunction(
      (count) => {
        const types = [...(globalThis as any).document.querySelectorAll('#node-input-plcwire-tags .plcwire-tag-type')];
        return types.length === count && types.every((e: any) => e.textContent !== '');
      },
      n,
      { timeout: 20_000 },
    );
    await page.waitForFunction(
      () =>
        !(globalThis as any).document.querySelector(
          '.red-ui-tray.red-ui-tray-animating, .red-ui-tray:not(.red-ui-tray-closed):is(:animated)',
        ),
    );
    // Two frames: the resize the editor does on opening (and on a window resize) has been laid out.
    await page.evaluate(
      () => new Promise((r) => (globalThis as any).requestAnimationFrame(() => (globalThis as any).requestAnimationFrame(r))),
    );
  }

  /** The checks of the issue, on what the dialog shows now. */
  async function expectTidy(page: Page, what: string): Promise<void> {
    const layout = await layoutOf(page);
    expect(layout.rows.length, what).to.equal(tags.length);
    for (const [i, row] of layout.rows.entries()) {
      const where = `${what}, row ${i + 1} (${row.address})`;
      expect(row.box.top, `${where}: top`).to.be.at.least(layout.list.top - 1);
      expect(row.box.bottom, `${where}: bottom`).to.be.at.most(layout.list.bottom + 1);
      expect(row.box.left, `${where}: left`).to.be.at.least(layout.list.left - 1);
      expect(row.box.right, `${where}: right`).to.be.at.most(layout.list.right + 1);
      expect(row.addressFits, `${where}: the address input shows it in full`).to.equal(true);
    }
    expect(layout.list.bottom, `${what}: the list ends above the add button`).to.be.at.most(layout.add.top + 1);
    expect(layout.addOnTop, `${what}: no row drawn over the add button`).to.equal(true);

    // "Plant".MotorRun and "Plant".MotorRunning: both names and their absolute addresses read in full.
    const run = layout.rows.find((r) => r.address === '"Plant".MotorRun')!;
    const running = layout.rows.find((r) => r.address === '"Plant".MotorRunning')!;
    expect([run.type, run.resolved, running.type, running.resolved], what).to.deep.equal(['BOOL', 'DB1.DBX4.0', 'BOOL', 'DB1.DBX4.1']);
    for (const r of layout.rows.filter((x) => x.resolved))
      expect(r.resolvedFits, `${what}: ${r.address} → ${r.resolved} in full`).to.equal(true);

    // The name that does not resolve says why, in the row, in full.
    const typo = layout.rows.find((r) => r.address === UNRESOLVED)!;
    expect(typo.type, what).to.equal(EN.plcwire.editor.invalid);
    expect(typo.problem, what).to.include('MotorRunnin');
    expect(typo.problemShown, `${what}: the reason is visible, not cut off`).to.equal(true);
  }

  /** Clicks "add" as a user does (the button must be the element under the pointer) and sees one more row. */
  async function addRow(page: Page): Promise<void> {
    const before = await page.locator('#node-input-plcwire-tags > li').count();
    await page.locator('.node-input-plcwire-tags-row .red-ui-editableList-addButton').click({ timeout: 5000 });
    await page.waitForFunction(
      (n) => (globalThis as any).document.querySelectorAll('#node-input-plcwire-tags > li').length === n + 1,
      before,
    );
  }

  for (const [width, height] of [
    [1600, 1000],
    [1280, 800],
    [1024, 640],
  ] as const) {
    it(`${width}×${height}: every row inside the list, the add button clickable, addresses and the reason readable`, async () => {
      const { context, page, errors } = await openReadDialog(width, height);
      try {
        await expectTidy(page, `${width}×${height}`);
        await addRow(page);
        expect(errors.map((e) => e.message)).to.deep.equal([]);
      } finally {
        await context.close();
      }
    });
  }

  it('after the window is resized (smaller, then larger) the rows still stay inside the list', async () => {
    const { context, page, errors } = await openReadDialog(1600, 1000);
    try {
      await expectTidy(page, '1600×1000');
      for (const [width, height] of [
        [1024, 640],
        [1280, 800],
      ] as const) {
        const listHeight = () =>
          page.evaluate(() => (globalThis as any).document.querySelector('#node-input-plcwire-tags').parentElement.clientHeight);
        const was = await listHeight();
        await page.setViewportSize({ width, height });
        // The editor resizes the open dialog on the window's resize event: the list's height follows.
        await page.waitForFunction(
          (h) => (globalThis as any).document.querySelector('#node-input-plcwire-tags').parentElement.clientHeight !== h,
          was,
        );
        await settled(page, tags.length);
        await expectTidy(page, `resized to ${width}×${height}`);
      }
      await addRow(page);
      expect(errors.map((e) => e.message)).to.deep.equal([]);
    } finally {
      await context.close();
    }
  });
});
