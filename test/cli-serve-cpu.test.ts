/**
 * `plcwire serve s7` with an S7-1200 or S7-1500 profile, as a user runs it: the simulated CPU serves PUT/GET and
 * S7CommPlus on one port, with the profile's data blocks (DB1–DB100) or the --layout's when no --source gives a
 * program (issue #31: the empty S7CommPlus program had replaced them, so the README's own `write … DB1,INT2=42`
 * answered "object does not exist").
 */
import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import { once } from 'node:events';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { EXIT } from '../lib/cli/io';
import { S7Server } from '../lib/s7/server';
import { S7PlusService } from '../lib/s7plus/server';
import { freePort } from './support/net';
import { until } from './support/wait';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');

interface Run {
  child: ChildProcess;
  output: () => { out: string; err: string };
  exit: Promise<number>;
}

/** The real bin in a child process, its output collected until it exits. */
function run(args: string[]): Run {
  const child = spawn(process.execPath, [BIN, ...args], { stdio: ['ignore', 'pipe', 'pipe'] });
  let out = '';
  let err = '';
  child.stdout!.on('data', (d: Buffer) => (out += d.toString()));
  child.stderr!.on('data', (d: Buffer) => (err += d.toString()));
  const exit = once(child, 'exit').then(([code]) => code as number);
  return { child, output: () => ({ out, err }), exit };
}

/** Runs a short command to its end: exit code and output. */
async function done(args: string[]): Promise<{ code: number; out: string; err: string }> {
  const r = run(args);
  const code = await r.exit;
  return { code, ...r.output() };
}

/** Starts `serve s7 …`, waits (with a deadline) for the line that says how to reach it, and stops it after `work`. */
async function withServe(args: string[], work: (out: string, port: number) => Promise<void>): Promise<void> {
  const port = await freePort();
  const srv = run(['serve', 's7', '--port', String(port), ...args]);
  try {
    await until(() => /^Ctrl-C stops/m.test(srv.output().out) || srv.child.exitCode !== null, 15000, 'serve prints how to reach it');
    expect(srv.child.exitCode, srv.output().err).to.equal(null);
    await work(srv.output().out, port);
  } finally {
    srv.child.kill('SIGINT');
  }
  expect(await srv.exit, srv.output().err).to.equal(0);
}

