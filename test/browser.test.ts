/**
 * The first five minutes of a new user, in a real browser: `npm start`'s
 * Node-RED with the demo flow, the editor's palette and the flows as it
 * draws them, and the Dashboard 2.0 page showing live values, BOOLs as
 * lamps, the motor switch following the PLC and writing back to it, and the
 * widgets of a link that went down greyed out as stale, and the CPU panel:
 * the S7-1200's identity, state, clock and diagnostic buffer, its Stop button
 * freezing the process and its Start button setting it going again.
 * Headless Chromium driven by playwright-core (test/support/browser.ts).
 * PLCWIRE_SCREENSHOT=<file.png> saves the dashboard with the motor running (after a CPU stop and restart),
 * after PLCWIRE_SCREENSHOT_WAIT_MS more of chart history (docs/dashboard.png:
 * PLCWIRE_SCREENSHOT=docs/dashboard.png PLCWIRE_SCREENSHOT_WAIT_MS=60000).
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import type { Browser, Page } from 'playwright-core';
import { launchChromium } from './support/browser';
import { createClient } from '../lib/connect';
import { estimatedSize, overlap, placementOf, type Box, type FlowNode } from './support/flow-layout';
import { freePort } from './support/net';
import { until } from './support/wait';

const ROOT = path.resolve(__dirname, '../..');
const EXAMPLES = path.join(ROOT, 'examples');
/** The class the demo's watchdogs put on the widgets of a quiet link (demo/flows.js). */
const STALE = 'plcwire-stale';

interface Demo {
  editor: string;
  dashboard: string;
  plant: {
    memory: { area(a: string, db?: number): Buffer | undefined };
    urls: { s7: string; s7plus: string };
    tank: {
      snapshot(): { phase: string; setpoint: number; drive: { running: boolean; speed: number; current: number }; levels: number[] };
    };
    s7: {
      faults: { refuseConnections: boolean; dropConnections(): void };
      state: string;
      cpu: {
        identity: { orderCode: string; firmware: string; serialNumber: string; moduleTypeName: string; moduleName: string; asName: string };
      };
      diagnostics: { eventId: number; description?: string }[];
      on(event: 'request', listener: (e: { kind: string }) => void): unknown;
      off(event: 'request', listener: (e: { kind: string }) => void): unknown;
    };
    fetchwrite: { faults: { silent: boolean; dropConnections(): void } };
  };
  stop(): Promise<void>;
}

/** A node as the editor drew it: centre, size, label, and the box of all it draws (ports and status included). */
interface Drawn {
  id: string;
  type: string;
  x: number;
  y: number;
  w: number;
  h: number;
  label: string;
  /** In page coordinates. */
  box: { left: number; top: number; right: number; bottom: number };
  /** How far the shown status reaches below the node's body. */
  below: number;
}

/** The nodes the editor has drawn on workspace `z`, once every one of them has its size. */
async function drawnNodes(page: Page, z: string): Promise<Drawn[]> {
  await page.waitForFunction(
    (tab) => {
      const RED = (globalThis as any).RED;
      let ready = true;
      RED.nodes.eachNode((n: any) => {
        if (n.z === tab && !(n.w > 0 && n.h > 0 && !n.resize && (globalThis as any).document.getElementById(n.id))) ready = false;
      });
      return ready;
    },
    z,
    { timeout: 15_000 },
  );
  return page.evaluate((tab) => {
    const RED = (globalThis as any).RED;
    const doc = (globalThis as any).document;
    const out: Drawn[] = [];
    RED.nodes.eachNode((n: any) => {
      if (n.z !== tab) return;
      // What the node draws: its body, its ports, its button (an inject's left of it, a debug's right) and a
      // status that is shown, in page coordinates (the corner badges for "changed" and "has a description" are left out).
      const g = doc.getElementById(n.id);
      const parts = [
        ...g.querySelectorAll(
          ':scope > rect.red-ui-flow-node, .red-ui-flow-port, .red-ui-flow-node-button-background, .red-ui-flow-node-status-group',
        ),
      ].filter((e: any) => (globalThis as any).getComputedStyle(e).display !== 'none');
      const rects = parts.map((e: any) => e.getBoundingClientRect());
      const box = {
        left: Math.min(...rects.map((r: any) => r.left)),
        top: Math.min(...rects.map((r: any) => r.top)),
        right: Math.max(...rects.map((r: any) => r.right)),
        bottom: Math.max(...rects.map((r: any) => r.bottom)),
      };
      const body = g.querySelector(':scope > rect.red-ui-flow-node').getBoundingClientRect();
      out.push({
        id: n.id,
        type: n.type,
        x: n.x,
        y: n.y,
        w: n.w,
        h: n.h,
        label: RED.utils.getNodeLabel(n, n.type),
        box,
        below: box.bottom - body.bottom,
      });
    });
    return out;
  }, z);
}

/** Pairs of drawn nodes (with their ports and status) closer than `gap` px. */
function overlapsOf(nodes: Drawn[], gap: number): string[] {
  const box = (n: Drawn): Box => ({ id: n.id, label: n.label, ...n.box });
  const found: string[] = [];
  for (let i = 0; i < nodes.length; i++) {
    for (let j = i + 1; j < nodes.length; j++) {
      if (overlap(box(nodes[i]!), box(nodes[j]!), gap)) found.push(`"${nodes[i]!.label}" and "${nodes[j]!.label}"`);
    }
  }
  return found;
}

/** Nodes the editor drew larger, or with a status reaching further down, than test/support/flow-layout.ts estimates (it must be an upper bound). */
function underestimated(drawn: Drawn[], source: (id: string) => FlowNode | undefined): string[] {
  return drawn.flatMap((d) => {
    const n = source(d.id);
    if (!n) return [`${d.id} not in the flow`];
    const e = estimatedSize(n);
    return e.w >= d.w && e.h >= d.h && e.below >= d.below
      ? []
      : [`"${d.label}" drawn ${d.w}x${d.h} +${d.below} below, estimated ${e.w}x${e.h} +${e.below}`];
  });
}

/** Whether the widget with class `cls` carries the stale mark. */
function staleOf(page: Page, cls: string): Promise<boolean> {
  return page.evaluate(
    ([c, stale]) => (globalThis as any).document.querySelector(`.${c}`)?.classList.contains(stale) ?? false,
    [cls, STALE],
  );
}

