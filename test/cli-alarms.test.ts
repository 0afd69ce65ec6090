/**
 * `plcwire alarms` and `plcwire ack` through the real binary (bin/plcwire.js
 * in a child process): help, exit codes, and the refusals that need no PLC
 * (an acknowledgement the URL forbids is refused before connecting: the
 * simulator sees no connection).
 */
import { expect } from 'chai';
import { spawn } from 'node:child_process';
import { once } from 'node:events';
import * as path from 'node:path';
import { EXIT } from '../lib/cli/io';
import { S7Server } from '../lib/s7/server';
import { PlcMemory } from '../lib/sim/memory';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');

/** Runs the binary to its end (with a deadline); its exit code and output. */
async function plcwire(args: string[], ms = 15000): Promise<{ code: number; out: string; err: string }> {
  const child = spawn(process.execPath, [BIN, ...args], { stdio: ['pipe', 'pipe', 'pipe'] });
  let out = '';
  let err = '';
  child.stdout.on('data', (d: Buffer) => (out += d.toString()));
  child.stderr.on('data', (d: Buffer) => (err += d.toString()));
  child.stdin.end();
  const timer = setTimeout(() => child.kill('SIGKILL'), ms);
  try {
    const [code] = (await once(child, 'exit')) as [number];
    return { code, out, err };
  } finally {
    clearTimeout(timer);
  }
}

describe('cli: plcwire alarms and plcwire ack', function () {
  this.timeout(30000);
  let server: S7Server;
  let port: number;
  let connections: number;

  before(async () => {
    server = new S7Server({ port: 0, memory: new PlcMemory(), profile: 's7-300' });
    port = await server.listen();
    connections = 0;
    server.on('connection', () => connections++);
  });

  after(() => server.close());

  const url = (extra = '') => `s7://127.0.0.1:${port}?rack=0&slot=2${extra}`;

  it('prints each command’s help with its options and an example', async () => {
    const alarms = await plcwire(['alarms', '--help']);
    expect(alarms.code).to.equal(EXIT.OK);
    expect(alarms.out).to.match(/^usage: plcwire alarms <url>/);
    for (const option of ['--watch', '--mode', '--diagnostics', '--language', '--json']) expect(alarms.out).to.contain(option);
    const ack = await plcwire(['help', 'ack']);
    expect(ack.code).to.equal(EXIT.OK);
    expect(ack.out).to.match(/^usage: plcwire ack <url> <alarm id> \[--yes\]/);
    expect(ack.out).to.contain('ALARMS or ALARM<id>');
    const all = await plcwire(['--help']);
    expect(all.out).to.contain('plcwire alarms <url>').and.to.contain('plcwire ack   <url> <alarm id>');
  });

  it('refuses an acknowledgement on a read-only URL before connecting (exit 4)', async () => {
    const before = connections;
    const r = await plcwire(['ack', url('&readOnly=true'), '1001', '--yes']);
    expect(r.code).to.equal(EXIT.REFUSED);
    expect(r.err).to.equal('plcwire: acknowledge of alarm 1001 refused: the connection is read-only\n');
    expect(connections, 'nothing was sent').to.equal(before);
  });

  it('refuses an alarm the allow-list does not name, by its id in 16#hex too (exit 4)', async () => {
    const before = connections;
    const r = await plcwire(['ack', url('&allow=DB1,ALARM7'), '16#3E9', '--yes']);
    expect(r.code).to.equal(EXIT.REFUSED);
    expect(r.err).to.contain('acknowledge of alarm 1001 refused').and.to.contain('names neither ALARMS nor ALARM1001');
    expect(connections, 'nothing was sent').to.equal(before);
  });

  it('bad command lines are usage errors (exit 2) that say what is wrong', async () => {
    const cases: [string[], RegExp][] = [
      [['ack', url(), '12x'], /alarm id "12x" is not a number/],
      [['ack', url()], /ack needs the id of the alarm/],
      [['alarms'], /alarms needs an? /],
      [['alarms', url(), '--mode'], /--mode goes with --watch/],
      [['alarms', 'fetchwrite://127.0.0.1'], /alarms: fetchwrite:\/\/ has no alarms/],
      [['ack', 'freeport+tcp://127.0.0.1:4001', '1', '--yes'], /ack: freeport:\/\/ has no alarms/],
    ];
    for (const [args, message] of cases) {
      const r = await plcwire(args);
      expect(r.code, args.join(' ')).to.equal(EXIT.USAGE);
      expect(r.err, args.join(' ')).to.match(message);
    }
  });
});
