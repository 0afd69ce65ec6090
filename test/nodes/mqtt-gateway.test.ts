/**
 * The MQTT gateway example (examples/MQTT gateway - publish tags, guarded
 * writes.json) in a real Node-RED, with Node-RED's own MQTT nodes, against a
 * real broker (aedes on 127.0.0.1) and our S7 simulator; independent MQTT
 * clients on their own connections subscribe and publish.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { TestBroker } from '../support/mqtt-broker';
import { helper, nodes, ROOT, until } from './support';
import { s7Sim } from './sims';
import type { Sim } from './support';

const mqtt = require('mqtt');

const RED_PATH = require.resolve(process.env.PLCWIRE_NODE_RED || 'node-red');
const CORE = path.dirname(require.resolve('@node-red/nodes/package.json', { paths: [path.dirname(RED_PATH)] }));
const core = (file: string) => require(path.join(CORE, 'core', file));
const NODES = [
  nodes.connection,
  nodes.read,
  nodes.write,
  nodes.catch,
  core('network/10-mqtt.js'),
  core('function/10-function.js'),
  core('common/90-comment.js'),
];
const EXAMPLE = path.join(ROOT, 'examples/MQTT gateway - publish tags, guarded writes.json');
const GATEWAY = 'plcwire-gateway-1';

/** The example as shipped, with the simulator's URL and the test broker's port. */
function exampleFlow(sim: Sim, broker: TestBroker): object[] {
  const flow = JSON.parse(fs.readFileSync(EXAMPLE, 'utf8')) as any[];
  const conn = flow.find((n) => n.type === 'plcwire-connection');
  const brokerNode = flow.find((n) => n.type === 'mqtt-broker');
  expect(conn.url).to.equal('s7://127.0.0.1:10102?rack=0&slot=1&control=true');
  expect([brokerNode.broker, brokerNode.port, brokerNode.clientid]).to.deep.equal(['127.0.0.1', '1883', GATEWAY]);
  conn.url = sim.url;
  brokerNode.port = String(broker.port);
  const tab = { id: 'tab', type: 'tab', label: 'mqtt' };
  return [tab, ...flow.map((n) => (n.type === 'plcwire-connection' || n.type === 'mqtt-broker' ? n : { ...n, z: 'tab' }))];
}

/** An independent MQTT client that keeps every message it receives. */
class Client {
  readonly messages: { topic: string; payload: any; retain: boolean }[] = [];
  private wake: (() => void) | undefined;
  private constructor(readonly mq: any) {
    mq.on('message', (topic: string, payload: Buffer, packet: any) => {
      let body: any = payload.toString();
      try {
        body = JSON.parse(body);
      } catch {
        /* not JSON */
      }
      this.messages.push({ topic, payload: body, retain: !!packet.retain });
      this.wake?.();
    });
  }

  static async connect(url: string, options: Record<string, unknown> = {}): Promise<Client> {
    return new Client(await mqtt.connectAsync(url, { reconnectPeriod: 100, connectTimeout: 5000, ...options }));
  }

  /** The first message (received so far or later) that satisfies `match`. */
  async next(
    match: (m: { topic: string; payload: any; retain: boolean }) => boolean,
    ms = 6000,
    what = 'a message',
  ): Promise<{ topic: string; payload: any; retain: boolean }> {
    const deadline = Date.now() + ms;
    for (;;) {
      const found = this.messages.find(match);
      if (found) return found;
      const left = deadline - Date.now();
      if (left <= 0)
        throw new Error(`no ${what} within ${ms} ms (got ${this.messages.length}: ${JSON.stringify(this.messages.slice(-3))})`);
      await new Promise<void>((resolve) => {
        const timer = setTimeout(resolve, left);
        this.wake = () => {
          clearTimeout(timer);
          resolve();
        };
      });
    }
  }

  end(): Promise<void> {
    return this.mq.endAsync(true);
  }
}

