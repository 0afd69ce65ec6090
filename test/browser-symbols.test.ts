/**
 * Tags by name in the editor, in a real browser: a real Node-RED (a child
 * process with this package linked into its user directory, admin
 * authentication on), the in-process S7 simulator, and headless Chromium
 * (test/support/browser.ts). Sources uploaded and pasted in the connection
 * dialog, its block list with lengths and its errors with file and line; a
 * read node's tag table completing a name, showing its address and type,
 * adding all members of a struct; an unknown name's red triangle; and the
 * admin endpoint's permission.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as http from 'node:http';
import * as path from 'node:path';
import type { Browser, BrowserContext, Page } from 'playwright-core';
import { launchChromium } from './support/browser';
import { openEditor as openEditorOf, startNodeRedProcess, type NodeRedProcess } from './support/node-red-process';

const ROOT = path.resolve(__dirname, '../..');
const lib = require(path.join(ROOT, 'dist/lib/index.js'));

const MOTOR_UDT = `TYPE "Motor"
VERSION : 0.1
   STRUCT
      Speed : Real;
      Run : Bool;
   END_STRUCT;

END_TYPE
`;
const TANK_DB = `DATA_BLOCK "Tank"
{ S7_Optimized_Access := 'FALSE' }
VERSION : 0.1
NON_RETAIN
   STRUCT
      Level : Real;
      Count : Int;
      Motor : "Motor";
   END_STRUCT;


BEGIN

END_DATA_BLOCK
`;
const SOURCES = [
  { name: 'Motor.udt', content: MOTOR_UDT },
  { name: 'Tank.db', content: TANK_DB },
];

/** A user who may read the flows but holds no plcwire permission. */
const VIEWER = { username: 'viewer', password: 'viewer-pass', permissions: 'flows.read' };

function testFlow(url: string): object[] {
  const read = (id: string, y: number, connection: string, tags: object[]) => ({
    id,
    type: 'plcwire-read',
    name: id,
    z: 'tab',
    x: 200,
    y,
    wires: [[]],
    connection,
    interval: 0,
    output: 'object',
    deadband: 0,
    tags,
  });
  return [
    { id: 'tab', type: 'tab', label: 'symbols' },
    { id: 'conn-sym', type: 'plcwire-connection', name: 'tank', url, symbolSources: SOURCES, dbNumbers: [{ block: 'Tank', db: 1 }] },
    { id: 'conn-new', type: 'plcwire-connection', name: 'new', url, symbolSources: [], dbNumbers: [] },
    read('read-sym', 40, 'conn-sym', [{ name: 'level', address: 'Tank.Level' }]),
    read('read-badsym', 100, 'conn-sym', [{ name: 'x', address: 'Tank.Levl' }]),
    read('read-abs', 160, 'conn-sym', [{ name: 'raw', address: 'DB1.DBW4:INT' }]),
  ];
}

/** Node-RED in a child process, with admin authentication (anonymous: every permission; VIEWER: flows.read only). */
function startNodeRed(flow: object[]): Promise<NodeRedProcess> {
  const bcrypt = require(require.resolve('bcryptjs', { paths: [path.dirname(require.resolve('@node-red/editor-api/package.json'))] }));
  const adminAuth = {
    type: 'credentials',
    users: [{ username: VIEWER.username, password: bcrypt.hashSync(VIEWER.password, 8), permissions: VIEWER.permissions }],
    default: { permissions: '*' },
  };
  return startNodeRedProcess(flow, { adminAuth });
}

/** A JSON request to the runtime: status code and parsed body. */
function request(url: string, body: unknown, headers: Record<string, string> = {}): Promise<{ status: number; body: any }> {
  return new Promise((resolve, reject) => {
    const data = JSON.stringify(body);
    const req = http.request(url, { method: 'POST', headers: { 'content-type': 'application/json', ...headers } }, (res) => {
      let text = '';
      res.on('data', (d: Buffer) => (text += d.toString()));
      res.on('end', () => {
        let parsed: unknown = text;
        try {
          parsed = JSON.parse(text);
        } catch {
          // not JSON (a 401 page): kept as text
        }
        resolve({ status: res.statusCode ?? 0, body: parsed });
      });
    });
    req.on('error', reject);
    req.end(data);
  });
}

