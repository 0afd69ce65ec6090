/**
 * test/support/install-peers.js, the pretest step that installs the test-only
 * peers, for the Python peers awlsim and s7commplus (a venv each): installed already, it does nothing and
 * needs no network; without python3 or PyPI it warns, leaves no half-made
 * venv behind and lets `npm test` go on (the awlsim test then skips, saying
 * why). Run on a copy of the script in a temporary tree, so the worktree's
 * own venv is never touched.
 */
import { expect } from 'chai';
import { spawnSync } from 'node:child_process';
import * as fs from 'node:fs';
import * as net from 'node:net';
import * as os from 'node:os';
import * as path from 'node:path';
import { skipBecause } from './support/skip';

const ROOT = path.resolve(__dirname, '../..');
const SCRIPT = path.join(ROOT, 'test/support/install-peers.js');
const { AWLSIM_VERSION, S7COMMPLUS_VERSION, PLC4X_VERSION } = require(SCRIPT) as {
  AWLSIM_VERSION: string;
  S7COMMPLUS_VERSION: string;
  PLC4X_VERSION: string;
};

/**
 * A tree with the script at its usual place and, if `awlsim` is given, a venv
 * (`venvDir` under test/interop) whose Python reports that version.
 */
function tree(awlsim?: string, venvDir = '.venv'): { dir: string; venv: string } {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-peers-'));
  fs.mkdirSync(path.join(dir, 'test/support'), { recursive: true });
  fs.copyFileSync(SCRIPT, path.join(dir, 'test/support/install-peers.js'));
  const venv = path.join(dir, 'test/interop', venvDir);
  if (awlsim !== undefined) {
    fs.mkdirSync(path.join(venv, 'bin'), { recursive: true });
    fs.writeFileSync(path.join(venv, 'bin/python'), `#!/bin/sh\necho ${awlsim}\n`, { mode: 0o755 });
  }
  return { dir, venv };
}

/** Runs the script of `dir` for `sets` with `env` over a pip that can reach no index (a closed loopback port). */
function install(dir: string, sets: string[], env: NodeJS.ProcessEnv, closedPort: number) {
  return spawnSync(process.execPath, [path.join(dir, 'test/support/install-peers.js'), ...sets], {
    cwd: dir,
    encoding: 'utf8',
    timeout: 300_000,
    env: {
      ...env,
      PIP_INDEX_URL: `http://127.0.0.1:${closedPort}/simple`,
      PIP_CONFIG_FILE: os.devNull,
      PIP_NO_CACHE_DIR: '1',
      PIP_FIND_LINKS: '',
    },
  });
}

describe('install-peers: awlsim for the layout comparison', function () {
  this.timeout(300_000);
  const dirs: string[] = [];
  let closedPort = 0;
  let emptyBin = '';

  before(async function () {
    if (process.platform === 'win32') skipBecause(this, 'the stand-in venv Python is a shell script');
    // A port that was listening a moment ago and is closed now: pip's requests are refused at once.
    const s = net.createServer().listen(0, '127.0.0.1');
    await new Promise((r) => s.once('listening', r));
    closedPort = (s.address() as net.AddressInfo).port;
    await new Promise((r) => s.close(r));
    emptyBin = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-nopython-'));
    dirs.push(emptyBin);
  });
  after(() => dirs.forEach((d) => fs.rmSync(d, { recursive: true, force: true })));

  it('does nothing when the venv has the pinned awlsim: no output, no python3 needed, no network', () => {
    const { dir, venv } = tree(AWLSIM_VERSION);
    dirs.push(dir);
    const r = install(dir, ['awlsim'], { ...process.env, PATH: emptyBin }, closedPort);
    expect(r.status, r.stderr).to.equal(0);
    expect(r.stdout + r.stderr).to.equal('');
    expect(fs.readFileSync(path.join(venv, 'bin/python'), 'utf8')).to.include(AWLSIM_VERSION);
  });

  it('without python3 warns that the awlsim test will skip, and exits 0 so npm test goes on', () => {
    const { dir, venv } = tree();
    dirs.push(dir);
    const r = install(dir, ['awlsim'], { ...process.env, PATH: emptyBin }, closedPort);
    expect(r.status, r.stderr).to.equal(0);
    expect(r.stderr).to.match(new RegExp(`awlsim ${AWLSIM_VERSION.replace(/\./g, '\\.')} not installed: no python3 \\(ENOENT\\)`));
    expect(r.stderr).to.include('test/symbols-awlsim.test.ts will skip');
    expect(fs.existsSync(venv)).to.equal(false);
  });

  it('replaces a venv of another awlsim version; when PyPI cannot be reached it warns, removes the half-made venv and exits 0', function () {
    const python3 = spawnSync('python3', ['-c', 'import venv, ensurepip'], { encoding: 'utf8' });
    if (python3.status !== 0)
      skipBecause(this, `python3 with venv and ensurepip is needed (${python3.error?.message ?? python3.stderr.trim()})`);
    const { dir, venv } = tree('0.76.0');
    dirs.push(dir);
    const r = install(dir, ['awlsim'], process.env, closedPort);
    expect(r.status, r.stderr).to.equal(0);
    expect(r.stdout).to.include(`Installing awlsim ${AWLSIM_VERSION} into test/interop/.venv (it has awlsim 0.76.0)`);
    expect(r.stderr).to.include(`awlsim ${AWLSIM_VERSION} not installed (pip install failed); test/symbols-awlsim.test.ts will skip.`);
    expect(fs.existsSync(venv), 'the venv pip could not complete').to.equal(false);
  });

  it('refuses a set it does not know, naming the ones it does', () => {
    const { dir } = tree();
    dirs.push(dir);
    const r = install(dir, ['awlsin'], process.env, closedPort);
    expect(r.status).to.not.equal(0);
    expect(r.stderr).to.include('install-peers: unknown set "awlsin" (interop, nr5, awlsim, s7commplus, plc4x, tahu)');
  });

  it('is what npm test runs before the suite, with .ci/run using the same installer', () => {
    const pkg = JSON.parse(fs.readFileSync(path.join(ROOT, 'package.json'), 'utf8')) as { scripts: Record<string, string> };
    expect(pkg.scripts.pretest).to.match(/node test\/support\/install-peers\.js( \w+)* awlsim\b/);
    expect(pkg.scripts.pretest).to.match(/node test\/support\/install-peers\.js( \w+)* s7commplus\b/);
    expect(pkg.scripts.pretest).to.match(/node test\/support\/install-peers\.js( \w+)* plc4x\b/);
    const ci = fs.readFileSync(path.join(ROOT, '.ci/run'), 'utf8');
    expect(ci).to.match(/^node test\/support\/install-peers\.js awlsim$/m);
    expect(ci).to.match(/^node test\/support\/install-peers\.js s7commplus$/m);
    expect(ci).to.match(/^node test\/support\/install-peers\.js plc4x$/m);
  });

  it('plc4x: without java, javac or mvn warns which is missing and that the PLC4X test will skip, and exits 0', () => {
    const { dir } = tree();
    dirs.push(dir);
    const r = install(dir, ['plc4x'], { ...process.env, PATH: emptyBin }, closedPort);
    expect(r.status, r.stderr).to.equal(0);
    expect(r.stderr).to.include(`Apache PLC4X ${PLC4X_VERSION} peer not built: no java (ENOENT); test/plc4x-interop.test.ts will skip.`);
  });
});

