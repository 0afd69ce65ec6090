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
import type { AlarmDefinition } from '../lib/alarms/model';
import { EXIT } from '../lib/cli/io';
import { S7Client } from '../lib/s7/client';
import { S7Server } from '../lib/s7/server';
import type { GeneratedCertificate } from '../lib/s7plus/transport/cert';
import { DataType } from '../lib/sparkplug/datatypes';
import type { DataSet } from '../lib/sparkplug/model';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { Mosquitto, testCa, tlsMosquitto } from './support/mosquitto';
import { requirePeers } from './support/sparkplug-peers';
import { SparkplugListener, type HeardMessage } from './support/sparkplug-listener';
import { until } from './support/wait';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');

interface Run {
  child: ChildProcess;
  err: () => string;
  /** Resolves when stderr matches `re`, rejects after `ms` with what stderr said. */
  errMatches: (re: RegExp, ms?: number) => Promise<void>;
  exit: Promise<number | null>;
}

function run(args: string[], env: NodeJS.ProcessEnv = process.env): Run {
  const child = spawn(process.execPath, [BIN, ...args], { stdio: ['ignore', 'pipe', 'pipe'], env });
  let err = '';
  child.stdout!.resume();
  child.stderr!.on('data', (d: Buffer) => (err += d.toString()));
  const errMatches = (re: RegExp, ms = 20_000): Promise<void> =>
    new Promise((resolve, reject) => {
      const check = (): void => {
        if (!re.test(err)) return;
        clearTimeout(timer);
        child.stderr!.off('data', check);
        resolve();
      };
      const timer = setTimeout(() => {
        child.stderr!.off('data', check);
        reject(new Error(`stderr did not match ${re} within ${ms} ms:\n${err}`));
      }, ms);
      child.stderr!.on('data', check);
      check();
    });
  return { child, err: () => err, errMatches, exit: once(child, 'exit').then(([code]) => code as number | null) };
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
    requirePeers(this);
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

  /**
   * --buffer-dir across a restart: a first run keeps a change on disk while the broker is away and ends; a second
   * run with the same directory forwards it as historical DDATA after its births. `brokerFirst`: the broker is back
   * before the second run starts (its session may come before the PLC's first read); else it comes back once the
   * second run has its PLC, and the second run waits for a primary host's STATE, which this test publishes once it
   * listens (so it hears the births however slow the broker's start).
   */
  async function bufferAcrossRestart(brokerFirst: boolean): Promise<void> {
    const bufferDir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-spb-buffer-'));
    const kept = path.join(bufferDir, 'Plant.Edge1.buffer.ndjson');
    try {
      const db = server.memory.area('DB', 1)!;
      db.writeInt16BE(100, 0);
      listener = new SparkplugListener(broker.url);
      await listener.ready();
      const first = edge('--buffer-dir', bufferDir);
      const birth = await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Line1', 30_000);
      const alias = birth.payload!.metrics.find((m) => m.name === 'DB1.DBW0:INT')!.alias;
      await listener.close();
      listener = undefined;

      // The broker goes away; the edge node sees its session end, and keeps the change it reads meanwhile on disk.
      await broker.stop();
      await first.errMatches(/online on [^\n]*\n(?:.*\n)*plcwire: connecting to /);
      const changedAt = Date.now();
      db.writeInt16BE(4321, 0);
      await until(() => fs.existsSync(kept) && fs.readFileSync(kept, 'utf8').split('\n').length > 1, 20_000, 'the change kept on disk');
      first.child.kill('SIGINT');
      expect(await first.exit).to.equal(EXIT.INTERRUPTED);
      expect(fs.readFileSync(kept, 'utf8'), 'still kept after the process ended').to.match(/"device":"Line1"/);

      // A new process with the same directory, and the broker back: births, then what the first run kept.
      if (brokerFirst) await broker.start();
      const secondAt = Date.now();
      const second = edge('--buffer-dir', bufferDir, ...(brokerFirst ? [] : ['--primary-host', 'Historian']));
      if (!brokerFirst) {
        // Its PLC is up and read while the broker is away; then the broker, this host, and its STATE online.
        await second.errMatches(/Line1: connected to [^\n]*\n(?:.*\n)*plcwire: connecting to /);
        await broker.start();
      }
      listener = new SparkplugListener(broker.url);
      await listener.ready();
      if (!brokerFirst) {
        await second.errMatches(/waiting for the primary host Historian/);
        await listener.publish('spBv1.0/STATE/Historian', JSON.stringify({ online: true, timestamp: Date.now() }), {
          qos: 1,
          retain: true,
        });
      }
      const dbirth = await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Line1', 30_000);
      const historical = await listener.waitFor(
        (m) => m.type === 'DDATA' && m.device === 'Line1' && m.payload!.metrics.some((x) => x.isHistorical === true),
        20_000,
        listener.heard.indexOf(dbirth),
        'a historical DDATA after the DBIRTH',
      );
      const value = historical.payload!.metrics.find((x) => x.alias === alias && x.value === 4321)!;
      expect(value, 'the kept change, by the alias of its birth').to.not.equal(undefined);
      expect(value.isHistorical).to.equal(true);
      // Its own time, from the first run: the poll that read it (stamped when the poll started, so up to a poll before the change).
      expect(Number(value.timestamp)).to.be.within(changedAt - 1000, secondAt);
      // Forwarded once: the file is emptied, a third run would send nothing again.
      expect(fs.readFileSync(kept, 'utf8')).to.equal('');
      second.child.kill('SIGINT');
      expect(await second.exit).to.equal(EXIT.INTERRUPTED);
      await listener.publish('spBv1.0/STATE/Historian', '', { qos: 1, retain: true });
    } finally {
      fs.rmSync(bufferDir, { recursive: true, force: true });
    }
  }

  it('--buffer-dir: a value one run kept while the broker was away, the next run forwards as historical after its births', async () => {
    await bufferAcrossRestart(false);
  });

  it('--buffer-dir: the same when the broker is back before the next run has read its PLC', async () => {
    // Before the fix, a device born after the NBIRTH (its first read later) kept its values until the next session.
    await bufferAcrossRestart(true);
  });

  describe('--alarms: an S7-300 simulator raising an ALARM_SQ', () => {
    const TANK_HIGH: AlarmDefinition = {
      id: 257,
      kind: 'ALARM_SQ',
      texts: { 'en-US': 'Tank high' },
      needsAck: true,
      trigger: 'M10.0',
      values: ['MW20:INT'],
    };
    const classic = new S7Server({ port: 0, profile: 's7-300', alarms: [TANK_HIGH] });
    let url = '';
    let operator: S7Client | undefined;
    before(async () => {
      url = `s7://127.0.0.1:${await classic.listen()}?rack=0&slot=2`;
      operator = new S7Client(parseUrl(`${url}&timeout=3000`) as S7Endpoint);
      await operator.connect();
    });
    after(async () => {
      await operator?.close();
      await classic.close();
    });

    const aliases = (birth: HeardMessage) => new Map(birth.payload!.metrics.map((m) => [m.alias, m.name]));
    /** The message's metrics by name (DDATA carries aliases: the birth names them). */
    const named = (m: HeardMessage, names: Map<number | bigint | undefined, string | undefined>) =>
      Object.fromEntries(m.payload!.metrics.map((x) => [x.name ?? names.get(x.alias), x]));

    it('births the five Alarms metrics, reports a coming alarm as Event and Active, acknowledges by DCMD where allowed and not read-only', async () => {
      listener = new SparkplugListener(broker.url);
      await listener.ready();
      const r = run([
        'sparkplug',
        '--broker',
        broker.url,
        '--group',
        'Plant',
        '--node',
        'Alarms1',
        '--device',
        `Line1=${url}&allow=ALARMS`,
        '--device',
        `Line2=${url}&readOnly=true`,
        '--tags',
        'Line1:MW20:INT',
        '--tags',
        'Line2:MW20:INT',
        '--alarms',
        'Line1',
        '--alarms',
        'Line2',
        '--writable',
        'Line1:Alarms/Acknowledge',
        '--writable',
        'Line2:Alarms/Acknowledge',
        '--interval',
        '50',
      ]);
      children.push(r.child);
      const births = {
        Line1: await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Line1', 30_000),
        Line2: await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Line2', 30_000),
      };
      const born = named(births.Line1, new Map());
      expect(Object.keys(born)).to.include.members([
        'Alarms/Active',
        'Alarms/Active Count',
        'Alarms/Unacknowledged Count',
        'Alarms/Event',
        'Alarms/Acknowledge',
      ]);
      expect(born['Alarms/Active']).to.include({ datatype: DataType.DataSet });
      expect((born['Alarms/Active']!.value as DataSet).rows).to.deep.equal([]);
      expect(born['Alarms/Active Count']).to.include({ datatype: DataType.Int32, value: 0 });
      expect(born['Alarms/Acknowledge']).to.include({ datatype: DataType.UInt32 });

      // The trigger bit goes TRUE: the CPU pushes the coming ALARM_SQ.
      const from = listener.heard.length;
      classic.memory.write('M', 0, 20, Buffer.of(0x00, 0x58));
      classic.memory.writeBit('M', 0, 10, 0, true);
      const line1 = aliases(births.Line1);
      const coming = await listener.waitFor(
        (m) => m.type === 'DDATA' && m.device === 'Line1' && named(m, line1)['Alarms/Event'] !== undefined,
        20_000,
        from,
        'a DDATA with Alarms/Event',
      );
      const data = named(coming, line1);
      const event = JSON.parse(data['Alarms/Event']!.value as string);
      expect(event).to.deep.include({ type: 'alarm', change: 'coming' });
      expect(event.alarm).to.include({ id: 257, kind: 'ALARM_SQ', state: 'coming', needsAck: true, acknowledged: false });
      expect(event.alarm.values).to.deep.equal([{ type: 'INT', value: 88 }]);
      const table = data['Alarms/Active']!.value as DataSet;
      expect(table.rows).to.have.length(1);
      const row = Object.fromEntries(table.columns.map((c, i) => [c, table.rows[0]![i]]));
      expect(row).to.include({ Id: 257, Kind: 'ALARM_SQ', State: 'coming', Acknowledged: false });
      expect(data['Alarms/Unacknowledged Count']).to.include({ value: 1 });

      // Acknowledged through the read-only connection: refused before the PLC, one line, the alarm still waits.
      await listener.publish('spBv1.0/Plant/DCMD/Alarms1/Line2', {
        timestamp: Date.now(),
        metrics: [{ name: 'Alarms/Acknowledge', datatype: DataType.UInt32, value: 257 }],
      });
      await r.errMatches(/Line2: Alarms\/Acknowledge 257: .*read-only/);
      expect(
        r
          .err()
          .split('\n')
          .filter((l) => /Alarms\/Acknowledge 257/.test(l)),
      ).to.have.length(1);
      expect((await operator!.alarms()).map((a) => [a.id, a.acknowledged])).to.deep.equal([[257, false]]);

      // Through the connection whose allow-list names ALARMS: the CPU acknowledges it, the next DDATA says so.
      const beforeAck = listener.heard.length;
      await listener.publish('spBv1.0/Plant/DCMD/Alarms1/Line1', {
        timestamp: Date.now(),
        metrics: [{ name: 'Alarms/Acknowledge', datatype: DataType.UInt32, value: 257 }],
      });
      const acked = await listener.waitFor(
        (m) => {
          if (m.type !== 'DDATA' || m.device !== 'Line1') return false;
          const t = named(m, line1)['Alarms/Active']?.value as DataSet | undefined;
          return t?.rows[0]?.[t.columns.indexOf('Acknowledged')] === true;
        },
        20_000,
        beforeAck,
        'a DDATA whose Alarms/Active shows Acknowledged true',
      );
      expect(named(acked, line1)['Alarms/Unacknowledged Count']).to.include({ value: 0 });
      expect((await operator!.alarms()).map((a) => [a.id, a.acknowledged])).to.deep.equal([[257, true]]);
      await r.errMatches(/Line1: DCMD acknowledged alarm 257/);

      classic.memory.writeBit('M', 0, 10, 0, false);
      r.child.kill('SIGINT');
      expect(await r.exit).to.equal(EXIT.INTERRUPTED);
    });
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
    // A device whose protocol has no alarms, a buffer directory that is not there: one line each, no connection made.
    const before = server.connectionCount;
    const cp = run(
      [...['sparkplug', '--broker', broker.url, '--group', 'Plant', '--node', 'E'], ...['--device', `Line1=${plc}`]]
        .concat(['--device', 'CP=fetchwrite://127.0.0.1?fetchPort=1&writePort=2', '--tags', 'Line1:MW0', '--tags', 'CP:DB1,INT0'])
        .concat(['--alarms', 'CP']),
    );
    children.push(cp.child);
    expect(await cp.exit).to.equal(EXIT.USAGE);
    expect(cp.err()).to.equal(
      'plcwire: --alarms CP: its PLC is reached over fetchwrite://, which reports no alarms (s7:// or s7plus:// do) (plcwire --help)\n',
    );
    const dir = run(
      ['sparkplug', '--broker', broker.url, '--group', 'Plant', '--node', 'E', '--device', `Line1=${plc}`, '--tags', 'Line1:MW0'].concat([
        '--buffer-dir',
        path.join(stateDir, 'no-such-dir'),
      ]),
    );
    children.push(dir.child);
    expect(await dir.exit).to.equal(EXIT.USAGE);
    expect(dir.err()).to.match(/^plcwire: --buffer-dir ".*no-such-dir": no such directory \(plcwire --help\)\n$/);
    expect(server.connectionCount).to.equal(before);
  });

  it('prints its help', async () => {
    const r = run(['sparkplug', '--help']);
    let out = '';
    r.child.stdout!.on('data', (d: Buffer) => (out += d.toString()));
    expect(await r.exit).to.equal(EXIT.OK);
    expect(out).to.match(/^usage: plcwire sparkplug --broker/);
    expect(out).to.match(/--writable NAME:t/);
    expect(out).to.match(/--alarms NAME +the device's PLC's alarms as its metrics Alarms\/Active/);
    expect(out).to.match(/NAME:Alarms\/Acknowledge lets a host acknowledge/);
    expect(out).to.match(/--buffer-dir DIR +keep them on disk in DIR too/);
    expect(out).to.match(/--mqtt-user U +the broker's user; its password is the first line of --mqtt-password-file F/);
    expect(out).to.match(/--mqtt-ca F +mqtts:\/\/ \(wss:\/\/\): the CA \(PEM\)/);
  });
});

