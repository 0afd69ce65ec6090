/**
 * What a user sees of the S7CommPlus dialogs in a real browser (issue #31),
 * against the S7-1500 simulator over TLS, at 1024x700 and 1600x1000:
 *   - the connection dialog: the certificate's fingerprint whole (wrapped,
 *     monospace, copied by its button), the pinned fingerprint whole in its
 *     field, the Protocol select's choice whole, every Test connection step's
 *     text whole;
 *   - a read node in push mode on an s7plus:// connection as narrow as the
 *     tray (Node-RED makes the tray body as wide as the form's unwrapped
 *     width at opening: a long hint on one line made it wider than the tray);
 *   - switching to "when the PLC reports a change" shows the PLC's sample
 *     time, 100 ms unless given, and leaves the node valid.
 * "Whole" is measured, not guessed: an element's scrollWidth within its
 * clientWidth, its box within the tray's, a select's text within its box.
 * PLCWIRE_SCREENSHOT_DIR=<dir> keeps a screenshot of each dialog.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import type { Browser, Page } from 'playwright-core';
import { S7Server } from '../lib/s7/server';
import { S7PlusService } from '../lib/s7plus/server';
import { generateCertificate } from '../lib/s7plus/transport/cert';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { launchChromium } from './support/browser';
import { openEditor, startNodeRedProcess, type NodeRedProcess } from './support/node-red-process';

const ROOT = path.resolve(__dirname, '../..');
const CATALOG = JSON.parse(fs.readFileSync(path.join(ROOT, 'nodes/locales/en-US/connection.json'), 'utf8'))['plcwire-connection'];
const SIZES = [
  [1024, 700],
  [1600, 1000],
] as const;

async function shot(page: Page, name: string): Promise<void> {
  if (process.env.PLCWIRE_SCREENSHOT_DIR) await page.screenshot({ path: path.join(process.env.PLCWIRE_SCREENSHOT_DIR, `${name}.png`) });
}

/** Resolves once the open tray has slid in: its right edge at its stack's (Node-RED's tray slides in from the right). */
async function trayInPlace(page: Page): Promise<void> {
  await page.waitForFunction(
    () => {
      const doc = (globalThis as any).document;
      const trays = doc.querySelectorAll('.red-ui-tray');
      const stack = doc.getElementById('red-ui-editor-stack').getBoundingClientRect();
      return trays.length > 0 && Math.abs(trays[trays.length - 1].getBoundingClientRect().right - stack.right) < 1;
    },
    undefined,
    { timeout: 5_000 },
  );
}

/** Clicks `button` of the open tray and resolves once the tray is gone (the editor opens no other while one closes). */
async function closed(page: Page, button: string): Promise<void> {
  await page.click(button);
  await page.waitForSelector('.red-ui-tray', { state: 'detached', timeout: 5_000 });
}

/**
 * What of the open tray's form is not whole: a visible element whose box reaches past the tray body's,
 * an element whose content is wider than its box, a select whose chosen text is wider than its box, the body scrolling sideways.
 */
