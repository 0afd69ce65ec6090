/**
 * The Sparkplug B nodes in Node-RED (nodes/sparkplug-edge.js, nodes/sparkplug-device.js)
 * against a real mosquitto and our S7 simulator: the device's births, its
 * status, a change as DDATA, a permitted DCMD write sent on as a message, a
 * refused one on the Catch node (the PLC untouched), and NDEATH when the flow
 * stops. Without mosquitto the suite skips and says why (fails in .ci/run).
 */
import { expect } from 'chai';
import * as path from 'node:path';
import { DataType } from '../../lib/sparkplug/datatypes';
import { Mosquitto } from '../support/mosquitto';
import { missingMosquitto, sparkplugRequired } from '../support/sparkplug-peers';
import { skipBecause } from '../support/skip';
import { SparkplugListener } from '../support/sparkplug-listener';
import { s7Sim } from './sims';
import { helper, nodes, Recorder, ROOT, until, type Sim } from './support';

const edgeNode = require(path.join(ROOT, 'nodes/sparkplug-edge.js'));
const deviceNode = require(path.join(ROOT, 'nodes/sparkplug-device.js'));
const INT16 = DataType.Int16;

describe('nodes: Sparkplug B edge node and device, mosquitto and the S7 simulator', function () {
  this.timeout(60_000);
  const broker = new Mosquitto();
  let sim: Sim;
  let listener: SparkplugListener;

  before(async function () {
    const missing = missingMosquitto();
    if (missing) {
      if (sparkplugRequired()) throw new Error(`PLCWIRE_REQUIRE_SPARKPLUG=1 but ${missing}`);
      skipBecause(this, missing);
    }
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
});