describe('plcwire sparkplug: a TLS broker with a login (mosquitto with a TLS listener and a password file)', function () {
  this.timeout(90_000);
  const SECRET = 'Edge-Secret-77';
  let ca: GeneratedCertificate;
  let broker: Mosquitto;
  const server = new S7Server({ port: 0, profile: 's7-1500' });
  let plc = '';
  let dir = '';
  const children: ChildProcess[] = [];
  let listener: SparkplugListener | undefined;

  before(async function () {
    requirePeers(this);
    ca = await testCa('plant CA');
    broker = await tlsMosquitto(ca, { edge1: SECRET, scada: 'host-pw' });
    await broker.start();
    plc = `s7://127.0.0.1:${await server.listen()}?rack=0&slot=1`;
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-spb-tls-'));
    fs.writeFileSync(path.join(dir, 'ca.pem'), ca.cert);
    const other = await testCa('another CA');
    fs.writeFileSync(path.join(dir, 'other-ca.pem'), other.cert);
  });
  afterEach(async () => {
    for (const c of children.splice(0)) if (c.exitCode === null && c.signalCode === null) c.kill('SIGKILL');
    await listener?.close();
    listener = undefined;
  });
  after(async () => {
    await server.close();
    await broker?.dispose();
    if (dir) fs.rmSync(dir, { recursive: true, force: true });
  });

  const edge = (caFile: string) => {
    const r = run(
      ['sparkplug', '--broker', broker.url, '--mqtt-ca', caFile, '--mqtt-user', 'edge1', '--group', 'Plant', '--node', 'Tls1'].concat([
        '--device',
        `Line1=${plc}`,
        '--tags',
        'Line1:DB1.DBW0:INT',
        '--interval',
        '100',
      ]),
      { ...process.env, PLCWIRE_MQTT_PASSWORD: SECRET },
    );
    children.push(r.child);
    return r;
  };

  it('reaches it with --mqtt-ca, --mqtt-user and PLCWIRE_MQTT_PASSWORD: births a host hears; the password is on no line it prints', async () => {
    listener = new SparkplugListener(broker.url, 'spBv1.0/#', { ca: ca.cert, username: 'scada', password: 'host-pw' });
    await listener.ready();
    const r = edge(path.join(dir, 'ca.pem'));
    await r.errMatches(/online on mqtts:\/\/127\.0\.0\.1:\d+ \(bdSeq \d+\): births sent/);
    const dbirth = await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Line1', 20_000);
    expect(dbirth.payload!.metrics.map((m) => m.name)).to.deep.equal(['DB1.DBW0:INT']);
    r.child.kill('SIGINT');
    expect(await r.exit).to.equal(EXIT.INTERRUPTED);
    expect(r.err()).to.not.include(SECRET);
  });

  it('a CA that did not sign the broker: "its TLS certificate was refused", never online, nothing published', async () => {
    listener = new SparkplugListener(broker.url, 'spBv1.0/#', { ca: ca.cert, username: 'scada', password: 'host-pw' });
    await listener.ready();
    const r = edge(path.join(dir, 'other-ca.pem'));
    await r.errMatches(/plcwire: broker mqtts:\/\/127\.0\.0\.1:\d+: its TLS certificate was refused \(.*\); nothing was sent/);
    r.child.kill('SIGINT');
    expect(await r.exit).to.equal(EXIT.INTERRUPTED);
    expect(r.err()).to.not.match(/online on/);
    expect(listener.heard.filter((m) => m.topic.includes('/Tls1'))).to.deep.equal([]);
  });

  it('a password in the broker URL is exit 2 and one line that does not repeat it', async () => {
    const r = run(
      ['sparkplug', '--broker', broker.url.replace('mqtts://', `mqtts://edge1:${SECRET}@`), '--group', 'G', '--node', 'E'].concat([
        '--device',
        `L=${plc}`,
        '--tags',
        'L:MW0',
      ]),
    );
    children.push(r.child);
    expect(await r.exit).to.equal(EXIT.USAGE);
    expect(r.err()).to.match(/^plcwire: --broker "mqtts:\/\/edge1:\*\*\*@127\.0\.0\.1:\d+": no user or password in the URL .*\n$/);
    expect(r.err()).to.not.include(SECRET);
  });
});
