/**
 * The simulator's certificate kept in a directory (issue #31: a new certificate at every start broke every pinned
 * flow after a restart): `certificateInDirectory()`, `plcwire serve s7 --tls-dir`, the demo plant's `tlsDir` and the
 * per-user directory `npm start` keeps it in.
 */
import { expect } from 'chai';
import { spawn } from 'node:child_process';
import { once } from 'node:events';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { EXIT } from '../lib/cli/io';
import { PlcError } from '../lib/errors';
import { startPlant } from '../lib/plant/plant';
import { demoCertificateDir } from '../lib/plant/certificate-dir';
import { certificateInDirectory, CERTIFICATE_FILES } from '../lib/s7plus/transport/cert-dir';
import { freePort } from './support/net';
import { until } from './support/wait';

const ROOT = path.resolve(__dirname, '../..');
const BIN = path.join(ROOT, 'bin/plcwire.js');
const POSIX = process.platform !== 'win32';

/** Permission bits of a file. */
const modeOf = (file: string) => fs.statSync(file).mode & 0o777;

/** `plcwire serve s7 …` until it printed its S7CommPlus URL; its output, then stopped (exit 0 expected). */
async function serveOnce(args: string[]): Promise<string> {
  const child = spawn(process.execPath, [BIN, 'serve', 's7', '--port', String(await freePort()), ...args], {
    stdio: ['ignore', 'pipe', 'pipe'],
  });
  let out = '';
  let err = '';
  child.stdout.on('data', (d: Buffer) => (out += d.toString()));
  child.stderr.on('data', (d: Buffer) => (err += d.toString()));
  const exit = once(child, 'exit');
  try {
    await until(() => /^Ctrl-C stops/m.test(out) || child.exitCode !== null, 15000, `serve starts (${err})`);
  } finally {
    child.kill('SIGINT');
  }
  const [code] = (await exit) as [number];
  expect(code, err).to.equal(0);
  return out;
}

/** A short CLI run to its end. */
async function cli(args: string[]): Promise<{ code: number; err: string }> {
  const child = spawn(process.execPath, [BIN, ...args], { stdio: ['ignore', 'ignore', 'pipe'] });
  let err = '';
  child.stderr.on('data', (d: Buffer) => (err += d.toString()));
  const [code] = (await once(child, 'exit')) as [number];
  return { code, err };
}

