/**
 * The Sparkplug B nodes in Node-RED (nodes/sparkplug-edge.js, nodes/sparkplug-device.js)
 * against a real mosquitto and our S7 simulator: the device's births, its
 * status, a change as DDATA, a permitted DCMD write sent on as a message, a
 * refused one on the Catch node (the PLC untouched), and NDEATH when the flow
 * stops. With an S7-300 simulator raising an ALARM_SQ: the Alarms metrics of
 * a device whose box is set (and none for the other), an alarm as DDATA, a
 * host's acknowledgement, and each device's errors on its own Catch only.
 * Without mosquitto the suite skips and says why (fails in .ci/run).
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import type { AlarmDefinition } from '../../lib/alarms/model';
import { S7Server } from '../../lib/s7/server';
import { DataType } from '../../lib/sparkplug/datatypes';
import type { DataSet } from '../../lib/sparkplug/model';
import { Mosquitto, testCa, tlsMosquitto } from '../support/mosquitto';
import { requirePeers } from '../support/sparkplug-peers';
import { SparkplugListener, type HeardMessage } from '../support/sparkplug-listener';
import { fetchWriteSim, s7Sim } from './sims';
import type { GeneratedCertificate } from '../../lib/s7plus/transport/cert';
import { CORE_NODES, helper, nodes, Recorder, ROOT, until, type Sim } from './support';

const edgeNode = require(path.join(ROOT, 'nodes/sparkplug-edge.js'));
const deviceNode = require(path.join(ROOT, 'nodes/sparkplug-device.js'));
const INT16 = DataType.Int16;

describe('nodes: Sparkplug B edge node and device, mosquitto and the S7 simulator', function () {
  this.timeout(60_000);
  const broker = new Mosquitto();
  let sim: Sim;
  let listener: SparkplugListener;

  before(async function () {
    requirePeers(this);
    await broker.start();
    sim = await s7Sim();
  });
  beforeEach(async () => {
    await helper.startServer();
    listener = new SparkplugListener(broker.url);
    await listener.ready();
  });
  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
    await listener?.close();
  });
  after(async () => {
    await sim?.close();
    await broker.dispose();
  });

  const flow = () => {
    const at = { z: 'tab' };
    return [
      { id: 'tab', type: 'tab', label: 'sparkplug' },
      { id: 'conn', type: 'plcwire-connection', url: sim.url },
      { id: 'edge', type: 'plcwire-sparkplug-edge', brokers: broker.url, group: 'Plant', nodeId: 'RedEdge', interval: 50, buffer: 1000 },
      {
        id: 'dev',
        type: 'plcwire-sparkplug-device',
        ...at,
        edge: 'edge',
        connection: 'conn',
        device: 'Line1',
        tags: [
          { name: 'Level', address: sim.addr(0) },
          { name: 'Setpoint', address: sim.addr(1) },
        ],
        writable: 'Setpoint',
        wires: [['out']],
      },
      { id: 'out', type: 'helper', ...at },
      { id: 'catcher', type: 'catch', ...at, scope: null, uncaught: false, wires: [['caught']] },
      { id: 'caught', type: 'helper', ...at },
    ];
  };

  it('births the device, shows online, reports a change, writes a permitted DCMD, refuses another, and sends NDEATH when stopped', async () => {
    sim.set(0, 11);
    sim.set(1, 22);
    await helper.load([nodes.connection, edgeNode, deviceNode, nodes.catch], flow());
    const out = new Recorder(helper.getNode('out'));
    const caught = new Recorder(helper.getNode('caught'));
    const dev = helper.getNode('dev');
    const statuses: any[] = [];
    dev.on('call:status', (call: any) => statuses.push(call.args[0]));

    const dbirth = await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Line1', 30_000);
    const byName = Object.fromEntries(dbirth.payload!.metrics.map((m) => [m.name, m]));
    expect(byName.Level).to.include({ datatype: INT16, value: 11 });
    expect(byName.Setpoint).to.include({ datatype: INT16, value: 22 });
    await until(() => statuses.some((s) => s.fill === 'green'), 10_000, 'a green status');

    const from = listener.heard.length;
    sim.set(0, 12);
    const ddata = await listener.waitFor((m) => m.type === 'DDATA' && m.payload!.metrics.some((x) => x.value === 12), 10_000, from);
    expect(ddata.payload!.metrics[0]!.alias).to.equal(byName.Level!.alias);

    await listener.publish('spBv1.0/Plant/DCMD/RedEdge/Line1', {
      timestamp: Date.now(),
      metrics: [{ name: 'Setpoint', datatype: INT16, value: 40 }],
    });
    const done = await out.next(() => true, 10_000, 'the done write');
    expect(done.payload).to.deep.equal({ device: 'Line1', metric: 'Setpoint', value: 40 });
    expect(sim.get(1)).to.equal(40);

    await listener.publish('spBv1.0/Plant/DCMD/RedEdge/Line1', {
      timestamp: Date.now(),
      metrics: [{ name: 'Level', datatype: INT16, value: 99 }],
    });
    const refused = await caught.next(() => true, 10_000, 'the refused write on Catch');
    expect(refused.error.message).to.match(/Level/);
    expect(refused.error.source.id).to.equal('dev');
    expect(sim.get(0)).to.equal(12);

    const beforeStop = listener.heard.length;
    await helper.unload();
    const ndeath = await listener.waitFor((m) => m.type === 'NDEATH', 10_000, beforeStop);
    expect(ndeath.payload!.metrics.map((m) => m.name)).to.deep.equal(['bdSeq']);
  });
  describe("the PLC's alarms: an S7-300 simulator raising an ALARM_SQ", () => {
    const TANK_HIGH: AlarmDefinition = { id: 257, kind: 'ALARM_SQ', texts: { 'en-US': 'Tank high' }, needsAck: true, trigger: 'M10.0' };
    const classic = new S7Server({ port: 0, profile: 's7-300', alarms: [TANK_HIGH] });
    let url = '';
    before(async () => {
      url = `s7://127.0.0.1:${await classic.listen()}?rack=0&slot=2&timeout=1000`;
    });
    afterEach(() => classic.memory.writeBit('M', 0, 10, 0, false));
    after(() => classic.close());

    /** Two devices of one PLC: "Press 1" publishes its alarms (hosts may acknowledge), "Press" does not. */
    const alarmFlow = (edge: object = {}) => {
      const at = { z: 'tab' };
      const tags = [{ name: 'Level', address: 'MW20:INT' }];
      return [
        { id: 'tab', type: 'tab', label: 'sparkplug alarms' },
        { id: 'conn', type: 'plcwire-connection', url },
        { id: 'edge', type: 'plcwire-sparkplug-edge', brokers: broker.url, group: 'Plant', nodeId: 'AlarmEdge', interval: 50, ...edge },
        {
          id: 'devA',
          type: 'plcwire-sparkplug-device',
          ...at,
          edge: 'edge',
          connection: 'conn',
          device: 'Press 1',
          tags,
          writable: '',
          alarms: true,
          acknowledge: true,
          wires: [['outA']],
        },
        {
          id: 'devB',
          type: 'plcwire-sparkplug-device',
          ...at,
          edge: 'edge',
          connection: 'conn',
          device: 'Press',
          tags: [...tags, { name: 'Setpoint', address: 'MW22:INT' }],
          writable: 'Setpoint',
          alarms: false,
          wires: [[]],
        },
        { id: 'outA', type: 'helper', ...at },
        // One Catch for both (the test helper loads a core node's module once per node of its type): who raised is msg.error.source.
        { id: 'catcher', type: 'catch', ...at, scope: null, uncaught: false, wires: [['caught']] },
        { id: 'caught', type: 'helper', ...at },
      ];
    };
    const ALARM_NAMES = ['Alarms/Active', 'Alarms/Active Count', 'Alarms/Unacknowledged Count', 'Alarms/Event', 'Alarms/Acknowledge'];
    /** A message's metrics by name (DDATA carries aliases: the birth names them). */
    const named = (m: HeardMessage, birth: HeardMessage) => {
      const names = new Map(birth.payload!.metrics.map((x) => [x.alias, x.name]));
      return Object.fromEntries(m.payload!.metrics.map((x) => [x.name ?? names.get(x.alias), x]));
    };

    it('births the Alarms metrics where the box is set and not elsewhere, sends an alarm as DDATA Alarms/Event, and a host acknowledges it', async () => {
      await helper.load([nodes.connection, edgeNode, deviceNode, nodes.catch], alarmFlow());
      const out = new Recorder(helper.getNode('outA'));
      const birthA = await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Press 1', 30_000);
      const birthB = await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Press', 30_000);
      expect(birthA.payload!.metrics.map((m) => m.name)).to.include.members(['Level', ...ALARM_NAMES]);
      expect(birthB.payload!.metrics.map((m) => m.name)).to.deep.equal(['Level', 'Setpoint']);

      const from = listener.heard.length;
      classic.memory.writeBit('M', 0, 10, 0, true);
      const coming = await listener.waitFor(
        (m) => m.type === 'DDATA' && m.device === 'Press 1' && named(m, birthA)['Alarms/Event'] !== undefined,
        15_000,
        from,
        'DDATA Alarms/Event',
      );
      const event = JSON.parse(named(coming, birthA)['Alarms/Event']!.value as string);
      expect(event).to.deep.include({ type: 'alarm', change: 'coming' });
      expect(event.alarm).to.include({ id: 257, acknowledged: false });

      // "hosts may acknowledge alarms": Alarms/Acknowledge is writable; the connection has no allow-list.
      const beforeAck = listener.heard.length;
      await listener.publish('spBv1.0/Plant/DCMD/AlarmEdge/Press 1', {
        timestamp: Date.now(),
        metrics: [{ name: 'Alarms/Acknowledge', datatype: DataType.UInt32, value: 257 }],
      });
      const done = await out.next(() => true, 10_000, 'the acknowledgement done');
      expect(done.payload).to.deep.equal({ device: 'Press 1', metric: 'Alarms/Acknowledge', value: 257 });
      await listener.waitFor(
        (m) => {
          if (m.type !== 'DDATA' || m.device !== 'Press 1') return false;
          const t = named(m, birthA)['Alarms/Active']?.value as DataSet | undefined;
          return t?.rows[0]?.[t.columns.indexOf('Acknowledged')] === true;
        },
        15_000,
        beforeAck,
        'DDATA Alarms/Active acknowledged',
      );
    });

    it('the edge node keeps store-and-forward in its buffer directory', async () => {
      const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-nr-buffer-'));
      try {
        await helper.load([nodes.connection, edgeNode, deviceNode, nodes.catch], alarmFlow({ bufferDir: dir }));
        await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Press 1', 30_000);
        expect(fs.readdirSync(dir)).to.deep.equal(['Plant.AlarmEdge.buffer.ndjson']);
      } finally {
        await helper.unload();
        fs.rmSync(dir, { recursive: true, force: true });
      }
    });

    it('the alarms box on a connection whose protocol has no alarms is one error on Catch naming the device, once the flows started', async () => {
      const cp = await fetchWriteSim();
      try {
        const flow = alarmFlow().filter((n: any) => n.id !== 'devB');
        const conn = flow.find((n: any) => n.id === 'conn') as { url: string };
        conn.url = cp.url;
        const devA = flow.find((n: any) => n.id === 'devA') as { tags: unknown };
        devA.tags = [{ name: 'Level', address: cp.addr(0) }];
        await helper.load([nodes.connection, edgeNode, deviceNode, nodes.catch], flow);
        const caught = new Recorder(helper.getNode('caught'));
        const msg = await caught.next(() => true, 10_000, 'the refusal on Catch');
        expect(msg.error.message).to.match(
          /^(PlcError: )?Sparkplug device Press 1: its connection \(fetchwrite:\/\/\) reports no alarms \(s7:\/\/ or s7plus:\/\/ do\)$/,
        );
        expect(msg.error.source.id).to.equal('devA');
        expect(caught.messages).to.have.length(1);
      } finally {
        await helper.unload();
        await cp.close();
      }
    });

    it("each device's errors are raised by its own node only, by the device the edge node names (not by words in the message)", async () => {
      await helper.load([nodes.connection, edgeNode, deviceNode, nodes.catch], alarmFlow());
      const caught = new Recorder(helper.getNode('caught'));
      await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Press 1', 30_000);
      await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Press', 30_000);
      // A refused write to "Press 1", then one to "Press": the edge node takes them in order.
      for (const device of ['Press 1', 'Press'])
        await listener.publish(`spBv1.0/Plant/DCMD/AlarmEdge/${device}`, {
          timestamp: Date.now(),
          metrics: [{ name: 'Level', datatype: DataType.Int16, value: 1 }],
        });
      await until(() => caught.messages.length >= 2, 10_000, 'both refusals caught');
      // Before the fix, a regex took "Press" out of "device Press 1: …": A's error was raised by B's node, and not by A's.
      expect(
        caught.messages.map((m) => [m.error.source.id, /device Press 1:/.test(m.error.message) ? 'Press 1' : 'Press']),
      ).to.have.deep.members([
        ['devA', 'Press 1'],
        ['devB', 'Press'],
      ]);
    });
  });
});