function cutOff(page: Page, selectors: string[]): Promise<string[]> {
  return page.evaluate((sels) => {
    const doc = (globalThis as any).document;
    const win = globalThis as any;
    const trays = doc.querySelectorAll('.red-ui-tray');
    const tray = trays[trays.length - 1];
    const body = tray.querySelector('.red-ui-tray-body');
    const box = tray.getBoundingClientRect();
    const problems: string[] = [];
    if (body.scrollWidth > body.clientWidth + 1) problems.push(`the tray body scrolls sideways: ${body.scrollWidth} > ${body.clientWidth}`);
    const canvas = doc.createElement('canvas').getContext('2d');
    for (const sel of sels) {
      const found = [...doc.querySelectorAll(sel)].filter((e: any) => e.offsetParent !== null);
      if (found.length === 0) problems.push(`${sel}: not shown`);
      for (const e of found as any[]) {
        const r = e.getBoundingClientRect();
        const name = `${sel}${found.length > 1 ? `[${found.indexOf(e)}]` : ''}`;
        if (r.left < box.left - 0.5 || r.right > box.right + 0.5)
          problems.push(`${name}: ${r.left}..${r.right} outside the tray ${box.left}..${box.right}`);
        if (r.right > win.innerWidth + 0.5) problems.push(`${name}: right edge ${r.right} past the window ${win.innerWidth}`);
        if (e.tagName === 'SELECT') {
          const style = win.getComputedStyle(e);
          canvas.font = `${style.fontWeight} ${style.fontSize} ${style.fontFamily}`;
          const text = e.options[e.selectedIndex]?.textContent ?? '';
          // The text, the select's padding and the drop-down arrow (about 20 px).
          const need = canvas.measureText(text).width + parseFloat(style.paddingLeft) + parseFloat(style.paddingRight) + 20;
          if (need > e.clientWidth) problems.push(`${name}: "${text}" needs ${Math.ceil(need)} px, has ${e.clientWidth}`);
        } else if (e.scrollWidth > e.clientWidth + 1 && win.getComputedStyle(e).display !== 'inline') {
          problems.push(`${name}: content ${e.scrollWidth} px wide in ${e.clientWidth}`);
        }
        if (e.tagName === 'TEXTAREA' && e.scrollHeight > e.clientHeight + 1)
          problems.push(`${name}: content ${e.scrollHeight} px high in ${e.clientHeight}`);
      }
    }
    return problems;
  }, selectors);
}

