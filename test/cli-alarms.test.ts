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
import { PassThrough } from 'node:stream';
import type { PlcAlarm } from '../lib/alarms/model';
import { ackOn, alarmsOn } from '../lib/cli/alarms';
import { parseArgs } from '../lib/cli/args';
import { EXIT } from '../lib/cli/io';
import { createClient, type AnyClient } from '../lib/connect';
import { PlcError } from '../lib/errors';
import { S7Server } from '../lib/s7/server';
import { PlcMemory } from '../lib/sim/memory';
import { StandInPort } from './support/alarm-port';
import { until } from './support/wait';

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

  describe('on a live link, through a stand-in of the alarms port', () => {
    /** The command's streams, captured, and its Ctrl-C. */
    function io() {
      const stdout = new PassThrough();
      const stderr = new PassThrough();
      const out = { text: '', err: '' };
      stdout.on('data', (d: Buffer) => (out.text += d.toString()));
      stderr.on('data', (d: Buffer) => (out.err += d.toString()));
      const ctrlC = new AbortController();
      return { io: { stdout, stderr, stdin: new PassThrough(), signal: ctrlC.signal }, out, ctrlC };
    }
    const args = (...words: string[]) => parseArgs(words, ['language'], ['json', 'watch', 'mode', 'diagnostics']);
    const tankHigh: PlcAlarm = {
      id: 1001,
      kind: 'ALARM_S',
      state: 'coming',
      needsAck: true,
      acknowledged: false,
      coming: new Date('2026-12-03T10:00:00.000Z'),
      values: [{ type: 'REAL', value: 95.5 }],
      texts: { 'en-US': { text: 'Tank high level' }, 'de-DE': { text: 'Tank Füllstand hoch' } },
    };
    let client: AnyClient;
    beforeEach(() => {
      client = createClient(url());
      client.on('error', () => {});
    });
    afterEach(() => client.close());

    it('lists the active alarms, one line each in the language asked for, and closes the connection', async () => {
      const stand = new StandInPort<AnyClient>();
      stand.active = [tankHigh];
      const before = connections;
      const c = io();
      expect(await alarmsOn(client, stand, args('--language', 'de'), c.io)).to.equal(EXIT.OK);
      expect(c.out.text).to.equal('1001 ALARM_S coming unacknowledged came 2026-12-03T10:00:00.000Z "Tank Füllstand hoch" (REAL 95.5)\n');
      expect(connections).to.equal(before + 1);
      expect(client.state).to.equal('closed');
    });

    it('--json: the active alarms as one JSON array, times as ISO strings; none active: stderr says so, stdout stays empty', async () => {
      const stand = new StandInPort<AnyClient>();
      stand.active = [tankHigh];
      const c = io();
      await alarmsOn(client, stand, args('--json'), c.io);
      const [shown] = JSON.parse(c.out.text) as Record<string, unknown>[];
      expect(shown).to.deep.include({
        id: 1001,
        kind: 'ALARM_S',
        coming: '2026-12-03T10:00:00.000Z',
        values: [{ type: 'REAL', value: 95.5 }],
      });
      const empty = io();
      await alarmsOn(createClient(url()), new StandInPort<AnyClient>(), args(), empty.io);
      expect(empty.out.text).to.equal('');
      expect(empty.out.err).to.match(/^plcwire: no active alarms on /);
    });

    it('--watch --json: one JSON object per event, in order, until Ctrl-C (exit 130), the subscription and link closed', async () => {
      const stand = new StandInPort<AnyClient>();
      const c = io();
      const done = alarmsOn(client, stand, args('--watch', '--json', '--mode'), c.io);
      await until(() => stand.subs.length === 1, 5000, 'subscribed');
      expect(stand.options[0]).to.deep.include({ mode: true, diagnostics: false });
      const at = new Date('2026-12-03T10:00:01.000Z');
      stand.subs[0]!.push({ type: 'alarm', change: 'coming', alarm: tankHigh, at });
      stand.subs[0]!.push({ type: 'mode', from: 'RUN', to: 'STOP', at });
      stand.subs[0]!.push({ type: 'alarm', change: 'going', alarm: { ...tankHigh, state: 'going' }, at, during: 'outage' });
      await until(() => c.out.text.split('\n').length === 4, 5000, 'three lines');
      const lines = c.out.text
        .trim()
        .split('\n')
        .map((l) => JSON.parse(l) as Record<string, unknown>);
      expect(lines.map((l) => [l.type, l.change ?? l.to, l.during])).to.deep.equal([
        ['alarm', 'coming', undefined],
        ['mode', 'STOP', undefined],
        ['alarm', 'going', 'outage'],
      ]);
      expect(lines[0]).to.deep.include({ at: '2026-12-03T10:00:01.000Z' });
      c.ctrlC.abort();
      expect(await done).to.equal(EXIT.INTERRUPTED);
      expect(stand.subs[0]!.closed).to.equal(true);
      expect(client.state).to.equal('closed');
    });

    it('ack: "alarm <id> acknowledged" once the port resolved; the PLC’s refusal names the alarm', async () => {
      const stand = new StandInPort<AnyClient>();
      const c = io();
      expect(await ackOn(client, stand, 1001, args(), c.io)).to.equal(EXIT.OK);
      expect(c.out.text).to.equal('alarm 1001 acknowledged\n');
      expect(stand.acks).to.deep.equal([1001]);
      const refusing = new StandInPort<AnyClient>();
      refusing.acknowledge = () => Promise.reject(new PlcError('PLC_ERROR', 'no such alarm'));
      const err = await ackOn(createClient(url()), refusing, 7, args(), io().io).then(
        () => undefined,
        (e: unknown) => e,
      );
      expect(err).to.be.instanceOf(PlcError).with.property('message', 'alarm 7: no such alarm');
    });
  });
});