describe('plcwire serve s7: the S7-1200/1500 CPU on one port (issue #31)', function () {
  this.timeout(60000);

  for (const profile of ['s7-1200', 's7-1500'] as const) {
    it(`--profile ${profile} without --source serves DB1–DB100 over PUT/GET and lists them over S7CommPlus`, async () => {
      await withServe(['--profile', profile], async (out, port) => {
        // The README's own example, as written (rack 0, slot 1 by default).
        const target = `s7://127.0.0.1:${port}`;
        const w = await done(['write', target, 'DB1,INT2=42', 'DB1.DBD4:REAL=1.5', 'DB1,X12.2=true', 'DB100,INT1022=-7']);
        expect(w.code, w.err).to.equal(EXIT.OK);
        const r = await done(['read', target, 'DB1,INT2', 'DB1.DBD4:REAL', 'DB1,X12.2', 'DB100,INT1022', '--json']);
        expect(r.code, r.err).to.equal(EXIT.OK);
        expect(JSON.parse(r.out)).to.deep.equal({ 'DB1,INT2': 42, 'DB1.DBD4:REAL': 1.5, 'DB1,X12.2': true, 'DB100,INT1022': -7 });

        // The try: line ends with addresses, and runs as printed.
        const tryLine = /^try: plcwire read "([^"]+)" (.+)$/m.exec(out);
        expect(tryLine, out).to.not.equal(null);
        const addresses = tryLine![2]!.trim().split(/\s+/);
        expect(addresses).to.include('DB1,INT0');
        const t = await done(['read', tryLine![1]!, ...addresses, '--json']);
        expect(t.code, t.err).to.equal(EXIT.OK);

        // Over S7CommPlus the same CPU lists its data blocks.
        const plusUrl = /^\s+(s7plus:\/\/\S+)$/m.exec(out)![1]!;
        const b = await done(['blocks', plusUrl, 'DB', '--json']);
        expect(b.code, b.err).to.equal(EXIT.OK);
        expect((JSON.parse(b.out) as { numbers: number[] }).numbers).to.deep.equal(Array.from({ length: 100 }, (_, i) => i + 1));
        // … and serves them by address: what PUT/GET wrote is what S7CommPlus reads.
        const p = await done(['read', plusUrl, 'DB1,INT2', 'DB100,INT1022', '--json']);
        expect(p.code, p.err).to.equal(EXIT.OK);
        expect(JSON.parse(p.out)).to.deep.equal({ 'DB1,INT2': 42, 'DB100,INT1022': -7 });
      });
    });
  }

  it('--layout keeps its data blocks on an S7-1500 (the S7CommPlus side serves them too)', async () => {
    const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-layout-'));
    try {
      const layout = path.join(dir, 'layout.json');
      fs.writeFileSync(layout, JSON.stringify({ dbs: { 7: 64, 300: 16 } }));
      await withServe(['--profile', 's7-1500', '--layout', layout], async (out, port) => {
        const target = `s7://127.0.0.1:${port}`;
        const w = await done(['write', target, 'DB7,INT62=1234', 'DB300,X15.7=true']);
        expect(w.code, w.err).to.equal(EXIT.OK);
        const r = await done(['read', target, 'DB7,INT62', 'DB300,X15.7', 'DB1,INT0', '--json']);
        // The layout's blocks, and only those: DB1 is not in it.
        expect(r.code).to.equal(EXIT.TAG_ERROR);
        expect(JSON.parse(r.out)).to.deep.equal({ 'DB7,INT62': 1234, 'DB300,X15.7': true, 'DB1,INT0': null });
        const plusUrl = /^\s+(s7plus:\/\/\S+)$/m.exec(out)![1]!;
        const b = await done(['blocks', plusUrl, 'DB', '--json']);
        expect(b.code, b.err).to.equal(EXIT.OK);
        expect(JSON.parse(b.out)).to.deep.equal({ type: 'DB', numbers: [7, 300] });
      });
    } finally {
      fs.rmSync(dir, { recursive: true, force: true });
    }
  });
});

describe('S7Server with S7CommPlus: whose data blocks (issue #31)', () => {
  it("a program without data blocks leaves the profile's DB1–DB100; one with data blocks replaces them", () => {
    const empty = new S7Server({ port: 0, profile: 's7-1500', s7plus: new S7PlusService({ sources: [], tls: false }) });
    expect(empty.memory.dataBlockNumbers()).to.deep.equal(Array.from({ length: 100 }, (_, i) => i + 1));
    expect(empty.memory.area('DB', 1)!.length).to.equal(1024);
    const layout = new S7Server({
      port: 0,
      profile: 's7-1200',
      layout: { dbs: { 9: 32 } },
      s7plus: new S7PlusService({ sources: [], tls: false }),
    });
    expect(layout.memory.dataBlockNumbers()).to.deep.equal([9]);
    const source = {
      name: 'Tank.db',
      content:
        'DATA_BLOCK "Tank"\n{ S7_Optimized_Access := \'FALSE\' }\nVERSION : 0.1\nSTRUCT\n  Level : REAL := 2.5;\nEND_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n',
    };
    const program = new S7Server({
      port: 0,
      profile: 's7-1500',
      s7plus: new S7PlusService({ sources: [source], db: { Tank: 3 }, tls: false }),
    });
    expect(program.memory.dataBlockNumbers()).to.deep.equal([3]);
    expect(program.memory.area('DB', 3)!.readFloatBE(0)).to.equal(2.5);
    expect(new S7Server({ port: 0, profile: 's7-1200' }).memory.dataBlockNumbers()).to.have.length(100);
  });
});