describe('install-peers: s7commplus, the independent S7CommPlus peer', function () {
  this.timeout(300_000);
  const dirs: string[] = [];
  let closedPort = 0;
  let emptyBin = '';

  before(async function () {
    if (process.platform === 'win32') skipBecause(this, 'the stand-in venv Python is a shell script');
    const s = net.createServer().listen(0, '127.0.0.1');
    await new Promise((r) => s.once('listening', r));
    closedPort = (s.address() as net.AddressInfo).port;
    await new Promise((r) => s.close(r));
    emptyBin = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-nopython-'));
    dirs.push(emptyBin);
  });
  after(() => dirs.forEach((d) => fs.rmSync(d, { recursive: true, force: true })));

  it('does nothing when its own venv has the pinned s7commplus, and leaves the awlsim venv alone', () => {
    const { dir, venv } = tree(S7COMMPLUS_VERSION, '.venv-s7commplus');
    dirs.push(dir);
    // A venv where awlsim's would be, which an installer that mixed up the two would replace or remove.
    const awlsimVenv = path.join(dir, 'test/interop/.venv');
    fs.mkdirSync(path.join(awlsimVenv, 'bin'), { recursive: true });
    fs.writeFileSync(path.join(awlsimVenv, 'bin/python'), `#!/bin/sh\necho ${AWLSIM_VERSION}\n`, { mode: 0o755 });
    const r = install(dir, ['s7commplus'], { ...process.env, PATH: emptyBin }, closedPort);
    expect(r.status, r.stderr).to.equal(0);
    expect(r.stdout + r.stderr).to.equal('');
    expect(fs.readFileSync(path.join(venv, 'bin/python'), 'utf8')).to.include(S7COMMPLUS_VERSION);
    expect(fs.readFileSync(path.join(awlsimVenv, 'bin/python'), 'utf8')).to.include(AWLSIM_VERSION);
  });

  it('without python3 warns that the S7CommPlus interop tests will skip, and exits 0', () => {
    const { dir, venv } = tree(undefined, '.venv-s7commplus');
    dirs.push(dir);
    const r = install(dir, ['s7commplus'], { ...process.env, PATH: emptyBin }, closedPort);
    expect(r.status, r.stderr).to.equal(0);
    expect(r.stderr).to.include(
      `s7commplus ${S7COMMPLUS_VERSION} not installed: no python3 (ENOENT); the tests against the s7commplus peer (test/support/s7commplus-peer.ts) will skip.`,
    );
    expect(fs.existsSync(venv)).to.equal(false);
  });

  it('replaces a venv of another s7commplus version; when PyPI cannot be reached it warns, removes the half-made venv and exits 0', function () {
    const python3 = spawnSync('python3', ['-c', 'import venv, ensurepip'], { encoding: 'utf8' });
    if (python3.status !== 0)
      skipBecause(this, `python3 with venv and ensurepip is needed (${python3.error?.message ?? python3.stderr.trim()})`);
    const { dir, venv } = tree('0.2.0', '.venv-s7commplus');
    dirs.push(dir);
    const r = install(dir, ['s7commplus'], process.env, closedPort);
    expect(r.status, r.stderr).to.equal(0);
    expect(r.stdout).to.include(`Installing s7commplus ${S7COMMPLUS_VERSION} into test/interop/.venv-s7commplus (it has s7commplus 0.2.0)`);
    expect(r.stderr).to.include(`s7commplus ${S7COMMPLUS_VERSION} not installed (pip install failed)`);
    expect(fs.existsSync(venv), 'the venv pip could not complete').to.equal(false);
    expect(fs.existsSync(path.join(dir, 'test/interop/.venv')), "awlsim's venv").to.equal(false);
  });
});
