/**
 * The S7CommPlus section of `npm run bench` (bench/s7plus.js, issue #25)
 * runs in --quick mode and prints its tables: our client by name, its
 * transport alone, the s7commplus Python client (or why it is not there),
 * our s7:// and s7plus:// on the same standard tags, and the targets. Every
 * client's first poll is checked by the bench against the members' start
 * values, so a row with figures is a row of right answers. No figure is
 * asserted but the requests per poll, which do not depend on the machine.
 */
import { expect } from 'chai';
import { spawn } from 'node:child_process';
import * as path from 'node:path';
import { findS7CommPlus } from './support/s7commplus-peer';

const RUN = path.join(__dirname, '..', '..', 'bench', 'run.js');

function runBench(args: string[], env: NodeJS.ProcessEnv = {}): Promise<{ code: number | null; out: string }> {
  return new Promise((resolve, reject) => {
    const child = spawn(process.execPath, [RUN, ...args], { stdio: ['ignore', 'pipe', 'pipe'], env: { ...process.env, ...env } });
    let out = '';
    child.stdout.on('data', (d: Buffer) => (out += d.toString()));
    child.stderr.on('data', (d: Buffer) => (out += d.toString()));
    child.on('error', reject);
    child.on('close', (code) => resolve({ code, out }));
  });
}

/** The cells of the table row that starts with `label` (columns are two or more spaces apart). */
function row(out: string, label: string): string[] {
  const line = out.split('\n').find((l) => l.startsWith(label));
  expect(line, `no row "${label}" in:\n${out}`).to.be.a('string');
  return line!
    .slice(label.length)
    .trim()
    .split(/\s{2,}/);
}

describe('npm run bench: the S7CommPlus section (issue #25)', function () {
  this.timeout(120_000);

  it('--quick --sections s7plus prints our client, its floor, the Python client or why not, s7:// against s7plus://, and the targets', async () => {
    const { code, out } = await runBench(['--quick', '--sections', 's7plus', '--duration', '200']);
    expect(code, out).to.equal(0);
    expect(out).to.include('S7CommPlus: 100 tags by name in an optimized DB');
    expect(out).to.include('Our s7plus:// against our s7:// on the same 100 tags of a standard DB');
    expect(out).to.include('S7CommPlus targets (issues #25, #32)');
    // Our rows measured (a wrong first value would be "not measured: wrong value …"): polls/s, CPU ms/poll, requests/poll.
    for (const label of ['ours (s7plus://, by name)', '  its transport alone (floor)', 'ours s7:// (PUT/GET)', 'ours s7plus:// (TLS)']) {
      const cells = row(out, label);
      expect(Number(cells[0]), `${label}: ${cells.join(' | ')}`).to.be.above(0);
      expect(Number(cells[1]), `${label}: ${cells.join(' | ')}`).to.be.above(0);
    }
    // 100 names, each with its SymbolCrc, and no program check (issue #32): the S7-1500's SystemLimits (100) would allow
    // one read, the 1024-byte frame takes 2; by our own count and by the proxy's TLS records.
    expect(row(out, 'ours (s7plus://, by name)').slice(2, 4)).to.deep.equal(['2.0', '2.0']);
    expect(row(out, 'ours s7plus:// (TLS)').slice(2, 4)).to.deep.equal(['2.0', '2.0']);
    expect(row(out, 'requests per poll, S7-1200: 100 names at SystemLimits 50 = 2')).to.deep.equal(['2.0 (ours) / 2.0 (proxy)', 'pass']);
    expect(row(out, 'requests per poll, S7-1500: 100 names at SystemLimits 100 = 1')).to.deep.equal([
      '2.0 (ours) / 2.0 (proxy)',
      'the 1024-byte frame: 2',
    ]);
    for (const target of [
      "polls/s at least 10× the s7commplus client's",
      'CPU per poll by name at most 2× its TLS-in-COTP transport floor',
    ]) {
      expect(out.split('\n').find((l) => l.startsWith(target))).to.match(/(pass|FAIL|not measured)$/);
    }
    const python = row(out, 's7commplus 0.3.0 (Python)');
    if ('python' in findS7CommPlus()) {
      expect(Number(python[0]), python.join(' | ')).to.be.above(0);
      // Its requests counted by the proxy: the same 2 (it splits at 50 items too).
      expect(python[3], python.join(' | ')).to.equal('2.0');
    } else {
      expect(python[0]).to.match(/^not measured: s7commplus .* is not installed/);
    }
  });

  it('without the s7commplus package the table says so, its target is not measured, and the rest runs', async () => {
    const { code, out } = await runBench(['--quick', '--sections', 's7plus', '--duration', '200'], {
      PLCWIRE_BENCH_PYTHON: path.join(__dirname, 'no-such-python'),
    });
    expect(code, out).to.equal(0);
    expect(row(out, 's7commplus 0.3.0 (Python)')[0]).to.match(
      /^not measured: s7commplus 0\.3\.0 is not installed \(no-such-python: ENOENT\)/,
    );
    expect(row(out, "polls/s at least 10× the s7commplus client's (by name)")).to.deep.equal(['–', 'not measured']);
    expect(Number(row(out, 'ours (s7plus://, by name)')[0])).to.be.above(0);
    expect(Number(row(out, 'ours s7plus:// (TLS)')[0])).to.be.above(0);
  });
});
