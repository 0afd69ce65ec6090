/**
 * `plcwire symbols` of a TIA source with optimized blocks, and a read of
 * such a name over s7://, through the installed binary (bin/plcwire.js) in
 * child processes. Fixture: test/fixtures/symbols/optimized/.
 */
import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import { once } from 'node:events';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { EXIT } from '../lib/cli/io';
import { until } from './support/wait';
import { S7Server, type S7RequestEvent } from '../lib/s7/server';
import { compileSymbols } from '../lib/symbols';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');
const FIXTURES = path.resolve(__dirname, '../../test/fixtures/symbols/optimized');
const NUMBERS = ['--db', 'Tank=1', '--db', 'Recipe=2', '--db', 'Line=3'];

/** The real bin in a child process in the fixtures' folder: the child, its output so far, its exit code. */
function run(args: string[]): { child: ChildProcess; output: () => { out: string; err: string }; exit: Promise<number> } {
  const child = spawn(process.execPath, [BIN, ...args], { cwd: FIXTURES, stdio: ['ignore', 'pipe', 'pipe'] });
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

/** The note `symbols` writes on stderr for an optimized block. */
const note = (block: string) =>
  `note: ${block} has optimized access: its members have no byte, bit or address; ` +
  'they are read and written by name over s7plus:// (S7CommPlus), not over s7:// or fetchwrite://';

describe('plcwire symbols: optimized blocks (the installed binary)', function () {
  this.timeout(30000);

  it('--json lists the members of an optimized block with byte, bit and address null, and says once per block how to read them', async () => {
    const r = await done(['symbols', 'tia-optimized.db', ...NUMBERS, '--json']);
    expect(r.code, r.err).to.equal(EXIT.OK);
    const rows = JSON.parse(r.out) as Record<string, unknown>[];
    const by = new Map(rows.map((row) => [row.name, row]));
    expect(by.get('"Recipe".Heater.Power')).to.deep.equal({
      name: '"Recipe".Heater.Power',
      type: 'LREAL',
      db: 2,
      byte: null,
      bit: null,
      address: null,
    });
    expect(by.get('"Recipe".Pumps')).to.deep.equal({
      name: '"Recipe".Pumps',
      type: 'ARRAY[0..1] OF "Pump"',
      db: 2,
      byte: null,
      bit: null,
      address: null,
    });
    expect(by.get('"Line".Pump.Run')).to.include({ db: 3, byte: null, bit: null, address: null });
    // The standard block beside them keeps its offsets.
    expect(by.get('"Tank".Pump.Fault')).to.deep.equal({
      name: '"Tank".Pump.Fault',
      type: 'BOOL',
      db: 1,
      byte: 4,
      bit: 1,
      address: 'DB1.DBX4.1',
    });
    expect(rows.filter((row) => row.address === null)).to.have.length(rows.length - 5);
    expect(r.err).to.equal(`${note('DB2 "Recipe"')}\n${note('DB3 "Line"')}\n`);
  });

  it('the table leaves the address, byte and bit of those members empty; a source without optimized blocks gets no note', async () => {
    const r = await done(['symbols', 'tia-optimized.db', ...NUMBERS]);
    expect(r.code, r.err).to.equal(EXIT.OK);
    const lines = r.out.split('\n');
    expect(lines[0]).to.match(/^name\s+address\s+type\s+byte\s+bit$/);
    expect(lines.find((l) => l.startsWith('"Recipe".Start '))).to.match(/^"Recipe"\.Start\s+BOOL$/);
    expect(lines.find((l) => l.startsWith('"Tank".Pump.Run '))).to.match(/^"Tank"\.Pump\.Run\s+DB1\.DBX4\.0\s+BOOL\s+4\s+0$/);
    expect(r.err.split('\n').filter((l) => l.startsWith('note: '))).to.have.length(2);
    const standard = await done(['symbols', '../cli/Tank.db', '--db', 'Tank=1']);
    expect([standard.code, standard.err]).to.deep.equal([EXIT.OK, '']);
  });

  it('read over s7:// of a name in an optimized block fails before anything is sent, naming the tag, the block and s7plus://', async () => {
    const table = compileSymbols([{ name: 'tia-optimized.db', content: fs.readFileSync(path.join(FIXTURES, 'tia-optimized.db')) }], {
      db: { Tank: 1, Recipe: 2, Line: 3 },
    });
    const server = new S7Server({ port: 0, profile: 's7-1500', symbols: table });
    await server.listen();
    const requests: S7RequestEvent[] = [];
    server.on('request', (q: S7RequestEvent) => requests.push(q));
    try {
      const url = `s7://127.0.0.1:${server.port}?slot=1&timeout=2000`;
      const r = await done(['read', url, '"Recipe".Temperature', '--symbols', 'tia-optimized.db', ...NUMBERS]);
      expect(r.code).to.equal(EXIT.USAGE);
      expect(r.err)
        .to.contain('"Recipe".Temperature is in DB2 "Recipe", a block with optimized access')
        .and.contain('over s7plus:// (S7CommPlus)');
      expect(r.out).to.equal('');
      expect(requests.filter((q) => q.kind === 'read' || q.kind === 'write')).to.deep.equal([]);
    } finally {
      await server.close();
    }
  });

  it('serve s7 --source says it does not serve an optimized block by address, and its try: line names a member it serves', async () => {
    const srv = run(['serve', 's7', '--port', '0', '--source', 'tia-optimized.db', ...NUMBERS]);
    try {
      await until(() => /^try: /m.test(srv.output().out), 10000, 'serve prints how to reach it');
      const lines = srv.output().out.split('\n');
      expect(lines.filter((l) => /serving DB/.test(l))).to.deep.equal([
        'not serving DB2 "Recipe" by address: it has optimized access, its members are read by name over s7plus:// (tia-optimized.db)',
        'not serving DB3 "Line" by address: it has optimized access, its members are read by name over s7plus:// (tia-optimized.db)',
        'serving DB1 "Tank" of 10 bytes (tia-optimized.db)',
      ]);
      expect(lines.find((l) => l.startsWith('try: '))).to.match(/ '"Tank"\.Level'$/);
    } finally {
      srv.child.kill('SIGINT');
      expect(await srv.exit).to.equal(EXIT.OK);
    }
  });
});
