/**
 * The packed tarball installed the way users install it (npm into a Node-RED
 * user directory), then a real Node-RED 4 on Node 20 and Node-RED 5 on Node 22
 * started on it: our node types load with no error, their locales and the
 * examples are served.
 */
import { expect } from 'chai';
import { execFileSync, spawn, type ChildProcess } from 'node:child_process';
import * as fs from 'node:fs';
import * as http from 'node:http';
import * as os from 'node:os';
import * as path from 'node:path';
import { freePort } from './support/net';
import { NodeRedPortTaken, waitForNodeRed } from './support/node-red-process';
import { packTarball, ROOT } from './support/pack';

const PACKAGE = JSON.parse(fs.readFileSync(path.join(ROOT, 'package.json'), 'utf8')) as { name: string; 'node-red': { nodes: object } };
/** Every node type the package declares (each file registers the type of its key). */
const TYPES = Object.keys(PACKAGE['node-red'].nodes);
const MODULE = PACKAGE.name;

const RUNTIMES = [
  { name: 'Node-RED 4 on Node 20', node: process.execPath, red: path.join(ROOT, 'node_modules/node-red/red.js'), major: '4.' },
  {
    name: 'Node-RED 5 on Node 22',
    node: path.join(ROOT, 'test/nr5/node_modules/node/bin/node'),
    red: path.join(ROOT, 'test/nr5/node_modules/node-red/red.js'),
    major: '5.',
  },
];

function get(url: string, accept = 'application/json'): Promise<{ status: number; body: string }> {
  return new Promise((resolve, reject) => {
    http
      .get(url, { headers: { Accept: accept } }, (res) => {
        let body = '';
        res.setEncoding('utf8');
        res.on('data', (d: string) => (body += d));
        res.on('end', () => resolve({ status: res.statusCode ?? 0, body }));
      })
      .on('error', reject);
  });
}

describe('install: the tarball in a fresh Node-RED user directory', function () {
  // npm install and a Node-RED start each take seconds alone, and minutes on a loaded 2-core machine.
  this.timeout(300_000);
  let work: string;
  let tarball: string;

  before(() => {
    work = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-install-'));
    tarball = packTarball(work);
  });
  after(() => fs.rmSync(work, { recursive: true, force: true }));

  for (const runtime of RUNTIMES) {
    describe(runtime.name, () => {
      let child: ChildProcess | undefined;
      let base: string;
      let log = '';

      before(async () => {
        if (!fs.existsSync(runtime.node) || !fs.existsSync(runtime.red))
          throw new Error(`${runtime.name} is not installed: node test/support/install-peers.js nr5 installs it (npm test does)`);
        const userDir = fs.mkdtempSync(path.join(work, 'user-'));
        fs.writeFileSync(path.join(userDir, 'package.json'), JSON.stringify({ name: 'node-red-project', private: true }));
        // What the palette manager does: npm install the package into the user directory.
        execFileSync('npm', ['install', '--no-audit', '--no-fund', '--prefer-offline', '--omit=dev', tarball], {
          cwd: userDir,
          stdio: 'pipe',
        });
        // A port free a moment ago may be taken before Node-RED binds it (other tests run beside): then another.
        for (let attempt = 1; ; attempt++) {
          const port = await freePort();
          fs.writeFileSync(
            path.join(userDir, 'settings.js'),
            `module.exports = { uiHost: '127.0.0.1', uiPort: ${port}, flowFile: 'flows.json', credentialSecret: false, diagnostics: { enabled: false }, telemetry: { enabled: false }, logging: { console: { level: 'info' } } };\n`,
          );
          log = '';
          child = spawn(runtime.node, [runtime.red, '--userDir', userDir, '--settings', path.join(userDir, 'settings.js')], {
            cwd: userDir,
            stdio: ['ignore', 'pipe', 'pipe'],
          });
          child.stdout!.on('data', (d: Buffer) => (log += d.toString()));
          child.stderr!.on('data', (d: Buffer) => (log += d.toString()));
          base = `http://127.0.0.1:${port}`;
          try {
            // "Started flows" comes before red.js opens the port: wait for the admin API to answer too.
            await waitForNodeRed(child, `${base}/settings`, () => log, 240_000);
            break;
          } catch (err) {
            if (!(err instanceof NodeRedPortTaken) || attempt === 3) throw err;
          }
        }
      });

      let shownLog = false;
      afterEach(function () {
        // A failure here is about a runtime in another process: its log says why (once).
        if (this.currentTest?.state !== 'failed' || shownLog) return;
        shownLog = true;
        console.error(`${runtime.name} (exit code ${child?.exitCode ?? 'none: still running'}) logged:\n${log}`);
      });

      after(async () => {
        if (child && child.exitCode === null && child.signalCode === null) {
          const exited = new Promise((r) => child!.once('exit', r));
          child.kill('SIGINT');
          const force = setTimeout(() => child!.kill('SIGKILL'), 10_000);
          await exited;
          clearTimeout(force);
        }
      });

      it('runs the Node-RED major it claims', async () => {
        const settings = JSON.parse((await get(`${base}/settings`)).body) as { version: string };
        expect(settings.version.startsWith(runtime.major), settings.version).to.equal(true);
      });

      it(`lists our ${TYPES.length} node types (${TYPES.join(', ')}), enabled and without error`, async () => {
        const res = await get(`${base}/nodes`);
        expect(res.status).to.equal(200);
        const sets = (JSON.parse(res.body) as { module: string; types: string[]; enabled: boolean; err?: string }[]).filter(
          (s) => s.module === MODULE,
        );
        expect(sets.map((s) => s.err).filter(Boolean), log).to.deep.equal([]);
        expect(sets.every((s) => s.enabled)).to.equal(true);
        expect(sets.flatMap((s) => s.types)).to.have.members(TYPES);
        expect(log).not.to.match(/\[error\].*plcwire/i);
      });

      it('serves our locales in en-US, zh-CN and de', async () => {
        for (const lng of ['en-US', 'zh-CN', 'de']) {
          const res = await get(`${base}/nodes/messages?lng=${lng}`); // what the editor loads
          expect(res.status).to.equal(200);
          const catalogs = JSON.parse(res.body) as Record<string, unknown>;
          const ours = Object.keys(catalogs).filter((ns) => ns.startsWith(MODULE));
          expect(ours.length, `${lng} catalogs among ${Object.keys(catalogs).slice(0, 8).join(', ')}`).to.be.greaterThan(0);
        }
      });

      it('serves the editor code every dialog loads, at the URL the dialogs name', async () => {
        const configs = await get(`${base}/nodes`, 'text/html'); // what the editor loads
        expect(configs.status).to.equal(200);
        const sources = new Set([...configs.body.matchAll(/<script\b[^>]*\bsrc="(resources\/[^"]+)"/g)].map((m) => m[1]!));
        expect([...sources]).to.deep.equal([`resources/${MODULE}/plcwire-editor.js`]);
        const res = await get(`${base}/${[...sources][0]}`, '*/*');
        expect(res.status).to.equal(200);
        expect(res.body).to.include('window.plcwireEditor');
      });

      it('serves the examples', async () => {
        const res = await get(`${base}/library/examples/flows/${MODULE}`);
        expect(res.status).to.equal(200);
        const listing = JSON.parse(res.body) as unknown[];
        expect(listing.length).to.be.greaterThan(0);
      });
    });
  }
});