describe('the simulator certificate kept in a directory (issue #31)', function () {
  this.timeout(60000);
  let dir: string;

  beforeEach(() => {
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-tls-dir-'));
  });
  afterEach(() => fs.rmSync(dir, { recursive: true, force: true }));

  it('certificateInDirectory: made on the first call, the same after; the key readable by its owner alone', async () => {
    const keep = path.join(dir, 'nested', 'sim');
    const first = await certificateInDirectory(keep, { keyType: 'ec' });
    const second = await certificateInDirectory(keep, { keyType: 'ec' });
    expect(second.fingerprint)
      .to.match(/^[0-9A-F]{64}$/)
      .and.equal(first.fingerprint);
    expect(second.cert).to.equal(first.cert);
    expect(fs.readdirSync(keep).sort()).to.deep.equal([CERTIFICATE_FILES.cert, CERTIFICATE_FILES.key]);
    if (POSIX) {
      expect(modeOf(path.join(keep, CERTIFICATE_FILES.key)).toString(8)).to.equal('600');
      expect(modeOf(keep).toString(8)).to.equal('700');
    }
    expect(first.source).to.match(/^made and kept in /);
    expect(second.source).to.match(/^kept in /);
  });

  it('refuses a key others can read, half a pair, and a directory inside the package, naming the file', async function () {
    await certificateInDirectory(dir, { keyType: 'ec' });
    const key = path.join(dir, CERTIFICATE_FILES.key);
    if (POSIX) {
      fs.chmodSync(key, 0o644);
      const err = await certificateInDirectory(dir).then(
        () => undefined,
        (e: unknown) => e,
      );
      expect(err).to.be.instanceOf(PlcError).with.property('message').that.includes(key).and.includes('chmod 600');
      fs.chmodSync(key, 0o600);
    }
    fs.rmSync(path.join(dir, CERTIFICATE_FILES.cert));
    const half = await certificateInDirectory(dir).then(
      () => undefined,
      (e: unknown) => e,
    );
    expect(half).to.be.instanceOf(PlcError).with.property('message').that.includes(key).and.includes(CERTIFICATE_FILES.cert);
    expect(fs.readFileSync(key, 'utf8'), 'the key is left as it was').to.match(/PRIVATE KEY/);
    const inPackage = path.join(ROOT, 'dist', 'tls-test-never-made');
    const refused = await certificateInDirectory(inPackage).then(
      () => undefined,
      (e: unknown) => e,
    );
    expect(refused).to.be.instanceOf(PlcError).with.property('message').that.includes('inside the plcwire package');
    expect(fs.existsSync(inPackage)).to.equal(false);
  });

  it('plcwire serve s7 --tls-dir: two starts, the same fingerprint; the key file mode 0600', async () => {
    const keep = path.join(dir, 'sim');
    const fingerprintOf = (out: string) => /certificate SHA-256 ([0-9A-F]{64})/.exec(out)?.[1];
    const first = await serveOnce(['--profile', 's7-1500', '--tls-dir', keep]);
    const second = await serveOnce(['--profile', 's7-1500', '--tls-dir', keep]);
    expect(fingerprintOf(first), first).to.match(/^[0-9A-F]{64}$/);
    expect(fingerprintOf(second)).to.equal(fingerprintOf(first));
    expect(second).to.include(`kept in ${keep}`);
    if (POSIX) expect(modeOf(path.join(keep, CERTIFICATE_FILES.key)).toString(8)).to.equal('600');
    // Without it, a new one at every start (as before).
    expect(fingerprintOf(await serveOnce(['--profile', 's7-1500']))).to.not.equal(fingerprintOf(first));
  });

  it('--tls-dir with --tls-cert, or on a CPU without S7CommPlus, is a usage error', async () => {
    const both = await cli(['serve', 's7', '--port', '0', '--tls-dir', dir, '--tls-cert', 'c.pem', '--tls-key', 'k.pem']);
    expect(both.code).to.equal(EXIT.USAGE);
    expect(both.err).to.match(/--tls-dir .*--tls-cert\/--tls-key .*one or the other/);
    const s7300 = await cli(['serve', 's7', '--port', '0', '--profile', 's7-300', '--tls-dir', dir]);
    expect(s7300.code).to.equal(EXIT.USAGE);
    expect(s7300.err).to.match(/--tls-dir .*not s7-300/);
    expect(fs.readdirSync(dir)).to.deep.equal([]);
  });

  it('the demo plant keeps its certificate in tlsDir: the pinned s7plus:// URL is the same after a restart', async () => {
    const ports = { s7: 0, fetch: 0, write: 0, freeport: 0 };
    const first = await startPlant({ ports, tlsDir: dir });
    const url1 = first.urls.s7plus;
    await first.close();
    const second = await startPlant({ ports, tlsDir: dir });
    const url2 = second.urls.s7plus;
    await second.close();
    expect(/fingerprint=([0-9A-F]{64})/.exec(url2)![1]).to.equal(/fingerprint=([0-9A-F]{64})/.exec(url1)![1]);
  });

  it("npm start's directory is the user's own, outside the package, as each platform keeps state", () => {
    expect(demoCertificateDir({}, 'linux', '/home/ada')).to.equal('/home/ada/.local/state/plcwire/demo-tls');
    expect(demoCertificateDir({ XDG_STATE_HOME: '/var/ada' }, 'linux', '/home/ada')).to.equal('/var/ada/plcwire/demo-tls');
    // A relative XDG_STATE_HOME is invalid (XDG Base Directory Specification) and ignored.
    expect(demoCertificateDir({ XDG_STATE_HOME: 'state' }, 'linux', '/home/ada')).to.equal('/home/ada/.local/state/plcwire/demo-tls');
    expect(demoCertificateDir({}, 'darwin', '/Users/ada')).to.equal('/Users/ada/Library/Application Support/plcwire/demo-tls');
    expect(demoCertificateDir({ LOCALAPPDATA: 'C:\\Users\\ada\\AppData\\Local' }, 'win32', 'C:\\Users\\ada')).to.equal(
      'C:\\Users\\ada\\AppData\\Local\\plcwire\\demo-tls',
    );
    const mine = path.resolve(demoCertificateDir());
    expect(path.relative(ROOT, mine).startsWith('..'), mine).to.equal(true);
  });
});
