import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { S7Client } from '../lib/s7/client';
import { S7Server } from '../lib/s7/server';
import { PlcMemory } from '../lib/sim/memory';
import { SparkplugEdgeNode, type SparkplugEdgeNodeOptions } from '../lib/sparkplug';
import { DataType } from '../lib/sparkplug/datatypes';
import { encodePayload } from '../lib/sparkplug/payload';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { Mosquitto } from './support/mosquitto';
import { requirePeers } from './support/sparkplug-peers';
import { BlackholeProxy } from './support/net';
import { TestHost } from './support/sparkplug-host';
import { until } from './support/wait';

const FAST = { backoff: { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 } };
const bdSeqOf = (m: { payload?: { metrics: { name?: string; value?: unknown }[] } | undefined }): unknown =>
  m.payload!.metrics.find((x) => x.name === 'bdSeq')!.value;

describe('Sparkplug edge node sessions: primary host, brokers, PLC links, store-and-forward, Will', function () {
  this.timeout(30000);
  const brokers: Mosquitto[] = [];
  const hosts: TestHost[] = [];
  let server: S7Server;
  let memory: PlcMemory;
  let plc: S7Client;
  let node: SparkplugEdgeNode | undefined;
  let child: ChildProcess | undefined;

  before(function () {
    requirePeers(this);
  });

  beforeEach(async () => {
    memory = new PlcMemory({ dataBlocks: { 1: 16 } });
    server = new S7Server({ port: 0, profile: 's7-1500', memory });
    await server.listen();
    plc = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?timeout=1000`) as S7Endpoint, FAST);
    await plc.connect();
  });

  afterEach(async () => {
    child?.kill('SIGKILL');
    child = undefined;
    await node?.stop();
    node = undefined;
    for (const h of hosts.splice(0)) await h.close();
    await plc.close();
    await server.close();
    for (const b of brokers.splice(0)) await b.dispose();
  });

  async function broker(): Promise<Mosquitto> {
    const b = new Mosquitto();
    await b.start();
    brokers.push(b);
    return b;
  }

  async function host(b: Mosquitto): Promise<TestHost> {
    const h = new TestHost(b.url);
    await h.connect();
    hosts.push(h);
    return h;
  }

  function edge(urls: string[], extra: Partial<SparkplugEdgeNodeOptions> = {}): SparkplugEdgeNode {
    node = new SparkplugEdgeNode({
      brokers: urls,
      group: 'G',
      node: 'E',
      interval: 50,
      reconnectDelay: 50,
      devices: [{ name: 'PLC1', client: plc, tags: { Level: 'DB1.DBW0:INT' } }],
      ...extra,
    });
    node.on('error', () => undefined);
    node.start();
    return node;
  }

  it('tck-id-message-flow-edge-node-birth-publish-phid-wait tck-id-message-flow-edge-node-birth-publish-phid-wait-online tck-id-message-flow-edge-node-birth-publish-phid-wait-id: no birth before the configured host says online', async () => {
    const b = await broker();
    const h = await host(b);
    edge([b.url], { primaryHost: 'SCADA' });
    await until(() => node!.stats.state === 'waiting-for-host', 5000, 'waiting for the host');
    await h.state('OtherHost', true);
    await h.state('SCADA', false);
    await until(() => h.messages.filter((m) => m.parsed.type === 'STATE').length >= 2, 5000, 'STATE delivered');
    expect(h.messages.some((m) => m.parsed.type === 'NBIRTH')).to.equal(false);
    await h.state('SCADA', true);
    const nbirth = await h.nextOf('NBIRTH');
    expect(nbirth.payload!.seq).to.equal(0);
  });

  it('tck-id-operational-behavior-edge-node-termination-host-offline tck-id-message-flow-edge-node-birth-publish-phid-offline tck-id-operational-behavior-edge-node-termination-host-offline-reconnect tck-id-operational-behavior-primary-application-state-with-multiple-servers-walk: host offline on broker A: NDEATH there, then births on broker B with bdSeq +1', async () => {
    const a = await broker();
    const b = await broker();
    const ha = await host(a);
    const hb = await host(b);
    const t0 = Date.now();
    await ha.state('SCADA', true, t0);
    edge([a.url, b.url], { primaryHost: 'SCADA' });
    const first = await ha.nextOf('NBIRTH');
    expect(bdSeqOf(first)).to.equal(0n);
    await ha.state('SCADA', false, t0 + 1);
    const ndeath = await ha.nextOf('NDEATH');
    expect(bdSeqOf(ndeath)).to.equal(0n);
    await hb.state('SCADA', true, t0 + 2);
    const second = await hb.nextOf('NBIRTH', undefined, 10000);
    expect(bdSeqOf(second)).to.equal(1n);
    await hb.nextOf('DBIRTH', 'PLC1');
  });

  it('tck-id-operational-behavior-edge-node-termination-host-offline-timestamp tck-id-message-flow-edge-node-birth-publish-phid-wait-timestamp: an offline STATE older than the online one is ignored', async () => {
    const b = await broker();
    const h = await host(b);
    const t0 = Date.now();
    await h.state('SCADA', true, t0);
    edge([b.url], { primaryHost: 'SCADA' });
    await h.nextOf('DBIRTH');
    await h.client.publishAsync('spBv1.0/STATE/SCADA', JSON.stringify({ online: false, timestamp: t0 - 1000 }), { qos: 1 });
    memory.write('DB', 1, 0, Buffer.from([0, 9]));
    const ddata = await h.nextOf('DDATA');
    expect(ddata.payload!.metrics[0]!.value).to.equal(9);
    expect(h.messages.some((m) => m.parsed.type === 'NDEATH')).to.equal(false);
  });

  it('tck-id-operational-behavior-device-ddeath tck-id-topics-ddeath-seq-num tck-id-topics-ddeath-mqtt: a lost PLC link is a DDEATH with the next seq; back, a DBIRTH with current values', async () => {
    const b = await broker();
    const h = await host(b);
    edge([b.url]);
    const dbirth = await h.nextOf('DBIRTH');
    const port = server.port;
    await server.close();
    const ddeath = await h.nextOf('DDEATH', 'PLC1');
    expect(ddeath.qos).to.equal(0);
    expect(ddeath.retain).to.equal(false);
    expect(ddeath.payload!.seq).to.equal((dbirth.payload!.seq! + 1) % 256);
    memory.write('DB', 1, 0, Buffer.from([0, 77]));
    server = new S7Server({ port, profile: 's7-1500', memory });
    await server.listen();
    const again = await h.nextOf('DBIRTH', 'PLC1', 10000);
    expect(again.payload!.seq).to.equal((ddeath.payload!.seq! + 1) % 256);
    expect(again.payload!.metrics[0]).to.include({ name: 'Level', datatype: DataType.Int16, value: 77 });
  });

  it('tck-id-payloads-sequence-num-always-included tck-id-payloads-sequence-num-zero-nbirth tck-id-payloads-sequence-num-incrementing: seq +1 on every message, 255 then 0, across NBIRTH, DBIRTH, DDATA and DDEATH; an NBIRTH is always 0', async function () {
    this.timeout(90_000); // about 260 messages, each one poll and one broker round trip
    const b = await broker();
    const h = await host(b);
    edge([b.url], { interval: 10 });
    await h.nextOf('DBIRTH', 'PLC1');
    // One change per DDATA, written when the previous one arrived, up to seq 254.
    let last = 1;
    for (let value = 1; last !== 254; value++) {
      expect(value, 'DDATA before seq 254').to.be.below(300);
      memory.write('DB', 1, 0, Buffer.from([value >> 8, value & 0xff]));
      last = (await h.nextOf('DDATA', 'PLC1')).payload!.seq!;
    }
    // The PLC lost (DDEATH 255) and back (DBIRTH 0), a change (DDATA 1), then a rebirth: NBIRTH 0, not 2.
    const port = server.port;
    await server.close();
    expect((await h.nextOf('DDEATH', 'PLC1')).payload!.seq).to.equal(255);
    server = new S7Server({ port, profile: 's7-1500', memory });
    await server.listen();
    expect((await h.nextOf('DBIRTH', 'PLC1', 10_000)).payload!.seq).to.equal(0);
    memory.write('DB', 1, 0, Buffer.from([0x7f, 0x00]));
    expect((await h.nextOf('DDATA', 'PLC1')).payload!.seq).to.equal(1);
    const rebirth = encodePayload({
      timestamp: Date.now(),
      metrics: [{ name: 'Node Control/Rebirth', datatype: DataType.Boolean, value: true }],
    });
    await h.client.publishAsync('spBv1.0/G/NCMD/E', rebirth, { qos: 0 });
    expect((await h.nextOf('NBIRTH')).payload!.seq).to.equal(0);
    expect((await h.nextOf('DBIRTH', 'PLC1')).payload!.seq).to.equal(1);

    // What the edge node sent, as the host got it (NDEATH has no seq; none came): an NBIRTH 0, every other one +1 mod 256.
    const stream = h.messages.filter((m) => ['NBIRTH', 'DBIRTH', 'NDATA', 'DDATA', 'DDEATH'].includes(m.parsed.type));
    expect(h.messages.filter((m) => m.parsed.type === 'NDEATH')).to.deep.equal([]);
    expect(stream.map((m) => m.parsed.type)).to.include.members(['NBIRTH', 'DBIRTH', 'DDATA', 'DDEATH']);
    let previous: number | undefined;
    for (const [k, m] of stream.entries()) {
      const seq = m.payload!.seq;
      const where = `message ${k}, ${m.topic}`;
      expect(seq, where).to.be.a('number');
      if (m.parsed.type === 'NBIRTH') expect(seq, where).to.equal(0);
      else expect(seq, where).to.equal((previous! + 1) % 256);
      previous = seq;
    }
    const wraps = stream.filter((m, k) => k > 0 && m.payload!.seq === 0 && m.parsed.type !== 'NBIRTH');
    expect(wraps.map((m) => m.parsed.type)).to.deep.equal(['DBIRTH']);
    expect(stream.filter((m) => m.payload!.seq === 255).map((m) => m.parsed.type)).to.deep.equal(['DDEATH']);
  });

  it('store-and-forward: changes while the broker is down are sent after the new births as historical metrics, in order', async () => {
    const b = await broker();
    let h = await host(b);
    await h.state('SCADA', true);
    edge([b.url], { primaryHost: 'SCADA' });
    await h.nextOf('DBIRTH');
    await b.stop();
    for (const level of [1, 2, 3]) {
      memory.write('DB', 1, 0, Buffer.from([0, level]));
      await until(() => node!.stats.buffered >= level, 5000, `value ${level} buffered`);
    }
    await b.start();
    h = await host(b);
    await h.state('SCADA', true);
    await h.nextOf('NBIRTH', undefined, 10000);
    const dbirth = await h.nextOf('DBIRTH');
    expect(dbirth.payload!.metrics[0]!.value).to.equal(3);
    const history = await h.nextOf('DDATA');
    expect(history.payload!.metrics.map((m) => [m.value, m.isHistorical])).to.deep.equal([
      [1, true],
      [2, true],
      [3, true],
    ]);
    const stamps = history.payload!.metrics.map((m) => m.timestamp!);
    expect(stamps).to.deep.equal([...stamps].sort((x, y) => x - y));
    expect(node!.stats.buffered).to.equal(0);
  });

  it('a path to the broker that dies without a close (a cable pulled): the data sent into it is sent again as historical after the new births, nothing lost', async () => {
    const b = await broker();
    const proxy = new BlackholeProxy(b.port);
    const port = await proxy.listen();
    try {
      const h = await host(b);
      const n = edge([`mqtt://127.0.0.1:${port}`], { mqtt: { keepalive: 1 } });
      await h.nextOf('DBIRTH', 'PLC1');
      const sent: number[] = [];
      n.on('publish', (m) => m.type === 'DDATA' && sent.push(...m.payload.metrics.map((x) => x.value as number)));
      proxy.cut();
      for (const level of [1, 2, 3]) {
        memory.write('DB', 1, 0, Buffer.from([0, level]));
        await until(() => sent.includes(level), 5000, `value ${level} published into the dead path`);
      }
      await until(() => n.stats.state === 'connecting', 10000, 'the keepalive timeout');
      proxy.heal();
      await h.nextOf('NBIRTH', undefined, 20000);
      await h.nextOf('DBIRTH', 'PLC1');
      const history = await h.nextOf('DDATA', 'PLC1');
      expect(history.payload!.metrics.map((m) => [m.value, m.isHistorical])).to.deep.equal([
        [1, true],
        [2, true],
        [3, true],
      ]);
      // The host saw none of them before: they went into the dead path.
      const live = h.messages.filter((m) => m.parsed.type === 'DDATA' && m !== history).flatMap((m) => m.payload!.metrics);
      expect(live.filter((m) => !m.isHistorical).map((m) => m.value)).to.deep.equal([]);
    } finally {
      await node?.stop();
      node = undefined;
      await proxy.close();
    }
  });

  it('tck-id-message-flow-edge-node-birth-publish-will-message tck-id-message-flow-edge-node-birth-publish-will-message-qos tck-id-message-flow-edge-node-birth-publish-will-message-will-retained tck-id-topics-nbirth-bdseq-matching: a killed edge process leaves its Will, an NDEATH with the NBIRTH bdSeq', async () => {
    const b = await broker();
    const h = await host(b);
    const script = `
      const { S7Server, PlcMemory, S7Client, SparkplugEdgeNode, parseUrl } = require(${JSON.stringify(path.resolve(__dirname, '../lib/index.js'))});
      (async () => {
        const server = new S7Server({ port: 0, profile: 's7-1500', memory: new PlcMemory({ dataBlocks: { 1: 4 } }) });
        await server.listen();
        const plc = new S7Client(parseUrl('s7://127.0.0.1:' + server.port));
        await plc.connect();
        const node = new SparkplugEdgeNode({ brokers: [${JSON.stringify(b.url)}], group: 'G', node: 'Killed', devices: [{ name: 'P', client: plc, tags: { X: 'DB1.DBW0:INT' } }] });
        node.on('error', () => {});
        node.start();
      })();`;
    child = spawn(process.execPath, ['-e', script], { stdio: 'ignore' });
    const nbirth = await h.next((m) => m.parsed.type === 'NBIRTH' && m.parsed.node === 'Killed', 10000, 'NBIRTH of Killed');
    child.kill('SIGKILL');
    const will = await h.next((m) => m.parsed.type === 'NDEATH' && m.parsed.node === 'Killed', 10000, 'the Will');
    expect(will.topic).to.equal('spBv1.0/G/NDEATH/Killed');
    expect(will.qos).to.equal(1);
    expect(will.retain).to.equal(false);
    expect(will.payload!.metrics).to.have.length(1);
    expect(will.payload!.metrics[0]).to.include({ name: 'bdSeq', datatype: DataType.Int64 });
    expect(bdSeqOf(will)).to.equal(bdSeqOf(nbirth));
    expect(will.payload!.seq).to.equal(undefined);
  });

  it('store-and-forward on disk (buffer.dir): values kept by an edge node that stopped during the outage are forwarded by the next one', async () => {
    const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-spb-buffer-'));
    try {
      const b = await broker();
      let h = await host(b);
      await h.state('SCADA', true);
      edge([b.url], { primaryHost: 'SCADA', buffer: { dir } });
      await h.nextOf('DBIRTH');
      await b.stop();
      for (const level of [4, 5]) {
        memory.write('DB', 1, 0, Buffer.from([0, level]));
        await until(() => node!.stats.buffered >= level - 3, 5000, `value ${level} buffered`);
      }
      await node!.stop();
      memory.write('DB', 1, 0, Buffer.from([0, 6]));
      await b.start();
      h = await host(b);
      await h.state('SCADA', true);
      edge([b.url], { primaryHost: 'SCADA', buffer: { dir } });
      expect(node!.stats.buffered).to.equal(2);
      const dbirth = await h.nextOf('DBIRTH', undefined, 10000);
      expect(dbirth.payload!.metrics[0]!.value).to.equal(6);
      const history = await h.nextOf('DDATA');
      expect(history.payload!.metrics.map((m) => [m.value, m.isHistorical])).to.deep.equal([
        [4, true],
        [5, true],
      ]);
      expect(fs.readFileSync(path.join(dir, 'G.E.buffer.ndjson'), 'utf8')).to.equal('');
    } finally {
      fs.rmSync(dir, { recursive: true, force: true });
    }
  });
});
