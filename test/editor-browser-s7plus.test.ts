/**
 * The connection dialog on S7CommPlus in a real browser (issue #25), against
 * the S7-1500 simulator serving S7CommPlus over TLS: choosing the protocol
 * shows the TLS fields (certificate, CA file, TLS, insecure, password) and
 * hides the S7comm ones; "Get certificate" shows the PLC certificate's
 * fingerprint, subject and validity (the en-US catalog's text), and "Pin"
 * puts the fingerprint into the field and the URL; "Test connection" walks
 * the S7CommPlus doctor, a typed password in no answer.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import type { Browser } from 'playwright-core';
import { S7Server } from '../lib/s7/server';
import { S7PlusService } from '../lib/s7plus/server';
import { generateCertificate } from '../lib/s7plus/transport/cert';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { launchChromium } from './support/browser';
import { openEditor, startNodeRedProcess, type NodeRedProcess } from './support/node-red-process';

const CATALOG = JSON.parse(fs.readFileSync(path.join(__dirname, '../../nodes/locales/en-US/connection.json'), 'utf8'))[
  'plcwire-connection'
];

describe('editor in Chromium: the connection dialog on s7plus://', function () {
  this.timeout(120_000);
  let server: S7Server;
  let service: S7PlusService;
  let red: NodeRedProcess;
  let browser: Browser;

  before(async () => {
    const cert = await generateCertificate();
    service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await server.listen();
    red = await startNodeRedProcess([
      { id: 'tab', type: 'tab', label: 's7plus' },
      { id: 'conn', type: 'plcwire-connection', name: 'plc', url: `s7://127.0.0.1:${server.port}?rack=0&slot=1` },
      {
        id: 'read',
        type: 'plcwire-read',
        z: 'tab',
        x: 200,
        y: 40,
        wires: [[]],
        connection: 'conn',
        interval: 0,
        tags: [{ name: 'count', address: 'DB1.DBW4:INT' }],
      },
    ]);
    browser = await launchChromium();
  });

  after(async () => {
    await browser?.close();
    await red?.stop();
    await server?.close();
  });

  it('S7CommPlus shows the TLS fields; Get certificate shows the fingerprint, Pin puts it in the URL; Browse PLC answers in view', async () => {
    const { context, page, errors } = await openEditor(browser, red, 'en-US', 'read');
    try {
      await page.evaluate(() => (globalThis as any).RED.editor.editConfig('', 'plcwire-connection', 'conn'));
      await page.waitForSelector('#node-config-plcwire-protocol', { state: 'visible', timeout: 10_000 });
      // S7comm first: no TLS field in view.
      expect(await page.isVisible('#node-config-plcwire-fingerprint')).to.equal(false);
      await page.selectOption('#node-config-plcwire-protocol', 's7plus');
      for (const id of ['fingerprint', 'ca', 'tls', 'insecure', 'getcert'])
        await page.waitForSelector(`#node-config-plcwire-${id}`, { state: 'visible', timeout: 5_000 });
      await page.waitForSelector('#node-config-input-password', { state: 'visible', timeout: 5_000 });
      expect(await page.isVisible('#node-config-plcwire-rack'), 'the S7comm rack field').to.equal(false);
      expect(await page.isChecked('#node-config-plcwire-tls')).to.equal(true);
      expect(await page.textContent('label[for="node-config-plcwire-fingerprint"]')).to.include('Certificate');
      await page.waitForFunction(
        () => /^s7plus:\/\/127\.0\.0\.1:\d+/.test((globalThis as any).document.querySelector('#node-config-input-url').value),
        undefined,
        { timeout: 5_000 },
      );

      await page.click('#node-config-plcwire-getcert');
      await page.waitForSelector('#node-config-plcwire-pin', { state: 'visible', timeout: 15_000 });
      const shown = (await page.textContent('#node-config-plcwire-cert')) ?? '';
      const colons = service.fingerprint!.replace(/(..)(?!$)/g, '$1:');
      expect(shown).to.include(`SHA-256 ${colons}`).and.include('subject O=plcwire, CN=plcwire simulator').and.include(', valid ');
      expect(await page.inputValue('#node-config-plcwire-fingerprint')).to.equal('');

      await page.click('#node-config-plcwire-pin');
      expect(await page.inputValue('#node-config-plcwire-fingerprint')).to.equal(service.fingerprint!);
      await page.waitForFunction(
        (fp) => (globalThis as any).document.querySelector('#node-config-input-url').value.includes(`fingerprint=${fp}`),
        service.fingerprint!,
        { timeout: 5_000 },
      );
      expect(await page.isVisible('#node-config-plcwire-pin')).to.equal(false);

      // Browse PLC: visible, clickable, and its answer shown; with a client that browses, the tag tables complete from it.
      await page.click('#node-config-plcwire-browse');
      await page.waitForFunction(
        (asking) => {
          const text = (globalThis as any).document.querySelector('#node-config-plcwire-browse-result').textContent;
          return text !== '' && text !== asking;
        },
        CATALOG.editor.browsing,
        { timeout: 20_000 },
      );
      const answer = (await page.textContent('#node-config-plcwire-browse-result')) ?? '';
      expect(answer).to.match(/^\d+ tags in \d+ blocks/);
      const names = await page.evaluate(
        () =>
          new Promise<string[]>((resolve) => {
            const ed = (globalThis as any).plcwireEditor;
            ed.compileSymbols(ed.symbolsOf('conn'), (a: any) => resolve(a.entries.map((e: any) => e.name)));
          }),
      );
      expect(names).to.include('"Recipe".Step');
      expect(errors, errors.join('\n')).to.deep.equal([]);
    } finally {
      await context.close();
    }
  });

  it('Test connection on s7plus:// walks the S7CommPlus steps in the dialog (TLS with the pinned certificate, session, identity, browse, the read node address); a typed password goes to the runtime and never comes back', async () => {
    const { context, page, errors } = await openEditor(browser, red, 'en-US', 'read');
    try {
      await page.evaluate(() => (globalThis as any).RED.editor.editConfig('', 'plcwire-connection', 'conn'));
      await page.waitForSelector('#node-config-plcwire-protocol', { state: 'visible', timeout: 10_000 });
      await page.selectOption('#node-config-plcwire-protocol', 's7plus');
      await page.fill('#node-config-plcwire-fingerprint', service.fingerprint!);
      await page.dispatchEvent('#node-config-plcwire-fingerprint', 'change');
      await page.waitForFunction(
        (fp) => (globalThis as any).document.querySelector('#node-config-input-url').value.includes(`fingerprint=${fp}`),
        service.fingerprint!,
        { timeout: 5_000 },
      );
      await page.waitForSelector('#node-config-plcwire-test', { state: 'visible', timeout: 5_000 });
      expect(await page.isVisible('#node-config-plcwire-test-hint')).to.equal(true);
      expect(await page.textContent('#node-config-plcwire-test-hint')).to.equal(CATALOG.hint.testS7plus);
      await page.click('#node-config-plcwire-test');
      await page.waitForFunction(
        (done) =>
          [done.ok, done.failed].includes((globalThis as any).document.querySelector('#node-config-plcwire-test-summary').textContent),
        { ok: CATALOG.editor.testOk, failed: CATALOG.editor.testFailed },
        { timeout: 30_000 },
      );
      const steps = await page.$$eval('#node-config-plcwire-test-steps li', (lis) =>
        lis.map((li) => `${li.getAttribute('data-step')}:${li.className.includes('ok') ? 'ok' : 'bad'}`),
      );
      expect(steps).to.deep.equal([
        'tcp:ok',
        'cotp:ok',
        'InitSSL:ok',
        'TLS:ok',
        'session:ok',
        'password:ok',
        'identity:ok',
        'browse:ok',
        'address DB1.DBW4:INT:ok',
      ]);
      expect(await page.textContent('#node-config-plcwire-test-summary')).to.equal(CATALOG.editor.testOk);
      expect(await page.textContent('li[data-step="TLS"]')).to.contain("matches the URL's fingerprint");
      expect(await page.textContent('li[data-step="identity"]')).to.contain('6ES7 516-3AN02-0AB0 firmware V3.1');
      // A typed password reaches the runtime's doctor and is in no answer.
      const secret = 'typed-Secret-42';
      const answer = await page.evaluate(
        ({ url, password }) =>
          new Promise<string>((resolve) => {
            const $ = (globalThis as any).$;
            $.ajax({
              url: 'plcwire/doctor',
              type: 'POST',
              contentType: 'application/json',
              data: JSON.stringify({ url, password, id: 'conn' }),
              complete: (xhr: any) => resolve(xhr.responseText),
            });
          }),
        { url: await page.inputValue('#node-config-input-url'), password: secret },
      );
      expect(answer).to.contain('"step":"password"').and.not.contain(secret);
      expect(errors, errors.join('\n')).to.deep.equal([]);
    } finally {
      await context.close();
    }
  });
});