/** An en-US catalog text of the connection node, its placeholders filled in. */
function connectionText(key: string, params: Record<string, unknown>): string {
  const catalog = JSON.parse(fs.readFileSync(path.join(ROOT, 'nodes/locales/en-US/connection.json'), 'utf8'));
  const template = String(key.split('.').reduce((o: any, k) => o?.[k], catalog));
  return template.replace(/__(\w+)__/g, (_m, name: string) => String(params[name]));
}

describe('editor: tags by name in headless Chromium', function () {
  this.timeout(120_000);
  let s7: any;
  let red: NodeRedProcess;
  let browser: Browser;

  before(async () => {
    s7 = new lib.S7Server({ port: 0, memory: new lib.PlcMemory({ dataBlocks: { 1: 12 } }), profile: 's7-1500' });
    const port: number = await s7.listen();
    red = await startNodeRed(testFlow(`s7://127.0.0.1:${port}?rack=0&slot=1&timeout=1000`));
    browser = await launchChromium();
  });

  after(async () => {
    await browser?.close();
    await red?.stop();
    await s7?.close();
  });

  function openEditor(): Promise<{ context: BrowserContext; page: Page; errors: Error[] }> {
    return openEditorOf(browser, red, 'en-US', 'read-sym');
  }

  async function editConnection(page: Page, id: string): Promise<void> {
    await page.evaluate((nodeId) => (globalThis as any).RED.editor.editConfig('', 'plcwire-connection', nodeId), id);
    await page.locator('#node-config-plcwire-add-files').waitFor({ state: 'visible' });
  }

  async function editTags(page: Page, id: string): Promise<void> {
    await page.evaluate((nodeId) => (globalThis as any).RED.editor.edit((globalThis as any).RED.nodes.node(nodeId)), id);
    await page.waitForSelector('#node-input-plcwire-tags .red-ui-editableList-addButton, .red-ui-editableList-addButton', {
      timeout: 10_000,
    });
    await page.waitForSelector('#node-dialog-ok', { state: 'visible' });
  }

  const blockRows = (page: Page) => page.$$eval('#node-config-plcwire-blocks li', (list) => list.map((li) => li.textContent));

  it('uploads one source and pastes another, numbers the DB, lists the block with its length, and keeps the sources in the flow', async () => {
    const { context, page, errors } = await openEditor();
    try {
      await editConnection(page, 'conn-new');
      await page.setInputFiles('#node-config-plcwire-source-files', [
        { name: 'Motor.udt', mimeType: 'text/plain', buffer: Buffer.from(MOTOR_UDT) },
      ]);
      await page.waitForSelector('#node-config-plcwire-sources li[data-name="Motor.udt"]');
      await page.click('#node-config-plcwire-paste');
      await page.fill('#node-config-plcwire-paste-name', 'Tank.db');
      await page.fill('#node-config-plcwire-paste-text', TANK_DB);
      await page.click('#node-config-plcwire-paste-add');
      await page.waitForSelector('#node-config-plcwire-sources li[data-name="Tank.db"]');
      // Without a DB number the TIA source's block is not placed: the number makes it a block.
      await page.click('#node-config-plcwire-dbnumbers + .red-ui-editableList-addButton, .plcwire-symbols .red-ui-editableList-addButton');
      await page.fill('.plcwire-dbnumber-block', 'Tank');
      await page.fill('.plcwire-dbnumber-db', '1');
      const row = connectionText('plcwire-connection.editor.blockRow', { db: 1, name: 'Tank', length: 12, file: 'Tank.db' });
      await page.waitForFunction(
        (text) =>
          [...(globalThis as any).document.querySelectorAll('#node-config-plcwire-blocks li')].some((li) => li.textContent === text),
        row,
        { timeout: 10_000 },
      );
      expect(await blockRows(page)).to.deep.equal([row]);
      await page.click('#node-config-dialog-ok');
      await page.waitForSelector('#node-config-plcwire-add-files', { state: 'detached', timeout: 10_000 });
      const saved = await page.evaluate(() => {
        const n = (globalThis as any).RED.nodes.node('conn-new');
        return { symbolSources: n.symbolSources, dbNumbers: n.dbNumbers };
      });
      expect(saved).to.deep.equal({
        symbolSources: [
          { name: 'Motor.udt', content: MOTOR_UDT },
          { name: 'Tank.db', content: TANK_DB },
        ],
        dbNumbers: [{ block: 'Tank', db: 1 }],
      });
      expect(errors).to.deep.equal([]);
    } finally {
      await context.close();
    }
  });

  it('lists an optimized block as one read by name over s7plus://, beside a standard one with its length', async () => {
    const { context, page, errors } = await openEditor();
    try {
      await editConnection(page, 'conn-new');
      await page.click('#node-config-plcwire-paste');
      await page.fill('#node-config-plcwire-paste-name', 'Both.db');
      const optimized = TANK_DB.replace('"Tank"', '"Recipe"').replace("'FALSE'", "'TRUE'").replace('Motor : "Motor";', 'Step : Int;');
      await page.fill('#node-config-plcwire-paste-text', `${optimized}\n${TANK_DB.replace('Motor : "Motor";', 'Step : Int;')}`);
      await page.click('#node-config-plcwire-paste-add');
      await page.waitForSelector('#node-config-plcwire-sources li[data-name="Both.db"]');
      for (const [block, db] of [
        ['Recipe', '2'],
        ['Tank', '1'],
      ] as const) {
        await page.click('.plcwire-symbols .red-ui-editableList-addButton');
        await page.locator('.plcwire-dbnumber-block').last().fill(block);
        await page.locator('.plcwire-dbnumber-db').last().fill(db);
      }
      const rows = [
        connectionText('plcwire-connection.editor.blockRowOptimized', { db: 2, name: 'Recipe', file: 'Both.db' }),
        connectionText('plcwire-connection.editor.blockRow', { db: 1, name: 'Tank', length: 8, file: 'Both.db' }),
      ];
      expect(rows[0]).to.equal('DB2 Recipe: optimized access, read by name over s7plus:// (Both.db)');
      await page.waitForFunction(
        (texts) => {
          const shown = [...(globalThis as any).document.querySelectorAll('#node-config-plcwire-blocks li')].map(
            (li: any) => li.textContent,
          );
          return JSON.stringify(shown) === JSON.stringify(texts);
        },
        rows,
        { timeout: 10_000 },
      );
      await page.locator('#node-config-plcwire-blocks li', { hasText: 'optimized access' }).waitFor({ state: 'visible' });
      expect(errors).to.deep.equal([]);
    } finally {
      await context.close();
    }
  });

  it('shows the errors of a source that does not compile with file, line and column, and the connection gets the red triangle', async () => {
    const { context, page, errors } = await openEditor();
    try {
      await editConnection(page, 'conn-new');
      await page.click('#node-config-plcwire-paste');
      await page.fill('#node-config-plcwire-paste-name', 'Broken.db');
      await page.fill('#node-config-plcwire-paste-text', TANK_DB.replace('"Tank"', '"Broken"').replace('Count : Int;', 'Count : Integr;'));
      await page.click('#node-config-plcwire-paste-add');
      await page.waitForSelector('#node-config-plcwire-symbol-errors li', { timeout: 10_000 });
      const shown = await page.$$eval('#node-config-plcwire-symbol-errors li', (list) => list.map((li) => li.textContent ?? ''));
      expect(shown[0]).to.match(/^Broken\.db line 7, column \d+: Broken\.db:7:\d+: .*Integr/);
      await page.click('#node-config-dialog-ok');
      await page.waitForSelector('#node-config-plcwire-add-files', { state: 'detached', timeout: 10_000 });
      await page.waitForFunction(() => (globalThis as any).RED.nodes.node('conn-new').valid === false, undefined, { timeout: 10_000 });
      const reasons = await page.evaluate(() => (globalThis as any).RED.nodes.node('conn-new').validationErrors);
      expect(reasons.join(' ')).to.match(/Broken\.db:7:\d+/);
      expect(errors).to.deep.equal([]);
    } finally {
      await context.close();
    }
  });

  it("completes a name typed in a read node's row, shows its address and type, and adds all members of a struct", async () => {
    const { context, page, errors } = await openEditor();
    try {
      await editTags(page, 'read-sym');
      await page.click('.red-ui-editableList-addButton');
      const address = page.locator('#node-input-plcwire-tags .plcwire-tag-address').last();
      await address.pressSequentially('tank.motor.sp');
      const option = page.locator('.red-ui-autoComplete-container li', { hasText: '"Tank".Motor.Speed' });
      await option.waitFor({ state: 'visible', timeout: 10_000 });
      await option.click();
      expect(await address.inputValue()).to.equal('"Tank".Motor.Speed');
      const row = page.locator('#node-input-plcwire-tags .plcwire-tag-row').last();
      await page.waitForFunction(
        () => (globalThis as any).document.querySelectorAll('#node-input-plcwire-tags .plcwire-tag-resolved')[1]?.textContent !== '',
        undefined,
        { timeout: 10_000 },
      );
      expect(await row.locator('.plcwire-tag-resolved').textContent()).to.equal('DB1.DBD6:REAL');
      expect(await row.locator('.plcwire-tag-type').textContent()).to.match(/^real$/i);
      // The first row, a name written without quotes, shows what it resolves to as well.
      expect(await page.locator('#node-input-plcwire-tags .plcwire-tag-resolved').first().textContent()).to.equal('DB1.DBD0:REAL');

      // A struct's row: "all members" adds one row per member, named by its path.
      await address.fill('Tank.Motor');
      const members = row.locator('.plcwire-tag-members');
      await members.waitFor({ state: 'visible', timeout: 10_000 });
      await members.click();
      await page.waitForFunction(
        () => (globalThis as any).document.querySelectorAll('#node-input-plcwire-tags .plcwire-tag-row').length === 4,
        undefined,
        { timeout: 10_000 },
      );
      await page.click('#node-dialog-ok');
      await page.waitForSelector('#node-input-plcwire-tags', { state: 'detached', timeout: 10_000 });
      const tags = await page.evaluate(() => (globalThis as any).RED.nodes.node('read-sym').tags);
      expect(tags).to.deep.equal([
        { name: 'level', address: 'Tank.Level' },
        { name: '', address: 'Tank.Motor' },
        { name: 'Motor.Speed', address: '"Tank".Motor.Speed' },
        { name: 'Motor.Run', address: '"Tank".Motor.Run' },
      ]);
      expect(errors).to.deep.equal([]);
    } finally {
      await context.close();
    }
  });

  it('gives a read node with an unknown name the red triangle, naming the closest names; names and absolute addresses are valid', async () => {
    const { context, page, errors } = await openEditor();
    try {
      await page.waitForFunction(() => (globalThis as any).RED.nodes.node('read-badsym').valid === false, undefined, { timeout: 10_000 });
      const state = await page.evaluate(() =>
        Object.fromEntries(
          ['read-badsym', 'read-sym', 'read-abs', 'conn-sym'].map((id) => {
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
      );
      expect(state['read-badsym'].triangle).to.equal(true);
      expect(state['read-badsym'].errors).to.include('unknown symbol Tank.Levl; did you mean "Tank".Level?');
      for (const id of ['read-sym', 'read-abs', 'conn-sym']) expect(state[id].valid, `${id}: ${state[id].errors}`).to.equal(true);
      for (const id of ['read-sym', 'read-abs']) expect(state[id].triangle, `${id} has no red triangle`).to.equal(false);
      expect(errors).to.deep.equal([]);
    } finally {
      await context.close();
    }
  });

  it('POST /plcwire/symbols asks for the plcwire.read permission, as the other plcwire endpoints do', async () => {
    const login = await request(`${red.url}auth/token`, {
      client_id: 'node-red-admin',
      grant_type: 'password',
      scope: '',
      username: VIEWER.username,
      password: VIEWER.password,
    });
    expect(login.status).to.equal(200);
    const viewer = { authorization: `Bearer ${login.body.access_token}` };
    const body = { symbolSources: SOURCES, dbNumbers: [{ block: 'Tank', db: 1 }] };
    expect((await request(`${red.url}plcwire/symbols`, body, viewer)).status).to.equal(401);
    expect((await request(`${red.url}plcwire/validate`, { addresses: ['Tank.Level'], ...body }, viewer)).status).to.equal(401);
    const anonymous = await request(`${red.url}plcwire/symbols`, body);
    expect(anonymous.status).to.equal(200);
    expect(anonymous.body.blocks).to.deep.equal([{ name: 'Tank', db: 1, length: 12, file: 'Tank.db' }]);
  });
});
