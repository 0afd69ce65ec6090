import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import { once } from 'node:events';
import * as path from 'node:path';
import { PassThrough } from 'node:stream';
import { EXIT, main } from '../lib/cli/main';
import { S7Server } from '../lib/s7/server';
import { freePort } from './support/net';
import { until } from './support/wait';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');

/** Runs the CLI in-process with captured output. */
async function cli(args: string[], stdinIsTty = false): Promise<{ code: number; out: string; err: string }> {
  const stdout = new PassThrough();
  const stderr = new PassThrough();
  const stdin = Object.assign(new PassThrough(), { isTTY: stdinIsTty });
  let out = '';
  let err = '';
  stdout.on('data', (d: Buffer) => (out += d.toString()));
  stderr.on('data', (d: Buffer) => (err += d.toString()));
  const code = await main(args, { stdout, stderr, stdin, signal: new AbortController().signal });
  return { code, out, err };
}

/** Runs the real bin in a child process; collects output until it exits. */
function run(args: string[]): { child: ChildProcess; output: () => { out: string; err: string }; exit: Promise<number> } {
  const child = spawn(process.execPath, [BIN, ...args], { stdio: ['pipe', 'pipe', 'pipe'] });
  let out = '';
  let err = '';
  child.stdout!.on('data', (d: Buffer) => (out += d.toString()));
  child.stderr!.on('data', (d: Buffer) => (err += d.toString()));
  const exit = once(child, 'exit').then(([code]) => code as number);
  return { child, output: () => ({ out, err }), exit };
}

