/**
 * Tags by name on the command line, through the installed binary
 * (bin/plcwire.js) in child processes: `plcwire symbols` (table, --json,
 * --csv, errors as file:line:column), --db forms, and `serve s7 --source`
 * with read, write, watch and blocks by symbol against it over a real socket.
 * Fixtures: test/fixtures/symbols/cli/ (Tank.db's bytes are worked out in
 * test/symbols-simulator.test.ts).
 */
import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import { once } from 'node:events';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { EXIT } from '../lib/cli/io';
import { freePort } from './support/net';
import { until } from './support/wait';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');
const FIXTURES = path.resolve(__dirname, '../../test/fixtures/symbols/cli');

/** The real bin in a child process run in the fixtures' folder (so sources are named as a user types them); output until it exits. */
function run(args: string[]): { child: ChildProcess; output: () => { out: string; err: string }; exit: Promise<number> } {
  const child = spawn(process.execPath, [BIN, ...args], { cwd: FIXTURES, stdio: ['pipe', 'pipe', 'pipe'] });
  let out = '';
  let err = '';
  child.stdout!.on('data', (d: Buffer) => (out += d.toString()));
  child.stderr!.on('data', (d: Buffer) => (err += d.toString()));
  const exit = once(child, 'exit').then(([code]) => code as number);
  return { child, output: () => ({ out, err }), exit };
}

/** Runs to the end: exit code and output. */
async function done(args: string[]): Promise<{ code: number; out: string; err: string }> {
  const r = run(args);
  const code = await r.exit;
  return { code, ...r.output() };
}

interface Row {
  name: string;
  type: string;
  db: number | null;
  byte: number;
  bit: number | null;
  address: string;
}

