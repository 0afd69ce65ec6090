/**
 * `plcwire alarms` and `plcwire ack` through the real binary against our
 * S7-1500 simulator raising a Program_Alarm over S7CommPlus (TLS, the
 * fingerprint pinned): the active list with its text and values, every
 * event of `--watch --json` until Ctrl-C (exit 130), and an acknowledgement
 * the S7CommPlus client refuses as it must (no public layout of the request).
 */
import { expect } from 'chai';
import { spawn } from 'node:child_process';
import { once } from 'node:events';
import * as path from 'node:path';
import type { AlarmDefinition } from '../lib/alarms/model';
import { EXIT } from '../lib/cli/io';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { startPlusSimulator, type PlusSimulator } from './support/s7plus-sim';
import { until } from './support/wait';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');

const TANK_HIGH: AlarmDefinition = {
  id: 7,
  kind: 'Program_Alarm',
  texts: { 'en-US': 'Tank level high: @1%5.1f@ m', 'de-DE': 'Tankpegel hoch: @1%5.1f@ m' },
  needsAck: true,
  priority: 5,
  trigger: '"Tank".Alarm',
  values: ['"Tank".Level'],
};

/** The binary running; its output so far, its exit. */
function start(args: string[]) {
  const child = spawn(process.execPath, [BIN, ...args], { stdio: ['pipe', 'pipe', 'pipe'] });
  const out = { text: '', err: '' };
  child.stdout.on('data', (d: Buffer) => (out.text += d.toString()));
  child.stderr.on('data', (d: Buffer) => (out.err += d.toString()));
  child.stdin.end();
  const timer = setTimeout(() => child.kill('SIGKILL'), 30000);
  const exit = once(child, 'exit').then(([code]) => {
    clearTimeout(timer);
    return code as number;
  });
  return { child, out, exit };
}

describe('cli: plcwire alarms on an S7-1500 (our simulator, S7CommPlus)', function () {
  this.timeout(60000);
  let sim: PlusSimulator;
  const trigger = (on: boolean) => sim.server.memory.writeBit('DB', 1, 6, 1, on); // "Tank".Alarm is DB1.DBX6.1

  before(async () => {
    sim = await startPlusSimulator({ sources: SOURCES, db: DB_NUMBERS, alarms: [TANK_HIGH] });
  });
  afterEach(() => trigger(false));
  after(() => sim?.server.close());

  it('prints the active alarm with its text in the language asked for and its value; none: says so on stderr', async () => {
    const none = start(['alarms', sim.url]);
    expect(await none.exit).to.equal(EXIT.OK);
    expect(none.out.text).to.equal('');
    expect(none.out.err).to.match(/^plcwire: no active alarms on /);
    trigger(true);
    const one = start(['alarms', sim.url, '--language', 'de-DE']);
    expect(await one.exit, one.out.err).to.equal(EXIT.OK);
    // "Tank".Level starts at 12.5 (test/fixtures/s7plus/Tank.db); %5.1f pads it to five places.
    expect(one.out.text).to.match(
      /^7 Program_Alarm coming unacknowledged priority 5 class 1 came \S+Z "Tankpegel hoch: {2}12\.5 m" \(REAL 12\.5\)\n$/,
    );
    const json = start(['alarms', sim.url, '--json']);
    expect(await json.exit).to.equal(EXIT.OK);
    const [alarm] = JSON.parse(json.out.text) as { id: number; texts: Record<string, { text: string }> }[];
    expect(alarm).to.deep.include({ id: 7, kind: 'Program_Alarm', state: 'coming', needsAck: true, acknowledged: false });
    expect(alarm!.texts['en-US']!.text).to.match(/^Tank level high: /);
  });

  it('--watch --json: one JSON object per event as the trigger comes and goes, until Ctrl-C (exit 130)', async () => {
    const watch = start(['alarms', sim.url, '--watch', '--json']);
    await until(() => /subscribed to the alarms of /.test(watch.out.err), 20000, 'subscribed');
    trigger(true);
    await until(() => watch.out.text.includes('\n'), 10000, 'the coming event');
    trigger(false);
    await until(() => watch.out.text.split('\n').length >= 3, 10000, 'the going event');
    watch.child.kill('SIGINT');
    expect(await watch.exit).to.equal(EXIT.INTERRUPTED);
    const events = watch.out.text
      .trim()
      .split('\n')
      .map((l) => JSON.parse(l) as { type: string; change: string; alarm: { id: number }; at: string });
    expect(events.map((e) => [e.type, e.change, e.alarm.id])).to.deep.equal([
      ['alarm', 'coming', 7],
      ['alarm', 'going', 7],
    ]);
    expect(events[0]!.at).to.match(/^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z$/);
  });

  it('ack: the S7CommPlus client refuses it, naming why, and the alarm stays unacknowledged', async () => {
    trigger(true);
    const ack = start(['ack', sim.url, '7']);
    expect(await ack.exit).to.equal(EXIT.TAG_ERROR);
    expect(ack.out.err).to.contain('acknowledge of alarm 7').and.to.contain('no public source shows how S7CommPlus acknowledges');
    const list = start(['alarms', sim.url, '--json']);
    await list.exit;
    expect(JSON.parse(list.out.text)).to.have.length(1).and.to.have.nested.property('[0].acknowledged', false);
  });
});
