/**
 * The alarm definitions file (lib/alarms/definitions.ts) and `plcwire serve s7 --alarms FILE` on an S7-300:
 * the file's alarms come and go with their trigger bits, as a client sees them over s7://.
 */
import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import { once } from 'node:events';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import type { AlarmEvent } from '../lib/alarms/model';
import { parseAlarmDefinitions } from '../lib/alarms/definitions';
import { DRIVERS } from '../lib/drivers';
import { SourceError } from '../lib/errors';
import { S7Client } from '../lib/s7/client';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { freePort } from './support/net';
import { until } from './support/wait';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');

function problem(text: string): SourceError {
  try {
    parseAlarmDefinitions(text, 'plant-alarms.json');
  } catch (err) {
    expect(err).to.be.instanceOf(SourceError);
    return err as SourceError;
  }
  throw new Error('no error');
}

describe('alarm definitions file (--alarms)', () => {
  it('reads an array or { alarms: [...] }, with the kind deciding needsAck unless given, ids in decimal or 16#hex', () => {
    const text = JSON.stringify({
      alarms: [
        { id: 257, kind: 'ALARM_SQ', texts: { 'en-US': 'Tank high @1%d@' }, trigger: 'M10.0', values: ['MW20:INT'] },
        { id: '16#200', kind: 'ALARM_8', signal: 3, texts: { 'de-DE': 'Motor 3 Störung' }, trigger: 'Motor.Fault', priority: 4 },
        { id: 3, kind: 'NOTIFY', texts: { 'en-US': 'Door open' }, trigger: 'DB1.DBX0.0' },
      ],
    });
    expect(parseAlarmDefinitions(text, 'a.json')).to.deep.equal([
      { id: 257, kind: 'ALARM_SQ', texts: { 'en-US': 'Tank high @1%d@' }, needsAck: true, trigger: 'M10.0', values: ['MW20:INT'] },
      { id: 0x200, kind: 'ALARM_8', signal: 3, texts: { 'de-DE': 'Motor 3 Störung' }, needsAck: true, trigger: 'Motor.Fault', priority: 4 },
      { id: 3, kind: 'NOTIFY', texts: { 'en-US': 'Door open' }, needsAck: false, trigger: 'DB1.DBX0.0' },
    ]);
    expect(parseAlarmDefinitions('[]', 'a.json')).to.deep.equal([]);
  });

  it('names the file, line, column and field of every mistake', () => {
    const lines = ['[', '  { "id": 1, "kind": "ALARM_S", "texts": { "en": "x" }, "trigger": "M0.0" },', '  { "id": 2, "kind": "ALARM_X",'];
    let e = problem([...lines, '    "texts": { "en": "y" }, "trigger": "M0.1" }', ']'].join('\n'));
    expect(e.message).to.match(/^plant-alarms\.json:3:14: alarm 2, field "kind": "ALARM_X" is not one of ALARM_S, /);
    e = problem('[\n  { "id": 1, "kind": "NOTIFY", "texts": { "en": "x" }, "trigger": "M0.0",\n    "needsAck": true }\n]');
    expect(e.message).to.match(/^plant-alarms\.json:3:5: alarm 1, field "needsAck": a NOTIFY cannot be acknowledged/);
    e = problem('[{ "id": 1, "kind": "ALARM_S", "texts": { "en": "x" }, "trigger": "M0.0", "trigerr": 1 }]');
    expect(e.message).to.match(/:1:75: alarm 1, field "trigerr": unknown field/);
    e = problem('[{ "id": 1, "kind": "ALARM_S", "texts": { "en": "x" } }]');
    expect(e.message).to.match(/:1:2: alarm 1: the field "trigger" is missing/);
    e = problem(
      '[{ "id": 1, "kind": "ALARM_S", "texts": {"en": "x"}, "trigger": "M0.0" },\n { "id": 1, "kind": "ALARM_S", "texts": {"en": "x"}, "trigger": "M0.1" }]',
    );
    expect(e.message).to.match(/:2:4: alarm 2, field "id": alarm 1 is defined twice \(also alarm 1\)/);
    e = problem('[{ "id": 1, "kind": "ALARM_S", "signal": 2, "texts": {"en": "x"}, "trigger": "M0.0" }]');
    expect(e.message).to.match(/field "signal": only the 8-signal blocks/);
    e = problem('[{ "id": -1, "kind": "ALARM_S", "texts": {"en": "x"}, "trigger": "M0.0" }]');
    expect(e.message).to.match(/field "id": expected a whole number/);
    e = problem('[{ "id": 1,\n  "kind": "ALARM_S" ');
    expect(e.message).to.match(/^plant-alarms\.json:2:21: expected "," or "}"/);
    e = problem('{ "alarm": [] }');
    expect(e.message).to.match(/^plant-alarms\.json:1:1: expected an array of alarms/);
  });
});

describe('plcwire serve s7 --alarms (issue #33)', function () {
  this.timeout(60000);
  let dir: string;
  let child: ChildProcess | undefined;
  let client: S7Client | undefined;

  before(() => {
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-alarms-'));
  });

  after(async () => {
    await client?.close();
    if (child && child.exitCode === null) {
      child.kill('SIGINT');
      await once(child, 'exit');
    }
    fs.rmSync(dir, { recursive: true, force: true });
  });

  it("an S7-300 raises the file's alarm when its trigger bit is written TRUE and lists it in the query", async () => {
    const file = path.join(dir, 'alarms.json');
    fs.writeFileSync(
      file,
      JSON.stringify([{ id: 77, kind: 'ALARM_SQ', texts: { 'en-US': 'High level' }, trigger: 'M5.1', values: ['MW6:INT'] }]),
    );
    const port = await freePort();
    child = spawn(process.execPath, [BIN, 'serve', 's7', '--profile', 's7-300', '--port', String(port), '--alarms', file], {
      stdio: ['ignore', 'pipe', 'pipe'],
    });
    let out = '';
    child.stdout!.on('data', (d: Buffer) => (out += d.toString()));
    await until(() => /^Ctrl-C stops/m.test(out) || child!.exitCode !== null, 15000, 'serve prints how to reach it');
    expect(out).to.match(/1 alarm from .*alarms\.json: ALARM_S\/SQ\/8, NOTIFY over s7:\/\//);
    client = new S7Client(parseUrl(`s7://127.0.0.1:${port}?slot=2&timeout=3000`) as S7Endpoint);
    await client.connect();
    const events: AlarmEvent[] = [];
    const port7 = DRIVERS.s7.alarms!;
    const sub = await port7.subscribe(client, {}, (e) => events.push(e));
    await client.write({ MW6: 1234 });
    await client.write({ 'M5.1': true });
    await until(() => events.length === 1, 5000, 'the coming alarm');
    expect(events[0]).to.deep.include({ type: 'alarm', change: 'coming' });
    const listed = await port7.list(client);
    expect(listed.map((a) => [a.id, a.kind, a.state, a.values])).to.deep.equal([
      [77, 'ALARM_SQ', 'coming', [{ type: 'INT', value: 1234 }]],
    ]);
    await port7.acknowledge(client, 77);
    await until(() => events.length === 2, 5000, 'the acknowledgement');
    await sub.close();
  });
});