describe("nodes: the Sparkplug edge node on a TLS broker with a login (Node-RED's tls-config node, mosquitto)", function () {
  this.timeout(60_000);
  const SECRET = 'Red-Edge-Secret';
  const tlsNode = require(path.join(CORE_NODES, 'core/network/05-tls.js'));
  let ca: GeneratedCertificate;
  let broker: Mosquitto;
  let sim: Sim;
  let dir = '';
  let listener: SparkplugListener | undefined;

  before(async function () {
    requirePeers(this);
    ca = await testCa('plant CA');
    broker = await tlsMosquitto(ca, { edge: SECRET, scada: 'host-pw' });
    await broker.start();
    sim = await s7Sim();
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-red-tls-'));
    fs.writeFileSync(path.join(dir, 'ca.pem'), ca.cert);
  });
  beforeEach(() => helper.startServer());
  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
    await listener?.close();
    listener = undefined;
  });
  after(async () => {
    await sim?.close();
    await broker?.dispose();
    if (dir) fs.rmSync(dir, { recursive: true, force: true });
  });

  const flow = (caFile: string) => [
    { id: 'tab', type: 'tab', label: 'tls' },
    { id: 'tlscfg', type: 'tls-config', name: 'plant CA', cert: '', key: '', ca: caFile, verifyservercert: true },
    { id: 'conn', type: 'plcwire-connection', url: sim.url },
    { id: 'edge', type: 'plcwire-sparkplug-edge', brokers: broker.url, group: 'Plant', nodeId: 'TlsEdge', interval: 50, tls: 'tlscfg' },
    {
      id: 'dev',
      type: 'plcwire-sparkplug-device',
      z: 'tab',
      edge: 'edge',
      connection: 'conn',
      device: 'Line1',
      tags: [{ name: 'Level', address: sim.addr(0) }],
    },
    { id: 'catcher', type: 'catch', z: 'tab', scope: null, uncaught: false, wires: [['caught']] },
    { id: 'caught', type: 'helper', z: 'tab' },
  ];
  const credentials = { edge: { username: 'edge', password: SECRET } };

  it('births through TLS with the CA of a tls-config node and the user and password of its credentials', async () => {
    listener = new SparkplugListener(broker.url, 'spBv1.0/#', { ca: ca.cert, username: 'scada', password: 'host-pw' });
    await listener.ready();
    await helper.load([nodes.connection, edgeNode, deviceNode, nodes.catch, tlsNode], flow(path.join(dir, 'ca.pem')), credentials);
    const dbirth = await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Line1', 30_000);
    expect(dbirth.payload!.metrics.map((m) => m.name)).to.deep.equal(['Level']);
  });

  it('a CA that did not sign the broker: the device node reports CERTIFICATE_UNTRUSTED on Catch and nothing is published', async () => {
    const other = await testCa('another CA');
    fs.writeFileSync(path.join(dir, 'other.pem'), other.cert);
    listener = new SparkplugListener(broker.url, 'spBv1.0/#', { ca: ca.cert, username: 'scada', password: 'host-pw' });
    await listener.ready();
    await helper.load([nodes.connection, edgeNode, deviceNode, nodes.catch, tlsNode], flow(path.join(dir, 'other.pem')), credentials);
    const caught = new Recorder(helper.getNode('caught'));
    const msg = await caught.next(() => true, 20_000, 'the refusal on Catch');
    expect(msg.error.message).to.match(/its TLS certificate was refused .*nothing was sent/);
    expect(JSON.stringify(msg)).to.not.include(SECRET);
    expect(listener.heard.filter((m) => m.topic.includes('/TlsEdge'))).to.deep.equal([]);
  });
});
