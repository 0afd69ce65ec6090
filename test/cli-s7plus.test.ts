/**
 * The CLI on s7plus:// URLs, through the installed binary (bin/plcwire.js)
 * in child processes, against our simulator: `plcwire serve s7 --profile
 * s7-1500 --source ...` serving S7CommPlus over TLS on its PUT/GET port and
 * printing its certificate's fingerprint. The program: test/fixtures/s7plus/
 * (a standard DB "Tank" = DB1, an optimized DB "Recipe" = DB2).
 */
import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import { once } from 'node:events';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { EXIT } from '../lib/cli/io';
import { createClient } from '../lib/connect';
import type { S7PlusClient } from '../lib/s7plus/client';
import { until } from './support/wait';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');
const FIXTURES = path.resolve(__dirname, '../../test/fixtures/s7plus');
const SECRET = 'Pa55-w0rd!not-for-logs';

interface Run {
  child: ChildProcess;
  output: () => { out: string; err: string };
  exit: Promise<number>;
}

function run(args: string[], env: NodeJS.ProcessEnv = {}): Run {
  const clean = { ...process.env };
  delete clean.PLCWIRE_PASSWORD;
  const child = spawn(process.execPath, [BIN, ...args], { cwd: FIXTURES, env: { ...clean, ...env }, stdio: ['ignore', 'pipe', 'pipe'] });
  let out = '';
  let err = '';
  child.stdout!.on('data', (d: Buffer) => (out += d.toString()));
  child.stderr!.on('data', (d: Buffer) => (err += d.toString()));
  const exit = once(child, 'exit').then(([code]) => code as number);
  return { child, output: () => ({ out, err }), exit };
}

async function done(args: string[], env: NodeJS.ProcessEnv = {}): Promise<{ code: number; out: string; err: string }> {
  const r = run(args, env);
  const code = await r.exit;
  return { code, ...r.output() };
}

/** `plcwire serve s7 --profile s7-1500` on the fixtures, with `extra` flags: its process and the URLs it prints. */
async function startSimulator(extra: string[]): Promise<{ sim: Run; url: string; s7url: string; fingerprint: string }> {
  const sim = run([
    'serve',
    's7',
    '--profile',
    's7-1500',
    '--port',
    '0',
    ...['Valve.udt', 'Tank.db', 'Recipe.db'].flatMap((f) => ['--source', f]),
    ...['--db', 'Tank=1', '--db', 'Recipe=2'],
    ...extra,
  ]);
  await until(() => /Ctrl-C stops/.test(sim.output().out + sim.output().err), 20000, 'the simulator to start');
  const text = sim.output().out;
  const url = /(s7plus:\/\/\S+)/.exec(text)![1]!;
  const s7url = /"(s7:\/\/[^"]+)"/.exec(text)![1]!;
  const fingerprint = /certificate SHA-256 ([0-9A-F]{64})/.exec(text)![1]!;
  expect(url).to.include(`fingerprint=${fingerprint}`);
  return { sim, url, s7url, fingerprint };
}

async function stop(sim: Run | undefined): Promise<void> {
  if (sim && sim.child.exitCode === null) {
    sim.child.kill('SIGTERM');
    await sim.exit;
  }
}

