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

  it('info: the identity PUT/GET gives for the profile (order code, firmware), the CPU state and the certificate of the TLS session the fingerprint pinned', async () => {
    const r = await done(['info', url, '--json']);
    expect(r.code, r.err).to.equal(EXIT.OK);
    const info = JSON.parse(r.out) as Record<string, unknown> & { certificate: { fingerprint: string; subject: string } };
    expect(info).to.include({
      orderCode: '6ES7 516-3AN02-0AB0',
      firmware: 'V3.1',
      state: 'RUN',
      device: '1;6ES7 516-3AN02-0AB0 ;V3.1',
      protocolVersion: 2,
    });
    expect(info.certificate.fingerprint).to.equal(fingerprint);
    expect(info.certificate.subject).to.include('CN=plcwire simulator');
    // The same order code as s7:// tells, and its firmware's major.minor: the device string carries no more.
    const s7 = JSON.parse((await done(['info', s7url, '--json'])).out) as { orderCode: string; firmware: string };
    expect(s7.orderCode).to.equal(info.orderCode);
    expect(s7.firmware.startsWith(`${info.firmware as string}.`)).to.equal(true);
    const text = await done(['info', url]);
    expect(text.out).to.match(/^orderCode: 6ES7 516-3AN02-0AB0\nfirmware: V3\.1\nstate: RUN\n/);
  });

  it('blocks: the data blocks with their names and access (standard, optimized); a type S7CommPlus does not list is refused before connecting', async () => {
    const all = await done(['blocks', url]);
    expect(all.code, all.err).to.equal(EXIT.OK);
    expect(all.out).to.equal('DB1  Tank  standard\nDB2  Recipe  optimized\n');
    const json = await done(['blocks', url, '--json']);
    expect(JSON.parse(json.out)).to.deep.equal({
      DB: [
        { number: 1, name: 'Tank', optimized: false },
        { number: 2, name: 'Recipe', optimized: true },
      ],
    });
    const db = await done(['blocks', url, 'DB', '--json']);
    expect(JSON.parse(db.out)).to.deep.equal({ type: 'DB', numbers: [1, 2] });
    const fb = await done(['blocks', url, 'FB']);
    expect(fb.code).to.equal(EXIT.TAG_ERROR);
    expect(fb.err).to.include('cannot list FB blocks (only data blocks)');
    const one = await done(['blocks', url, 'DB', '1']);
    expect(one.err).to.include('cannot read block information');
  });

  it('doctor: the S7CommPlus walk in text and --json, a name of the optimized block with its value and type; unpinned, the TLS step fails (exit 3) with the URL that pins it', async () => {
    const r = await done(['doctor', url, '"Recipe".Step', '--json']);
    expect(r.code, r.out + r.err).to.equal(EXIT.OK);
    const report = JSON.parse(r.out) as { ok: boolean; steps: { step: string; ok: boolean; detail: string }[] };
    expect(report.ok).to.equal(true);
    expect(report.steps.map((s) => s.step)).to.deep.equal([
      'tcp',
      'cotp',
      'InitSSL',
      'TLS',
      'session',
      'password',
      'identity',
      'browse',
      'symbol "Recipe".Step',
    ]);
    expect(report.steps.at(-1)!.detail).to.match(/^"Recipe"\.Step = -?\d+ \(INT\)$/);
    const text = await done(['doctor', url.replace(/fingerprint=[0-9A-F]+&?/, '')]);
    expect(text.code).to.equal(EXIT.CONNECTION);
    expect(text.out)
      .to.match(/^ok {3}tcp: /m)
      .and.match(/^FAIL TLS: the PLC's certificate was refused/m);
    expect(text.out).to.contain(`fix: Check the fingerprint`).and.contain(`fingerprint=${fingerprint}`);
    const missing = await done(['doctor', url, '"Recipe".Nope']);
    expect(missing.code).to.equal(EXIT.TAG_ERROR);
    expect(missing.out).to.match(/^FAIL symbol "Recipe".Nope: /m);
  });

  it('doctor with a password (PLCWIRE_PASSWORD): it goes to the client, never to the output, text or --json', async () => {
    for (const json of [[], ['--json']]) {
      const r = await done(['doctor', url, ...json], { PLCWIRE_PASSWORD: SECRET });
      expect(r.out + r.err).to.not.contain(SECRET);
      expect(r.out).to.contain('password');
    }
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

  it('a REAL read by name in an optimized DB shows the digits TIA shows (the browsed table gives its type), in text and --json, alone, in an array and in its whole block', async () => {
    const w = await done(['write', url, '"Recipe".Target=40.4']);
    expect(w.code, w.err).to.equal(EXIT.OK);
    const text = await done(['read', url, '"Recipe".Target']);
    expect(text.out).to.equal('"Recipe".Target = 40.4\n');
    const a = await done(['write', url, '"Tank".Temps=[1.1, 40.4, 3.3]']);
    expect(a.code, a.err).to.equal(EXIT.OK);
    const json = await done(['read', url, '"Recipe".Target', '"Tank".Temps', '"Recipe"', '--json']);
    const values = JSON.parse(json.out);
    expect(values).to.deep.include({ '"Recipe".Target': 40.4, '"Tank".Temps': [1.1, 40.4, 3.3] });
    // A data block named alone is the struct of its members, as with compiled sources.
    expect(values['"Recipe"']).to.include({ Target: 40.4, Done: false });
    expect(Math.fround(40.4)).to.not.equal(40.4); // as read, the float32 would show 40.400001525878906
  });

  it('a struct partly given writes the members it names, as over s7:// (one struct walker for both drivers)', async () => {
    const w = await done(['write', url, '"Recipe".Step=47', '"Tank".Motor={"Speed":1200}', '--yes']);
    expect(w.code, w.err).to.equal(EXIT.OK);
    const r = await done(['read', url, '"Recipe".Step', '"Tank".Motor', '--json']);
    expect(JSON.parse(r.out)).to.deep.equal({ '"Recipe".Step': 47, '"Tank".Motor': { Speed: 1200, On: false } });
  });

  it('every value is checked before the first byte is sent: a bad member or an unknown name writes nothing (exit 2), naming it', async () => {
    const member = await done(['write', url, '"Recipe".Step=48', '"Tank".Motor={"Speed":1300,"Nope":1}', '--yes']);
    expect(member.code, member.err).to.equal(EXIT.USAGE);
    expect(member.err).to.match(/"Tank"\.Motor.*no member "Nope" \(its members: Speed, On\)/);
    const range = await done(['write', url, '"Recipe".Step=48', '"Tank".Motor={"On":3}', '--yes']);
    expect(range.code, range.err).to.equal(EXIT.USAGE);
    const name = await done(['write', url, '"Recipe".Step=48', '"Tank".Motr={"Speed":1}', '--yes']);
    expect(name.code, name.err).to.equal(EXIT.USAGE);
    expect(name.err).to.match(/unknown name "Tank"\.Motr on the PLC; did you mean "Tank"\.Motor/);
    const r = await done(['read', url, '"Recipe".Step', '"Tank".Motor', '--json']);
    expect(JSON.parse(r.out)).to.deep.equal({ '"Recipe".Step': 47, '"Tank".Motor': { Speed: 1200, On: false } });
  });

  it('a write the PLC refuses after others were written says which were written and exits 1, not 2 (which means nothing was sent)', async () => {
    const w = await done(['write', url, '"Recipe".Step=49', 'DB1.DBW900:INT=1', '--yes']);
    expect(w.code, w.err).to.equal(EXIT.TAG_ERROR);
    expect(w.err).to.include('partly written: "Recipe".Step written; DB1.DBW900:INT not written');
    const r = await done(['read', url, '"Recipe".Step', '--json']);
    expect(JSON.parse(r.out)).to.deep.equal({ '"Recipe".Step': 49 });
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
    /** A password given to a PLC that wants none: the command works (full access without it), and nothing shows the password. */
    function reachedClient(r: { code: number; out: string; err: string }): void {
      expect(r.out + r.err).not.to.include(SECRET);
      expect(r.code, r.err).to.equal(EXIT.OK);
    }

    it('from PLCWIRE_PASSWORD, to a PLC that wants none: the command works and never prints it, not with --debug nor --json', async () => {
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

    it('a PLC protected with the simulator --password-file: without a password a write is refused saying how to give it; with the file or PLCWIRE_PASSWORD it goes through; a wrong one is refused; the password is never printed', async () => {
      const pwFile = path.join(tmp, 'plc-password.txt');
      fs.writeFileSync(pwFile, `${SECRET}\n`);
      const guarded = await startSimulator(['--password-file', pwFile]);
      try {
        expect(guarded.sim.output().out).to.include('protected: writes need the password').and.not.include(SECRET);
        const w = await done(['write', guarded.url, 'DB1.DBW4:INT=99']);
        expect(w.code, w.err).to.equal(EXIT.TAG_ERROR);
        expect(w.err).to.include('gives this connection read access only without its password');
        expect(w.err).to.include('PLCWIRE_PASSWORD or --password-file FILE for the CLI');
        const read = async () => JSON.parse((await done(['read', guarded.s7url, 'DB1.DBW4:INT', '--json'])).out) as unknown;
        expect(await read()).to.deep.equal({ 'DB1.DBW4:INT': 7 });
        // The password of the file legitimates the session: the write goes through.
        const byFile = await done(['write', guarded.url, 'DB1.DBW4:INT=99', '--password-file', pwFile, '--debug']);
        expect(byFile.code, byFile.err).to.equal(EXIT.OK);
        expect(byFile.out + byFile.err).not.to.include(SECRET);
        expect(await read()).to.deep.equal({ 'DB1.DBW4:INT': 99 });
        // The file comes before PLCWIRE_PASSWORD.
        const first = await done(['write', guarded.url, 'DB1.DBW4:INT=97', '--password-file', pwFile], { PLCWIRE_PASSWORD: 'other' });
        expect(first.code, first.err).to.equal(EXIT.OK);
        // So does PLCWIRE_PASSWORD; reads with --json show it nowhere.
        const byEnv = await done(['write', guarded.url, 'DB1.DBW4:INT=98'], { PLCWIRE_PASSWORD: SECRET });
        expect(byEnv.code, byEnv.err).to.equal(EXIT.OK);
        expect(await read()).to.deep.equal({ 'DB1.DBW4:INT': 98 });
        const json = await done(['read', guarded.url, 'DB1.DBW4:INT', '"Recipe".Step', '--json', '--debug'], { PLCWIRE_PASSWORD: SECRET });
        expect(JSON.parse(json.out)).to.deep.equal({ 'DB1.DBW4:INT': 98, '"Recipe".Step': 3 });
        expect(json.out + json.err).not.to.include(SECRET);
        // A wrong one: refused in words that name the PLC, never the password; nothing written.
        const wrong = `${SECRET}-old`;
        const refused = await done(['write', guarded.url, 'DB1.DBW4:INT=1', '--debug'], { PLCWIRE_PASSWORD: wrong });
        expect(refused.code).to.not.equal(EXIT.OK);
        expect(refused.err).to.include('refused the password (wrong password');
        expect(refused.out + refused.err).not.to.include(wrong);
        expect(await read()).to.deep.equal({ 'DB1.DBW4:INT': 98 });
        // A wrong password is a connection that could not be made: one exit code (3) in read, write and doctor, as the README's table says.
        const readWrong = await done(['read', guarded.url, 'DB1.DBW4:INT'], { PLCWIRE_PASSWORD: wrong });
        const doctorWrong = await done(['doctor', guarded.url], { PLCWIRE_PASSWORD: wrong });
        expect(doctorWrong.out).to.match(/^FAIL password: /m);
        expect([refused.code, readWrong.code, doctorWrong.code], readWrong.err).to.deep.equal([
          EXIT.CONNECTION,
          EXIT.CONNECTION,
          EXIT.CONNECTION,
        ]);
        expect(readWrong.out + readWrong.err + doctorWrong.out + doctorWrong.err).not.to.include(wrong);
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
      const w = run(['watch', url, '"Recipe".Step', '"Tank".Count', 'DB99.DBW0', '--interval', '60000']);
      try {
        await writer.write({ '"Recipe".Step': 21 });
        await until(() => /"Recipe"\.Step = \d+/.test(w.output().out), 20000, 'the first value line');
        await until(() => /subscribed to 3 tag\(s\)/.test(w.output().err), 20000, 'the subscription');
        await until(() => /DB99\.DBW0 cannot be subscribed .*polled every 60000 ms/.test(w.output().err), 20000, 'the fallback message');
        const started = Date.now();
        await writer.write({ '"Recipe".Step': 22 });
        await until(() => /"Recipe"\.Step = 22\n/.test(w.output().out), 5000, 'the changed value line');
        const latency = Date.now() - started;
        this.test!.title += ` (a change showed after ${latency} ms)`;
        expect(latency).to.be.below(1000);
        expect(w.output().out).to.match(/"Tank"\.Count = \d+/);
        // DB99.DBW0 was read at once when it fell back to polling, not after the 60 s interval: its poll's outcome is on stderr.
        await until(
          () => /DB99\.DBW0.*(no such|refused|not)/i.test(w.output().err.split('polled every')[1] ?? ''),
          5000,
          'the poll of DB99.DBW0',
        );
        // Only one line per change: the value did not change again, no poll ran.
        expect(w.output().out.match(/"Recipe"\.Step = 22/g)).to.have.length(1);
      } finally {
        w.child.kill('SIGINT');
        expect(await w.exit).to.equal(EXIT.INTERRUPTED);
        await writer.close();
      }
    });
    it('a REAL the PLC reports shows the digits TIA shows, as read and the doctor show it (one rule on every path), in text and --json', async () => {
      const writer = createClient(url) as S7PlusClient;
      await writer.connect();
      const w = run(['watch', url, '"Recipe".Target', '--interval', '60000']);
      const j = run(['watch', url, '"Recipe".Target', '"Tank".Temps', '--interval', '60000', '--json']);
      try {
        await until(
          () => /subscribed to 1 tag/.test(w.output().err) && /subscribed to 2 tag/.test(j.output().err),
          20000,
          'both subscriptions',
        );
        await writer.write({ '"Recipe".Target': 11.1, '"Tank".Temps': [1.1, 75.9, 3.3] });
        await until(() => /"Recipe"\.Target = 11\.1\n/.test(w.output().out), 5000, 'the text line with 11.1');
        await until(() => j.output().out.includes('"\\"Tank\\".Temps":[1.1,75.9,3.3]'), 5000, 'the JSON line with the array');
        expect(w.output().out).to.not.match(/11\.10\d{5,}/);
        const doctor = await done(['doctor', url, '"Recipe".Target']);
        expect(doctor.out).to.match(/"Recipe"\.Target = 11\.1 \(Real\)|"Recipe"\.Target = 11\.1 \(REAL\)/);
      } finally {
        w.child.kill('SIGINT');
        j.child.kill('SIGINT');
        await Promise.all([w.exit, j.exit]);
        await writer.close();
      }
    });
  });

  it('serve with an optimized source only (demo/Tank.db): the try: line is the s7plus:// read by name it serves, pinned, and works as printed', async () => {
    const tank = path.resolve(__dirname, '../../demo/Tank.db');
    const only = run(['serve', 's7', '--profile', 's7-1500', '--port', '0', '--source', tank, '--db', 'Tank=2']);
    try {
      await until(() => /Ctrl-C stops/.test(only.output().out + only.output().err), 20000, 'the simulator to start');
      const fp = /certificate SHA-256 ([0-9A-F]{64})/.exec(only.output().out)![1]!;
      const line = /^try: plcwire (.+)$/m.exec(only.output().out)![1]!;
      expect(line).to.match(new RegExp(`^read "s7plus://127\\.0\\.0\\.1:\\d+\\?fingerprint=${fp}" '"Tank"\\.Phase'$`));
      // As a user pastes it into a shell.
      const child = spawn('sh', ['-c', `"${process.execPath}" "${BIN}" ${line}`], { stdio: ['ignore', 'pipe', 'pipe'] });
      let out = '';
      let err = '';
      child.stdout.on('data', (d: Buffer) => (out += d.toString()));
      child.stderr.on('data', (d: Buffer) => (err += d.toString()));
      const [code] = await once(child, 'exit');
      expect(code, err).to.equal(0);
      expect(out).to.equal('"Tank".Phase = "Filling"\n');
    } finally {
      await stop(only);
    }
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
