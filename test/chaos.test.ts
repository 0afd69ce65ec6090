/**
 * The chaos run of issue #26 (bench/chaos/run.js, `npm run chaos`) for 60 s
 * inside the suite: simulated PLCs of every driver, each resetting, going
 * silent, answering slowly or with garbage, restarting, refusing, filling its
 * backlog, cutting a frame, failing one item or going to STOP on a schedule
 * drawn from the seed, while one client process polls and writes.
 *
 * Its fleet is 20 PLCs (two of each driver), not 100: on this 2-core machine
 * shared with other work, the same client process could not keep 100 PLCs ×
 * 100 tags at 100 ms even without a fault (`npm run chaos -- --calm`:
 * 36 % of the polls due, event-loop p99 157 ms), and an overloaded client
 * times out against healthy PLCs, which would be the machine's fault, not
 * the library's. 20 PLCs keep every fault in play. The assertions are
 * counts, not rates (`--counts-only`): writes lost, applied twice or
 * never written, wrong values, unexplained item errors, untyped errors,
 * overlapping polls, links not back within their backoff, connections at
 * the simulators at the end, handles left behind. CHAOS_SEED replays a seed.
 */
import { expect } from 'chai';
import { fork, type ChildProcess } from 'node:child_process';
import * as path from 'node:path';

const RUN = path.join(__dirname, '..', '..', 'bench', 'chaos', 'run.js');
/**
 * Every fault in play, three of them slow freeport answers later than the
 * timeout: without the line drained after a timeout (lib/freeport/session.ts)
 * this seed reads another station's data as good (23 wrong values).
 */
const SEED = process.env.CHAOS_SEED ?? '392';
const PLCS = 20;
const SECONDS = 60;

interface Row {
  check: string;
  measured: string;
  ok: boolean;
  skipped: boolean;
}

describe('chaos: 20 simulated PLCs with faults for 60 s, polled and written (issue #26)', function () {
  this.timeout(100_000);
  let child: ChildProcess | undefined;

  after(() => {
    if (child && child.exitCode === null) child.kill('SIGKILL');
  });

  it('loses no write, applies none twice, reads no wrong value, brings every link back and leaves nothing behind', async () => {
    const output: string[] = [];
    const run = fork(RUN, ['--seed', SEED, '--seconds', String(SECONDS), '--plcs', String(PLCS), '--counts-only'], {
      execArgv: ['--expose-gc'],
      stdio: ['ignore', 'pipe', 'pipe', 'ipc'],
    });
    child = run;
    run.stdout!.on('data', (b: Buffer) => output.push(b.toString()));
    run.stderr!.on('data', (b: Buffer) => output.push(b.toString()));
    let result: { rows: Row[]; failed: string[] } | undefined;
    run.on('message', (m: { ok: boolean; result: { rows: Row[]; failed: string[] } }) => (result = m.result));
    const code = await new Promise<number | null>((resolve) => run.once('exit', resolve));
    const printed = output.join('');
    expect(result, `no result from the chaos run (exit ${code}):\n${printed}`).to.not.equal(undefined);
    expect(result!.failed, printed).to.deep.equal([]);
    const checked = result!.rows.filter((r) => !r.skipped);
    expect(checked.map((r) => r.check)).to.include.members([
      'writes acknowledged, applied exactly once',
      'values read that the PLC did not hold',
      'links back within backoff after a fault',
      'connections at the simulators at the end',
      'handles left behind',
    ]);
    for (const r of checked) expect(r.ok, `${r.check}: ${r.measured}\n${printed}`).to.equal(true);
    // Not a quiet run: faults happened, links went down and came back, writes were acknowledged.
    const back = /^(\d+) of (\d+)/.exec(checked.find((r) => r.check.startsWith('links back'))!.measured);
    expect(Number(back?.[2]), printed).to.be.at.least(PLCS);
    const acked = /^(\d+) of (\d+)/.exec(checked.find((r) => r.check.startsWith('writes acknowledged'))!.measured);
    expect(Number(acked?.[1]), printed).to.be.above(0);
    expect(Number(acked?.[1]), printed).to.be.below(Number(acked?.[2]));
    expect(code, printed).to.equal(0);
  });
});