describe('editor in Chromium: the S7CommPlus dialogs, whole at 1024x700 and 1600x1000', function () {
  this.timeout(180_000);
  let server: S7Server;
  let service: S7PlusService;
  let red: NodeRedProcess;
  let browser: Browser;

  before(async () => {
    const cert = await generateCertificate();
    service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await server.listen();
    const at = (y: number) => ({ z: 'tab', x: 200, y, wires: [[]] });
    red = await startNodeRedProcess([
      { id: 'tab', type: 'tab', label: 'dialogs' },
      { id: 'plus', type: 'plcwire-connection', name: 'S7-1500', url: `s7plus://127.0.0.1:${server.port}` },
      { id: 'classic', type: 'plcwire-connection', name: 'S7-300', url: `s7://127.0.0.1:${server.port}?rack=0&slot=1` },
      // As the example's read node: no mode, no cycle (a flow from before the push mode).
      {
        id: 'read-plus',
        type: 'plcwire-read',
        ...at(40),
        connection: 'plus',
        interval: 1000,
        output: 'object',
        deadband: 0,
        tags: [{ name: 'step', address: '"Recipe".Step' }],
      },
      {
        id: 'read-classic',
        type: 'plcwire-read',
        ...at(120),
        connection: 'classic',
        interval: 1000,
        output: 'object',
        deadband: 0,
        tags: [{ name: 'count', address: 'DB1.DBW4:INT' }],
      },
      // A Sparkplug device without its alarms (issue #34); its edge node's broker is never reached, which the dialogs don't need.
      {
        id: 'spb-edge',
        type: 'plcwire-sparkplug-edge',
        brokers: 'mqtt://127.0.0.1:1',
        group: 'Plant',
        nodeId: 'Edge1',
        interval: 1000,
        buffer: 10000,
      },
      {
        id: 'spb-device',
        type: 'plcwire-sparkplug-device',
        ...at(200),
        edge: 'spb-edge',
        connection: 'classic',
        device: 'Press',
        tags: [{ name: 'count', address: 'DB1.DBW4:INT' }],
        writable: '',
      },
    ]);
    browser = await launchChromium();
  });

  after(async () => {
    await browser?.close();
    await red?.stop();
    await server?.close();
  });

  for (const [width, height] of SIZES) {
    it(`at ${width}x${height}: the fingerprint whole (monospace, wrapped, copied by its button) before and after Pin, the Protocol choice whole, every Test connection step whole`, async () => {
      const { context, page, errors } = await openEditor(browser, red, 'en-US', 'read-plus');
      try {
        await context.grantPermissions(['clipboard-read', 'clipboard-write']);
        await page.setViewportSize({ width, height });
        await page.evaluate(() => (globalThis as any).RED.editor.editConfig('', 'plcwire-connection', 'plus'));
        await page.waitForSelector('#node-config-plcwire-getcert', { state: 'visible', timeout: 10_000 });
        await trayInPlace(page);
        expect(
          await cutOff(page, ['#node-config-plcwire-protocol', '#node-config-plcwire-fingerprint', '#node-config-plcwire-getcert']),
        ).to.deep.equal([]);

        await page.click('#node-config-plcwire-getcert');
        await page.waitForSelector('#node-config-plcwire-pin', { state: 'visible', timeout: 15_000 });
        const colons = service.fingerprint!.toUpperCase().replace(/(..)(?!$)/g, '$1:');
        const shown = await page.$eval('#node-config-plcwire-cert .plcwire-fingerprint', (e: any) => ({
          text: e.textContent,
          font: (globalThis as any).getComputedStyle(e).fontFamily,
          lines: Math.round(e.getBoundingClientRect().height / parseFloat((globalThis as any).getComputedStyle(e).lineHeight)),
        }));
        expect(shown.text).to.equal(colons);
        expect(shown.font).to.match(/mono/i);
        await shot(page, `connection-certificate-${width}`);
        expect(
          await cutOff(page, [
            '#node-config-plcwire-cert',
            '#node-config-plcwire-cert .plcwire-fingerprint',
            '#node-config-plcwire-copy',
            '#node-config-plcwire-pin',
          ]),
        ).to.deep.equal([]);
        // Copy: the fingerprint as shown, to compare with TIA Portal's.
        await page.click('#node-config-plcwire-copy');
        expect(await page.evaluate(() => (globalThis as any).navigator.clipboard.readText())).to.equal(colons);

        await page.click('#node-config-plcwire-pin');
        expect(await page.inputValue('#node-config-plcwire-fingerprint')).to.equal(service.fingerprint);
        expect(
          await page.$eval('#node-config-plcwire-fingerprint', (e: any) => (globalThis as any).getComputedStyle(e).fontFamily),
        ).to.match(/mono/i);
        expect(await cutOff(page, ['#node-config-plcwire-fingerprint'])).to.deep.equal([]);

        await page.click('#node-config-plcwire-test');
        await page.waitForFunction(
          (done) => done.includes((globalThis as any).document.querySelector('#node-config-plcwire-test-summary').textContent),
          [CATALOG.editor.testOk, CATALOG.editor.testFailed],
          { timeout: 30_000 },
        );
        expect(await page.textContent('#node-config-plcwire-test-summary')).to.equal(CATALOG.editor.testOk);
        await shot(page, `connection-test-${width}`);
        const steps = await page.$$eval('#node-config-plcwire-test-steps li', (lis) => lis.map((li) => li.getAttribute('data-step')));
        expect(steps).to.include('TLS').and.include('identity');
        // The TLS step names the whole fingerprint (one long word): wrapped, not cut.
        expect(await page.textContent('li[data-step="TLS"]')).to.contain(service.fingerprint!.toUpperCase());
        expect(await cutOff(page, ['#node-config-plcwire-test-steps li', '#node-config-plcwire-test-hint'])).to.deep.equal([]);
        expect(errors.map((e) => e.message)).to.deep.equal([]);
        await page.click('#node-config-dialog-cancel');
      } finally {
        await context.close();
      }
    });
  }

  it('at 1024x700 a read node in push mode on an s7plus:// connection fits the tray (edit button, hint, tag rows) as one on s7:// does, in English and German', async () => {
    for (const locale of ['en-US', 'de-DE']) {
      const { context, page, errors } = await openEditor(browser, red, locale, 'read-plus');
      try {
        await page.setViewportSize({ width: 1024, height: 700 });
        const opened = async (id: string) => {
          await page.evaluate((n) => (globalThis as any).RED.editor.edit((globalThis as any).RED.nodes.node(n)), id);
          await page.waitForSelector('#node-input-mode', { state: 'visible', timeout: 10_000 });
          await trayInPlace(page);
        };
        const parts = [
          '#node-input-connection',
          '#node-input-btn-connection-edit',
          '#node-input-mode',
          '.plcwire-form .plcwire-hint',
          '.plcwire-tag-row',
        ];
        await opened('read-plus');
        await page.selectOption('#node-input-mode', 'push');
        await closed(page, '#node-dialog-ok');
        // Opened again in push mode: the tray is sized from the push form.
        await opened('read-plus');
        expect(await page.inputValue('#node-input-mode')).to.equal('push');
        await shot(page, `read-push-${locale}`);
        expect(await cutOff(page, [...parts, '#node-input-cycle', '#node-input-deadband']), `${locale} push`).to.deep.equal([]);
        await closed(page, '#node-dialog-cancel');
        await opened('read-classic');
        expect(await cutOff(page, [...parts, '#node-input-interval', '#node-input-output']), `${locale} s7://`).to.deep.equal([]);
        await closed(page, '#node-dialog-cancel');
        expect(errors.map((e) => e.message)).to.deep.equal([]);
      } finally {
        await context.close();
      }
    }
  });

  it('the sparkplug device dialog: its two alarm boxes whole in each language, "hosts may acknowledge" only with "publish the PLC\'s alarms", both saved; the edge node\'s buffer directory with its placeholder', async () => {
    const catalog = (locale: string, file: string) =>
      JSON.parse(fs.readFileSync(path.join(ROOT, `nodes/locales/${locale}/${file}.json`), 'utf8'))[`plcwire-${file}`];
    for (const [locale, dir] of [
      ['en-US', 'en-US'],
      ['de-DE', 'de'],
      ['zh-CN', 'zh-CN'],
    ] as const) {
      const { context, page, errors } = await openEditor(browser, red, locale, 'spb-device');
      try {
        await page.setViewportSize({ width: 1024, height: 700 });
        const opened = async () => {
          await page.evaluate(() => (globalThis as any).RED.editor.edit((globalThis as any).RED.nodes.node('spb-device')));
          await page.waitForSelector('#node-input-alarms', { state: 'visible', timeout: 10_000 });
          await trayInPlace(page);
        };
        const saved = () =>
          page.evaluate(() => {
            const n = (globalThis as any).RED.nodes.node('spb-device');
            return { alarms: n.alarms, acknowledge: n.acknowledge, valid: n.valid };
          });
        await opened();
        const labels = catalog(dir, 'sparkplug-device').label;
        expect(await page.textContent('label[for="node-input-alarms"][data-i18n$="publishAlarms"]'), locale).to.equal(labels.publishAlarms);
        expect(await page.textContent('label[for="node-input-acknowledge"]'), locale).to.equal(labels.acknowledge);
        expect([await page.isChecked('#node-input-alarms'), await page.isDisabled('#node-input-acknowledge')]).to.deep.equal([false, true]);
        await page.check('#node-input-alarms');
        expect(await page.isDisabled('#node-input-acknowledge')).to.equal(false);
        await page.check('#node-input-acknowledge');
        await shot(page, `sparkplug-device-${locale}`);
        expect(
          await cutOff(page, [
            '#node-input-alarms',
            '#node-input-acknowledge',
            'label[for="node-input-alarms"]',
            'label[for="node-input-acknowledge"]',
          ]),
          locale,
        ).to.deep.equal([]);
        await closed(page, '#node-dialog-ok');
        expect(await saved()).to.deep.equal({ alarms: true, acknowledge: true, valid: true });
        // Unpublished alarms cannot be acknowledged: the second box clears and locks with the first.
        await opened();
        await page.uncheck('#node-input-alarms');
        expect([await page.isChecked('#node-input-acknowledge'), await page.isDisabled('#node-input-acknowledge')]).to.deep.equal([
          false,
          true,
        ]);
        await closed(page, '#node-dialog-ok');
        expect(await saved()).to.deep.equal({ alarms: false, acknowledge: false, valid: true });

        await page.evaluate(() => (globalThis as any).RED.editor.editConfig('', 'plcwire-sparkplug-edge', 'spb-edge'));
        await page.waitForSelector('#node-config-input-bufferDir', { state: 'visible', timeout: 10_000 });
        await trayInPlace(page);
        const edge = catalog(dir, 'sparkplug-edge');
        expect(await page.textContent('label[for="node-config-input-bufferDir"]'), locale).to.contain(edge.label.bufferDir);
        expect(await page.getAttribute('#node-config-input-bufferDir', 'placeholder'), locale).to.equal(edge.placeholder.bufferDir);
        expect(await cutOff(page, ['#node-config-input-bufferDir', 'label[for="node-config-input-bufferDir"]']), locale).to.deep.equal([]);
        // The default poll interval (1000 ms) is a valid value of its field (with step 100 from min 10 the browser marked it red).
        expect(await page.inputValue('#node-config-input-interval'), locale).to.equal('1000');
        expect(
          await page.$eval('#node-config-input-interval', (el) => el.matches(':invalid')),
          `${locale}: 1000 ms shown as invalid`,
        ).to.equal(false);
        // The Name row says so (its key was another catalog's, and the label showed only its icon).
        expect((await page.textContent('label[for="node-config-input-name"]'))?.trim(), locale).to.equal(edge.label.name);
        // TLS: Node-RED's tls-config node, chosen (or added) from a select the editor draws for the config node type.
        expect(await page.textContent('label[for="node-config-input-tls"]'), locale).to.contain(edge.label.tls);
        expect(await page.isVisible('#node-config-input-tls'), `${locale}: the tls-config select`).to.equal(true);
        expect(await cutOff(page, ['#node-config-input-tls', 'label[for="node-config-input-tls"]']), locale).to.deep.equal([]);
        await page.click('#node-config-dialog-cancel');
        expect(errors.map((e) => e.message)).to.deep.equal([]);
      } finally {
        await context.close();
      }
    }
  });

  it('switching a read node without a sample time to "when the PLC reports a change" shows 100 ms and leaves it valid; the example flow imports valid', async () => {
    const { context, page, errors } = await openEditor(browser, red, 'en-US', 'read-classic');
    try {
      await page.setViewportSize({ width: 1024, height: 700 });
      const example = JSON.parse(fs.readFileSync(path.join(ROOT, 'examples/S7CommPlus optimized DB by name.json'), 'utf8')) as any[];
      const reads = example.filter((n) => n.type === 'plcwire-read');
      expect(reads.length).to.be.at.least(1);
      const ids: string[] = await page.evaluate((nodes) => {
        const RED = (globalThis as any).RED;
        const { nodeMap } = RED.view.importNodes(nodes, { generateIds: true, addFlow: true });
        return Object.values(nodeMap as Record<string, any>)
          .filter((n: any) => n.type === 'plcwire-read')
          .map((n: any) => n.id)
          .filter((id: string, i: number, all: string[]) => all.indexOf(id) === i);
      }, example);
      expect(ids.length).to.equal(reads.length);
      for (const id of ids) {
        await page.evaluate((n) => (globalThis as any).RED.editor.edit((globalThis as any).RED.nodes.node(n)), id);
        await page.waitForSelector('#node-input-mode', { state: 'visible', timeout: 10_000 });
        await page.selectOption('#node-input-mode', 'push');
        expect(await page.isVisible('#node-input-cycle')).to.equal(true);
        expect(await page.inputValue('#node-input-cycle'), 'the sample time shown').to.equal('100');
        expect(await page.getAttribute('#node-input-cycle', 'placeholder')).to.equal('100');
        await closed(page, '#node-dialog-ok');
        const node = await page.evaluate((n) => {
          const x = (globalThis as any).RED.nodes.node(n);
          return { mode: x.mode, cycle: Number(x.cycle), valid: x.valid };
        }, id);
        expect(node).to.deep.equal({ mode: 'push', cycle: 100, valid: true });
      }
      // A push node whose sample time is missing from the flow is valid too: the runtime samples every 100 ms.
      const valid = await page.evaluate(() => {
        const RED = (globalThis as any).RED;
        const { nodeMap } = RED.view.importNodes(
          [
            {
              id: 'bare',
              type: 'plcwire-read',
              x: 100,
              y: 400,
              connection: 'plus',
              mode: 'push',
              interval: 1000,
              output: 'object',
              deadband: 0,
              tags: [{ name: 'step', address: '"Recipe".Step' }],
            },
          ],
          { generateIds: true },
        );
        const n: any = Object.values(nodeMap as Record<string, any>).find((x: any) => x.type === 'plcwire-read');
        RED.editor.validateNode(n);
        return { valid: n.valid, errors: n.validationErrors ?? [] };
      });
      expect(valid).to.deep.equal({ valid: true, errors: [] });
      expect(errors.map((e) => e.message)).to.deep.equal([]);
    } finally {
      await context.close();
    }
  });
});
