/**
 * A struct's TIME, DATE, TIME_OF_DAY, S5TIME, LTIME, DATE_AND_TIME and DTL
 * members in the CLI's text output, as TIA writes them (issue #31): read,
 * write and watch (polled over s7:// with --symbols, pushed over s7plus:// by
 * name), through the installed binary against `plcwire serve s7 --profile
 * s7-1500`, which serves both protocols on one port. --json keeps the numbers
 * and ISO dates.
 */
import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import { once } from 'node:events';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { EXIT } from '../lib/cli/io';
import { until } from './support/wait';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');

const CLOCK_DB = `DATA_BLOCK "Clock"
{ S7_Optimized_Access := 'FALSE' }
VERSION : 0.1
NON_RETAIN
   STRUCT
      Shift : Struct
         Length : Time := T#8H_30M;
         Day : Date := D#2024-01-31;
         Start : Time_Of_Day := TOD#06:00:00;
         Delay : S5Time := S5T#2M_7S;
         Long : LTime := LT#1S_500MS;
         Stamp : Date_And_Time := DT#2024-01-31-12:00:01.250;
         Exact : DTL := DTL#2024-01-31-12:00:01.25;
         Count : Int := 3;
      END_STRUCT;
      Laps : Array[0..1] of Time := [T#1S, T#2M];
   END_STRUCT;
BEGIN
END_DATA_BLOCK
`;

/** The struct "Clock".Shift as TIA shows it, Length given. */
const shift = (length: string) =>
  `{ Length: ${length}, Day: D#2024-01-31, Start: TOD#06:00:00.000, Delay: S5T#2M_7S, Long: LT#1S_500MS, ` +
  'Stamp: DT#2024-01-31-12:00:01.250, Exact: DTL#2024-01-31-12:00:01.250, Count: 3 }';

interface Run {
  child: ChildProcess;
  output: () => { out: string; err: string };
  exit: Promise<number>;
}

describe('a struct’s time members in the CLI’s text, as TIA writes them (issue #31)', function () {
  this.timeout(60000);
  let dir: string;
  let sim: Run;
  let s7: string;
  let s7plus: string;
  const symbols = ['--symbols', 'Clock.db', '--db', 'Clock=3'];

  function run(args: string[]): Run {
    const child = spawn(process.execPath, [BIN, ...args], { cwd: dir, stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    let err = '';
    child.stdout!.on('data', (d: Buffer) => (out += d.toString()));
    child.stderr!.on('data', (d: Buffer) => (err += d.toString()));
    const exit = once(child, 'exit').then(([code]) => code as number);
    return { child, output: () => ({ out, err }), exit };
  }

  async function done(args: string[]): Promise<{ code: number; out: string; err: string }> {
    const r = run(args);
    const code = await r.exit;
    return { code, ...r.output() };
  }

  async function stopped(r: Run): Promise<number> {
    if (r.child.exitCode === null) r.child.kill('SIGINT');
    return r.exit;
  }

  before(async () => {
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-struct-times-'));
    fs.writeFileSync(path.join(dir, 'Clock.db'), CLOCK_DB);
    sim = run(['serve', 's7', '--profile', 's7-1500', '--port', '0', '--source', 'Clock.db', '--db', 'Clock=3']);
    await until(() => /Ctrl-C stops/.test(sim.output().out), 20000, 'the simulator to start');
    const text = sim.output().out;
    s7 = /"(s7:\/\/[^"]+)"/.exec(text)![1]!;
    s7plus = /(s7plus:\/\/\S+)/.exec(text)![1]!;
  });

  after(async () => {
    if (sim) await stopped(sim);
    fs.rmSync(dir, { recursive: true, force: true });
  });

  it('read: over s7:// with --symbols and over s7plus:// by name, a struct, an array of TIME and the whole block; --json keeps the numbers', async () => {
    for (const args of [[s7, ...symbols], [s7plus]]) {
      const r = await done(['read', ...args, '"Clock".Shift', '"Clock".Laps', '"Clock"']);
      expect(r.code, r.err).to.equal(EXIT.OK);
      expect(r.out.trim().split('\n'), args[0]).to.deep.equal([
        `"Clock".Shift = ${shift('T#8H_30M')}`,
        '"Clock".Laps = [T#1S, T#2M]',
        `"Clock" = { Shift: ${shift('T#8H_30M')}, Laps: [T#1S, T#2M] }`,
      ]);
      const json = await done(['read', ...args, '"Clock".Shift', '--json']);
      expect(JSON.parse(json.out), args[0]).to.deep.equal({
        '"Clock".Shift': {
          Length: 30_600_000,
          Day: '2024-01-31T00:00:00.000Z',
          Start: 21_600_000,
          Delay: 127_000,
          Long: 1_500_000_000,
          Stamp: '2024-01-31T12:00:01.250Z',
          Exact: '2024-01-31T12:00:01.250Z',
          Count: 3,
        },
      });
    }
  });

  it('write: the struct written is printed with its time members as TIA writes them', async () => {
    const r = await done(['write', s7, ...symbols, '"Clock".Shift={"Length":5000}']);
    expect(r.code, r.err).to.equal(EXIT.OK);
    expect(r.out).to.equal('"Clock".Shift = { Length: T#5S } ok\n');
    const back = await done(['write', s7plus, '"Clock".Shift={"Length":30600000}']);
    expect(back.code, back.err).to.equal(EXIT.OK);
    expect(back.out).to.equal('"Clock".Shift = { Length: T#8H_30M } ok\n');
  });

  it('watch: polled over s7:// with --symbols and pushed over s7plus://, a change shows as TIA writes it', async () => {
    const polled = run(['watch', s7, ...symbols, '"Clock".Shift', '--interval', '100']);
    const pushed = run(['watch', s7plus, '"Clock".Shift', '--interval', '60000']);
    try {
      await until(() => /subscribed to 1 tag/.test(pushed.output().err), 20000, 'the subscription');
      await until(() => polled.output().out.includes(`"Clock".Shift = ${shift('T#8H_30M')}\n`), 20000, 'the polled first line');
      await until(() => pushed.output().out.includes(`"Clock".Shift = ${shift('T#8H_30M')}\n`), 20000, 'the pushed first line');
      const w = await done(['write', s7plus, '"Clock".Shift={"Length":93784005}']);
      expect(w.code, w.err).to.equal(EXIT.OK);
      const changed = `"Clock".Shift = ${shift('T#1D_2H_3M_4S_5MS')}\n`;
      await until(() => polled.output().out.includes(changed), 20000, 'the polled change');
      await until(() => pushed.output().out.includes(changed), 20000, 'the pushed change');
    } finally {
      expect(await stopped(polled)).to.equal(EXIT.INTERRUPTED);
      expect(await stopped(pushed)).to.equal(EXIT.INTERRUPTED);
      await done(['write', s7plus, '"Clock".Shift={"Length":30600000}']);
    }
  });
});