function waitForStale(page: Page, classes: string[], stale: boolean, ms: number): Promise<unknown> {
  return page.waitForFunction(
    ([list, mark, want]) =>
      (list as string[]).every((c) => (globalThis as any).document.querySelector(`.${c}`)?.classList.contains(mark) === want),
    [classes, STALE, stale] as const,
    { timeout: ms },
  );
}

/** Widgets of each link (their classes, demo/flows.js). */
const S7_WIDGETS = [
  'plcwire-level',
  'plcwire-temp',
  'plcwire-chart',
  'plcwire-motor',
  'plcwire-ui-running',
  'plcwire-ui-heater',
  'plcwire-ui-speed',
  'plcwire-ui-parts',
];
const CP_WIDGETS = ['plcwire-ui-fw-level', 'plcwire-ui-fw-parts'];
const S7_200_WIDGETS = ['plcwire-ui-fp-level', 'plcwire-ui-fp-parts'];
const PLUS_WIDGETS = ['plcwire-ui-plus-phase', 'plcwire-setpoint', 'plcwire-ui-plus-drive', 'plcwire-ui-plus-levels'];

/** The text of the first element matching `selector`, '' when there is none. */
function textOf(page: Page, selector: string): Promise<string> {
  return page.evaluate((sel) => ((globalThis as any).document.querySelector(sel)?.innerText ?? '') as string, selector);
}

/** The CPU panel's Stop and Start buttons: whether each is enabled. */
function cpuButtons(page: Page): Promise<{ stop: boolean; start: boolean }> {
  return page.evaluate(() => {
    const enabled = (cls: string) => (globalThis as any).document.querySelector(`.${cls} button`)?.disabled === false;
    return { stop: enabled('plcwire-cpu-stop'), start: enabled('plcwire-cpu-start') };
  });
}

function waitForButtons(page: Page, want: { stop: boolean; start: boolean }): Promise<unknown> {
  return page.waitForFunction(
    ([stop, start]) => {
      const enabled = (cls: string) => (globalThis as any).document.querySelector(`.${cls} button`)?.disabled === false;
      return enabled('plcwire-cpu-stop') === stop && enabled('plcwire-cpu-start') === start;
    },
    [want.stop, want.start] as const,
    { timeout: 10_000 },
  );
}

/**
 * What keeps a user from reading the CPU panel at the page's width: an identity
 * value other than expected, clipped (wider than its box, outside its card or the
 * window, cut off by an ancestor that hides overflow) or broken over lines; a
 * diagnostic description with fewer than 12 characters a line (a word or two a
 * line), or (on a card narrower than 576 px, where the table is stacked)
 * narrower than 60 % of the card.
 */
function cpuPanelProblems(page: Page, identity: string[]): Promise<string[]> {
  return page.evaluate((want) => {
    const doc = (globalThis as any).document;
    const view = doc.documentElement.clientWidth;
    const problems: string[] = [];
    // Lines of text in an element: the line boxes of its text nodes, those starting within half a line of each other one line.
    const lines = (el: any) => {
      const walker = doc.createTreeWalker(el, 4 /* NodeFilter.SHOW_TEXT */);
      const rects: any[] = [];
      for (let t = walker.nextNode(); t; t = walker.nextNode()) {
        const range = doc.createRange();
        range.selectNodeContents(t);
        rects.push(...[...range.getClientRects()].filter((r: any) => r.width > 0));
      }
      rects.sort((a, b) => a.top - b.top);
      let count = 0;
      let last = -Infinity;
      for (const r of rects) {
        if (r.top - last <= r.height / 2) continue;
        count++;
        last = r.top;
      }
      return count;
    };
    const values = [...doc.querySelectorAll('.plcwire-cpu-identity b')];
    const shown = values.map((b: any) => b.textContent.trim());
    if (JSON.stringify(shown) !== JSON.stringify(want)) problems.push(`identity shows ${JSON.stringify(shown)}`);
    const card = doc.querySelector('.plcwire-ui-cpu-identity').closest('.nrdb-ui-group').getBoundingClientRect();
    for (const b of values) {
      const r = b.getBoundingClientRect();
      const name = `"${b.textContent.trim()}"`;
      if (b.scrollWidth > b.clientWidth) problems.push(`${name} wider (${b.scrollWidth}) than its box (${b.clientWidth})`);
      if (r.left < Math.max(0, card.left) - 0.5 || r.right > Math.min(view, card.right) + 0.5)
        problems.push(`${name} at ${r.left}..${r.right} outside its card ${card.left}..${card.right} or the window 0..${view}`);
      for (let a = b.parentElement; a && a !== doc.body; a = a.parentElement) {
        const style = (globalThis as any).getComputedStyle(a);
        if (style.overflowX === 'visible' && style.overflowY === 'visible') continue;
        const c = a.getBoundingClientRect();
        if (r.left < c.left - 0.5 || r.right > c.right + 0.5 || r.top < c.top - 0.5 || r.bottom > c.bottom + 0.5)
          problems.push(`${name} cut off by ${a.tagName.toLowerCase()}.${String(a.className).split(' ').join('.')}`);
      }
      if (lines(b) !== 1) problems.push(`${name} on ${lines(b)} lines`);
    }
    const table = doc.querySelector('.plcwire-cpu-diag').closest('.nrdb-ui-group').getBoundingClientRect();
    const descriptions = [...doc.querySelectorAll('.plcwire-cpu-diag tbody td[data-column-key="description"] .nrdb-table-cell-align')];
    if (descriptions.length === 0) problems.push('no diagnostic entries');
    for (const d of descriptions) {
      const name = `"${d.textContent.trim()}"`;
      const text = d.textContent.trim();
      if (text.length / lines(d) < 12) problems.push(`${name} on ${lines(d)} lines`);
      const width = d.getBoundingClientRect().width;
      if (table.width < 576 && width < 0.6 * table.width) problems.push(`${name} ${width} px wide on a card of ${table.width}`);
    }
    return problems;
  }, identity);
}

/** Toasts and alerts on screen over a widget, and whether the page offers itself as an installable app (a web manifest). */
function coveringToasts(page: Page): Promise<{ covering: string[]; manifest: boolean }> {
  return page.evaluate(() => {
    const doc = (globalThis as any).document;
    const widgets = [...doc.querySelectorAll('.nrdb-ui-widget')];
    const covering: string[] = [];
    for (const t of doc.querySelectorAll('.pwa-toast, [role="alert"], .v-snackbar__wrapper')) {
      const r = t.getBoundingClientRect();
      if (r.width === 0 || r.height === 0) continue;
      for (const w of widgets) {
        const b = w.getBoundingClientRect();
        if (r.left < b.right && b.left < r.right && r.top < b.bottom && b.top < r.bottom)
          covering.push(`"${t.innerText.trim()}" over ${w.id}`);
      }
    }
    return { covering, manifest: doc.querySelector('link[rel="manifest"]') !== null };
  });
}

