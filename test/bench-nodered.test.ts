/**
 * The Node-RED layer's section of `npm run bench` (bench/nodered.js layerSection, issue #32): one run prints the
 * library alone and our read node in a real Node-RED on the same PLCs, side by side, with the ratio and the
 * machine's load. No figure is asserted (they depend on the machine); every PLC must be polled by both.
 */
import { expect } from 'chai';
import { spawn } from 'node:child_process';
import * as path from 'node:path';

const RUN = path.join(__dirname, '..', '..', 'bench', 'run.js');

function runBench(args: string[]): Promise<{ code: number | null; out: string }> {
  return new Promise((resolve, reject) => {
    const child = spawn(process.execPath, [RUN, ...args], { stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    child.stdout.on('data', (d: Buffer) => (out += d.toString()));
    child.stderr.on('data', (d: Buffer) => (out += d.toString()));
    child.on('error', reject);
    child.on('close', (code) => resolve({ code, out }));
  });
}

describe('npm run bench: the Node-RED layer (issue #32)', function () {
  this.timeout(180_000);

  it('--quick --sections nodered prints the library alone and the read node from one run, their ratio and the load', async () => {
    const { code, out } = await runBench(['--quick', '--sections', 'nodered', '--duration', '1000']);
    expect(code, out).to.equal(0);
    expect(out).to.match(/Node-RED layer: 50 PLCs × 100 tags .* load \d+\.\d on \d+ CPUs/);
    const cells = (label: string) => {
      const line = out.split('\n').find((l) => l.startsWith(`50 × 100     ${label} `));
      expect(line, `no row "${label}" in:\n${out}`).to.be.a('string');
      return line!.split(/\s{2,}/);
    };
    for (const mode of ['lib ours', 'ours object']) expect(Number(cells(mode)[2]), `${mode} polls/s`).to.be.greaterThan(0);
    expect(cells('ours object / lib ours').join(' ')).to.match(/\d+\.\d\d×/);
  });
});