describe('plcwire symbols and tags by name (the installed binary)', function () {
  this.timeout(30000);

  describe('symbols', () => {
    it('--json gives every member with name, type, db, byte, bit (0-7 for BOOL, else null) and address', async () => {
      const r = await done(['symbols', 'Tank.db', '--db', 'Tank=1', '--json']);
      expect(r.code, r.err).to.equal(0);
      const rows = JSON.parse(r.out) as Row[];
      const by = new Map(rows.map((row) => [row.name, row]));
      expect(by.get('"Tank".Level')).to.deep.equal({
        name: '"Tank".Level',
        type: 'REAL',
        db: 1,
        byte: 0,
        bit: null,
        address: 'DB1.DBD0:REAL',
      });
      expect(by.get('"Tank".Valve')).to.include({ db: 1, byte: 4, bit: 2, address: 'DB1.DBX4.2' });
      expect(by.get('"Tank".Name')).to.include({ byte: 8, bit: null, address: 'DB1.DBB8:STRING[6]' });
      expect(by.get('"Tank".Name')!.type).to.equal('STRING[6]');
      expect(by.get('"Tank".Flags')!.type).to.equal('ARRAY[0..9] OF BOOL');
      expect(by.get('"Tank".Motor')!.type).to.equal('STRUCT');
      expect(by.get('"Tank".Label')).to.include({ byte: 22, address: 'DB1.DBB22:WSTRING[3]' });
      expect(by.get('"Tank".Flags[9]')).to.include({ byte: 63, bit: 1 });
      expect(by.get('"Tank".Motor')).to.include({ byte: 64, bit: null });
      expect(by.get('"Tank".Motor.On')).to.include({ byte: 68, bit: 0, address: 'DB1.DBX68.0' });
      // Declaration order: a struct before its members.
      const names = rows.map((row) => row.name);
      expect(names.indexOf('"Tank".Motor')).to.be.below(names.indexOf('"Tank".Motor.Speed'));
      expect(names[0]).to.equal('"Tank".Level');
    });

    it('the table has a header and aligned columns: name, address, type, byte, bit', async () => {
      const r = await done(['symbols', 'Tank.db', '--db', 'Tank=1']);
      expect(r.code, r.err).to.equal(0);
      const lines = r.out.trimEnd().split('\n');
      expect(lines[0]).to.match(/^name\s+address\s+type\s+byte\s+bit$/);
      const level = lines.find((l) => l.startsWith('"Tank".Level '))!;
      expect(level).to.match(/^"Tank"\.Level\s+DB1\.DBD0:REAL\s+\S+\s+0$/);
      expect(lines.find((l) => l.startsWith('"Tank".Valve '))).to.match(/DB1\.DBX4\.2\s+\S+\s+4\s+2$/);
      const column = (l: string, word: string) => l.indexOf(word);
      expect(column(level, 'DB1.')).to.equal(column(lines[0]!, 'address'));
      const on = lines.find((l) => l.startsWith('"Tank".Motor.On '))!;
      expect(column(on, 'DB1.')).to.equal(column(lines[0]!, 'address'));
    });

    it('--csv has a header row and quotes fields as RFC 4180 (quotes doubled), lines ending CRLF', async () => {
      const r = await done(['symbols', 'Tank.db', 'Mix.db', '--db', 'Tank=1', '--db', 'Mix=2', '--csv']);
      expect(r.code, r.err).to.equal(0);
      const lines = r.out.split('\r\n');
      expect(lines[0]).to.equal('name,address,type,db,byte,bit');
      expect(lines.at(-1)).to.equal('');
      expect(lines.find((l) => l.startsWith('"""Tank"".Level"'))).to.match(/^"""Tank""\.Level",DB1\.DBD0:REAL,REAL,1,0,$/);
      expect(lines.find((l) => l.startsWith('"""Tank"".Running"'))).to.match(/,1,4,0$/);
      expect(lines.find((l) => l.startsWith('"""Mix"".Ratio"'))).to.match(/^"""Mix""\.Ratio",DB2\.DBD0:REAL,\w+,2,0,$/);
      expect(r.out).not.to.match(/[^\r]\n/);
    });

    it('a source that does not compile prints file:line:column: problem, nothing on stdout, and exits 2', async () => {
      const r = await done(['symbols', 'Tank.db', 'Broken.db', '--db', 'Tank=1', '--db', 'Broken=3']);
      expect(r.code).to.equal(EXIT.USAGE);
      expect(r.out).to.equal('');
      expect(r.err).to.match(/^Broken\.db:5:\d+: .*Reel/);
      expect(r.err.trim().split('\n')).to.have.length(1);
    });

    it('a missing file is "no such file: NAME" (exit 2, no errno code, no --help pointer) wherever a file is named', async () => {
      const cases: [string[], string][] = [
        [['symbols', 'Tank.db', 'Nope.db', '--db', 'Tank=1'], 'Nope.db'],
        [['read', 's7://127.0.0.1:1', '"Tank".Level', '--symbols', 'Plant.db', '--db', 'Plant=1'], 'Plant.db'],
        [['write', 's7://127.0.0.1:1', '"Tank".Level=1', '--symbols', 'gone/Tank.db'], 'gone/Tank.db'],
        [['watch', 's7://127.0.0.1:1', '"Tank".Level', '--symbols', 'Nope.sdf'], 'Nope.sdf'],
        [['serve', 's7', '--port', '0', '--source', 'Nope.db', '--db', 'Nope=1'], 'Nope.db'],
        [['serve', 'fetchwrite', '--port', '0', '--source', 'Nope.db', '--db', 'Nope=1'], 'Nope.db'],
        [['serve', 's7', '--port', '0', '--layout', 'nope.json'], 'nope.json'],
      ];
      const results = await Promise.all(cases.map(([args]) => done(args)));
      results.forEach((r, i) => {
        const [args, file] = cases[i]!;
        expect(r.code, `${args.join(' ')}: ${r.err}`).to.equal(EXIT.USAGE);
        expect(r.err, args.join(' ')).to.equal(`plcwire: no such file: ${file}\n`);
        expect(r.out).to.equal('');
      });
      const folder = await done(['symbols', '.']);
      expect(folder.code).to.equal(EXIT.USAGE);
      expect(folder.err).to.equal('plcwire: . is a folder, not a file\n');
      const none = await done(['symbols']);
      expect(none.code).to.equal(EXIT.USAGE);
      expect(none.out).to.equal('');
    });

    it('--db takes NAME=N with the name bare or quoted as TIA writes it; a bad form is named', async () => {
      const forms = [['--db', 'Mix=2'], ['--db', '"Mix"=2'], ['--db=Mix=2'], ['--db', ' "Mix" = 2 ']];
      const outs = await Promise.all(forms.map((f) => done(['symbols', 'Mix.db', ...f, '--json'])));
      for (const o of outs) expect(o.code, o.err).to.equal(0);
      expect(new Set(outs.map((o) => o.out)).size).to.equal(1);
      expect((JSON.parse(outs[0]!.out) as Row[])[0]).to.include({ name: '"Mix".Ratio', db: 2, address: 'DB2.DBD0:REAL' });
      for (const [bad, message] of [
        ['Mix', /--db "Mix": give NAME=NUMBER/],
        ['=2', /--db "=2": give NAME=NUMBER/],
        ['Mix=0', /--db "Mix=0": "0" is not a DB number 1\.\.65535/],
        ['Mix=x', /--db "Mix=x": "x" is not a DB number/],
        ['Mix=70000', /"70000" is not a DB number/],
      ] as const) {
        const r = await done(['symbols', 'Mix.db', '--db', bad]);
        expect(r.code, bad).to.equal(EXIT.USAGE);
        expect(r.err, bad).to.match(message);
        expect(r.out).to.equal('');
      }
      const misspelt = await done(['symbols', 'Tank.db', '--db', 'Tnak=7']);
      expect(misspelt.code).to.equal(EXIT.USAGE);
      expect(misspelt.err).to.contain('a number is given for "Tnak", which is not a DB of the sources (did you mean "Tank"? DBs: "Tank")');
      expect(misspelt.err).to.not.contain('has no number');
      expect(misspelt.out).to.equal('');
      const twice = await done(['symbols', 'Mix.db', '--db', 'Mix=2', '--db', 'Mix=3']);
      expect(twice.err).to.match(/--db gives "Mix" two numbers: 2 and 3/);
      const shared = await done(['symbols', 'Mix.db', 'Tank.db', '--db', 'Mix=2', '--db', 'Tank=2']);
      expect(shared.err).to.match(/--db gives DB2 to two blocks: "Mix" and "Tank"/);
    });
  });

  describe('serve s7 --source, and read, write, watch by symbol', () => {
    let srv: ReturnType<typeof run>;
    let url: string;
    const symbols = ['--symbols', 'Tank.db', '--db', 'Tank=1'];

    before(async () => {
      const port = await freePort();
      srv = run(['serve', 's7', '--port', String(port), '--profile', 's7-300', '--source', 'Tank.db', '--db', 'Tank=1']);
      await until(() => /^try: /m.test(srv.output().out), 10000, 'serve prints how to reach it');
      url = `s7://127.0.0.1:${port}?rack=0&slot=2`;
    });

    after(async () => {
      srv.child.kill('SIGINT');
      expect(await srv.exit).to.equal(0);
    });

    it('prints the blocks it serves with their lengths, and a read by name to try', () => {
      const out = srv.output().out;
      expect(out).to.match(/^serving DB1 "Tank" of 70 bytes \(Tank\.db\)$/m);
      expect(out).to.match(/^try: plcwire read "s7:\/\/127\.0\.0\.1:\d+\?rack=0&slot=2" --symbols Tank\.db --db Tank=1 '"Tank"\.Level'$/m);
    });

    it('block info reports the declared length', async () => {
      const r = await done(['blocks', url, 'DB', '1', '--json']);
      expect(r.code, r.err).to.equal(0);
      expect(JSON.parse(r.out)).to.include({ number: 1, mc7Size: 70 });
    });

    it('read mixes names (quoted or not) and addresses, keyed as given', async () => {
      const r = await done(['read', url, '"Tank".Level', 'Tank.Count', 'Tank.Name', 'DB1.DBD64:REAL', ...symbols, '--json']);
      expect(r.code, r.err).to.equal(0);
      expect(JSON.parse(r.out)).to.deep.equal({ '"Tank".Level': 12.5, 'Tank.Count': -2, 'Tank.Name': 'AB', 'DB1.DBD64:REAL': 1.5 });
      const plain = await done(['read', url, '"Tank".Level', 'Tank.Valve', ...symbols]);
      expect(plain.out).to.equal('"Tank".Level = 12.5\nTank.Valve = true\n');
    });

    it('a whole STRUCT reads as an object keyed by member name, in --json and in plain text', async () => {
      const json = await done(['read', url, '"Tank".Motor', ...symbols, '--json']);
      expect(json.code, json.err).to.equal(0);
      expect(JSON.parse(json.out)).to.deep.equal({ '"Tank".Motor': { Speed: 1.5, On: true } });
      const plain = await done(['read', url, '"Tank".Motor', ...symbols]);
      expect(plain.out).to.equal('"Tank".Motor = { Speed: 1.5, On: true }\n');
    });

    it('write parses each value per its symbol type, a STRUCT as JSON; a read gives them back', async () => {
      const w = await done([
        'write',
        url,
        'Tank.Count=-300',
        'Tank.Name=hello',
        'Tank.Alarm=1',
        '"Tank".Motor={"Speed":2.5,"On":false}',
        ...symbols,
      ]);
      expect(w.code, w.err).to.equal(0);
      expect(w.out).to.include('Tank.Count = -300 ok\n');
      expect(w.out).to.include('"Tank".Motor = { Speed: 2.5, On: false } ok\n');
      const r = await done(['read', url, 'Tank.Count', 'Tank.Name', 'Tank.Alarm', 'Tank.Motor', 'DB1.DBB8', ...symbols, '--json']);
      expect(JSON.parse(r.out)).to.deep.equal({
        'Tank.Count': -300,
        'Tank.Name': 'hello',
        'Tank.Alarm': true,
        'Tank.Motor': { Speed: 2.5, On: false },
        'DB1.DBB8': 6, // the STRING[6] max-length byte the download put there
      });
    });

    it('a value that does not fit the symbol type exits 2 and writes nothing', async () => {
      const w = await done(['write', url, 'Tank.Count=70000', 'Tank.Level=1', ...symbols]);
      expect(w.code).to.equal(EXIT.USAGE);
      expect(w.err).to.match(/Tank\.Count/);
      const bad = await done(['write', url, '"Tank".Motor={"Speed":1,"Of":true}', ...symbols]);
      expect(bad.code).to.equal(EXIT.USAGE);
      expect(bad.err).to.match(/"Tank"\.Motor.*no member "Of" \(its members: Speed, On\)/);
    });

    it('an unknown name exits 2 before connecting and suggests the closest names', async () => {
      const r = await done(['read', url, 'Tank.Levle', ...symbols]);
      expect(r.code).to.equal(EXIT.USAGE);
      expect(r.out).to.equal('');
      expect(r.err).to.match(/unknown symbol Tank\.Levle; did you mean "Tank"\.Level\b/);
      const without = await done(['read', url, '"Tank".Level']);
      expect(without.code).to.equal(EXIT.USAGE);
      const dbAlone = await done(['read', url, 'MW0', '--db', 'Tank=1']);
      expect(dbAlone.err).to.match(/--db numbers the blocks of --symbols files: give --symbols too/);
    });

    it('watch prints a symbol and a struct, and their changes', async () => {
      const w = run(['watch', url, 'Tank.Level', '"Tank".Motor', ...symbols, '--interval', '50', '--json']);
      try {
        await until(() => w.output().out.includes('\n'), 10000, 'first line');
        const set = await done(['write', url, 'Tank.Level=77.5', ...symbols]);
        expect(set.code, set.err).to.equal(0);
        await until(() => w.output().out.includes('"Tank.Level":77.5'), 10000, 'the change');
      } finally {
        w.child.kill('SIGINT');
      }
      expect(await w.exit).to.equal(EXIT.INTERRUPTED);
      const lines = w
        .output()
        .out.trim()
        .split('\n')
        .map((l) => JSON.parse(l) as { values: Record<string, unknown> });
      expect(lines[0]!.values['"Tank".Motor']).to.have.keys('Speed', 'On');
      expect(lines.at(-1)!.values).to.deep.equal({ 'Tank.Level': 77.5 });
    });

    it('watch of a STRUCT prints the whole object again when one member changes, and no layout warning when the block matches', async () => {
      const w = run(['watch', url, '"Tank".Motor', ...symbols, '--interval', '50']);
      try {
        await until(() => w.output().out.includes('"Tank".Motor = {'), 10000, 'first line');
        const set = await done(['write', url, 'Tank.Motor.Speed=3.25', ...symbols]);
        expect(set.code, set.err).to.equal(0);
        await until(() => w.output().out.includes('Speed: 3.25'), 10000, 'the change');
      } finally {
        w.child.kill('SIGINT');
      }
      expect(await w.exit).to.equal(EXIT.INTERRUPTED);
      const lines = w.output().out.trim().split('\n');
      expect(lines.at(-1)).to.match(/^\S+ "Tank"\.Motor = \{ Speed: 3\.25, On: (true|false) \}$/);
      expect(w.output().err).not.to.match(/warning|note/);
    });
  });

  describe('a PLC whose data block no longer matches the sources (served from v2/Tank.db, read with Tank.db)', () => {
    // v2/Tank.db inserts a REAL after Level: the PLC's DB1 is 74 bytes, the sources declare 70, and every member after Level moved by 4.
    let srv: ReturnType<typeof run>;
    let url: string;
    const stale = ['--symbols', 'Tank.db', '--db', 'Tank=1'];
    const warning = /^warning: DB1 "Tank" is 74 bytes in the PLC, the sources declare 70: /m;

    before(async () => {
      const port = await freePort();
      srv = run(['serve', 's7', '--port', String(port), '--profile', 's7-300', '--source', 'v2/Tank.db', '--db', 'Tank=1']);
      await until(() => /^try: /m.test(srv.output().out), 10000, 'serve prints how to reach it');
      expect(srv.output().out).to.match(/^serving DB1 "Tank" of 74 bytes \(v2\/Tank\.db\)$/m);
      url = `s7://127.0.0.1:${port}?rack=0&slot=2`;
    });

    after(async () => {
      srv.child.kill('SIGINT');
      expect(await srv.exit).to.equal(0);
    });

    it("a read by name warns on stderr and still gives the values at the sources' offsets", async () => {
      const r = await done(['read', url, 'Tank.Level', 'Tank.Count', ...stale, '--json']);
      expect(r.code, r.err).to.equal(0);
      // Count's old offset (DBW6) is now the low half of Pressure (2.5 = 0x40200000): the shifted value the warning is about.
      expect(JSON.parse(r.out)).to.deep.equal({ 'Tank.Level': 12.5, 'Tank.Count': 0 });
      expect(r.err).to.match(warning);
      expect(r.err).to.match(/names in it are read at the offsets of the sources .*; recompile the sources or download the block$/m);
      expect(r.err.trim().split('\n')).to.have.length(1);
    });

    it("the sources of the PLC's own version read without a warning", async () => {
      const r = await done(['read', url, 'Tank.Count', '--symbols', 'v2/Tank.db', '--db', 'Tank=1', '--strict-symbols']);
      expect(r.code, r.err).to.equal(0);
      expect(r.out).to.equal('Tank.Count = -2\n');
      expect(r.err).to.equal('');
    });

    it('--strict-symbols: reads by name in the block fail with LAYOUT_MISMATCH (exit 1), absolute addresses of it still read', async () => {
      const r = await done(['read', url, 'Tank.Level', '"Tank".Motor', 'DB1.DBW10:INT', ...stale, '--strict-symbols', '--json']);
      expect(r.code).to.equal(EXIT.TAG_ERROR);
      expect(JSON.parse(r.out)).to.deep.equal({ 'Tank.Level': null, '"Tank".Motor': null, 'DB1.DBW10:INT': -2 });
      expect(r.err).to.match(
        /^warning: DB1 "Tank" is 74 bytes in the PLC, the sources declare 70: reads and writes by name in it are refused \(--strict-symbols\)/m,
      );
      expect(r.err).to.match(/^plcwire: .*Tank\.Level.*DB1 "Tank": the PLC's block is 74 bytes, the sources declare 70/m);
      expect(r.err).to.match(/^plcwire: .*"Tank"\.Motor.*the PLC's block is 74 bytes/m);
    });

    it('--strict-symbols: a write by name is refused and the PLC keeps its bytes', async () => {
      const w = await done(['write', url, 'Tank.Count=99', ...stale, '--strict-symbols']);
      expect(w.code).to.equal(EXIT.TAG_ERROR);
      expect(w.out).to.equal('');
      expect(w.err).to.match(/^plcwire: .*Tank\.Count.*the PLC's block is 74 bytes/m);
      const r = await done(['read', url, 'DB1.DBW6:INT', 'DB1.DBW10:INT', '--json']);
      expect(JSON.parse(r.out)).to.deep.equal({ 'DB1.DBW6:INT': 0, 'DB1.DBW10:INT': -2 });
    });

    it('--strict-symbols without --symbols is a usage error', async () => {
      const r = await done(['read', url, 'MW0', '--strict-symbols']);
      expect(r.code).to.equal(EXIT.USAGE);
      expect(r.err).to.match(/--strict-symbols checks the names of --symbols files: give --symbols too/);
    });

    it('watch keeps running, says the mismatch once for its connection, and reports the refused name once', async () => {
      const w = run(['watch', url, 'Tank.Level', 'DB1.DBD0:REAL', ...stale, '--strict-symbols', '--interval', '20', '--json']);
      try {
        await until(() => w.output().out.includes('"DB1.DBD0:REAL":12.5'), 10000, 'the absolute address');
        await until(() => /Tank\.Level: /.test(w.output().err), 10000, 'the refusal');
        // Several more polls: nothing is said again while the connection lasts.
        const polls = w.output().err.length;
        const set = await done(['write', url, 'DB1.DBD0:REAL=13.5']);
        expect(set.code, set.err).to.equal(0);
        await until(() => w.output().out.includes('"DB1.DBD0:REAL":13.5'), 10000, 'a later poll');
        expect(w.output().err.length).to.equal(polls);
      } finally {
        w.child.kill('SIGINT');
      }
      expect(await w.exit).to.equal(EXIT.INTERRUPTED);
      const err = w.output().err;
      expect(err.match(/^warning: /gm)).to.have.length(1);
      expect(err).to.match(warning);
      expect(err.match(/Tank\.Level: /g)).to.have.length(1);
    });
  });

  it('watch says a mismatch again on each reconnect, and keeps running', async () => {
    const port = await freePort();
    const serveV2 = () => run(['serve', 's7', '--port', String(port), '--profile', 's7-300', '--source', 'v2/Tank.db', '--db', 'Tank=1']);
    let srv = serveV2();
    await until(() => /^try: /m.test(srv.output().out), 10000, 'serve prints how to reach it');
    const w = run([
      'watch',
      `s7://127.0.0.1:${port}?rack=0&slot=2`,
      'Tank.Level',
      '--symbols',
      'Tank.db',
      '--db',
      'Tank=1',
      '--interval',
      '20',
    ]);
    const warnings = () => w.output().err.match(/^warning: DB1 "Tank" is 74 bytes in the PLC/gm)?.length ?? 0;
    try {
      await until(() => warnings() === 1, 10000, 'the first warning');
      srv.child.kill('SIGINT');
      expect(await srv.exit).to.equal(0);
      await until(() => /disconnected/.test(w.output().err), 10000, 'the link loss');
      srv = serveV2();
      await until(() => w.output().err.match(/^plcwire: connected/gm)?.length === 2, 20000, 'the reconnect');
      await until(() => warnings() === 2, 10000, 'the warning of the new connection');
      expect(w.child.exitCode).to.equal(null);
    } finally {
      w.child.kill('SIGINT');
      srv.child.kill('SIGINT');
      await srv.exit;
    }
    expect(await w.exit).to.equal(EXIT.INTERRUPTED);
  });

  it("the README's table of demo/Plant.db is what plcwire symbols prints", async () => {
    const readme = fs.readFileSync(path.resolve(__dirname, '../../README.md'), 'utf8');
    // Copy-pasteable from the repository's root, as the section says.
    const block = /```sh\n\s*npx plcwire symbols demo\/Plant\.db --db Plant=1\n((?:\s*# .*\n)+)/.exec(readme);
    expect(block, 'the README shows the command and its output').to.not.equal(null);
    const shown = block![1]!
      .split('\n')
      .filter(Boolean)
      .map((l) => l.replace(/^\s*# /, ''));
    const child = spawn(process.execPath, [BIN, 'symbols', 'demo/Plant.db', '--db', 'Plant=1'], { cwd: path.resolve(__dirname, '../..') });
    let out = '';
    child.stdout.on('data', (d: Buffer) => (out += d.toString()));
    const [code] = await once(child, 'exit');
    expect(code).to.equal(0);
    expect(shown).to.deep.equal(
      out
        .trimEnd()
        .split('\n')
        .map((l) => l.trimEnd()),
    );
  });

  describe('a reader that goes away (| head)', () => {
    it('symbols stops quietly with exit 0 when its stdout closes', async () => {
      const r = run(['symbols', 'Tank.db', '--db', 'Tank=1']);
      await until(() => r.output().out.length > 0, 10000, 'the first line');
      r.child.stdout!.destroy();
      const code = await r.exit;
      expect(r.output().err).to.not.match(/EPIPE|Unhandled/);
      expect(code).to.equal(0);
    });

    it('watch stops as on Ctrl-C (no crash) at its next write after its stdout closes', async () => {
      const port = await freePort();
      const srv = run(['serve', 's7', '--port', String(port), '--profile', 's7-300', '--source', 'Tank.db', '--db', 'Tank=1']);
      try {
        await until(() => /^try: /m.test(srv.output().out), 10000, 'serve prints how to reach it');
        const w = run(['watch', `s7://127.0.0.1:${port}?rack=0&slot=2`, 'Tank.Level', '--symbols', 'Tank.db', '--db', 'Tank=1']);
        await until(() => w.output().out.length > 0, 10000, 'the first value');
        w.child.stdout!.destroy();
        // A pipe tells its writer that the reader left at the next write: change the value.
        const write = await done([
          'write',
          `s7://127.0.0.1:${port}?rack=0&slot=2`,
          'Tank.Level=99.5',
          '--symbols',
          'Tank.db',
          '--db',
          'Tank=1',
        ]);
        expect(write.code, write.err).to.equal(0);
        const code = await w.exit;
        expect(w.output().err).to.not.match(/EPIPE|Unhandled/);
        expect(code).to.be.oneOf([0, 130]);
      } finally {
        srv.child.kill('SIGINT');
        await srv.exit;
      }
    });
  });

  describe("a PLC that cannot tell its blocks' lengths (FETCH/WRITE)", () => {
    it('a read by name prints a one-line note and the values', async () => {
      const port = await freePort();
      const srv = run(['serve', 'fetchwrite', '--port', String(port), '--source', 'Tank.db', '--db', 'Tank=1']);
      try {
        await until(() => /^try: /m.test(srv.output().out), 10000, 'serve prints how to reach it');
        const url = /^try: plcwire read "([^"]+)"/m.exec(srv.output().out)![1]!;
        const r = await done(['read', url, 'Tank.Level', '--symbols', 'Tank.db', '--db', 'Tank=1']);
        expect(r.code, r.err).to.equal(0);
        expect(r.out).to.equal('Tank.Level = 12.5\n');
        expect(r.err).to.equal(
          'note: FETCH/WRITE does not report the length of data blocks, so a DB changed in the PLC\'s project (DB1 "Tank") is not detected here; export the sources again after every change\n',
        );
      } finally {
        srv.child.kill('SIGINT');
        await srv.exit;
      }
    });
  });

  describe('an S7-1200, which answers block info "function not implemented" (0x8104)', () => {
    const NOTE =
      'note: this CPU does not report the length of its data blocks (S7-1200 and S7-1500 do not), so a DB changed in TIA Portal (DB1 "Tank") is not detected here; export the sources again after every change\n';

    it('read, write and read --json by name each print the note exactly once, in words (no hex code), and the values', async () => {
      const port = await freePort();
      const srv = run(['serve', 's7', '--port', String(port), '--profile', 's7-1200', '--source', 'Tank.db', '--db', 'Tank=1']);
      try {
        await until(() => /^try: /m.test(srv.output().out), 10000, 'serve prints how to reach it');
        const url = `s7://127.0.0.1:${port}?rack=0&slot=1`;
        const names = ['--symbols', 'Tank.db', '--db', 'Tank=1'];
        const read = await done(['read', url, 'Tank.Level', '"Tank".Motor.On', ...names]);
        expect(read.code, read.err).to.equal(0);
        expect(read.out).to.equal('Tank.Level = 12.5\n"Tank".Motor.On = true\n');
        expect(read.err).to.equal(NOTE);
        const write = await done(['write', url, 'Tank.Level=40.4', ...names]);
        expect(write.code, write.err).to.equal(0);
        expect(write.err).to.equal(NOTE);
        const json = await done(['read', url, 'Tank.Level', ...names, '--json']);
        expect(json.code, json.err).to.equal(0);
        expect(json.err).to.equal(NOTE);
        expect(json.out).to.equal('{"Tank.Level":40.4}\n');
      } finally {
        srv.child.kill('SIGINT');
        await srv.exit;
      }
    });

    it('watch prints it once for its connection, however many polls', async () => {
      const port = await freePort();
      const srv = run(['serve', 's7', '--port', String(port), '--profile', 's7-1200', '--source', 'Tank.db', '--db', 'Tank=1']);
      try {
        await until(() => /^try: /m.test(srv.output().out), 10000, 'serve prints how to reach it');
        const url = `s7://127.0.0.1:${port}?rack=0&slot=1`;
        const w = run(['watch', url, 'Tank.Level', '--symbols', 'Tank.db', '--db', 'Tank=1', '--interval', '10']);
        await until(() => w.output().out.length > 0 && w.output().err.includes('note: '), 10000, 'the first value and the note');
        for (const value of ['1.5', '2.5']) {
          const write = await done(['write', url, `Tank.Level=${value}`, '--symbols', 'Tank.db', '--db', 'Tank=1']);
          expect(write.code, write.err).to.equal(0);
          await until(() => w.output().out.includes(`Tank.Level = ${value}\n`), 10000, `watch shows ${value}`);
        }
        w.child.kill('SIGINT');
        await w.exit;
        expect(
          w
            .output()
            .err.split('\n')
            .filter((l) => l.startsWith('note: ')),
        ).to.deep.equal([NOTE.trimEnd()]);
      } finally {
        srv.child.kill('SIGINT');
        await srv.exit;
      }
    });
  });
});
