/**
 * The edit dialogs and deploy-time validation in a real browser: a real
 * Node-RED (a child process with this package linked into its user
 * directory, the way `npm install <folder>` does), a real S7 simulator, and
 * headless Chromium driven by playwright-core (test/support/browser.ts).
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import type { Browser, BrowserContext, Page } from 'playwright-core';
import { launchChromium } from './support/browser';
import { openEditor as openEditorOf, startNodeRedProcess, type NodeRedProcess } from './support/node-red-process';

const ROOT = path.resolve(__dirname, '../..');
const LOCALES = { 'en-US': 'en-US', de: 'de-DE', 'zh-CN': 'zh-CN' } as const;
type Locale = keyof typeof LOCALES;

const lib = require(path.join(ROOT, 'dist/lib/index.js'));

/** The flow the editor opens: nodes with and without configuration errors. */
function testFlow(s7Port: number, doctorPort: number): object[] {
  const at = (y: number) => ({ z: 'tab', x: 200, y, wires: [[]] });
  const good = `s7://127.0.0.1:${s7Port}?rack=0&slot=1&timeout=1000`;
  return [
    { id: 'tab', type: 'tab', label: 'editor test' },
    { id: 'conn-ok', type: 'plcwire-connection', name: 'plc', url: good },
    { id: 'conn-bad', type: 'plcwire-connection', name: 'typo', url: 's7://127.0.0.1?rack=0&slott=1' },
    // No node uses it: the runtime opens no link to its PLC, only Test connection does.
    { id: 'conn-doctor', type: 'plcwire-connection', name: 'doctor', url: `s7://127.0.0.1:${doctorPort}?rack=0&slot=1&timeout=1000` },
    {
      id: 'read-ok',
      type: 'plcwire-read',
      name: 'ok',
      ...at(40),
      connection: 'conn-ok',
      interval: 0,
      output: 'object',
      deadband: 0,
      tags: [{ name: 'speed', address: 'DB1.DBW0:INT' }],
    },
    {
      id: 'read-csv',
      type: 'plcwire-read',
      name: 'csv',
      ...at(100),
      connection: 'conn-ok',
      interval: 0,
      output: 'object',
      deadband: 0,
      tags: [{ name: 'speed', address: 'DB1.DBW0:INT' }],
    },
    {
      id: 'read-empty',
      type: 'plcwire-read',
      name: 'empty',
      ...at(160),
      connection: 'conn-ok',
      interval: 0,
      output: 'object',
      deadband: 0,
      tags: [],
    },
    {
      id: 'read-badurl',
      type: 'plcwire-read',
      name: 'bad url',
      ...at(220),
      connection: 'conn-bad',
      interval: 0,
      output: 'object',
      deadband: 0,
      tags: [{ name: 'a', address: 'DB1.DBW0:INT' }],
    },
    {
      id: 'read-badtag',
      type: 'plcwire-read',
      name: 'bad tag',
      ...at(280),
      connection: 'conn-ok',
      interval: 0,
      output: 'object',
      deadband: 0,
      tags: [{ name: 'x', address: 'XYZ%' }],
    },
    {
      id: 'read-dup',
      type: 'plcwire-read',
      name: 'dup',
      ...at(340),
      connection: 'conn-ok',
      interval: 0,
      output: 'object',
      deadband: 0,
      tags: [
        { name: 's', address: 'MW2' },
        { name: 's', address: 'MW4' },
      ],
    },
    {
      id: 'write-badtag',
      type: 'plcwire-write',
      name: 'bad write',
      ...at(400),
      connection: 'conn-ok',
      tags: [{ name: 'w', address: 'DB1.DBX0' }],
    },
    {
      id: 'hb-bad',
      type: 'plcwire-heartbeat',
      name: 'bad hb',
      ...at(460),
      connection: 'conn-ok',
      writeAddress: 'DB1.DBW2:REAL',
      writeMode: 'counter',
      interval: 1000,
      watchAddress: '',
      timeout: 3000,
    },
    {
      id: 'hb-ok',
      type: 'plcwire-heartbeat',
      name: 'hb',
      ...at(520),
      connection: 'conn-ok',
      writeAddress: 'DB1.DBW2:INT',
      writeMode: 'counter',
      interval: 1000,
      watchAddress: '',
      timeout: 3000,
    },
    { id: 'ctl-stop', type: 'plcwire-control', name: 'stop', ...at(580), connection: 'conn-ok', action: 'stop', newOnly: false },
    { id: 'conn-fw', type: 'plcwire-connection', name: 'fw', url: 'fetchwrite://127.0.0.1?port=1' },
    { id: 'ctl-fw', type: 'plcwire-control', name: 'not s7', ...at(640), connection: 'conn-fw', action: 'state', newOnly: false },
  ];
}