/** A widget text's colour and the opacity it is drawn with (its own and its ancestors' within the widget). */
function shownColour(page: Page, selector: string): Promise<{ color: string; opacity: number } | null> {
  return page.evaluate((sel) => {
    const el = (globalThis as any).document.querySelector(sel);
    if (!el) return null;
    let opacity = 1;
    for (let a = el; a && !a.classList.contains('nrdb-ui-group'); a = a.parentElement) {
      opacity *= Number((globalThis as any).getComputedStyle(a).opacity);
    }
    return { color: (globalThis as any).getComputedStyle(el).color, opacity };
  }, selector);
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
    page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  });

  after(async () => {
    await browser?.close();
    await demo?.stop();
    if (profile) fs.rmSync(profile, { recursive: true, force: true });
  });

  it('the editor lists our six nodes in the palette', async () => {
    await page.goto(demo.editor, { waitUntil: 'domcontentloaded' });
    for (const type of ['plcwire-connection', 'plcwire-read', 'plcwire-write', 'plcwire-heartbeat', 'plcwire-control', 'plcwire-alarms']) {
      if (type === 'plcwire-connection') continue; // config nodes are not in the palette
      await page.waitForSelector(`.red-ui-palette-node[data-palette-type="${type}"]`, { timeout: 30_000 });
    }
    const registered = await page.evaluate(() => (globalThis as any).RED.nodes.getType('plcwire-connection') !== undefined);
    expect(registered).to.equal(true);
  });

  it('the editor draws the demo flow with no node over another, none larger than the layout test estimates, all within a 1280 px window', async () => {
    const { demoFlow, DEMO_URLS } = require(path.join(ROOT, 'demo/flows.js')) as { demoFlow(u: unknown): FlowNode[]; DEMO_URLS: unknown };
    const flow = demoFlow(DEMO_URLS);
    const source = (id: string) => flow.find((n) => n.id === id);
    // The nodes' status shows once the flow runs: the polls' "connected", the switch's "off".
    await page.waitForFunction(
      () =>
        [...(globalThis as any).document.querySelectorAll('.red-ui-flow-node-status-group')].filter(
          (g: any) => (globalThis as any).getComputedStyle(g).display !== 'none',
        ).length >= 5,
      undefined,
      { timeout: 15_000 },
    );
    const drawn = await drawnNodes(page, 'demo.tab');
    expect(drawn.length).to.equal(flow.filter((n) => n.z === 'demo.tab').length);
    expect(underestimated(drawn, source)).to.deep.equal([]);
    expect(overlapsOf(drawn, 5)).to.deep.equal([]);
    // Drawn where the flow says: a deployed flow's x, y are the nodes' centres.
    for (const d of drawn) expect([d.x, d.y], d.label).to.deep.equal([source(d.id)!.x, source(d.id)!.y]);
    // Nothing off to the right of the workspace (palette and sidebar open): no scrolling sideways to find a widget;
    // nothing cut off at its left edge either (an inject's button reaches 25 px left of its body): 5 px of air at least.
    const visible = await page.evaluate(() => {
      const chart = (globalThis as any).document.getElementById('red-ui-workspace-chart');
      return {
        left: chart.getBoundingClientRect().left,
        right: chart.getBoundingClientRect().left + chart.clientWidth,
        scrolled: chart.scrollLeft,
      };
    });
    expect(visible.scrolled).to.equal(0);
    expect(
      drawn
        .filter((d) => d.box.left < visible.left + 5 || d.box.right > visible.right)
        .map((d) => `"${d.label}" at ${d.box.left}..${d.box.right}`),
      `workspace ${visible.left}..${visible.right}`,
    ).to.deep.equal([]);
  });

  it("the demo's S7 connection opens on its CPU preset, S7-1200, not custom", async () => {
    const editor = await browser.newPage({ viewport: { width: 1280, height: 900 } });
    try {
      await editor.goto(demo.editor, { waitUntil: 'domcontentloaded' });
      await editor.waitForFunction(() => (globalThis as any).RED?.nodes?.node?.('conn.s7') != null, undefined, { timeout: 30_000 });
      await editor.evaluate(() => (globalThis as any).RED.editor.editConfig('', 'plcwire-connection', 'conn.s7'));
      const cpu = editor.locator('#node-config-input-cpu');
      await cpu.waitFor({ state: 'visible', timeout: 15_000 });
      expect(await cpu.evaluate((s: any) => s.options[s.selectedIndex].textContent.trim())).to.equal('S7-1200');
      expect(await editor.locator('#node-config-plcwire-rack').inputValue()).to.equal('0');
      expect(await editor.locator('#node-config-plcwire-slot').inputValue()).to.equal('1');
      await editor.locator('#node-config-dialog-cancel').click();
    } finally {
      await editor.close({ runBeforeUnload: false });
    }
  });

  it('the editor draws every example, imported as a new flow, with no node over another, none larger than estimated', async () => {
    // A page of its own: the imports are not deployed, and the editor asks before leaving a page with changes.
    const editor = await browser.newPage({ viewport: { width: 1280, height: 900 } });
    try {
      await editor.goto(demo.editor, { waitUntil: 'domcontentloaded' });
      // Every type the examples use: the editor registers node sets one after another, each once the
      // scripts it loads (resources/…/plcwire-editor.js) have arrived, so one type says nothing of the next.
      await editor.waitForFunction(
        () =>
          ['plcwire-read', 'plcwire-write', 'plcwire-heartbeat', 'plcwire-control', 'plcwire-alarms'].every(
            (t) => (globalThis as any).RED?.nodes?.getType?.(t) !== undefined,
          ),
        undefined,
        { timeout: 30_000 },
      );
      const files = fs.readdirSync(EXAMPLES, { recursive: true, encoding: 'utf8' }).filter((f) => f.endsWith('.json'));
      expect(files.length).to.be.at.least(5);
      for (const file of files) {
        const flow = JSON.parse(fs.readFileSync(path.join(EXAMPLES, file), 'utf8')) as FlowNode[];
        const imported = await editor.evaluate((nodes) => {
          const RED = (globalThis as any).RED;
          const { nodeMap } = RED.view.importNodes(nodes, { generateIds: true, addFlow: true });
          const ids: Record<string, string> = {};
          let z = '';
          // The map holds old id -> new node, and new id -> itself.
          for (const [old, n] of Object.entries(nodeMap as Record<string, any>)) {
            if (old !== n.id) ids[n.id] = old;
            if (n.z) z = n.z;
          }
          RED.workspaces.show(z);
          return { ids, z };
        }, flow);
        const drawn = await drawnNodes(editor, imported.z);
        // A group has a position too, but the editor draws it as a frame around its nodes, not as a node.
        expect(drawn.length, file).to.equal(flow.filter((n) => typeof n.x === 'number' && n.type !== 'group').length);
        expect(
          underestimated(drawn, (id) => flow.find((n) => n.id === imported.ids[id])),
          file,
        ).to.deep.equal([]);
        // Ports may touch (they stick out 5 px), nodes may not overlap.
        expect(overlapsOf(drawn, 0), file).to.deep.equal([]);
        // Placed the way flow-layout.ts's placementOf says, up to one shift of the whole flow:
        // centred on x, y (a flow with its own tab), or left edges where x - 50 puts them.
        const centred = placementOf(flow, false) === 'centred';
        const source = (d: Drawn) => flow.find((n) => n.id === imported.ids[d.id])!;
        const shifts = new Set(drawn.map((d) => `${d.x - (centred ? 0 : d.w / 2 - 50) - source(d).x!},${d.y - source(d).y!}`));
        expect(shifts.size, `${file}: ${[...shifts]}`).to.equal(1);
      }
    } finally {
      await editor.close({ runBeforeUnload: false });
    }
  });

  it('the dashboard shows the tank level changing live', async () => {
    await page.goto(demo.dashboard, { waitUntil: 'domcontentloaded' });
    const selector = '.plcwire-ui-fw-level';
    await page.waitForFunction((sel) => /\d/.test((globalThis as any).document.querySelector(sel)?.textContent ?? ''), selector, {
      timeout: 30_000,
    });
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

  it('the temperature moves on the dashboard (the heater and the running motor warm the tank)', async () => {
    // The gauge's text: title, scale ends, value and unit ("Temperature 0 80 26.2 °C").
    const shown = () =>
      page
        .locator('.plcwire-temp')
        .innerText()
        .then((t) => Number(/(\d+(?:\.\d+)?)\s*°C/.exec(t)?.[1]));
    await page.waitForFunction(
      () => /\d\s*°C/.test((globalThis as any).document.querySelector('.plcwire-temp')?.innerText ?? ''),
      undefined,
      { timeout: 15_000 },
    );
    const first = await shown();
    expect(first).to.be.within(15, 60);
    await page.waitForFunction(
      (before) => {
        const m = /(\d+(?:\.\d+)?)\s*°C/.exec((globalThis as any).document.querySelector('.plcwire-temp')?.innerText ?? '');
        return m !== null && Number(m[1]) !== before;
      },
      first,
      { timeout: 15_000 },
    );
  });

  it("the demo starts the feed motor: the switch shows it on and the S7CommPlus group's feed drive (the same motor) turns; cleared or set by another client, the switch moves", async () => {
    const db1 = demo.plant.memory.area('DB', 1)!;
    await page.waitForFunction(
      () => (globalThis as any).document.querySelector('.plcwire-motor input[type=checkbox]') !== null,
      undefined,
      { timeout: 15_000 },
    );
    expect(db1[4]! & 0x01, '"Plant".MotorRun set by npm start').to.equal(1);
    await page.waitForFunction(
      () => (globalThis as any).document.querySelector('.plcwire-motor input[type=checkbox]').checked === true,
      undefined,
      { timeout: 10_000 },
    );
    // "Tank".Drive read over S7CommPlus: a speed, a current and a lit lamp, not "0 rpm · 0.0 A".
    await page.waitForFunction(
      () => {
        const drive = (globalThis as any).document.querySelector('.plcwire-ui-plus-drive');
        return /[1-9]\d* rpm · [1-9]\d*\.\d A/.test(drive?.innerText ?? '') && drive.querySelector('.plcwire-lamp-on') !== null;
      },
      undefined,
      { timeout: 20_000 },
    );
    const other = createClient(demo.plant.urls.s7);
    try {
      await other.connect();
      await other.write({ 'DB1.DBX4.0': false });
      await page.waitForFunction(
        () => (globalThis as any).document.querySelector('.plcwire-motor input[type=checkbox]').checked === false,
        undefined,
        { timeout: 10_000 },
      );
      await other.write({ 'DB1.DBX4.0': true });
      await page.waitForFunction(
        () => (globalThis as any).document.querySelector('.plcwire-motor input[type=checkbox]').checked === true,
        undefined,
        { timeout: 10_000 },
      );
      await other.write({ 'DB1.DBX4.0': false });
      await page.waitForFunction(
        () => (globalThis as any).document.querySelector('.plcwire-motor input[type=checkbox]').checked === false,
        undefined,
        { timeout: 10_000 },
      );
    } finally {
      await other.close();
    }
    // Nothing was written back by the switch showing the polled bit.
    await until(() => db1.readInt16BE(6) === 0, 10_000, 'motor stopped again');
    expect(db1[4]! & 0x01).to.equal(0);
  });

  it("clicking the motor switch writes the run command to the simulated PLC, and the switch shows the PLC's bit", async () => {
    const db1 = demo.plant.memory.area('DB', 1)!;
    expect(db1[4]! & 0x01).to.equal(0);
    // The switch's own control (Vuetify draws the thumb over a hidden checkbox).
    await page.locator('.plcwire-motor .v-selection-control__input').click();
    await until(() => (db1[4]! & 0x01) === 1, 10_000, 'DB1.DBX4.0 set by the dashboard');
    await page.waitForFunction(
      () => (globalThis as any).document.querySelector('.plcwire-motor input[type=checkbox]').checked === true,
      undefined,
      { timeout: 10_000 },
    );
    // The process reacts: the motor ramps up and the dashboard shows its speed.
    await until(() => db1.readInt16BE(6) > 0, 10_000, 'motor speed rising');
    await page.waitForFunction(
      () => /[1-9]/.test((globalThis as any).document.querySelector('.plcwire-ui-speed')?.textContent ?? ''),
      undefined,
      { timeout: 15_000 },
    );
  });

  it('the optimized DB over S7CommPlus has its own group, titled so, with the values the S7-1200 holds in DB2 "Tank", changing live', async () => {
    const group = page.locator('.nrdb-ui-group', { hasText: 'optimized DB "Tank" over S7CommPlus' });
    await group.first().waitFor({ state: 'visible', timeout: 15_000 });
    await page.waitForFunction(
      () => /plcwire-lamp-green/.test((globalThis as any).document.querySelector('.plcwire-ui-link-plus .plcwire-lamp')?.className ?? ''),
      undefined,
      { timeout: 20_000 },
    );
    // "Tank".Levels, an array read whole: five levels, newest first, and they move with the tank.
    const levels = async () => (await textOf(page, '.plcwire-ui-plus-levels')).match(/\d+\.\d/g) ?? [];
    await page.waitForFunction(
      () => ((globalThis as any).document.querySelector('.plcwire-ui-plus-levels')?.innerText ?? '').match(/\d+\.\d/g)?.length === 5,
      undefined,
      { timeout: 15_000 },
    );
    const first = (await levels()).join();
    await page.waitForFunction(
      (before) =>
        (((globalThis as any).document.querySelector('.plcwire-ui-plus-levels')?.innerText ?? '').match(/\d+\.\d/g) ?? []).join() !==
        before,
      first,
      { timeout: 15_000 },
    );
    // What the page shows is what the PLC holds: the phase, and the newest level of the history within a poll of it.
    expect(await textOf(page, '.plcwire-ui-plus-phase')).to.match(/Filling|Draining/);
    const deadline = Date.now() + 15_000;
    for (;;) {
      const tank = demo.plant.tank.snapshot();
      const phase = await textOf(page, '.plcwire-ui-plus-phase');
      const drive = await textOf(page, '.plcwire-ui-plus-drive');
      const shownLevels = (await levels()).map(Number);
      const same =
        phase.includes(tank.phase) &&
        drive.includes(`${tank.drive.speed} rpm`) &&
        shownLevels.every((v, i) => Math.abs(v - tank.levels[i]!) <= 0.05);
      if (same) break;
      if (Date.now() > deadline)
        throw new Error(`the page shows ${phase} / ${drive} / ${shownLevels.join()}, the PLC holds ${JSON.stringify(tank)}`);
      await page.waitForTimeout(200);
    }
    for (const c of PLUS_WIDGETS) expect(await staleOf(page, c), c).to.equal(false);
  });

  it('the setpoint slider writes "Tank".Setpoint to the S7-1200 by name over S7CommPlus, and follows the PLC when another client changes it', async () => {
    const field = page.locator('.plcwire-setpoint input[type=number], .plcwire-setpoint input[type=text]').first();
    await page.waitForFunction(
      () =>
        Number(
          (globalThis as any).document.querySelector('.plcwire-setpoint input[type=number], .plcwire-setpoint input[type=text]')?.value,
        ) === 42.5,
      undefined,
      { timeout: 15_000 },
    );
    await field.fill('47.5');
    await field.press('Enter');
    await until(() => demo.plant.tank.snapshot().setpoint === 47.5, 10_000, '"Tank".Setpoint written from the dashboard');
    // Another client (an HMI) writes it: the slider shows the PLC's value.
    const hmi = createClient(demo.plant.urls.s7plus);
    try {
      await hmi.connect();
      await hmi.write({ '"Tank".Setpoint': 40 });
      await page.waitForFunction(
        () =>
          Number(
            (globalThis as any).document.querySelector('.plcwire-setpoint input[type=number], .plcwire-setpoint input[type=text]')?.value,
          ) === 40,
        undefined,
        { timeout: 10_000 },
      );
      expect(demo.plant.tank.snapshot().setpoint, 'the polled value is not written back').to.equal(40);
      await hmi.write({ '"Tank".Setpoint': 42.5 });
    } finally {
      await hmi.close();
    }
  });

  it('BOOLs are lamps: Motor running lights while DB1.DBX4.1 is set, Heater on shows DB1.DBX4.2, and no true/false text', async () => {
    const db1 = demo.plant.memory.area('DB', 1)!;
    const lit = (cls: string) =>
      page.evaluate(
        (c) => (globalThis as any).document.querySelector(`.${c} .plcwire-lamp`)?.classList.contains('plcwire-lamp-on') ?? null,
        cls,
      );
    // The motor was started by the previous test.
    await page.waitForFunction(
      () => (globalThis as any).document.querySelector('.plcwire-ui-running .plcwire-lamp')?.classList.contains('plcwire-lamp-on'),
      undefined,
      { timeout: 10_000 },
    );
    expect(db1[4]! & 0x02).to.equal(0x02);
    // The heater lamp shows the thermostat's bit as last polled: it agrees with memory within a poll or two.
    const deadline = Date.now() + 10_000;
    let agree = false;
    while (!agree && Date.now() < deadline) {
      const bit = (db1[4]! & 0x04) !== 0;
      agree = (await lit('plcwire-ui-heater')) === bit && bit === ((db1[4]! & 0x04) !== 0);
      if (!agree) await page.waitForTimeout(100);
    }
    expect(agree, 'heater lamp agrees with DB1.DBX4.2').to.equal(true);
    const text = await page.locator('.nrdb-ui-group').allInnerTexts();
    expect(text.join('\n')).not.to.match(/\b(true|false)\b/);
  });

  /** The CPU panel's state lamp: its text and colour. */
  const cpuLamp = () =>
    page.evaluate(() => {
      const w = (globalThis as any).document.querySelector('.plcwire-ui-cpu-state');
      return {
        text: (w?.querySelector('.plcwire-lamp-text')?.textContent ?? '').trim(),
        lamp: w?.querySelector('.plcwire-lamp')?.className ?? '',
      };
    });
  const waitForCpu = (text: string, colour: string) =>
    page.waitForFunction(
      ([t, c]) => {
        const w = (globalThis as any).document.querySelector('.plcwire-ui-cpu-state');
        return (
          (w?.querySelector('.plcwire-lamp-text')?.textContent ?? '').trim() === t &&
          (w?.querySelector('.plcwire-lamp')?.classList.contains(`plcwire-lamp-${c}`) ?? false)
        );
      },
      [text, colour] as const,
      { timeout: 10_000 },
    );
  /** The diagnostic table's rows as the page shows them, cell texts joined by " | ". */
  const diagnosticRows = () =>
    page.evaluate(() =>
      [...(globalThis as any).document.querySelectorAll('.plcwire-cpu-diag tbody tr')].map((tr: any) =>
        [...tr.querySelectorAll('td')].map((td: any) => td.innerText.trim()).join(' | '),
      ),
    );
  const waitForTopRow = (pattern: RegExp) =>
    page.waitForFunction(
      ([source, flags]) =>
        new RegExp(source!, flags).test((globalThis as any).document.querySelector('.plcwire-cpu-diag tbody tr')?.innerText ?? ''),
      [pattern.source, pattern.flags] as const,
      { timeout: 10_000 },
    );
  /** Resolves once the S7 simulator served `n` more read jobs (the dashboard's poll, twice a second, and the heartbeat's watch read, once a second). */
  const readsServed = (n: number, ms = 15_000) =>
    new Promise<void>((resolve, reject) => {
      let seen = 0;
      const timer = setTimeout(() => {
        demo.plant.s7.off('request', on);
        reject(new Error(`only ${seen} of ${n} read jobs served within ${ms} ms`));
      }, ms);
      function on(e: { kind: string }) {
        if (e.kind !== 'read' || ++seen < n) return;
        clearTimeout(timer);
        demo.plant.s7.off('request', on);
        resolve();
      }
      demo.plant.s7.on('request', on);
    });
  const levelShown = async () => Number(/(\d+(?:\.\d+)?)\s*%/.exec(await page.locator('.plcwire-level').innerText())?.[1]);
  const partsShown = async () =>
    Number((await page.locator('.plcwire-ui-parts').innerText()).replace(/\D+/g, ' ').trim().split(' ').at(-1));
  const hex = (id: number) => `16#${id.toString(16).toUpperCase().padStart(4, '0')}`;

  it('the CPU panel shows the simulated S7-1200: its identity, RUN on a green lamp, its clock running, and the diagnostic buffer newest first', async () => {
    const id = demo.plant.s7.cpu.identity;
    await page.waitForFunction(
      (code) => ((globalThis as any).document.querySelector('.plcwire-ui-cpu-identity')?.innerText ?? '').includes(code),
      id.orderCode,
      { timeout: 15_000 },
    );
    const identity = await page.locator('.plcwire-ui-cpu-identity').innerText();
    for (const value of [id.moduleTypeName, id.orderCode, id.firmware, id.serialNumber]) expect(identity).to.include(value);
    await waitForCpu('RUN', 'green');
    // In RUN the CPU can be stopped, not started.
    await waitForButtons(page, { stop: true, start: false });
    await page.locator('.plcwire-cpu-stop button').waitFor({ state: 'visible' });
    // The clock as the CPU gives it, and it runs.
    const clock = () =>
      page
        .locator('.plcwire-ui-cpu-clock')
        .innerText()
        .then((t) => /\d{4}-\d\d-\d\d \d\d:\d\d:\d\d/.exec(t)?.[0] ?? '');
    await page.waitForFunction(
      () => /\d{4}-\d\d-\d\d \d\d:\d\d:\d\d/.test((globalThis as any).document.querySelector('.plcwire-ui-cpu-clock')?.innerText ?? ''),
      undefined,
      { timeout: 10_000 },
    );
    const first = await clock();
    expect(Math.abs(Date.parse(`${first.replace(' ', 'T')}Z`) - Date.now())).to.be.below(10_000);
    await page.waitForFunction(
      (before) => {
        const now = /\d{4}-\d\d-\d\d \d\d:\d\d:\d\d/.exec(
          (globalThis as any).document.querySelector('.plcwire-ui-cpu-clock')?.innerText ?? '',
        )?.[0];
        return now !== undefined && now > before;
      },
      first,
      { timeout: 10_000 },
    );
    // The simulator's buffer, newest first: power on, STOP to STARTUP, STARTUP to RUN.
    const log = demo.plant.s7.diagnostics;
    await page.waitForFunction(
      (n) => (globalThis as any).document.querySelectorAll('.plcwire-cpu-diag tbody tr').length === n,
      Math.min(10, log.length),
      { timeout: 10_000 },
    );
    const rows = await diagnosticRows();
    expect(rows.map((r) => r.split(' | ')[1])).to.deep.equal(log.slice(0, 10).map((e) => hex(e.eventId)));
    expect(rows[0]).to.match(/^\d{4}-\d\d-\d\d \d\d:\d\d:\d\d\.\d{3} \| 16#4302 \| Mode transition STARTUP to RUN$/);
  });

  it('Stop CPU on the dashboard stops the simulated CPU: STOP on a red lamp, the cause on top of the diagnostic buffer, the values held while the link stays live', async () => {
    const db1 = demo.plant.memory.area('DB', 1)!;
    // The motor runs (started above): the parts counter and the level both move while the CPU is in RUN.
    expect(db1.readInt16BE(6)).to.be.above(0);
    await page.locator('.plcwire-cpu-stop').locator('xpath=descendant-or-self::button').first().click();
    await until(() => demo.plant.s7.state === 'STOP', 10_000, 'the simulated CPU in STOP');
    expect(demo.plant.s7.diagnostics[0]).to.include({ eventId: 0x4304 });
    await waitForCpu('STOP', 'red');
    // In STOP: Start enabled, Stop not.
    await waitForButtons(page, { stop: false, start: true });
    await waitForTopRow(/16#4304\s*(\|\s*)?STOP by a programming device/);
    const held = { level: Math.round(db1.readFloatBE(0) * 10) / 10, parts: db1.readInt32BE(8) };
    // Polls served after the stop deliver the held values, and go on delivering them.
    await readsServed(3);
    await page.waitForFunction(
      ([level, parts]) => {
        const doc = (globalThis as any).document;
        const m = /(\d+(?:\.\d+)?)\s*%/.exec(doc.querySelector('.plcwire-level')?.innerText ?? '');
        return m !== null && Number(m[1]) === level && (doc.querySelector('.plcwire-ui-parts')?.innerText ?? '').includes(String(parts));
      },
      [held.level, held.parts] as const,
      { timeout: 10_000 },
    );
    // Six more read jobs: at least three more polls of the dashboard's values, all showing the same.
    await readsServed(6);
    expect(await levelShown()).to.equal(held.level);
    expect(await partsShown()).to.equal(held.parts);
    expect(Math.round(db1.readFloatBE(0) * 10) / 10).to.equal(held.level);
    // The link itself is fine: the values still arrive, nothing is greyed out.
    for (const c of S7_WIDGETS) expect(await staleOf(page, c), c).to.equal(false);
    // The PLC's heartbeat counter is part of the program: it stands still, and the heartbeat node says so.
    await page.waitForFunction(
      () => /plcwire-lamp-red/.test((globalThis as any).document.querySelector('.plcwire-ui-heartbeat .plcwire-lamp')?.className ?? ''),
      undefined,
      { timeout: 10_000 },
    );
  });

  it('Start CPU restarts it: RUN on a green lamp, the restart on top of the diagnostic buffer, and the values move again', async () => {
    const stopped = { level: await levelShown(), parts: await partsShown() };
    await page.locator('.plcwire-cpu-start').locator('xpath=descendant-or-self::button').first().click();
    await until(() => demo.plant.s7.state === 'RUN', 10_000, 'the simulated CPU in RUN');
    await waitForCpu('RUN', 'green');
    await waitForButtons(page, { stop: true, start: false });
    // A warm restart logs: manual warm restart, STOP to STARTUP, STARTUP to RUN (newest first).
    await waitForTopRow(/16#4302/);
    const rows = await diagnosticRows();
    expect(rows.slice(0, 4).map((r) => r.split(' | ')[1])).to.deep.equal(['16#4302', '16#4301', '16#1381', '16#4304']);
    await page.waitForFunction(
      ([level, parts]) => {
        const doc = (globalThis as any).document;
        const m = /(\d+(?:\.\d+)?)\s*%/.exec(doc.querySelector('.plcwire-level')?.innerText ?? '');
        const p = Number((doc.querySelector('.plcwire-ui-parts')?.innerText ?? '').replace(/\D+/g, ' ').trim().split(' ').at(-1));
        return m !== null && Number(m[1]) !== level && p > parts!;
      },
      [stopped.level, stopped.parts] as const,
      { timeout: 10_000 },
    );
    await page.waitForFunction(
      () => /plcwire-lamp-green/.test((globalThis as any).document.querySelector('.plcwire-ui-heartbeat .plcwire-lamp')?.className ?? ''),
      undefined,
      { timeout: 10_000 },
    );
    expect((await cpuLamp()).text).to.equal('RUN');
  });

  for (const [width, height] of [
    [412, 915],
    [1280, 800],
  ] as const) {
    it(`at ${width}x${height}: every CPU identity value whole on one line, diagnostic entries as lines, no toast over a widget, the motor switch's label in the text colour`, async () => {
      // A browser of its own, as a user opening the dashboard on a phone or a desktop for the first time.
      const own = await browser.newPage({ viewport: { width, height } });
      try {
        await own.goto(demo.dashboard, { waitUntil: 'domcontentloaded' });
        const id = demo.plant.s7.cpu.identity;
        const identity = [id.moduleTypeName, id.moduleName, id.orderCode, id.firmware, id.serialNumber, id.asName];
        await own.waitForFunction(
          (last) =>
            ((globalThis as any).document.querySelector('.plcwire-ui-cpu-identity')?.innerText ?? '').includes(last) &&
            (globalThis as any).document.querySelectorAll('.plcwire-cpu-diag tbody td[data-column-key="description"]').length > 0,
          id.asName,
          { timeout: 20_000 },
        );
        expect(await cpuPanelProblems(own, identity)).to.deep.equal([]);
        // Dashboard 2 offers an installable app only with a web manifest; without one no "App is offline ready" toast comes.
        expect(await coveringToasts(own)).to.deep.equal({ covering: [], manifest: false });
        await own.waitForFunction(() => (globalThis as any).document.querySelector('.plcwire-motor .v-label') !== null, undefined, {
          timeout: 10_000,
        });
        const motor = await shownColour(own, '.plcwire-motor .v-label');
        expect(motor).to.deep.equal(await shownColour(own, '.plcwire-ui-speed .nrdb-ui-text-label'));
        expect(motor!.opacity).to.equal(1);
        // The CPU is in RUN (restarted above): Stop enabled, Start not, on this page too.
        await waitForButtons(own, { stop: true, start: false });
        expect(await cpuButtons(own)).to.deep.equal({ stop: true, start: false });
        if (process.env.PLCWIRE_SCREENSHOT_DIR)
          await own.screenshot({ path: path.join(process.env.PLCWIRE_SCREENSHOT_DIR, `dashboard-${width}.png`), fullPage: true });
      } finally {
        await own.close();
      }
    });
  }

  for (const [width, height] of [
    [412, 915],
    [1280, 800],
  ] as const) {
    it(`at ${width}x${height}: the S7CommPlus group's title whole, its setpoint slider wide enough to drag, the level history on one line, its link lamp under the feed drive's`, async () => {
      const own = await browser.newPage({ viewport: { width, height } });
      try {
        await own.goto(demo.dashboard, { waitUntil: 'domcontentloaded' });
        await own.waitForFunction(
          () =>
            ((globalThis as any).document.querySelector('.plcwire-ui-plus-levels')?.innerText ?? '').match(/\d+\.\d/g)?.length === 5 &&
            /plcwire-lamp-green/.test((globalThis as any).document.querySelector('.plcwire-ui-link-plus .plcwire-lamp')?.className ?? ''),
          undefined,
          { timeout: 20_000 },
        );
        const seen = await own.evaluate(() => {
          const doc = (globalThis as any).document;
          const box = (e: any) => {
            const r = e.getBoundingClientRect();
            return { left: r.left, right: r.right, top: r.top, bottom: r.bottom, width: r.width, height: r.height };
          };
          const group = doc.getElementById('nrdb-ui-group-ui.g.plus');
          const title = group.querySelector('.v-card-title');
          const track = group.querySelector('.plcwire-setpoint .v-slider-track');
          const thumb = group.querySelector('.plcwire-setpoint .v-slider-thumb');
          thumb.scrollIntoView({ block: 'center' });
          const t = box(thumb);
          const hit = doc.elementFromPoint(t.left + t.width / 2, t.top + t.height / 2);
          const levels = group.querySelector('.plcwire-ui-plus-levels .plcwire-lamp-text');
          const label = group.querySelector('.plcwire-ui-plus-levels .plcwire-lamp-row > span');
          const lineHeight = (e: any) => parseFloat((globalThis as any).getComputedStyle(e).lineHeight) || 24;
          return {
            group: box(group.querySelector('.v-card-text')),
            title: { text: title.textContent, scroll: title.scrollWidth, client: title.clientWidth, ...box(title) },
            track: box(track),
            thumbOnTop: thumb.contains(hit),
            levels: { lines: Math.round(box(levels).height / lineHeight(levels)), ...box(levels) },
            label: { lines: Math.round(box(label).height / lineHeight(label)) },
            lamps: {
              drive: box(group.querySelector('.plcwire-ui-plus-drive .plcwire-lamp')).right,
              link: box(group.querySelector('.plcwire-ui-link-plus .plcwire-lamp')).right,
            },
          };
        });
        if (process.env.PLCWIRE_SCREENSHOT_DIR)
          await own
            .locator('#nrdb-ui-group-ui\\.g\\.plus')
            .screenshot({ path: path.join(process.env.PLCWIRE_SCREENSHOT_DIR, `plus-group-${width}.png`) });
        const report = JSON.stringify(seen);
        expect(seen.title.text, report).to.equal('S7-1200 optimized DB "Tank" over S7CommPlus (TLS)');
        expect(seen.title.scroll, `the title is not cut ${report}`).to.be.at.most(seen.title.client + 1);
        // A thumb a finger can drag: a track of 150 px at least (2.5 px per 0.5 °C step), the thumb on top where it is drawn.
        expect(seen.track.width, `slider track ${report}`).to.be.at.least(150);
        expect(seen.track.left).to.be.at.least(seen.group.left - 0.5);
        expect(seen.track.right).to.be.at.most(seen.group.right + 0.5);
        expect(seen.thumbOnTop, 'nothing over the thumb').to.equal(true);
        expect(seen.levels.lines, `level history on one line ${report}`).to.equal(1);
        expect(seen.label.lines, `its label on one line ${report}`).to.equal(1);
        expect(seen.levels.right).to.be.at.most(seen.group.right + 0.5);
        expect(Math.abs(seen.lamps.link - seen.lamps.drive), `the link lamp under the feed drive's ${report}`).to.be.at.most(1);
      } finally {
        await own.close();
      }
    });
  }

  it('every widget sits inside its group and on screen, at desktop, tablet and phone widths', async () => {
    if (process.env.PLCWIRE_SCREENSHOT) {
      // Let the chart gather some history.
      await page.waitForTimeout(Number(process.env.PLCWIRE_SCREENSHOT_WAIT_MS ?? 0));
      // The page from its top down to the lowest group and its margin (the buttons clicked above may have scrolled it).
      await page.evaluate(() => (globalThis as any).window.scrollTo(0, 0));
      const bottom = await page.evaluate(() =>
        Math.max(...[...(globalThis as any).document.querySelectorAll('.nrdb-ui-group')].map((g: any) => g.getBoundingClientRect().bottom)),
      );
      await page.screenshot({
        path: process.env.PLCWIRE_SCREENSHOT,
        fullPage: true,
        clip: { x: 0, y: 0, width: 1280, height: Math.ceil(bottom) + 12 },
      });
    }
    try {
      for (const width of [1280, 800, 390]) {
        await page.setViewportSize({ width, height: 900 });
        await page.waitForTimeout(300); // one layout pass after the resize
        const outside = await page.evaluate(() => {
          const doc = (globalThis as any).document;
          const view = { left: 0, right: doc.documentElement.clientWidth };
          const problems: string[] = [];
          for (const group of doc.querySelectorAll('.nrdb-ui-group')) {
            const g = group.getBoundingClientRect();
            if (g.left < view.left - 0.5 || g.right > view.right + 0.5) problems.push(`group ${group.id} ${g.left}..${g.right} off screen`);
            for (const widget of group.querySelectorAll('.nrdb-ui-widget')) {
              const w = widget.getBoundingClientRect();
              if (w.left < g.left - 0.5 || w.right > g.right + 0.5 || w.top < g.top - 0.5 || w.bottom > g.bottom + 0.5)
                problems.push(`${widget.id} ${w.left}..${w.right} outside ${group.id} ${g.left}..${g.right}`);
            }
          }
          return problems;
        });
        expect(outside, `at ${width} px`).to.deep.equal([]);
      }
    } finally {
      await page.setViewportSize({ width: 1280, height: 900 });
    }
  });

  it("an S7 link that goes down greys out its widgets as stale within seconds (S7comm and S7CommPlus: one CPU), the other links' stay live, and all recover", async () => {
    for (const c of [...S7_WIDGETS, ...PLUS_WIDGETS, ...CP_WIDGETS, ...S7_200_WIDGETS]) expect(await staleOf(page, c), c).to.equal(false);
    const faults = demo.plant.s7.faults;
    faults.refuseConnections = true;
    faults.dropConnections();
    try {
      // The watchdog fires 2 s after the last value (S7 polls every 500 ms).
      await waitForStale(page, S7_WIDGETS, true, 8_000);
      // The S7CommPlus link is polled every second, its watchdog fires after 3 s.
      await waitForStale(page, PLUS_WIDGETS, true, 10_000);
      for (const c of [...CP_WIDGETS, ...S7_200_WIDGETS]) expect(await staleOf(page, c), c).to.equal(false);
      const link = await page.evaluate(
        () => (globalThis as any).document.querySelector('.plcwire-ui-link-s7 .plcwire-lamp')?.className ?? '',
      );
      expect(link).to.match(/plcwire-lamp-(red|yellow)/);
    } finally {
      faults.refuseConnections = false;
    }
    // Reconnected on the backoff schedule, the first values clear the mark.
    await waitForStale(page, S7_WIDGETS, false, 30_000);
    await waitForStale(page, PLUS_WIDGETS, false, 30_000);
    await page.waitForFunction(
      () => /plcwire-lamp-green/.test((globalThis as any).document.querySelector('.plcwire-ui-link-s7 .plcwire-lamp')?.className ?? ''),
      undefined,
      { timeout: 10_000 },
    );
  });

  it('a hung CP (connected, answering nothing) greys out the FETCH/WRITE widgets too, and they recover when it answers again', async () => {
    const faults = demo.plant.fetchwrite.faults;
    faults.silent = true;
    try {
      // The watchdog fires 3 s after the last value (the CP is polled every second).
      await waitForStale(page, CP_WIDGETS, true, 15_000);
      for (const c of [...S7_WIDGETS, ...PLUS_WIDGETS]) expect(await staleOf(page, c), c).to.equal(false);
    } finally {
      faults.silent = false;
    }
    await waitForStale(page, CP_WIDGETS, false, 30_000);
  });
});
