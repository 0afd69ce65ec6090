/**
 * `plcwire watch s7://…` on an S7-300 (issue #33): the real CLI, its tags
 * reported by the CPU's cyclic data (userdata group 2), so a change shows
 * within the cycle whatever --interval says; on an S7-1500 over PUT/GET,
 * which refuses cyclic data, the tags are polled and stderr says why.
 */
import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import { once } from 'node:events';
import * as path from 'node:path';
import { EXIT } from '../lib/cli/io';
import { S7Server, type S7Profile } from '../lib/s7/server';
import { until } from './support/wait';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');

interface Run {
  child: ChildProcess;
  output: () => { out: string; err: string };
  exit: Promise<number>;
}

function run(args: string[]): Run {
  const child = spawn(process.execPath, [BIN, ...args], { stdio: ['ignore', 'pipe', 'pipe'] });
  let out = '';
  let err = '';
  child.stdout!.on('data', (d: Buffer) => (out += d.toString()));
  child.stderr!.on('data', (d: Buffer) => (err += d.toString()));
  const exit = once(child, 'exit').then(([code]) => code as number);
  return { child, output: () => ({ out, err }), exit };
}

describe('CLI: watch on s7:// with cyclic data (S7-300/400)', function () {
  this.timeout(40000);
  let server: S7Server;

  async function start(profile: S7Profile): Promise<string> {
    server = new S7Server({ port: 0, profile, layout: { dataBlocks: { 1: 64 } } });
    await server.listen();
    return `s7://127.0.0.1:${server.port}?rack=0&slot=${profile === 's7-300' ? 2 : 1}`;
  }

  afterEach(async () => {
    await server?.close();
  });

  it('an S7-300 reports the changes: a change shows long before the 60 s poll, and no Read Var runs', async function () {
    const url = await start('s7-300');
    server.memory.area('DB', 1)!.writeInt16BE(5, 2);
    let reads = 0;
    server.on('request', (r: { kind: string }) => r.kind === 'read' && reads++);
    const w = run(['watch', url, 'DB1,INT2', 'DB1,X4.0', '--interval', '60000', '--cycle', '250']);
    try {
      await until(() => /DB1,INT2 = 5\n/.test(w.output().out), 20000, 'the first value line');
      await until(() => /subscribed to 2 tag\(s\): the PLC reports changes every 300 ms/.test(w.output().err), 5000, 'the subscription');
      const started = Date.now();
      server.memory.area('DB', 1)!.writeInt16BE(6, 2);
      await until(() => /DB1,INT2 = 6\n/.test(w.output().out), 5000, 'the changed value line');
      const latency = Date.now() - started;
      this.test!.title += ` (a change showed after ${latency} ms)`;
      expect(latency).to.be.below(2000);
      expect(w.output().out).to.match(/DB1,X4\.0 = false/);
      expect(reads).to.equal(0);
    } finally {
      w.child.kill('SIGINT');
      expect(await w.exit).to.equal(EXIT.INTERRUPTED);
    }
  });

  it('an S7-1500 over PUT/GET refuses cyclic data: the tag is polled, stderr names s7plus://', async () => {
    const url = await start('s7-1500');
    server.memory.area('DB', 1)!.writeInt16BE(9, 2);
    const w = run(['watch', url, 'DB1,INT2', '--interval', '50']);
    try {
      await until(() => /DB1,INT2 = 9\n/.test(w.output().out), 20000, 'the first value line');
      await until(() => /DB1,INT2 cannot be subscribed \(.*s7plus:\/\/.*\): polled every 50 ms/.test(w.output().err), 5000, 'the fallback');
      server.memory.area('DB', 1)!.writeInt16BE(10, 2);
      await until(() => /DB1,INT2 = 10\n/.test(w.output().out), 5000, 'the polled change');
    } finally {
      w.child.kill('SIGINT');
      expect(await w.exit).to.equal(EXIT.INTERRUPTED);
    }
  });
});
