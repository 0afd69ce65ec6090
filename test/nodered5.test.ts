/**
 * Runs the Node-RED node suite (dist/test/nodes) a second time on Node-RED 5
 * under Node 22 — both installed from the npm registry into test/nr5 by
 * `npm test`'s pretest (test/support/install-peers.js nr5) — and reports each of its tests here, so `npm test` covers
 * Node-RED 4 / Node 20 and Node-RED 5 / Node 22 in one summary.
 */
import { expect } from 'chai';
import { spawn } from 'node:child_process';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import Mocha = require('mocha');

const ROOT = path.resolve(__dirname, '../..');
const NR5 = path.join(ROOT, 'test/nr5/node_modules');
const NODE22 = path.join(NR5, 'node/bin/node');
const SUITE = path.join(ROOT, 'dist/test/nodes');

interface JsonTest {
  fullTitle: string;
  err: { message?: string; stack?: string };
}

describe('Node-RED 5 on Node 22', function () {
  this.timeout(240_000);
  let report: { stats: { passes: number; failures: number }; passes: JsonTest[]; failures: JsonTest[] } | undefined;
  let output = '';

  before(async function () {
    if (!fs.existsSync(NODE22) || !fs.existsSync(path.join(NR5, 'node-red'))) {
      throw new Error('Node 22 / Node-RED 5 are not installed: run `node test/support/install-peers.js nr5` (npm test does)');
    }
    const files = fs.existsSync(SUITE) ? fs.readdirSync(SUITE).filter((f) => f.endsWith('.test.js')) : [];
    if (files.length === 0) throw new Error(`no node tests in ${SUITE}`);
    const out = path.join(fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-nr5-')), 'report.json');
    const mocha = require.resolve('mocha/bin/mocha.js', { paths: [ROOT] });
    const child = spawn(
      NODE22,
      [
        mocha,
        '--no-config',
        '--timeout',
        '20000',
        '--exit',
        '--reporter',
        'json',
        '--reporter-option',
        `output=${out}`,
        ...files.map((f) => path.join(SUITE, f)),
      ],
      { cwd: ROOT, env: { ...process.env, PLCWIRE_NODE_RED: path.join(NR5, 'node-red') }, stdio: ['ignore', 'pipe', 'pipe'] },
    );
    child.stdout.on('data', (d: Buffer) => (output += d.toString()));
    child.stderr.on('data', (d: Buffer) => (output += d.toString()));
    await new Promise((resolve) => child.on('exit', resolve));
    if (fs.existsSync(out)) report = JSON.parse(fs.readFileSync(out, 'utf8')) as typeof report;
    fs.rmSync(path.dirname(out), { recursive: true, force: true });
    // One test here per test there, so a failure on Node-RED 5 is named in the summary.
    const suite = this.test!.parent!;
    for (const t of report?.passes ?? []) suite.addTest(new Mocha.Test(t.fullTitle, () => undefined));
    for (const t of report?.failures ?? []) {
      suite.addTest(
        new Mocha.Test(t.fullTitle, () => {
          throw new Error(t.err.stack ?? t.err.message ?? 'failed on Node-RED 5');
        }),
      );
    }
  });

  it('ran the node suite under Node 22 with Node-RED 5', () => {
    expect(report, `no report from the Node 22 run:\n${output.slice(-3000)}`).to.not.equal(undefined);
    expect(report!.stats.passes + report!.stats.failures).to.be.greaterThan(0);
  });
});
