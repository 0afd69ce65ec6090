/**
 * The chaos run of issue #26 (bench/chaos/run.js, `npm run chaos`) for 60 s
 * inside the suite: simulated PLCs of every driver, each resetting, going
 * silent, answering slowly or with garbage, restarting, refusing, filling its
 * backlog, cutting a frame, failing one item or going to STOP on a schedule
 * drawn from the seed, while one client process polls and writes; the
 * S7CommPlus PLCs (S7-1500 over TLS, the certificate pinned) also end a
 * session with a TLS alert, cut a TLS record and RST, and restart with
 * another certificate, which the client must refuse at every attempt.
 *
 * Its fleet is 22 PLCs (two of each driver), not 100: on this 2-core machine
 * shared with other work, the same client process could not keep 100 PLCs ×
 * 100 tags at 100 ms even without a fault (`npm run chaos -- --calm`:
 * 36 % of the polls due, event-loop p99 157 ms), and an overloaded client
 * times out against healthy PLCs, which would be the machine's fault, not
 * the library's. 22 PLCs keep every fault in play. The assertions are
 * counts, not rates (`--counts-only`): writes lost, applied twice or
 * never written, wrong values, unexplained item errors, untyped errors,
 * overlapping polls, links not back within their backoff, certificates
 * trusted that were not the pinned one, connections at the simulators at
 * the end, handles left behind. CHAOS_SEED replays a seed.
 */
import { expect } from 'chai';
import { fork, type ChildProcess } from 'node:child_process';
import * as path from 'node:path';

const RUN = path.join(__dirname, '..', '..', 'bench', 'chaos', 'run.js');
/**
 * Every fault in play (73 episodes): two of them slow freeport answers later
 * than the timeout (the line drained after a timeout, lib/freeport/session.ts,
 * keeps another station's data from being read as good), and on the two
 * S7CommPlus PLCs three TLS alerts, two resets inside a record and a
 * certificate change.
 */
const SEED = process.env.CHAOS_SEED ?? '2261';
const PLCS = 22;
const SECONDS = 60;

interface Row {
  check: string;
  measured: string;
  ok: boolean;
  skipped: boolean;
}

describe('chaos: 22 simulated PLCs with faults for 60 s, polled and written (issue #26)', function () {
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
      'certificates changed: refused, never trusted',
      'connections at the simulators at the end',
      'handles left behind',
    ]);
    for (const r of checked) expect(r.ok, `${r.check}: ${r.measured}\n${printed}`).to.equal(true);
    // Not a quiet run: faults happened, links went down and came back, writes were acknowledged.
    const back = /^(\d+) of (\d+)/.exec(checked.find((r) => r.check.startsWith('links back'))!.measured);
    expect(Number(back?.[2]), printed).to.be.at.least(PLCS);
    const certificates = /^(\d+) of (\d+) refused \((\d+) refusals\), trusted (\d+)/.exec(
      checked.find((r) => r.check.startsWith('certificates changed'))!.measured,
    );
    expect(Number(certificates?.[2]), printed).to.be.at.least(1);
    expect(certificates?.[1], printed).to.equal(certificates?.[2]);
    expect(Number(certificates?.[4]), printed).to.equal(0);
    const acked = /^(\d+) of (\d+)/.exec(checked.find((r) => r.check.startsWith('writes acknowledged'))!.measured);
    expect(Number(acked?.[1]), printed).to.be.above(0);
    expect(Number(acked?.[1]), printed).to.be.below(Number(acked?.[2]));
    expect(code, printed).to.equal(0);
  });
});
