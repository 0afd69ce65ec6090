import { expect } from 'chai';
import type { EventEmitter } from 'node:events';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { PlcError } from '../lib/errors';
import { S7Client } from '../lib/s7/client';
import { S7Server } from '../lib/s7/server';
import { PlcMemory } from '../lib/sim/memory';
import { DataType } from '../lib/sparkplug/datatypes';
import { SparkplugEdgeNode, type SparkplugEdgeNodeOptions } from '../lib/sparkplug';
import type { SparkplugMetric } from '../lib/sparkplug/model';
import { encodePayload } from '../lib/sparkplug/payload';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { flattenSymbol } from '../lib/sparkplug/types';
import { Mosquitto } from './support/mosquitto';
import { requirePeers } from './support/sparkplug-peers';
import { TestHost } from './support/sparkplug-host';
import { compileClientSources } from './support/symbol-sources';
import { until, waitFor } from './support/wait';

const FAST = { backoff: { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 } };

describe('Sparkplug edge node against mosquitto and the S7 simulator', function () {
  this.timeout(20000);
  let broker: Mosquitto;
  let server: S7Server;
  let memory: PlcMemory;
  let plc: S7Client;
  let host: TestHost;
  let node: SparkplugEdgeNode | undefined;
  let stateDir: string;

  before(function () {
    requirePeers(this);
  });

  beforeEach(async () => {
    broker = new Mosquitto();
    await broker.start();
    memory = new PlcMemory({ dataBlocks: { 1: 64 } });
    server = new S7Server({ port: 0, profile: 's7-1500', memory });
    await server.listen();
    plc = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?timeout=1500`) as S7Endpoint, { ...FAST, allow: ['DB1.DBW2'] });
    await plc.connect();
    host = new TestHost(broker.url);
    await host.connect();
    stateDir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-spb-'));
  });

  afterEach(async () => {
    await node?.stop();
    node = undefined;
    await host.close();
    await plc.close();
    await server.close();
    await broker.dispose();
    fs.rmSync(stateDir, { recursive: true, force: true });
  });

  function edge(extra: Partial<SparkplugEdgeNodeOptions> = {}): SparkplugEdgeNode {
    node = new SparkplugEdgeNode({
      brokers: [broker.url],
      group: 'Plant',
      node: 'Line1',
      interval: 50,
      reconnectDelay: 50,
      stateDir,
      devices: [
        {
          name: 'Press',
          client: plc,
          tags: { Speed: 'DB1.DBW0:INT', Count: 'DB1.DBD4:DINT', Setpoint: 'DB1.DBW2:INT', Running: 'DB1.DBX8.0' },
          writable: ['Setpoint', 'Speed'],
        },
      ],
      ...extra,
    });
    node.on('error', () => undefined);
    node.start();
    return node;
  }

  it('tck-id-topics-nbirth-mqtt tck-id-topics-nbirth-seq-num tck-id-topics-nbirth-bdseq-included tck-id-topics-nbirth-rebirth-metric: NBIRTH QoS 0, not retained, seq 0, bdSeq and Node Control/Rebirth false', async () => {
    edge();
    const nbirth = await host.nextOf('NBIRTH');
    expect(nbirth.topic).to.equal('spBv1.0/Plant/NBIRTH/Line1');
    expect(nbirth.qos).to.equal(0);
    expect(nbirth.retain).to.equal(false);
    expect(nbirth.payload!.seq).to.equal(0);
    expect(nbirth.payload!.timestamp).to.be.a('number');
    const bdSeq = nbirth.payload!.metrics.find((m) => m.name === 'bdSeq')!;
    expect(bdSeq).to.include({ datatype: DataType.Int64, value: 0n });
    const rebirth = nbirth.payload!.metrics.find((m) => m.name === 'Node Control/Rebirth')!;
    expect(rebirth).to.include({ datatype: DataType.Boolean, value: false });
  });

  it('tck-id-topics-dbirth-seq tck-id-topics-dbirth-timestamp tck-id-topics-dbirth-metric-reqs: DBIRTH after NBIRTH, seq +1, every metric named, aliased, typed, timestamped, with its current value', async () => {
    memory.write('DB', 1, 0, Buffer.from([0xff, 0x9c])); // Speed = -100
    memory.write('DB', 1, 4, Buffer.from([0x00, 0x01, 0x00, 0x00])); // Count = 65536
    edge();
    await host.nextOf('NBIRTH');
    const dbirth = await host.nextOf('DBIRTH', 'Press');
    expect(dbirth.topic).to.equal('spBv1.0/Plant/DBIRTH/Line1/Press');
    expect(dbirth.qos).to.equal(0);
    expect(dbirth.retain).to.equal(false);
    expect(dbirth.payload!.seq).to.equal(1);
    const byName = Object.fromEntries(dbirth.payload!.metrics.map((m) => [m.name, m]));
    expect(byName['Speed']).to.include({ datatype: DataType.Int16, value: -100 });
    expect(byName['Count']).to.include({ datatype: DataType.Int32, value: 65536 });
    expect(byName['Running']).to.include({ datatype: DataType.Boolean, value: false });
    for (const m of dbirth.payload!.metrics) {
      expect(m.timestamp, m.name).to.be.a('number');
      expect(m.alias, m.name).to.be.a('number');
    }
    expect(new Set(dbirth.payload!.metrics.map((m) => m.alias)).size).to.equal(4);
  });

  it('tck-id-topics-ddata-seq-num tck-id-topics-ddata-mqtt: a change is a DDATA by alias with the next seq, only the changed metric', async () => {
    edge();
    const dbirth = await host.nextOf('DBIRTH', 'Press');
    const speedAlias = dbirth.payload!.metrics.find((m) => m.name === 'Speed')!.alias;
    memory.write('DB', 1, 0, Buffer.from([0x01, 0x2c])); // 300
    const ddata = await host.nextOf('DDATA', 'Press');
    expect(ddata.qos).to.equal(0);
    expect(ddata.payload!.seq).to.equal(2);
    expect(ddata.payload!.metrics).to.have.length(1);
    expect(ddata.payload!.metrics[0]).to.include({ alias: speedAlias, value: 300 });
    expect(ddata.payload!.metrics[0]!.name).to.equal(undefined);
  });

  it('tck-id-topics-nbirth-bdseq-increment tck-id-message-flow-edge-node-birth-publish-will-message-payload-bdSeq: bdSeq +1 per connect, kept in stateDir across edge nodes', async () => {
    edge();
    expect((await host.nextOf('NBIRTH')).payload!.metrics.find((m) => m.name === 'bdSeq')!.value).to.equal(0n);
    await node!.stop();
    edge();
    expect((await host.nextOf('NBIRTH')).payload!.metrics.find((m) => m.name === 'bdSeq')!.value).to.equal(1n);
    expect(JSON.parse(fs.readFileSync(path.join(stateDir, 'Plant.Line1.bdseq.json'), 'utf8'))).to.deep.equal({ bdSeq: 1 });
  });

  it('tck-id-operational-behavior-edge-node-intentional-disconnect-ndeath tck-id-topics-ndeath-payload tck-id-topics-ndeath-seq: stop() publishes NDEATH with only the bdSeq, no seq', async () => {
    edge();
    await host.nextOf('DBIRTH');
    await node!.stop();
    const ndeath = await host.nextOf('NDEATH');
    expect(ndeath.topic).to.equal('spBv1.0/Plant/NDEATH/Line1');
    expect(ndeath.payload!.seq).to.equal(undefined);
    expect(ndeath.payload!.metrics).to.have.length(1);
    expect(ndeath.payload!.metrics[0]).to.include({ name: 'bdSeq', datatype: DataType.Int64, value: 0n });
  });

  it('tck-id-operational-behavior-data-commands-rebirth-action-1 tck-id-operational-behavior-data-commands-rebirth-action-2 tck-id-operational-behavior-data-commands-rebirth-action-3: Node Control/Rebirth gives NBIRTH and DBIRTH again with the same bdSeq', async () => {
    edge();
    await host.nextOf('DBIRTH');
    const ncmd = encodePayload({
      timestamp: Date.now(),
      metrics: [{ name: 'Node Control/Rebirth', datatype: DataType.Boolean, value: true }],
    });
    await host.client.publishAsync('spBv1.0/Plant/NCMD/Line1', ncmd, { qos: 0 });
    const nbirth = await host.nextOf('NBIRTH');
    expect(nbirth.payload!.seq).to.equal(0);
    expect(nbirth.payload!.metrics.find((m) => m.name === 'bdSeq')!.value).to.equal(0n);
    const dbirth = await host.nextOf('DBIRTH');
    expect(dbirth.payload!.seq).to.equal(1);
    expect(dbirth.payload!.metrics.map((m) => m.name)).to.deep.equal(['Speed', 'Count', 'Setpoint', 'Running']);
  });

  it('a DCMD to a writable metric writes the PLC and the new value shows in the next DDATA', async () => {
    edge();
    await host.nextOf('DBIRTH');
    const done = waitFor(node as unknown as EventEmitter, 'command', 5000);
    await host.client.publishAsync(
      'spBv1.0/Plant/DCMD/Line1/Press',
      encodePayload({ timestamp: Date.now(), metrics: [{ name: 'Setpoint', datatype: DataType.Int16, value: -42 }] }),
    );
    await done;
    expect(memory.read('DB', 1, 2, 2).readInt16BE(0)).to.equal(-42);
    const ddata = await host.nextOf('DDATA');
    expect(ddata.payload!.metrics[0]).to.include({ value: -42 });
  });

  it('a DCMD refused by the client guard (allow list) is an error event and never reaches the PLC', async () => {
    edge();
    await host.nextOf('DBIRTH');
    const refused = waitFor<PlcError>(node as unknown as EventEmitter, 'error', 5000);
    await host.client.publishAsync(
      'spBv1.0/Plant/DCMD/Line1/Press',
      encodePayload({ timestamp: Date.now(), metrics: [{ name: 'Speed', datatype: DataType.Int16, value: 7 }] }),
    );
    const err = await refused;
    expect(err.code).to.equal('WRITE_NOT_ALLOWED');
    expect(memory.read('DB', 1, 0, 2).readInt16BE(0)).to.equal(0);
  });

  it("tck-id-message-flow-edge-node-ncmd-subscribe tck-id-message-flow-device-dcmd-subscribe tck-id-message-flow-edge-node-birth-publish-connect: a clean session, NCMD and DCMD subscribed with QoS 1 before the NBIRTH (the broker's own log)", async () => {
    edge();
    await host.nextOf('DBIRTH');
    const log = broker.log;
    expect(log).to.match(/as plcwire-Plant-Line1 \(p\d, c1, k\d+\)/);
    const subscribe = log.indexOf('spBv1.0/Plant/NCMD/Line1 (QoS 1)');
    const dcmd = log.indexOf('spBv1.0/Plant/DCMD/Line1/Press (QoS 1)');
    const nbirth = log.search(/Received PUBLISH from plcwire-Plant-Line1 .*'spBv1\.0\/Plant\/NBIRTH\/Line1'/);
    expect(subscribe, 'NCMD subscription').to.be.greaterThan(-1);
    expect(dcmd, 'DCMD subscription').to.be.greaterThan(-1);
    expect(nbirth, 'NBIRTH').to.be.greaterThan(subscribe);
    expect(nbirth).to.be.greaterThan(dcmd);
  });

  it('tck-id-payloads-alias-uniqueness tck-id-payloads-alias-birth-requirement tck-id-payloads-name-birth-data-requirement: aliases unique across the devices of the node, every birth and data metric timestamped', async () => {
    const other = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?timeout=1500`) as S7Endpoint, FAST);
    try {
      await other.connect();
      edge({
        devices: [
          { name: 'A', client: plc, tags: { X: 'DB1.DBW0:INT', Y: 'DB1.DBW2:INT' } },
          { name: 'B', client: other, tags: { X: 'DB1.DBW0:INT', Z: 'DB1.DBD4:REAL' } },
        ],
      });
      const a = await host.nextOf('DBIRTH', 'A');
      const b = await host.nextOf('DBIRTH', 'B');
      const aliases = [...a.payload!.metrics, ...b.payload!.metrics].map((m) => m.alias);
      expect(new Set(aliases).size).to.equal(4);
      memory.write('DB', 1, 0, Buffer.from([0, 5]));
      const d1 = await host.nextOf('DDATA');
      expect(d1.payload!.timestamp).to.be.a('number');
      for (const m of d1.payload!.metrics) expect(m.timestamp).to.be.a('number');
    } finally {
      await node?.stop();
      node = undefined;
      await other.close();
    }
  });

  it('report by exception with a deadband: a change within it is not sent, one beyond it is', async () => {
    edge({ deadbands: { Press: { Speed: 10 } } });
    await host.nextOf('DBIRTH');
    memory.write('DB', 1, 0, Buffer.from([0, 10])); // +10: within
    memory.write('DB', 1, 4, Buffer.from([0, 0, 0, 1])); // Count changes (no deadband): proves a poll ran
    const first = await host.nextOf('DDATA');
    expect(first.payload!.metrics.map((m) => m.value)).to.deep.equal([1]);
    memory.write('DB', 1, 0, Buffer.from([0, 11])); // +11: beyond
    const second = await host.nextOf('DDATA');
    expect(second.payload!.metrics.map((m) => m.value)).to.deep.equal([11]);
  });

  it('tck-id-payloads-propertyset-quality-value-type: a tag whose read fails is a null metric with the Quality property 0 (BAD) as Int32', async () => {
    edge({ devices: [{ name: 'Press', client: plc, tags: { Good: 'DB1.DBW0:INT', Missing: 'DB9.DBW0:INT' } }] });
    const dbirth = await host.nextOf('DBIRTH');
    const missing = dbirth.payload!.metrics.find((m) => m.name === 'Missing')!;
    expect(missing).to.include({ isNull: true, value: null, datatype: DataType.Int16 });
    expect(missing.properties).to.deep.equal({ Quality: { type: DataType.Int32, value: 0 } });
    expect(dbirth.payload!.metrics.find((m) => m.name === 'Good')!.properties).to.equal(undefined);
  });

  it('a DCMD to a metric not made writable, or with a value of another datatype, is refused before the PLC', async () => {
    edge();
    await host.nextOf('DBIRTH');
    const errors: PlcError[] = [];
    node!.on('error', (e) => errors.push(e));
    const dcmd = (metrics: SparkplugMetric[]) =>
      host.client.publishAsync('spBv1.0/Plant/DCMD/Line1/Press', encodePayload({ timestamp: Date.now(), metrics }));
    await dcmd([{ name: 'Count', datatype: DataType.Int32, value: 5 }]);
    await dcmd([{ name: 'Setpoint', datatype: DataType.Float, value: 1.5 }]);
    await dcmd([{ name: 'Nope', datatype: DataType.Int16, value: 1 }]);
    await until(() => errors.length >= 3, 5000, 'three refusals');
    expect(errors.map((e) => e.code)).to.deep.equal(['WRITE_NOT_ALLOWED', 'INVALID_VALUE', 'INVALID_ADDRESS']);
    expect(errors[0]!.message).to.match(/Count.*not writable/);
    expect(errors[1]!.message).to.match(/Int16.*Float/);
    expect(memory.read('DB', 1, 0, 8).equals(Buffer.alloc(8))).to.equal(true);
  });

  it('metrics from a symbol table: a DB flattened to its members, typed by their declarations (REAL → Float, Array of Real → FloatArray, STRING → String)', async () => {
    const table = compileClientSources('Motor.udt', 'Step.udt', 'Valve.udt', 'Tank.db');
    const named = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?timeout=1500`) as S7Endpoint, { ...FAST, symbols: table });
    try {
      await named.connect();
      const tags = flattenSymbol(table, '"Tank"', 'Tank');
      expect(Object.keys(tags)).to.include.members(['Tank/Level', 'Tank/Motor/Speed', 'Tank/Temps', 'Tank/Steps[1]/Temp']);
      edge({ devices: [{ name: 'Tank', client: named, tags, symbols: table }] });
      const dbirth = await host.nextOf('DBIRTH', 'Tank');
      const types = Object.fromEntries(dbirth.payload!.metrics.map((m) => [m.name, m.datatype]));
      expect(types).to.include({
        'Tank/Level': DataType.Float,
        'Tank/Count': DataType.Int16,
        'Tank/Motor/Run': DataType.Boolean,
        'Tank/Temps': DataType.FloatArray,
        'Tank/Label': DataType.String,
      });
      expect(dbirth.payload!.metrics.find((m) => m.name === 'Tank/Temps')!.value).to.deep.equal([0, 0, 0]);
    } finally {
      await node?.stop();
      node = undefined;
      await named.close();
    }
  });
});
