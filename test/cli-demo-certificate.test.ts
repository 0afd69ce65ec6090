/**
 * `plcwire demo` keeps its S7-1200's certificate between runs, as `npm start`
 * does (issue #31): in --tls-dir, by default the directory npm start keeps it
 * in (demoCertificateDir()), so an s7plus:// URL pinned once stays pinned. The
 * installed binary in child processes, every port a free one (--port 0 …),
 * never the demo's fixed ports other tests use.
 */
import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import { once } from 'node:events';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { EXIT } from '../lib/cli/io';
import { demoCertificateDir } from '../lib/plant/certificate-dir';
import { until } from './support/wait';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');
const FREE_PORTS = ['--port', '0', '--fetch-port', '0', '--write-port', '0', '--freeport-port', '0'];

interface Demo {
  child: ChildProcess;
  out: () => string;
  exit: Promise<number>;
}

describe('plcwire demo keeps its certificate between runs (issue #31)', function () {
  this.timeout(60000);
  let tmp: string;
  const running: Demo[] = [];

  function demo(args: string[], env: NodeJS.ProcessEnv): Demo {
    const child = spawn(process.execPath, [BIN, 'demo', ...FREE_PORTS, ...args], {
      env: { ...process.env, ...env },
      stdio: ['ignore', 'pipe', 'pipe'],
    });
    let out = '';
    child.stdout!.on('data', (d: Buffer) => (out += d.toString()));
    child.stderr!.on('data', (d: Buffer) => (out += d.toString()));
    const exit = once(child, 'exit').then(([code]) => code as number);
    const d = { child, out: () => out, exit };
    running.push(d);
    return d;
  }

  /** One run until it printed what to try, then Ctrl-C: the fingerprint it pinned and the directory it named. */
  async function oneRun(args: string[], env: NodeJS.ProcessEnv = {}): Promise<{ fingerprint: string; dir: string }> {
    const d = demo(args, env);
    await until(() => /^Ctrl-C stops\.$/m.test(d.out()) || d.child.exitCode !== null, 40000, 'the demo to start');
    const out = d.out();
    d.child.kill('SIGINT');
    expect(await d.exit, out).to.equal(EXIT.OK);
    const fingerprint = /s7plus:\/\/\S+fingerprint=([0-9A-F]{64})/.exec(out)?.[1];
    const dir = /the certificate is kept in (.+): the same fingerprint at every run$/m.exec(out)?.[1];
    expect(fingerprint, out).to.be.a('string');
    expect(dir, out).to.be.a('string');
    return { fingerprint: fingerprint!, dir: dir! };
  }

  beforeEach(() => {
    tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-demo-tls-'));
  });

  afterEach(async () => {
    for (const d of running.splice(0)) {
      if (d.child.exitCode === null) d.child.kill('SIGKILL');
      await d.exit;
    }
    fs.rmSync(tmp, { recursive: true, force: true });
  });

  it('--tls-dir: two runs pin the same fingerprint, the certificate made on the first and said where', async () => {
    const dir = path.join(tmp, 'certs');
    const first = await oneRun(['--tls-dir', dir]);
    expect(first.dir).to.equal(dir);
    expect(fs.readdirSync(dir).sort()).to.deep.equal(['cert.pem', 'key.pem']);
    const second = await oneRun(['--tls-dir', dir]);
    expect(second.fingerprint).to.equal(first.fingerprint);
  });

  it('without --tls-dir: the directory npm start keeps it in (demoCertificateDir()), the same fingerprint at the next run', async function () {
    if (process.platform === 'win32' || process.platform === 'darwin') this.skip(); // XDG_STATE_HOME moves it on Linux and POSIX only
    const env = { XDG_STATE_HOME: tmp };
    const expected = demoCertificateDir({ ...process.env, ...env });
    expect(expected.startsWith(tmp)).to.equal(true);
    const first = await oneRun([], env);
    expect(first.dir).to.equal(expected);
    expect(fs.existsSync(path.join(expected, 'cert.pem'))).to.equal(true);
    expect((await oneRun([], env)).fingerprint).to.equal(first.fingerprint);
  });

  it('a --tls-dir inside the package is a usage error naming the flag, and nothing is served', async () => {
    const d = demo(['--tls-dir', path.resolve(__dirname, '..', 'tls')], {});
    expect(await d.exit).to.equal(EXIT.USAGE);
    expect(d.out()).to.match(/--tls-dir: .* is inside the plcwire package/);
    expect(d.out()).to.not.include('Ctrl-C stops');
  });
});
