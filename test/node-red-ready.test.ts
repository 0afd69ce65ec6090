/**
 * waitForNodeRed (test/support/node-red-process.ts), the readiness wait of
 * every test that starts Node-RED in a child process, against a stand-in
 * that behaves as red.js does: it logs "Started flows" before it opens its
 * HTTP port (red.js listens only once the runtime's start resolved; Node-RED
 * 5 under load refused the install test's first request in that gap). The
 * stand-in opens its port when told to on stdin, so the gap is as long as the
 * test makes it, with no timer.
 */
import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import * as http from 'node:http';
import * as net from 'node:net';
import { freePort } from './support/net';
import { NodeRedPortTaken, waitForNodeRed } from './support/node-red-process';

const STAND_IN = `
const http = require('node:http');
const port = Number(process.argv[1]);
console.log('[info] Started flows');
process.stdin.on('data', (d) => {
  if (String(d).includes('listen')) {
    const server = http.createServer((req, res) => res.end('{}'));
    // As red.js does when its port is taken: two lines, exit code 1.
    server.on('error', (err) => {
      console.log('[error] Unable to listen on http://127.0.0.1:' + port + '/');
      console.log('[error] Error: port in use');
      process.exit(1);
    });
    server.listen(port, '127.0.0.1', () => console.log('[info] Server now running'));
  }
  if (String(d).includes('exit')) process.exit(3);
});
`;

function get(url: string): Promise<number | string> {
  return new Promise((resolve) => {
    http
      .get(url, (res) => {
        res.resume();
        resolve(res.statusCode ?? 0);
      })
      .on('error', (err: NodeJS.ErrnoException) => resolve(err.code ?? err.message));
  });
}

describe('waitForNodeRed: ready means the admin API answers, not only "Started flows" logged', function () {
  this.timeout(60_000);
  let child: ChildProcess | undefined;
  let output = '';
  let url = '';

  beforeEach(async () => {
    const port = await freePort();
    url = `http://127.0.0.1:${port}/settings`;
    output = '';
    child = spawn(process.execPath, ['-e', STAND_IN, String(port)], { stdio: ['pipe', 'pipe', 'pipe'] });
    child.stdout!.on('data', (d: Buffer) => (output += d.toString()));
    child.stderr!.on('data', (d: Buffer) => (output += d.toString()));
  });
  afterEach(async () => {
    if (child && child.exitCode === null && child.signalCode === null) {
      const exited = new Promise((r) => child!.once('exit', r));
      child.kill('SIGKILL');
      await exited;
    }
  });

  it('waits past "Started flows" while the port refuses, and resolves once the probe answers 200', async () => {
    let ready = false;
    const waiting = waitForNodeRed(child!, url, () => output).then(() => (ready = true));
    while (!/Started flows/.test(output)) await new Promise((r) => child!.stdout!.once('data', r));
    // The gap the install test fell into: the line is there, the port is not.
    expect(await get(url)).to.equal('ECONNREFUSED');
    expect(ready).to.equal(false);
    child!.stdin!.write('listen\n');
    await waiting;
    expect(await get(url)).to.equal(200);
  });

  it('rejects with the log when Node-RED exits before it answers', async () => {
    const waiting = waitForNodeRed(child!, url, () => output);
    while (!/Started flows/.test(output)) await new Promise((r) => child!.stdout!.once('data', r));
    child!.stdin!.write('exit\n');
    const err = await waiting.then(
      () => undefined,
      (e: Error) => e,
    );
    expect(err).to.be.instanceOf(Error).and.not.instanceOf(NodeRedPortTaken);
    expect(err?.message).to.match(
      new RegExp(`^Node-RED exited \\(3\\) before answering ${url.replace(/[./]/g, '\\$&')}:\\n\\[info\\] Started flows`),
    );
  });

  it('rejects with NodeRedPortTaken when Node-RED exits because its port was taken, so the caller can take another', async () => {
    // Another process on the port, one that hangs up on whoever connects.
    const taken = net.createServer((socket) => socket.destroy()).listen(Number(new URL(url).port), '127.0.0.1');
    await new Promise((r) => taken.once('listening', r));
    try {
      const waiting = waitForNodeRed(child!, url, () => output);
      while (!/Started flows/.test(output)) await new Promise((r) => child!.stdout!.once('data', r));
      child!.stdin!.write('listen\n');
      const err = await waiting.then(
        () => undefined,
        (e: Error) => e,
      );
      expect(err).to.be.instanceOf(NodeRedPortTaken);
      expect(err!.message).to.match(/^Node-RED exited \(1\) before answering .*: its port was taken:\n[\s\S]*\[error\] Error: port in use/);
    } finally {
      await new Promise((r) => taken.close(r));
    }
  });

  it('rejects at its deadline naming the probe and its last answer', async () => {
    while (!/Started flows/.test(output)) await new Promise((r) => child!.stdout!.once('data', r));
    const err = await waitForNodeRed(child!, url, () => output, 1000).then(
      () => undefined,
      (e: Error) => e,
    );
    expect(err?.message).to.include(`Node-RED did not answer ${url} within 1000 ms (last: ECONNREFUSED)`);
  });
});