describe('plcwire on s7plus:// (the installed binary against the S7-1500 simulator)', function () {
  this.timeout(60000);
  let sim: Run;
  let url: string;
  let s7url: string;
  let fingerprint: string;
  let tmp: string;

  before(async () => {
    tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-cli-s7plus-'));
    ({ sim, url, s7url, fingerprint } = await startSimulator([]));
  });

  after(async () => {
    await stop(sim);
    fs.rmSync(tmp, { recursive: true, force: true });
  });

  it('info: the CPU state and the certificate of the TLS session the fingerprint pinned', async () => {
    const r = await done(['info', url, '--json']);
    expect(r.code, r.err).to.equal(EXIT.OK);
    const info = JSON.parse(r.out) as { state: string; certificate: { fingerprint: string; subject: string } };
    expect(info.state).to.equal('RUN');
    expect(info.certificate.fingerprint).to.equal(fingerprint);
    expect(info.certificate.subject).to.include('CN=plcwire simulator');
    const text = await done(['info', url]);
    expect(text.out).to.match(/^state: RUN\n/);
  });

  it('blocks: the data blocks with their names (standard and optimized); a type S7CommPlus does not list is refused before connecting', async () => {
    const all = await done(['blocks', url]);
    expect(all.code, all.err).to.equal(EXIT.OK);
    expect(all.out).to.equal('DB1  Tank\nDB2  Recipe\n');
    const db = await done(['blocks', url, 'DB', '--json']);
    expect(JSON.parse(db.out)).to.deep.equal({ type: 'DB', numbers: [1, 2] });
    const fb = await done(['blocks', url, 'FB']);
    expect(fb.code).to.equal(EXIT.TAG_ERROR);
    expect(fb.err).to.include('cannot list FB blocks (only data blocks)');
    const one = await done(['blocks', url, 'DB', '1']);
    expect(one.err).to.include('cannot read block information');
  });

  it('read and write by address in the standard DB over S7CommPlus, the same bytes as over s7://', async () => {
    const before = await done(['read', url, 'DB1.DBW4:INT', 'DB1.DBD0:REAL', '--json']);
    expect(before.code, before.err).to.equal(EXIT.OK);
    expect(JSON.parse(before.out)).to.deep.equal({ 'DB1.DBW4:INT': 7, 'DB1.DBD0:REAL': 12.5 });
    const w = await done(['write', url, 'DB1.DBW4:INT=4242']);
    expect(w.code, w.err).to.equal(EXIT.OK);
    const viaS7 = await done(['read', s7url, 'DB1.DBW4:INT', '--json']);
    expect(JSON.parse(viaS7.out)).to.deep.equal({ 'DB1.DBW4:INT': 4242 });
  });

  it('a wrong pin is refused before any S7CommPlus data, with the certificate and the URL parameter that pins it', async () => {
    const wrong = url.replace(/fingerprint=[0-9A-F]+/, `fingerprint=${'ab'.repeat(32)}`);
    const r = await done(['read', wrong, 'DB1.DBW4:INT']);
    expect(r.code).to.equal(EXIT.CONNECTION);
    expect(r.out).to.equal('');
    expect(r.err).to.include(`pin the new one with fingerprint=${fingerprint}`);
    expect(r.err).to.include('CN=plcwire simulator');
  });

  describe('the password', () => {
    /** What the client does with a password today: it reached it (no legitimation yet), and nothing shows it. */
    function reachedClient(r: { code: number; out: string; err: string }): void {
      expect(r.out + r.err).not.to.include(SECRET);
      expect(r.err).to.include('a password (legitimation)');
    }

    it('from PLCWIRE_PASSWORD reaches the client and is never printed, not with --debug nor --json', async () => {
      reachedClient(await done(['read', url, 'DB1.DBW4:INT', '--debug'], { PLCWIRE_PASSWORD: SECRET }));
      reachedClient(await done(['info', url, '--json'], { PLCWIRE_PASSWORD: SECRET }));
      // Without it, the same command connects: the password was the difference.
      const plain = await done(['read', url, 'DB1.DBW4:INT']);
      expect(plain.code, plain.err).to.equal(EXIT.OK);
    });

    it('from --password-file: its first line (CRLF and a BOM trimmed), before PLCWIRE_PASSWORD', async () => {
      const file = path.join(tmp, 'password.txt');
      fs.writeFileSync(file, `\uFEFF${SECRET}\r\nsecond line\r\n`);
      reachedClient(await done(['read', url, 'DB1.DBW4:INT', '--password-file', file, '--debug']));
      reachedClient(await done(['blocks', url, '--password-file', file], { PLCWIRE_PASSWORD: 'other' }));
    });

    it('a missing or empty file, --password on the command line, and a file for another protocol are usage errors that never echo a secret', async () => {
      const missing = await done(['read', url, 'DB1.DBW4:INT', '--password-file', path.join(tmp, 'nope.txt')]);
      expect(missing.code).to.equal(EXIT.USAGE);
      expect(missing.err).to.include(`--password-file: no such file: ${path.join(tmp, 'nope.txt')}`);
      const empty = path.join(tmp, 'empty.txt');
      fs.writeFileSync(empty, '\n' + SECRET);
      const e = await done(['read', url, 'DB1.DBW4:INT', '--password-file', empty]);
      expect(e.code).to.equal(EXIT.USAGE);
      expect(e.err).to.include('its first line is empty').and.not.include(SECRET);
      for (const flag of [['--password', SECRET], [`--password=${SECRET}`]]) {
        const f = await done(['read', url, 'DB1.DBW4:INT', ...flag]);
        expect(f.code).to.equal(EXIT.USAGE);
        expect(f.err).to.include('--password is not an option: give the password in PLCWIRE_PASSWORD or with --password-file FILE');
        expect(f.err).not.to.include(SECRET);
      }
      const s7 = await done(['read', s7url, 'DB1.DBW4:INT', '--password-file', empty]);
      expect(s7.code).to.equal(EXIT.USAGE);
      expect(s7.err).to.include('--password-file is for s7plus:// URLs');
    });

    it('a PLC protected with the simulator --password-file: without a password a write is refused and nothing changes; the password of the file reaches the client', async () => {
      const pwFile = path.join(tmp, 'plc-password.txt');
      fs.writeFileSync(pwFile, `${SECRET}\n`);
      const guarded = await startSimulator(['--password-file', pwFile]);
      try {
        expect(guarded.sim.output().out).to.include('protected: writes need the password').and.not.include(SECRET);
        const w = await done(['write', guarded.url, 'DB1.DBW4:INT=99']);
        expect(w.code, w.err).to.equal(EXIT.TAG_ERROR);
        const r = await done(['read', guarded.s7url, 'DB1.DBW4:INT', '--json']);
        expect(JSON.parse(r.out)).to.deep.equal({ 'DB1.DBW4:INT': 7 });
        reachedClient(await done(['write', guarded.url, 'DB1.DBW4:INT=99', '--password-file', pwFile]));
      } finally {
        await stop(guarded.sim);
      }
    });

    it('in the URL it is refused without echoing it', async () => {
      const r = await done(['read', `${url}&password=${SECRET}`, 'DB1.DBW4:INT']);
      expect(r.code).to.equal(EXIT.USAGE);
      expect(r.out + r.err).not.to.include(SECRET);
      expect(r.err).to.include('PLCWIRE_PASSWORD');
    });
  });

  it('help: browse has its usage and example; watch says the PLC reports changes on s7plus://; the global usage names the password ways', async () => {
    const b = await done(['browse', '--help']);
    expect(b.code).to.equal(EXIT.OK);
    expect(b.out)
      .to.match(/^usage: plcwire browse <s7plus-url>/)
      .and.match(/\nexample:\n {2}plcwire browse "s7plus:\/\//);
    const w = await done(['watch', '--help']);
    expect(w.out).to.include('On s7plus:// the PLC reports the changes').and.include('--cycle ms');
    const all = await done(['--help']);
    expect(all.out).to.include('plcwire browse <s7plus-url>').and.include('PLCWIRE_PASSWORD or --password-file FILE');
  });

  describe('watch', () => {
    it('subscribes: a change written through a second client shows long before the 60 s poll; a tag that cannot be subscribed is polled and said so', async function () {
      const writer = createClient(url) as S7PlusClient;
      await writer.connect();
      const w = run(['watch', url, '"Recipe".Step', '"Tank".Count', 'MW10', '--interval', '60000']);
      try {
        await writer.write({ '"Recipe".Step': 21 });
        await until(() => /"Recipe"\.Step = \d+/.test(w.output().out), 20000, 'the first value line');
        await until(() => /subscribed to 3 tag\(s\)/.test(w.output().err), 20000, 'the subscription');
        await until(() => /MW10 cannot be subscribed .*polled every 60000 ms/.test(w.output().err), 20000, 'the fallback message');
        const started = Date.now();
        await writer.write({ '"Recipe".Step': 22 });
        await until(() => /"Recipe"\.Step = 22\n/.test(w.output().out), 5000, 'the changed value line');
        const latency = Date.now() - started;
        this.test!.title += ` (a change showed after ${latency} ms)`;
        expect(latency).to.be.below(1000);
        expect(w.output().out).to.match(/"Tank"\.Count = \d+/);
        // MW10 was read at once when it fell back to polling, not after the 60 s interval: its poll's outcome is on stderr.
        await until(() => /MW10.*(no such|refused|not)/i.test(w.output().err.split('polled every')[1] ?? ''), 5000, 'the poll of MW10');
        // Only one line per change: the value did not change again, no poll ran.
        expect(w.output().out.match(/"Recipe"\.Step = 22/g)).to.have.length(1);
      } finally {
        w.child.kill('SIGINT');
        expect(await w.exit).to.equal(EXIT.INTERRUPTED);
        await writer.close();
      }
    });
  });

  describe('browse', () => {
    it('refuses a URL that is not s7plus:// (the sources are listed by plcwire symbols)', async () => {
      const r = await done(['browse', s7url]);
      expect(r.code).to.equal(EXIT.USAGE);
      expect(r.err).to.include('give an s7plus:// URL (for s7://, list the sources with plcwire symbols)');
    });

    it('--json lists the PLC tags as plcwire symbols does: byte, bit and address null in the optimized block', async () => {
      const r = await done(['browse', url, '--json']);
      expect(r.code, r.err).to.equal(EXIT.OK);
      const rows = new Map((JSON.parse(r.out) as { name: string }[]).map((row) => [row.name, row]));
      expect(rows.get('"Recipe".Step')).to.deep.equal({ name: '"Recipe".Step', type: 'INT', db: 2, byte: null, bit: null, address: null });
      // What `plcwire symbols --json` prints for the same member of the sources: the PLC's offset equals it.
      expect(rows.get('"Tank".Count')).to.deep.equal({
        name: '"Tank".Count',
        type: 'INT',
        db: 1,
        byte: 4,
        bit: null,
        address: 'DB1.DBW4:INT',
      });
      expect(rows.get('"Tank".Alarm')).to.deep.equal({ name: '"Tank".Alarm', type: 'BOOL', db: 1, byte: 6, bit: 1, address: 'DB1.DBX6.1' });
      const text = await done(['browse', url]);
      expect(text.out.split('\n')[0]).to.match(/^name\s+address\s+type\s+byte\s+bit$/);
    });

    it('read and write a member of the optimized block by name', async () => {
      const w = await done(['write', url, '"Recipe".Step=9']);
      expect(w.code, w.err).to.equal(EXIT.OK);
      const r = await done(['read', url, '"Recipe".Step', '--json']);
      expect(r.code, r.err).to.equal(EXIT.OK);
      expect(JSON.parse(r.out)).to.deep.equal({ '"Recipe".Step': 9 });
    });
  });
});
