/**
 * `plcwire sparkplug` through the real binary (bin/plcwire.js) against a real
 * mosquitto and our S7 simulator: births with typed metrics, DDATA on a change,
 * a DCMD write to a --writable tag and the refusal of another, NDEATH on Ctrl-C
 * (exit code 130), bdSeq carried over by --state-dir, and the usage errors
 * (exit code 2) before anything connects.
 */
import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import { once } from 'node:events';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { EXIT } from '../lib/cli/io';
import { S7Server } from '../lib/s7/server';
import { DataType } from '../lib/sparkplug/datatypes';
import { Mosquitto } from './support/mosquitto';
import { missingMosquitto, sparkplugRequired } from './support/sparkplug-peers';
import { skipBecause } from './support/skip';
import { SparkplugListener } from './support/sparkplug-listener';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');

function run(args: string[]): { child: ChildProcess; err: () => string; exit: Promise<number | null> } {
  const child = spawn(process.execPath, [BIN, ...args], { stdio: ['ignore', 'pipe', 'pipe'] });
  let err = '';
  child.stdout!.resume();
  child.stderr!.on('data', (d: Buffer) => (err += d.toString()));
  return { child, err: () => err, exit: once(child, 'exit').then(([code]) => code as number | null) };
}

describe('plcwire sparkplug: the real binary, mosquitto and the S7 simulator', function () {
  this.timeout(90_000);
  const broker = new Mosquitto();
  const server = new S7Server({ port: 0, profile: 's7-1500' });
  let plc = '';
  let stateDir = '';
  const children: ChildProcess[] = [];
  let listener: SparkplugListener | undefined;

  before(async function () {
    const missing = missingMosquitto();
    if (missing) {
      if (sparkplugRequired()) throw new Error(`PLCWIRE_REQUIRE_SPARKPLUG=1 but ${missing}`);
      skipBecause(this, missing);
    }
    await broker.start();
    plc = `s7://127.0.0.1:${await server.listen()}?rack=0&slot=1`;
    stateDir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-spb-cli-'));
  });
  afterEach(async () => {
    for (const c of children.splice(0)) if (c.exitCode === null && c.signalCode === null) c.kill('SIGKILL');
    await listener?.close();
    listener = undefined;
  });
  after(async () => {
    await server.close();
    await broker.dispose();
    if (stateDir) fs.rmSync(stateDir, { recursive: true, force: true });
  });

  const edge = (...extra: string[]) => {
    const r = run([
      'sparkplug',
      '--broker',
      broker.url,
      '--group',
      'Plant',
      '--node',
      'Edge1',
      '--device',
      `Line1=${plc}`,
      '--tags',
      'Line1:DB1.DBW0:INT,DB1.DBD2:REAL,DB1.DBX6.0',
      '--writable',
      'Line1:DB1.DBW0:INT',
      '--interval',
      '50',
      '--state-dir',
      stateDir,
      ...extra,
    ]);
    children.push(r.child);
    return r;
  };

  it('births typed metrics, reports a change, writes a permitted DCMD, refuses another, and sends NDEATH on Ctrl-C', async () => {
    const db = server.memory.area('DB', 1)!;
    db.writeInt16BE(-7, 0);
    db.writeFloatBE(2.5, 2);
    listener = new SparkplugListener(broker.url);
    await listener.ready();
    const r = edge();
    const nbirth = await listener.waitFor((m) => m.type === 'NBIRTH', 30_000);
    const bdSeq = nbirth.payload!.metrics.find((m) => m.name === 'bdSeq')!.value;
    const dbirth = await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Line1');
    const metrics = Object.fromEntries(dbirth.payload!.metrics.map((m) => [m.name, m]));
    expect(metrics['DB1.DBW0:INT']).to.include({ datatype: DataType.Int16, value: -7 });
    expect(metrics['DB1.DBD2:REAL']).to.include({ datatype: DataType.Float, value: 2.5 });
    expect(metrics['DB1.DBX6.0']).to.include({ datatype: DataType.Boolean, value: false });

    const from = listener.heard.length;
    db[6] |= 1;
    const ddata = await listener.waitFor((m) => m.type === 'DDATA' && m.payload!.metrics.some((x) => x.value === true), 20_000, from);
    expect(ddata.payload!.metrics).to.have.length(1);
    expect(ddata.payload!.metrics[0]!.alias).to.equal(metrics['DB1.DBX6.0']!.alias);

    await listener.publish('spBv1.0/Plant/DCMD/Edge1/Line1', {
      timestamp: Date.now(),
      metrics: [{ name: 'DB1.DBW0:INT', datatype: DataType.Int16, value: 1234 }],
    });
    await listener.waitFor((m) => m.type === 'DDATA' && m.payload!.metrics.some((x) => x.value === 1234), 20_000, from);
    expect(db.readInt16BE(0)).to.equal(1234);
    await listener.publish('spBv1.0/Plant/DCMD/Edge1/Line1', {
      timestamp: Date.now(),
      metrics: [{ name: 'DB1.DBD2:REAL', datatype: DataType.Float, value: 9.5 }],
    });
    const deadline = Date.now() + 20_000;
    while (!/DB1\.DBD2:REAL/.test(r.err()) && Date.now() < deadline) await new Promise((res) => setTimeout(res, 20));
    expect(r.err()).to.match(/DB1\.DBD2:REAL/);
    expect(db.readFloatBE(2)).to.equal(2.5);

    const beforeStop = listener.heard.length;
    r.child.kill('SIGINT');
    expect(await r.exit).to.equal(EXIT.INTERRUPTED);
    const ndeath = await listener.waitFor((m) => m.type === 'NDEATH', 20_000, beforeStop);
    expect(ndeath.payload!.metrics.find((m) => m.name === 'bdSeq')!.value).to.equal(bdSeq);
    expect(r.err()).to.match(/online on mqtt:\/\/127\.0\.0\.1:\d+ \(bdSeq \d+\)/);
    expect(r.err()).to.match(/Line1: DCMD wrote DB1\.DBW0:INT = 1234/);

    // --state-dir: the next run goes on counting.
    const from2 = listener.heard.length;
    const again = edge();
    const next = await listener.waitFor((m) => m.type === 'NBIRTH', 30_000, from2);
    expect(Number(next.payload!.metrics.find((m) => m.name === 'bdSeq')!.value)).to.equal((Number(bdSeq) + 1) % 256);
    again.child.kill('SIGTERM');
    expect(await again.exit).to.equal(EXIT.INTERRUPTED);
  });

  it('waits for the primary host: no birth before its STATE online', async () => {
    listener = new SparkplugListener(broker.url);
    await listener.ready();
    await listener.publish('spBv1.0/STATE/SCADA', JSON.stringify({ online: false, timestamp: Date.now() }), { qos: 1, retain: true });
    const r = edge('--primary-host', 'SCADA');
    const deadline = Date.now() + 20_000;
    while (!/waiting for the primary host SCADA/.test(r.err()) && Date.now() < deadline) await new Promise((res) => setTimeout(res, 20));
    expect(r.err()).to.match(/waiting for the primary host SCADA/);
    expect(listener.heard.filter((m) => m.type === 'NBIRTH')).to.deep.equal([]);
    await listener.publish('spBv1.0/STATE/SCADA', JSON.stringify({ online: true, timestamp: Date.now() }), { qos: 1, retain: true });
    await listener.waitFor((m) => m.type === 'NBIRTH', 20_000);
    r.child.kill('SIGINT');
    expect(await r.exit).to.equal(EXIT.INTERRUPTED);
    await listener.publish('spBv1.0/STATE/SCADA', '', { qos: 1, retain: true });
  });

  it('refuses a bad command line with exit code 2 and one line, before anything connects', async () => {
    const r = run(['sparkplug', '--broker', broker.url, '--group', 'Plant', '--node', 'Edge/1', '--device', `Line1=${plc}`]);
    children.push(r.child);
    expect(await r.exit).to.equal(EXIT.USAGE);
    expect(r.err()).to.match(/^plcwire: --node "Edge\/1": a Sparkplug id cannot hold "\/" \(plcwire --help\)\n$/);
    const t = run(['sparkplug', '--broker', broker.url, '--group', 'Plant', '--node', 'E', '--device', `Line1=${plc}`]);
    children.push(t.child);
    expect(await t.exit).to.equal(EXIT.USAGE);
    expect(t.err()).to.match(/--device Line1: give its tags with --tags Line1:<tag>/);
  });

  it('prints its help', async () => {
    const r = run(['sparkplug', '--help']);
    let out = '';
    r.child.stdout!.on('data', (d: Buffer) => (out += d.toString()));
    expect(await r.exit).to.equal(EXIT.OK);
    expect(out).to.match(/^usage: plcwire sparkplug --broker/);
    expect(out).to.match(/--writable NAME:t/);
  });
});