describe('plcwire CLI', function () {
  this.timeout(15000);
  let server: S7Server;
  let url: string;
  let requests: number;

  beforeEach(async () => {
    server = new S7Server({ port: 0 });
    const port = await server.listen();
    url = `s7://127.0.0.1:${port}?rack=0&slot=1`;
    requests = 0;
    server.on('request', () => requests++);
    const db1 = server.memory.area('DB', 1)!;
    db1.writeInt16BE(1234, 2);
    db1.writeFloatBE(1.5, 4);
    db1[12] = 0b0000_0100;
    db1[20] = 10; // STRING[10]'s declared max length, as the PLC program sets it
  });

  afterEach(() => server.close());

  describe('read', () => {
    it('prints one JSON object keyed by the addresses as given', async () => {
      const r = await cli(['read', url, 'DB1,INT2', 'DB1.DBD4:REAL', 'db1,x12.2', '--json']);
      expect(r.err).to.equal('');
      expect(r.code).to.equal(EXIT.OK);
      expect(JSON.parse(r.out)).to.deep.equal({ 'DB1,INT2': 1234, 'DB1.DBD4:REAL': 1.5, 'db1,x12.2': true });
    });

    it('prints "address = value" lines for people', async () => {
      const r = await cli(['read', url, 'DB1,INT2', 'DB1,S20.10']);
      expect(r.code).to.equal(EXIT.OK);
      expect(r.out).to.equal('DB1,INT2 = 1234\nDB1,S20.10 = ""\n');
    });

    it('reports a missing DB on its tag, keeps the others, and exits 1', async () => {
      const r = await cli(['read', url, 'DB1,INT2', 'DB999,INT0', '--json']);
      expect(r.code).to.equal(EXIT.TAG_ERROR);
      expect(JSON.parse(r.out)).to.deep.equal({ 'DB1,INT2': 1234, 'DB999,INT0': null });
      expect(r.err).to.match(/DB999,INT0/);
      expect(r.err.trim().split('\n')).to.have.length(1);
    });

    it('refuses a malformed address with exit 2 before connecting', async () => {
      const r = await cli(['read', url, 'DB1,INT2', 'DB0,INT2']);
      expect(r.code).to.equal(EXIT.USAGE);
      expect(r.err).to.match(/^plcwire: invalid address "DB0,INT2": .+\n$/);
      expect(requests).to.equal(0);
      expect(server.connectionCount).to.equal(0);
    });

    it('exits 3 with one line when nothing listens', async () => {
      const port = await freePort();
      const r = await cli(['read', `s7://127.0.0.1:${port}?timeout=2000`, 'DB1,INT2']);
      expect(r.code).to.equal(EXIT.CONNECTION);
      expect(r.err).to.match(/127\.0\.0\.1/);
      expect(r.err).not.to.match(/\n\s+at /);
    });

    it('exits 2 on an unknown URL parameter or option', async () => {
      expect((await cli(['read', `${url}&slto=1`, 'DB1,INT2'])).code).to.equal(EXIT.USAGE);
      expect((await cli(['read', url, 'DB1,INT2', '--jsn'])).code).to.equal(EXIT.USAGE);
    });
  });

  describe('write', () => {
    it('writes values of several types and prints an acknowledgement per tag', async () => {
      const r = await cli(['write', url, 'DB1,INT2=-5', 'DB1.DBD4:REAL=2.25', 'DB1,X12.3=true', 'DB1,S20.10=hello']);
      expect(r.err).to.equal('');
      expect(r.code).to.equal(EXIT.OK);
      const db1 = server.memory.area('DB', 1)!;
      expect(db1.readInt16BE(2)).to.equal(-5);
      expect(db1.readFloatBE(4)).to.equal(2.25);
      expect(db1[12]).to.equal(0b0000_1100);
      expect(db1.subarray(20, 27).toString('latin1')).to.equal('\x0a\x05hello');
      expect(r.out.split('\n').filter(Boolean)).to.have.length(4);
    });

    it('refuses an out-of-range value with exit 2 and sends nothing', async () => {
      const r = await cli(['write', url, 'DB1,INT2=40000']);
      expect(r.code).to.equal(EXIT.USAGE);
      expect(r.err).to.match(/DB1,INT2/);
      expect(server.connectionCount).to.equal(0);
      expect(server.memory.area('DB', 1)!.readInt16BE(2)).to.equal(1234);
    });

    it('refuses to write to a remote PLC from a script without --yes (exit 4, never connects)', async () => {
      const r = await cli(['write', 's7://10.255.255.1?timeout=1000', 'DB1,INT2=1'], false);
      expect(r.code).to.equal(EXIT.REFUSED);
      expect(r.err).to.match(/--yes/);
    });

    it('refuses writes on a read-only connection (exit 4)', async () => {
      const r = await cli(['write', `${url}&readOnly=true`, 'DB1,INT2=7']);
      expect(r.code).to.equal(EXIT.REFUSED);
      expect(server.memory.area('DB', 1)!.readInt16BE(2)).to.equal(1234);
    });
  });

  describe('other protocols', () => {
    it('serve fetchwrite and serve freeport --tcp run simulators that read and write work against', async () => {
      const [fetchPort, writePort, busPort] = [await freePort(), await freePort(), await freePort()];
      const fw = run(['serve', 'fetchwrite', '--fetch-port', String(fetchPort), '--write-port', String(writePort)]);
      const fp = run(['serve', 'freeport', '--tcp', String(busPort), '--stations', '5,6']);
      try {
        await until(() => /listening/.test(fw.output().out) && /answering on tcp/.test(fp.output().out), 10000, 'both simulators up');
        const fwUrl = `fetchwrite://127.0.0.1?fetchPort=${fetchPort}&writePort=${writePort}`;
        expect((await cli(['write', fwUrl, 'DB1,INT4=-12', 'MB3=7'])).code).to.equal(EXIT.OK);
        const r1 = await cli(['read', fwUrl, 'DB1,INT4', 'MB3', '--json']);
        expect(JSON.parse(r1.out)).to.deep.equal({ 'DB1,INT4': -12, MB3: 7 });
        const fpUrl = `freeport+tcp://127.0.0.1:${busPort}`;
        const w = await cli(['write', fpUrl, 'ST6,B0.4=[230,39,161,195]']);
        expect(w.code, w.err).to.equal(EXIT.OK);
        const r2 = await cli(['read', fpUrl, 'ST6,DWORD0', 'ST5,INT0', '--json']);
        expect(r2.err).to.equal('');
        expect(JSON.parse(r2.out)).to.deep.equal({ 'ST6,DWORD0': 0xe627a1c3, 'ST5,INT0': 0 });
        const bad = await cli(['read', fpUrl, 'ST5,INT3']);
        expect(bad.code).to.equal(EXIT.USAGE);
      } finally {
        fw.child.kill('SIGINT');
        fp.child.kill('SIGINT');
      }
      expect(await fw.exit).to.equal(0);
      expect(await fp.exit).to.equal(0);
    });
  });

  describe('the installed binary', () => {
    it('serve s7 runs the simulator until Ctrl-C, and read/write talk to it', async () => {
      const port = await freePort();
      const srv = run(['serve', 's7', '--port', String(port), '--profile', 's7-1200']);
      try {
        await until(() => /listening on 127\.0\.0\.1:\d+/.test(srv.output().out), 10000, 'serve prints its address');
        const target = `s7://127.0.0.1:${port}`;
        const w = run(['write', target, 'MW10=321']);
        expect(await w.exit, w.output().err).to.equal(0);
        const r = run(['read', target, 'MW10', '--json']);
        expect(await r.exit, r.output().err).to.equal(0);
        expect(JSON.parse(r.output().out)).to.deep.equal({ MW10: 321 });
      } finally {
        srv.child.kill('SIGINT');
      }
      expect(await srv.exit).to.equal(0);
    });

    it('watch prints changes and survives the PLC going away and coming back', async () => {
      const port = server.port;
      const w = run(['watch', url, 'DB1,INT2', '--interval', '50', '--json']);
      try {
        await until(() => w.output().out.includes('1234'), 10000, 'first value');
        server.memory.area('DB', 1)!.writeInt16BE(77, 2);
        await until(() => w.output().out.includes('"DB1,INT2":77'), 5000, 'changed value');
        const memory = server.memory;
        await server.close();
        await until(() => /disconnected|reconnecting/.test(w.output().err), 5000, 'link loss reported');
        server = new S7Server({ port, memory });
        await server.listen();
        memory.area('DB', 1)!.writeInt16BE(78, 2);
        await until(() => w.output().out.includes('"DB1,INT2":78'), 10000, 'value after reconnect');
      } finally {
        w.child.kill('SIGINT');
      }
      expect(await w.exit).to.equal(0);
      const lines = w.output().out.trim().split('\n').map((l) => JSON.parse(l) as { values: Record<string, number> });
      expect(lines.map((l) => l.values['DB1,INT2'])).to.deep.equal([1234, 77, 78]);
    });

    it('prints usage and exits 2 without a command', async () => {
      const r = run([]);
      expect(await r.exit).to.equal(2);
      expect(r.output().out).to.match(/usage:/);
    });
  });
});