describe('MQTT gateway example: one poller per PLC publishes, everyone else subscribes', function () {
  this.timeout(30000);
  let sim: Sim;
  let broker: TestBroker;
  const clients: Client[] = [];
  const client = async (options: Record<string, unknown> = {}) => {
    const c = await Client.connect(broker.url, options);
    clients.push(c);
    return c;
  };

  beforeEach(async () => {
    sim = await s7Sim();
    for (let i = 0; i < 8; i++) sim.set(i, 0);
    broker = new TestBroker();
    await broker.start();
    helper.settings({ mqttReconnectTime: 200 });
    await helper.startServer();
  });

  afterEach(async () => {
    await Promise.all(clients.splice(0).map((c) => c.end()));
    await helper.unload();
    await helper.stopServer();
    helper.settings({});
    await broker.stop();
    await sim.close();
  });

  it('publishes each tag retained under plant/<plc>/<tag> with quality and timestamp to every subscriber, over one PLC connection', async () => {
    sim.set(0, 1200); // speed, DB1.DBW0:INT
    sim.set(5, 75); // setpoint, DB1.DBW10:INT
    const subscribers = await Promise.all(Array.from({ length: 10 }, () => client()));
    await Promise.all(subscribers.map((s) => s.mq.subscribeAsync('plant/press1/+', { qos: 1 })));
    const before = Date.now();
    await helper.load(NODES, exampleFlow(sim, broker));
    for (const s of subscribers) {
      const speed = await s.next((m) => m.topic === 'plant/press1/speed', 6000, 'speed');
      expect(speed.payload).to.include({ value: 1200, quality: 'good', address: 'DB1.DBW0:INT' });
      expect(speed.payload.ts).to.be.within(before, Date.now());
      const setpoint = await s.next((m) => m.topic === 'plant/press1/setpoint');
      expect(setpoint.payload).to.include({ value: 75, quality: 'good' });
      for (const tag of ['level', 'motor', 'mode']) await s.next((m) => m.topic === `plant/press1/${tag}`, 6000, tag);
    }
    // A change reaches every subscriber; the PLC still serves one connection.
    sim.set(0, 1300);
    for (const s of subscribers) await s.next((m) => m.topic === 'plant/press1/speed' && m.payload.value === 1300, 6000, 'new speed');
    expect(sim.connectionCount()).to.equal(1);
    // A subscriber that comes later gets every tag at once from the broker (retained), not from the PLC.
    const late = await client();
    await late.mq.subscribeAsync('plant/press1/+', { qos: 1 });
    const retained = await late.next((m) => m.topic === 'plant/press1/speed');
    expect([retained.retain, retained.payload.value]).to.deep.equal([true, 1300]);
    expect(sim.connectionCount()).to.equal(1);
    // The gateway announces itself (its will says "offline" if it dies).
    const status = await late.mq
      .subscribeAsync('plant/gateways/+', { qos: 1 })
      .then(() => late.next((m) => m.topic === `plant/gateways/${GATEWAY}`));
    expect(status.payload).to.equal('online');
  });

  it('writes an allow-listed tag from MQTT and answers on the reply topic only after the PLC acknowledged', async () => {
    await helper.load(NODES, exampleFlow(sim, broker));
    const requester = await client();
    await requester.mq.subscribeAsync('plant/press1/+/set/result', { qos: 1 });
    await until(() => broker.connected(GATEWAY), 6000, 'the gateway connected to the broker');
    let atResult: number | undefined;
    requester.mq.on('message', (topic: string) => {
      if (topic === 'plant/press1/setpoint/set/result') atResult ??= sim.get(5);
    });
    await requester.mq.publishAsync('plant/press1/setpoint/set', JSON.stringify({ value: 1234, id: 'w1' }), { qos: 1 });
    const result = await requester.next((m) => m.topic === 'plant/press1/setpoint/set/result');
    expect(result.payload).to.deep.equal({ ok: true, tag: 'setpoint', id: 'w1', value: 1234 });
    expect(atResult, 'the PLC held the value when the result arrived').to.equal(1234);
    // A bare value works too; the motor is a bit.
    await requester.mq.publishAsync('plant/press1/motor/set', 'true', { qos: 1 });
    const motor = await requester.next((m) => m.topic === 'plant/press1/motor/set/result');
    expect(motor.payload).to.include({ ok: true, tag: 'motor', value: true });
    expect(sim.get(4) & 0x100, 'DB1.DBX8.0').to.equal(0x100);
  });

  it('refuses tags outside the allow-list and bad values with an error on the reply topic, writing nothing', async () => {
    sim.set(0, 500);
    sim.set(5, 9);
    await helper.load(NODES, exampleFlow(sim, broker));
    const requester = await client();
    await requester.mq.subscribeAsync('plant/press1/#', { qos: 1 });
    await until(() => broker.connected(GATEWAY), 6000, 'the gateway connected to the broker');
    await requester.next((m) => m.topic === 'plant/press1/speed' && m.payload.value === 500, 6000, 'speed');
    // speed is read, not writable; an address is not a name in the allow-list either.
    for (const tag of ['speed', 'DB1.DBW0:INT']) {
      await requester.mq.publishAsync(`plant/press1/${tag}/set`, JSON.stringify({ value: 1, id: `x-${tag}` }), { qos: 1 });
      const refused = await requester.next((m) => m.topic === `plant/press1/${tag}/set/result`, 6000, `refusal of ${tag}`);
      expect(refused.payload).to.deep.include({ ok: false, tag, id: `x-${tag}` });
      expect(refused.payload.error.code).to.equal('NOT_WRITABLE');
    }
    await requester.mq.publishAsync('plant/press1/setpoint/set', JSON.stringify({ value: 'fast', id: 'bad' }), { qos: 1 });
    const bad = await requester.next((m) => m.topic === 'plant/press1/setpoint/set/result', 6000, 'result for the bad value');
    expect(bad.payload).to.deep.include({ ok: false, tag: 'setpoint', id: 'bad' });
    expect(bad.payload.error.code).to.equal('INVALID_VALUE');
    expect(bad.payload.error.message).to.include('setpoint');
    // Nothing was written (a write is answered only after the PLC acknowledged it, so it would be there by now).
    expect([sim.get(0), sim.get(5)]).to.deep.equal([500, 9]);
  });

  it('loses no write across broker restarts: what the broker acknowledged while the gateway was away, and what the requester could not yet send, reaches the PLC and is answered', async () => {
    await helper.load(NODES, exampleFlow(sim, broker));
    const requester = await client({ clientId: 'requester', clean: false });
    await requester.mq.subscribeAsync('plant/press1/+/set/result', { qos: 1 });
    await until(() => broker.connected(GATEWAY), 6000, 'the gateway connected to the broker');
    await requester.mq.publishAsync('plant/press1/setpoint/set', JSON.stringify({ value: 1001, id: 'w1' }), { qos: 1 });
    await requester.next((m) => m.payload.id === 'w1', 6000, 'result for w1');

    // The broker restarts; the gateway stays away (its CONNECT is held) while the requester is back.
    broker.hold(GATEWAY);
    await broker.restart();
    await until(() => broker.connected('requester'), 6000, 'the requester reconnected');
    await until(() => broker.waitingFor(GATEWAY), 6000, 'the gateway trying to reconnect');
    expect(broker.connected(GATEWAY)).to.equal(false);
    // Acknowledged by the broker (PUBACK) while the gateway is away …
    await requester.mq.publishAsync('plant/press1/setpoint/set', JSON.stringify({ value: 2002, id: 'w2' }), { qos: 1 });
    await requester.mq.publishAsync('plant/press1/motor/set', JSON.stringify({ value: true, id: 'w3' }), { qos: 1 });
    // … then the broker restarts again: they are only in its persistent store now.
    await broker.stop();
    // Published while the broker is down: the requester keeps it until a broker acknowledges it.
    const w4 = requester.mq.publishAsync('plant/press1/mode/set', JSON.stringify({ value: 3, id: 'w4' }), { qos: 1 });
    await broker.start();
    await w4;
    expect(sim.get(5)).to.equal(1001);
    expect(sim.get(6)).to.equal(0);

    broker.release(GATEWAY);
    const results = [];
    for (const id of ['w2', 'w3', 'w4']) results.push(await requester.next((m) => m.payload.id === id, 10000, `result for ${id}`));
    expect(results.map((r) => r.payload.ok)).to.deep.equal([true, true, true]);
    expect(sim.get(5), 'setpoint').to.equal(2002);
    expect(sim.get(4) & 0x100, 'motor').to.equal(0x100);
    expect(sim.get(6), 'mode').to.equal(3);
    expect(sim.connectionCount()).to.equal(1);
  });
});