/** Node-RED 4 in a child process on a free port, with `flow` deployed; resolves once the flows have started. */
function startNodeRed(flow: object[]): Promise<NodeRedProcess> {
  return startNodeRedProcess(flow);
}

/** Polls a condition of this process (a simulator's connection count) until it holds, within 3 s. */
async function waitFor(condition: () => boolean, what: string): Promise<void> {
  const deadline = Date.now() + 3000;
  while (!condition()) {
    if (Date.now() > deadline) throw new Error(`${what}: did not hold within 3 s`);
    await new Promise((r) => setTimeout(r, 20));
  }
}

/** What a user should read for a catalog text of ours: its placeholders (in either syntax) filled in. */
function catalogText(locale: Locale, key: string, params: Record<string, unknown> = {}): string {
  const catalog = JSON.parse(fs.readFileSync(path.join(ROOT, 'nodes/locales', locale, 'read.json'), 'utf8'));
  const template = String(key.split('.').reduce((o: any, k) => o?.[k], catalog));
  return template.replace(/__(\w+)__|\{\{(\w+)\}\}/g, (_m, a?: string, b?: string) => String(params[(a ?? b)!]));
}

describe('editor: the plcwire dialogs in headless Chromium', function () {
  this.timeout(120_000);
  let s7: any;
  let doctorSim: any;
  let red: NodeRedProcess;
  let browser: Browser;

  before(async () => {
    s7 = new lib.S7Server({ port: 0, memory: new lib.PlcMemory(), profile: 's7-1500' });
    const port: number = await s7.listen();
    doctorSim = new lib.S7Server({ port: 0, memory: new lib.PlcMemory(), profile: 's7-1200' });
    const doctorPort: number = await doctorSim.listen();
    red = await startNodeRed(testFlow(port, doctorPort));
    browser = await launchChromium();
  });

  after(async () => {
    await browser?.close();
    await red?.stop();
    await s7?.close();
    await doctorSim?.close();
  });

  /** The editor in `locale`, with every page error collected. */
  function openEditor(locale: Locale = 'en-US'): Promise<{ context: BrowserContext; page: Page; errors: Error[] }> {
    return openEditorOf(browser, red, LOCALES[locale], 'read-ok');
  }

  /** Opens the edit dialog of node `id` and waits for its tag table. */
  async function editTags(page: Page, id: string): Promise<void> {
    await page.evaluate((nodeId) => (globalThis as any).RED.editor.edit((globalThis as any).RED.nodes.node(nodeId)), id);
    await page.waitForSelector('#node-input-plcwire-tags .red-ui-editableList-item-content, .red-ui-editableList-addButton', {
      timeout: 10_000,
    });
    await page.waitForSelector('#node-dialog-ok', { state: 'visible' });
  }

  /** Closes the open dialog with Done or Cancel and waits until its tray is gone. */
  async function closeDialog(page: Page, button: 'ok' | 'cancel'): Promise<void> {
    await page.click(`#node-dialog-${button}`);
    await page.waitForSelector('#node-input-plcwire-tags', { state: 'detached', timeout: 10_000 });
  }

  /** Resolves once the page's timers of up to 300 ms set before now have fired (timers of shorter delay set earlier run first). */
  const after300ms = (page: Page) => page.evaluate(() => new Promise((r) => setTimeout(r, 400)));

  const tagsOf = (page: Page, id: string) => page.evaluate((nodeId) => (globalThis as any).RED.nodes.node(nodeId).tags, id);

  describe("deploy-time validation with the library's parser", () => {
    const INVALID = ['conn-bad', 'read-badurl', 'read-badtag', 'read-dup', 'write-badtag', 'hb-bad', 'ctl-fw'];

    it('gives nodes with a config error the red triangle, and says why', async () => {
      const { context, page, errors } = await openEditor();
      try {
        await page.waitForFunction((ids) => ids.every((id: string) => (globalThis as any).RED.nodes.node(id).valid === false), INVALID, {
          timeout: 10_000,
        });
        const state = await page.evaluate(
          (ids) =>
            Object.fromEntries(
              ids.map((id: string) => {
                const n = (globalThis as any).RED.nodes.node(id);
                const badge = (globalThis as any).document.querySelector(`[id="${id}"] .red-ui-flow-node-error`);
                return [
                  id,
                  {
                    valid: n.valid,
                    errors: (n.validationErrors || []).join(' | '),
                    triangle: badge ? !badge.classList.contains('hide') : null,
                  },
                ];
              }),
            ),
          [...INVALID, 'conn-ok', 'read-ok', 'read-csv', 'hb-ok', 'ctl-stop'],
        );
        expect(state['conn-bad'].errors).to.include('unknown parameter "slott"');
        expect(state['read-badtag'].errors).to.include('XYZ%');
        expect(state['read-dup'].errors).to.include('"s"');
        expect(state['write-badtag'].errors).to.include('DB1.DBX0');
        expect(state['hb-bad'].errors).to.include('REAL');
        expect(state['ctl-fw'].errors).to.include('"fw" is not S7comm');
        for (const id of ['read-badurl', 'read-badtag', 'read-dup', 'write-badtag', 'hb-bad', 'ctl-fw'])
          expect(state[id].triangle, `${id} has the red triangle`).to.equal(true);
        for (const id of ['conn-ok', 'read-ok', 'read-csv', 'hb-ok', 'ctl-stop'])
          expect(state[id].valid, `${id}: ${state[id].errors}`).to.equal(true);
        for (const id of ['read-ok', 'read-csv', 'hb-ok']) expect(state[id].triangle, `${id} has no red triangle`).to.equal(false);

        // Deploy asks first, listing them (nothing is deployed: the test cancels).
        await page.evaluate(() => (globalThis as any).RED.nodes.dirty(true));
        await page.click('#red-ui-header-button-deploy');
        const confirm = page.locator('.red-ui-notification', { has: page.locator('#red-ui-deploy-dialog-confirm-deploy-deploy') });
        await confirm.waitFor({ state: 'visible', timeout: 10_000 });
        const listed = await confirm.locator('.red-ui-deploy-dialog-confirm-list li').allInnerTexts();
        // Node-RED lists five and counts the rest ("+ 1 more").
        const more = Number(/^\+ (\d+)/.exec(listed[listed.length - 1] ?? '')?.[1] ?? 0);
        expect(listed.length - (more > 0 ? 1 : 0) + more).to.equal(INVALID.length);
        expect(listed[0]).to.equal('typo (plcwire-connection)');
        expect(listed.filter((l) => l.includes('(plcwire-')).length).to.equal(Math.min(5, INVALID.length));
        await confirm.getByRole('button', { name: 'Cancel' }).click();
        expect(errors).to.deep.equal([]);
      } finally {
        await context.close();
      }
    });
  });

  describe('the tag table dialog', () => {
    for (const button of ['ok', 'cancel'] as const) {
      it(`a row typed and the dialog closed at once (${button === 'ok' ? 'Done' : 'Cancel'}) raises no error later`, async () => {
        const { context, page, errors } = await openEditor();
        try {
          await editTags(page, 'read-ok');
          await page.click('.red-ui-editableList-addButton');
          const address = page.locator('#node-input-plcwire-tags .plcwire-tag-address').last();
          await address.pressSequentially('DB1.DBW4:INT');
          await closeDialog(page, button);
          await after300ms(page);
          expect(errors.map((e) => e.message)).to.deep.equal([]);
          const tags = await tagsOf(page, 'read-ok');
          expect(tags.map((t: any) => t.address)).to.deep.equal(button === 'ok' ? ['DB1.DBW0:INT', 'DB1.DBW4:INT'] : ['DB1.DBW0:INT']);
        } finally {
          await context.close();
        }
      });
    }

    it('the connection dialog keeps a field typed just before Done (the URL is built from the fields at once)', async () => {
      const { context, page, errors } = await openEditor();
      try {
        await page.evaluate(() => (globalThis as any).RED.editor.editConfig('', 'plcwire-connection', 'conn-ok'));
        const slot = page.locator('#node-config-plcwire-slot');
        await slot.waitFor({ state: 'visible' });
        await page.waitForFunction(() => (globalThis as any).document.querySelector('#node-config-plcwire-slot').value === '1');
        await slot.fill('2');
        await page.click('#node-config-dialog-ok');
        await page.waitForSelector('#node-config-plcwire-slot', { state: 'detached', timeout: 10_000 });
        await after300ms(page);
        const url = await page.evaluate(() => (globalThis as any).RED.nodes.node('conn-ok').url);
        expect(url).to.match(/[?&]slot=2(&|$)/);
        expect(errors).to.deep.equal([]);
      } finally {
        await context.close();
      }
    });

    async function importCsv(page: Page, csv: string): Promise<void> {
      await page.setInputFiles('.plcwire-tags-toolbar input[type=file]', {
        name: 'tags.csv',
        mimeType: 'text/csv',
        buffer: Buffer.from(csv),
      });
    }

    const rows = (page: Page) =>
      page.$$eval('#node-input-plcwire-tags .plcwire-tag-row', (list) =>
        list.map((r) => ({
          name: (r.querySelector('.plcwire-tag-name') as any).value,
          address: (r.querySelector('.plcwire-tag-address') as any).value,
          duplicate: r.querySelector('.plcwire-tag-name')!.classList.contains('plcwire-invalid'),
          type: r.querySelector('.plcwire-tag-type')!.textContent,
        })),
      );

    it('exports the rows of the dialog as CSV written by the runtime: a visible button, a download the import reads back', async () => {
      const { context, page, errors } = await openEditor();
      try {
        await editTags(page, 'read-ok');
        const shown = (await rows(page)).map(({ name, address }) => ({ name, address }));
        expect(shown.length).to.be.greaterThan(0);
        const button = page.locator('.plcwire-tags-toolbar button:has(i.fa-download)');
        await button.waitFor({ state: 'visible' });
        const [download] = await Promise.all([page.waitForEvent('download'), button.click()]);
        expect(download.suggestedFilename()).to.equal('plcwire-tags.csv');
        const csv = fs.readFileSync(await download.path(), 'utf8');
        expect(csv).to.equal(lib.tagsToCsv(shown));
        expect(lib.tagsFromCsv(csv).tags).to.deep.equal(shown);
        await closeDialog(page, 'cancel');
        expect(errors).to.deep.equal([]);
      } finally {
        await context.close();
      }
    });

    it('imports CSV with a type column, appending or replacing as chosen, and flags names used twice', async () => {
      const { context, page, errors } = await openEditor();
      try {
        await editTags(page, 'read-csv');
        await importCsv(page, 'name,address,type\nspeed,DB1.DBW6,INT\nlevel,DB1.DBD8,REAL\n');
        await page.waitForSelector('#plcwire-import-append');
        await page.click('#plcwire-import-append');
        await page.waitForFunction(
          () => (globalThis as any).document.querySelectorAll('#node-input-plcwire-tags .plcwire-tag-row').length === 3,
        );
        await page.waitForFunction(() =>
          [...(globalThis as any).document.querySelectorAll('#node-input-plcwire-tags .plcwire-tag-type')].every(
            (e) => e.textContent !== '',
          ),
        );
        // The names used twice come from the runtime (POST plcwire/duplicates): the mark follows its answer.
        await page.waitForFunction(
          () => (globalThis as any).document.querySelectorAll('#node-input-plcwire-tags .plcwire-tag-name.plcwire-invalid').length === 2,
        );
        expect(await rows(page)).to.deep.equal([
          { name: 'speed', address: 'DB1.DBW0:INT', duplicate: true, type: 'INT' },
          { name: 'speed', address: 'DB1.DBW6:INT', duplicate: true, type: 'INT' },
          { name: 'level', address: 'DB1.DBD8:REAL', duplicate: false, type: 'REAL' },
        ]);
        await closeDialog(page, 'ok');
        await page.waitForFunction(() => (globalThis as any).RED.nodes.node('read-csv').valid === false);

        await editTags(page, 'read-csv');
        await importCsv(page, 'speed;DB1.DBW6;INT\nlevel;DB1.DBD8;REAL\n');
        await page.click('#plcwire-import-replace');
        await page.waitForFunction(
          () => (globalThis as any).document.querySelectorAll('#node-input-plcwire-tags .plcwire-tag-row').length === 2,
        );
        expect((await rows(page)).map((r) => [r.name, r.address, r.duplicate])).to.deep.equal([
          ['speed', 'DB1.DBW6:INT', false],
          ['level', 'DB1.DBD8:REAL', false],
        ]);
        await closeDialog(page, 'ok');
        await page.waitForFunction(() => (globalThis as any).RED.nodes.node('read-csv').valid === true);
        expect(await tagsOf(page, 'read-csv')).to.deep.equal([
          { name: 'speed', address: 'DB1.DBW6:INT' },
          { name: 'level', address: 'DB1.DBD8:REAL' },
        ]);
        expect(errors).to.deep.equal([]);
      } finally {
        await context.close();
      }
    });

    for (const locale of Object.keys(LOCALES) as Locale[]) {
      it(`${locale}: the import message shows the number of tags and names a row whose type does not fit; status texts come rendered by the runtime`, async () => {
        const { context, page, errors } = await openEditor(locale);
        try {
          // Node statuses are rendered by the runtime (en-US here), so Status nodes and dashboards get the same words as the canvas.
          const connected = catalogText('en-US', 'plcwire.status.connected');
          await page.waitForFunction(
            (text) => (globalThis as any).document.querySelector('[id="read-ok"] .red-ui-flow-node-status-label')?.textContent === text,
            connected,
            { timeout: 10_000 },
          );
          await editTags(page, 'read-empty');
          await importCsv(page, 'a,MW2\nb,MW4\nc,MW6:INT,WORD\n');
          const message = catalogText(locale, 'plcwire.editor.imported', { count: 3 });
          await page.waitForFunction(
            (text) =>
              [...(globalThis as any).document.querySelectorAll('.red-ui-notification')].some((n) => n.textContent?.trim() === text),
            message,
            { timeout: 10_000 },
          );
          // The row whose type column contradicts its address is named, with its line.
          const problem = catalogText(locale, 'plcwire.editor.line', { line: 3, message: '"MW6:INT" is INT, the type column says WORD' });
          await page.waitForFunction(
            (text) => [...(globalThis as any).document.querySelectorAll('.red-ui-notification li')].some((n) => n.textContent === text),
            problem,
            { timeout: 10_000 },
          );
          await closeDialog(page, 'cancel');
          expect(errors).to.deep.equal([]);
        } finally {
          await context.close();
        }
      });
    }
  });

  describe('the connection dialog and the control node', () => {
    /** Opens the dialog of connection `id` and waits until the runtime's parser has filled its fields from the URL. */
    async function editConnection(page: Page, id: string): Promise<void> {
      await page.evaluate((nodeId) => (globalThis as any).RED.editor.editConfig('', 'plcwire-connection', nodeId), id);
      await page.locator('#node-config-plcwire-slot').waitFor({ state: 'visible' });
      await page.waitForFunction(() => (globalThis as any).document.querySelector('#node-config-plcwire-slot').value !== '');
    }

    async function doneConnection(page: Page): Promise<string> {
      await page.click('#node-config-dialog-ok');
      await page.waitForSelector('#node-config-plcwire-slot', { state: 'detached', timeout: 10_000 });
      return page.evaluate(() => (globalThis as any).RED.nodes.node('conn-ok').url);
    }

    it('"Allow PLC control" writes control=true into the URL, and the dialog reads it back', async () => {
      const { context, page, errors } = await openEditor();
      try {
        await editConnection(page, 'conn-ok');
        expect(await page.isChecked('#node-config-plcwire-control')).to.equal(false);
        await page.check('#node-config-plcwire-control');
        const url = await doneConnection(page);
        expect(url).to.match(/[?&]control=true(&|$)/);
        expect(lib.parseUrl(url).control).to.equal(true);
        await editConnection(page, 'conn-ok');
        expect(await page.isChecked('#node-config-plcwire-control')).to.equal(true);
        await page.uncheck('#node-config-plcwire-control');
        expect(await doneConnection(page)).not.to.include('control');
        expect(errors).to.deep.equal([]);
      } finally {
        await context.close();
      }
    });

    it('a CPU preset sets rack/slot or TSAPs and items per job as the library has them', async () => {
      const { context, page, errors } = await openEditor();
      try {
        await editConnection(page, 'conn-ok');
        await page.selectOption('#node-config-input-cpu', 's7-1200');
        await page.waitForFunction(
          () => (globalThis as any).document.querySelector('#node-config-plcwire-maxItems').value === '255',
          undefined,
          { timeout: 10_000 },
        );
        await page.selectOption('#node-config-input-cpu', 's7-200');
        await page.waitForFunction(
          () => (globalThis as any).document.querySelector('#node-config-plcwire-localTsap').value === '1000',
          undefined,
          { timeout: 10_000 },
        );
        expect(await page.inputValue('#node-config-plcwire-remoteTsap')).to.equal('1001');
        expect(await page.inputValue('#node-config-plcwire-maxItems')).to.equal('');
        await page.selectOption('#node-config-input-cpu', 's7-1500');
        await page.waitForFunction(
          () => (globalThis as any).document.querySelector('#node-config-plcwire-maxItems').value === '255',
          undefined,
          { timeout: 10_000 },
        );
        expect(await page.inputValue('#node-config-plcwire-addressing')).to.equal('rack');
        const url = await doneConnection(page);
        expect(lib.parseUrl(url)).to.include({ rack: 0, slot: 1, maxItems: 255 });
        expect(errors).to.deep.equal([]);
      } finally {
        await context.close();
      }
    });

    it("Test connection lists the doctor's steps: all passing, then the failing one with its fix on a wrong slot; no connection stays open", async () => {
      const { context, page, errors } = await openEditor();
      try {
        const catalog = JSON.parse(fs.readFileSync(path.join(ROOT, 'nodes/locales/en-US/connection.json'), 'utf8'))['plcwire-connection']
          .editor;
        const summary = () => page.textContent('#node-config-plcwire-test-summary');
        const steps = () =>
          page.$$eval('#node-config-plcwire-test-steps li', (list) =>
            list.map((li) => ({
              step: li.getAttribute('data-step'),
              ok: li.classList.contains('plcwire-step-ok'),
              text: li.textContent ?? '',
            })),
          );
        await page.evaluate(() => (globalThis as any).RED.editor.editConfig('', 'plcwire-connection', 'conn-doctor'));
        await page.locator('#node-config-plcwire-slot').waitFor({ state: 'visible' });
        await page.waitForFunction(() => (globalThis as any).document.querySelector('#node-config-plcwire-slot').value === '1');
        await page.click('#node-config-plcwire-test');
        await page.waitForFunction(
          (texts) => texts.includes((globalThis as any).document.querySelector('#node-config-plcwire-test-summary').textContent),
          [catalog.testOk, catalog.testFailed],
          { timeout: 20_000 },
        );
        expect(await summary()).to.equal(catalog.testOk);
        const passed = await steps();
        expect(passed.map((s) => s.step)).to.include.members(['tcp', 'cotp']);
        expect(
          passed.every((s) => s.ok),
          JSON.stringify(passed),
        ).to.equal(true);
        await waitFor(() => doctorSim.connectionCount === 0, 'no connection after the passing test');

        // A field typed just before the click counts: the URL is built from the fields at once.
        await page.fill('#node-config-plcwire-slot', '5');
        await page.click('#node-config-plcwire-test');
        await page.waitForFunction(
          (text) => (globalThis as any).document.querySelector('#node-config-plcwire-test-summary').textContent === text,
          catalog.testFailed,
          { timeout: 20_000 },
        );
        const failed = await steps();
        const last = failed[failed.length - 1]!;
        expect(last.ok, JSON.stringify(failed)).to.equal(false);
        expect(last.text).to.match(/slot/);
        expect(await page.textContent('#node-config-plcwire-test-steps li:last-child .plcwire-step-hint')).to.match(/slot=1|slot 1/);
        await waitFor(() => doctorSim.connectionCount === 0, 'no connection after the failing test');
        await page.click('#node-config-dialog-cancel');
        await page.waitForSelector('#node-config-plcwire-slot', { state: 'detached', timeout: 10_000 });
        expect(errors).to.deep.equal([]);
      } finally {
        await context.close();
      }
    });

    /** The control node's warning as shown, or '' when it is hidden. */
    const warning = (page: Page) =>
      page.evaluate(() => {
        const w = (globalThis as any).document.querySelector('#node-input-plcwire-control-warning');
        return w && w.style.display !== 'none' ? String(w.textContent) : '';
      });

    for (const locale of Object.keys(LOCALES) as Locale[]) {
      it(`${locale}: the control dialog warns while stop, start or clock-sync would be refused by the connection`, async () => {
        const { context, page, errors } = await openEditor(locale);
        try {
          const catalog = JSON.parse(fs.readFileSync(path.join(ROOT, 'nodes/locales', locale, 'control.json'), 'utf8'));
          const noControl = String(catalog['plcwire-control'].warning.noControl).replace('__name__', 'plc');
          await page.evaluate(() => (globalThis as any).RED.editor.edit((globalThis as any).RED.nodes.node('ctl-stop')));
          await page.waitForSelector('#node-input-action', { state: 'visible' });
          await page.waitForFunction(
            (text) => (globalThis as any).document.querySelector('#node-input-plcwire-control-warning')?.textContent === text,
            noControl,
            { timeout: 10_000 },
          );
          expect(await warning(page)).to.equal(noControl);
          await page.selectOption('#node-input-action', 'state');
          await page.waitForFunction(
            () => (globalThis as any).document.querySelector('#node-input-plcwire-control-warning').style.display === 'none',
          );
          await page.selectOption('#node-input-action', 'clock-sync');
          await page.waitForFunction(
            () => (globalThis as any).document.querySelector('#node-input-plcwire-control-warning')?.style.display !== 'none',
          );
          expect(await warning(page)).to.equal(noControl);
          await page.click('#node-dialog-cancel');
          await page.waitForSelector('#node-input-action', { state: 'detached', timeout: 10_000 });

          // With control allowed on the connection, no warning.
          await page.evaluate(() => {
            const c = (globalThis as any).RED.nodes.node('conn-ok');
            c.url += '&control=true';
          });
          await page.evaluate(() => (globalThis as any).RED.editor.edit((globalThis as any).RED.nodes.node('ctl-stop')));
          await page.waitForSelector('#node-input-action', { state: 'visible' });
          await after300ms(page);
          expect(await warning(page)).to.equal('');
          await page.click('#node-dialog-cancel');
          await page.waitForSelector('#node-input-action', { state: 'detached', timeout: 10_000 });
          expect(errors).to.deep.equal([]);
        } finally {
          await context.close();
        }
      });
    }
  });
});
