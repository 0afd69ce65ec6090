/**
 * The MQTT gateway example (examples/MQTT gateway - publish tags, guarded
 * writes.json) in a real Node-RED, with Node-RED's own MQTT nodes, against a
 * real broker (aedes on 127.0.0.1) and the demo plant it is made for
 * (lib/plant: the S7-1200 whose DB1 is built from the source the example's
 * connection carries); independent MQTT clients on their own connections
 * subscribe and publish. The plant's program is stopped and stepped by the
 * test, so every value it publishes is known; every write that reaches the
 * PLC is logged from the simulated memory.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { TestBroker } from '../support/mqtt-broker';
import { helper, nodes, ROOT, until } from './support';

const mqtt = require('mqtt');
const lib = require(path.join(ROOT, 'dist/lib/index.js'));
/** The plant's values as the read node sends them: REALs with the digits TIA shows (lib/values/float32.ts). */
const shown = <T extends { level: number; temperature: number }>(v: T): T => ({
  ...v,
  level: lib.values.shortestFloat32(v.level),
  temperature: lib.values.shortestFloat32(v.temperature),
});

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
  core('common/25-status.js'),
];
const EXAMPLE = path.join(ROOT, 'examples/MQTT gateway - publish tags, guarded writes.json');
const GATEWAY = 'plcwire-gateway-1';
/** The example's PLC (its group's environment variable PLC): topics are plant/tank/<tag>. */
const PLC = 'tank';
/** What the example publishes, by tag name, and the member of "Plant" each reads. */
const PUBLISHED = {
  level: lib.DEMO_SYMBOLS.level,
  temperature: lib.DEMO_SYMBOLS.temperature,
  heater: lib.DEMO_SYMBOLS.heater,
  run: lib.DEMO_SYMBOLS.run,
  running: lib.DEMO_SYMBOLS.running,
  speed: lib.DEMO_SYMBOLS.speed,
  parts: lib.DEMO_SYMBOLS.parts,
};
/** Byte offsets in DB1 of the two members the example may write (DEMO_TAGS: DB1.DBX4.0, DB1.DBW14:INT). */
const RUN_BYTE = 4;
const PC_HEARTBEAT = 14;

const example = () => JSON.parse(fs.readFileSync(EXAMPLE, 'utf8')) as any[];

/** The example as shipped, on a tab, with the plant's S7 port and the test broker's port. */
function exampleFlow(plant: any, broker: TestBroker): object[] {
  const flow = example();
  const conn = flow.find((n) => n.type === 'plcwire-connection');
  const brokerNode = flow.find((n) => n.type === 'mqtt-broker');
  expect(conn.url).to.equal('s7://127.0.0.1:10102?rack=0&slot=1&control=true');
  expect([brokerNode.broker, brokerNode.port, brokerNode.clientid]).to.deep.equal(['127.0.0.1', '1883', GATEWAY]);
  conn.url = conn.url.replace(':10102', `:${plant.ports.s7}`);
  brokerNode.port = String(broker.port);
  const tab = { id: 'tab', type: 'tab', label: 'mqtt' };
  return [tab, ...flow.map((n) => (n.type === 'plcwire-connection' || n.type === 'mqtt-broker' ? n : { ...n, z: 'tab' }))];
}

/** The allow-list as the example's guard function holds it (`const WRITABLE = [...]`). */
function allowList(flow: any[]): string[] {
  const func: string = flow.find((n) => n.id === 'mqttex.guard').func;
  const list = /const WRITABLE = (\[[^\]]*\]);/.exec(func)?.[1];
  expect(list, 'the guard declares WRITABLE').to.be.a('string');
  return JSON.parse(list!.replace(/'/g, '"'));
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

describe('MQTT gateway example: the demo plant published to a broker, guarded writes from it', function () {
  this.timeout(30000);
  let plant: any;
  let broker: TestBroker;
  /** Every write that reached the PLC's DB1, in order: its byte offset and the bytes it left there. */
  let writes: { offset: number; data: Buffer }[];
  const clients: Client[] = [];
  const client = async (options: Record<string, unknown> = {}) => {
    const c = await Client.connect(broker.url, options);
    clients.push(c);
    return c;
  };
  const db = (): Buffer => plant.memory.area('DB', 1);
  /** The written members, decoded: ['run', true], ['pcHeartbeat', 2002]; anything else by its offset. */
  const written = () =>
    writes.map((w) =>
      w.offset === RUN_BYTE && w.data.length === 1
        ? ['run', (w.data[0]! & 1) === 1]
        : w.offset === PC_HEARTBEAT && w.data.length === 2
          ? ['pcHeartbeat', w.data.readInt16BE(0)]
          : [`DB1 byte ${w.offset}`, [...w.data]],
    );

  beforeEach(async () => {
    plant = await lib.startPlant({ ports: { s7: 0, fetch: 0, write: 0, freeport: 0 } });
    // The plant's program is the test's to step: the values stand still between steps.
    plant.process.stop();
    writes = [];
    plant.memory.on('write', (e: any) => {
      if (e.area === 'DB' && e.dbNumber === 1) writes.push({ offset: e.offset, data: Buffer.from(e.data) });
    });
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
    await plant?.close();
  });

  it("reads the plant's members by name and writes only the run command and the PC's life sign", () => {
    const flow = example();
    const conn = flow.find((n) => n.type === 'plcwire-connection');
    expect(conn.symbolSources).to.deep.equal([{ name: lib.PLANT_SOURCE.name, content: lib.PLANT_SOURCE.content }]);
    expect(conn.dbNumbers).to.deep.equal(Object.entries(lib.PLANT_DB_NUMBERS).map(([block, db]) => ({ block, db })));
    const table = lib.compileSymbols(conn.symbolSources, { db: lib.PLANT_DB_NUMBERS });
    const read = flow.find((n) => n.type === 'plcwire-read');
    expect(Object.fromEntries(read.tags.map((t: any) => [t.name, t.address]))).to.deep.equal(PUBLISHED);
    const write = flow.find((n) => n.type === 'plcwire-write');
    const writable = Object.fromEntries(write.tags.map((t: any) => [t.name, table.lookup(t.address)?.address]));
    // The write node can reach exactly the two members nothing in the plant computes, and the allow-list names exactly those.
    expect(writable).to.deep.equal({ run: lib.DEMO_TAGS.run, pcHeartbeat: lib.DEMO_TAGS.pcHeartbeat });
    expect(allowList(flow).sort()).to.deep.equal(Object.keys(writable).sort());
    // What it reads again when the broker (re)connects is the read node's table.
    const again: string = flow.find((n) => n.id === 'mqttex.again').func;
    const listed = /const TAGS = \{([^}]*)\};/.exec(again)?.[1] ?? '';
    expect(Object.fromEntries([...listed.matchAll(/(\w+): '([^']*)',/g)].map((m) => [m[1], m[2]]))).to.deep.equal(PUBLISHED);
    expect(flow.find((n) => n.id === 'mqttex.brokerup').scope).to.deep.equal(['mqttex.pub']);
    expect(flow.find((n) => n.id === 'mqttex.sub').topic).to.equal(`plant/${PLC}/+/set`);
    expect(flow.find((n) => n.id === 'mqttex.group').env).to.deep.equal([{ name: 'PLC', value: PLC, type: 'str' }]);
  });

  it('publishes each tag retained under plant/tank/<tag> with quality and timestamp to every subscriber, over one PLC connection', async () => {
    // The motor has run for 3 s: every member holds a value of its own.
    db()[RUN_BYTE] |= 1;
    for (let i = 0; i < 30; i++) plant.process.step();
    const held = shown(plant.process.snapshot());
    expect([held.running, held.speed, held.parts > 0]).to.deep.equal([true, 1450, true]);
    const subscribers = await Promise.all(Array.from({ length: 10 }, () => client()));
    await Promise.all(subscribers.map((s) => s.mq.subscribeAsync(`plant/${PLC}/+`, { qos: 1 })));
    const before = Date.now();
    await helper.load(NODES, exampleFlow(plant, broker));
    const expected = {
      level: held.level,
      temperature: held.temperature,
      heater: held.heater,
      run: true,
      running: true,
      speed: 1450,
      parts: held.parts,
    };
    for (const s of subscribers) {
      for (const [tag, value] of Object.entries(expected)) {
        const m = await s.next((x) => x.topic === `plant/${PLC}/${tag}`, 6000, tag);
        expect(m.payload, tag).to.include({ value, quality: 'good', address: PUBLISHED[tag as keyof typeof PUBLISHED] });
        expect(m.payload.ts).to.be.within(before, Date.now());
      }
    }
    // A change reaches every subscriber; the PLC still serves one connection.
    const next = lib.values.shortestFloat32(plant.process.step().level);
    expect(next).to.not.equal(held.level);
    for (const s of subscribers) await s.next((m) => m.topic === `plant/${PLC}/level` && m.payload.value === next, 6000, 'new level');
    expect(plant.s7.connectionCount).to.equal(1);
    // A subscriber that comes later gets every tag at once from the broker (retained), not from the PLC.
    const late = await client();
    await late.mq.subscribeAsync(`plant/${PLC}/+`, { qos: 1 });
    const retained = await late.next((m) => m.topic === `plant/${PLC}/level`);
    expect([retained.retain, retained.payload.value]).to.deep.equal([true, next]);
    for (const tag of Object.keys(expected)) await late.next((m) => m.topic === `plant/${PLC}/${tag}` && m.retain, 6000, `retained ${tag}`);
    expect(plant.s7.connectionCount).to.equal(1);
    // The gateway announces itself (its will says "offline" if it dies).
    const status = await late.mq
      .subscribeAsync('plant/gateways/+', { qos: 1 })
      .then(() => late.next((m) => m.topic === `plant/gateways/${GATEWAY}`));
    expect(status.payload).to.equal('online');
    // Reading wrote nothing.
    expect(written()).to.deep.equal([]);
  });

  it('leaves no stale value on the broker after an outage: what changed while it was away is published when it is back, though it does not change again', async () => {
    await helper.load(NODES, exampleFlow(plant, broker));
    const subscriber = await client();
    await subscriber.mq.subscribeAsync(`plant/${PLC}/+`, { qos: 1 });
    await subscriber.next((m) => m.topic === `plant/${PLC}/speed` && m.payload.value === 0, 6000, 'the motor standing');
    const parts = plant.process.snapshot().parts;
    await subscriber.next((m) => m.topic === `plant/${PLC}/parts` && m.payload.value === parts, 6000, 'the parts count');

    await broker.stop();
    await until(() => helper.getNode('mqttex.pub') && !broker.connected(GATEWAY), 6000, 'the gateway away');
    // While the broker is away the motor starts and runs for 3 s; then the plant stands still again.
    db()[RUN_BYTE] |= 1;
    for (let i = 0; i < 30; i++) plant.process.step();
    const held = shown(plant.process.snapshot());
    expect([held.running, held.speed, held.parts > parts]).to.deep.equal([true, 1450, true]);
    // The gateway polls the new values twice (its publishes go nowhere): its changes filter has seen them.
    let reads = 0;
    const counted = () => reads++;
    plant.memory.on('read', counted);
    await until(() => reads >= 2, 6000, 'two polls while the broker is away');
    plant.memory.off('read', counted);

    await broker.start();
    const expected = { run: true, running: true, speed: 1450, parts: held.parts, level: held.level };
    for (const [tag, value] of Object.entries(expected))
      await subscriber.next(
        (m) => m.topic === `plant/${PLC}/${tag}` && m.payload.value === value,
        10000,
        `${tag} = ${value} after the outage`,
      );
    // What the broker keeps for a subscriber that comes later is current.
    const late = await client();
    await late.mq.subscribeAsync(`plant/${PLC}/+`, { qos: 1 });
    for (const [tag, value] of Object.entries(expected)) {
      const m = await late.next((x) => x.topic === `plant/${PLC}/${tag}`, 6000, `retained ${tag}`);
      expect([m.retain, m.payload.value], tag).to.deep.equal([true, value]);
    }
    expect(plant.s7.connectionCount).to.equal(1);
  });

  it('starts the motor from MQTT and answers on the reply topic only after the PLC acknowledged; the plant runs and the gateway publishes it', async () => {
    await helper.load(NODES, exampleFlow(plant, broker));
    const requester = await client();
    await requester.mq.subscribeAsync(`plant/${PLC}/#`, { qos: 1 });
    await until(() => broker.connected(GATEWAY), 6000, 'the gateway connected to the broker');
    await requester.next((m) => m.topic === `plant/${PLC}/running` && m.payload.value === false, 6000, 'the motor stopped');
    let atResult: number | undefined;
    requester.mq.on('message', (topic: string) => {
      if (topic === `plant/${PLC}/run/set/result`) atResult ??= db()[RUN_BYTE]! & 1;
    });
    await requester.mq.publishAsync(`plant/${PLC}/run/set`, JSON.stringify({ value: true, id: 'w1' }), { qos: 1 });
    const result = await requester.next((m) => m.topic === `plant/${PLC}/run/set/result`);
    expect(result.payload).to.deep.equal({ ok: true, tag: 'run', id: 'w1', value: true });
    expect(atResult, 'the PLC held the run command when the result arrived').to.equal(1);
    // The plant's program sees the command: the motor turns, and the gateway publishes it.
    for (let i = 0; i < 5; i++) plant.process.step();
    await requester.next((m) => m.topic === `plant/${PLC}/running` && m.payload.value === true, 6000, 'the motor running');
    await requester.next((m) => m.topic === `plant/${PLC}/run` && m.payload.value === true, 6000, 'the run command read back');
    // A bare value works too: the PC's life sign.
    await requester.mq.publishAsync(`plant/${PLC}/pcHeartbeat/set`, '1234', { qos: 1 });
    const life = await requester.next((m) => m.topic === `plant/${PLC}/pcHeartbeat/set/result`);
    expect(life.payload).to.include({ ok: true, tag: 'pcHeartbeat', value: 1234 });
    expect(db().readInt16BE(PC_HEARTBEAT), '"Plant".PcHeartbeat').to.equal(1234);
    expect(written()).to.deep.equal([
      ['run', true],
      ['pcHeartbeat', 1234],
    ]);
  });

  it('refuses what the plant computes, addresses and names outside the allow-list, and bad values with an error on the reply topic, writing nothing', async () => {
    for (let i = 0; i < 25; i++) plant.process.step();
    const held = shown(plant.process.snapshot());
    const before = Buffer.from(db());
    await helper.load(NODES, exampleFlow(plant, broker));
    const requester = await client();
    await requester.mq.subscribeAsync(`plant/${PLC}/#`, { qos: 1 });
    await until(() => broker.connected(GATEWAY), 6000, 'the gateway connected to the broker');
    await requester.next((m) => m.topic === `plant/${PLC}/level` && m.payload.value === held.level, 6000, 'level');
    // Read, not writable: the program's own values; an address or a member's name is not a name in the allow-list either
    // (DB1.DBD0:REAL is the tank level; the write node alone would take it).
    for (const tag of ['level', 'speed', 'parts', 'heater', 'plcHeartbeat', 'DB1.DBD0:REAL', '"Plant".MotorRun']) {
      await requester.mq.publishAsync(`plant/${PLC}/${tag}/set`, JSON.stringify({ value: 1, id: `x-${tag}` }), { qos: 1 });
      const refused = await requester.next((m) => m.topic === `plant/${PLC}/${tag}/set/result`, 6000, `refusal of ${tag}`);
      expect(refused.payload).to.deep.include({ ok: false, tag, id: `x-${tag}` });
      expect(refused.payload.error.code).to.equal('NOT_WRITABLE');
    }
    // Allowed tags with values that do not fit them: the write node refuses them, the Catch node answers.
    for (const [tag, value, id] of [
      ['pcHeartbeat', 'fast', 'bad-text'],
      ['pcHeartbeat', 40000, 'bad-range'],
    ] as const) {
      await requester.mq.publishAsync(`plant/${PLC}/${tag}/set`, JSON.stringify({ value, id }), { qos: 1 });
      const bad = await requester.next(
        (m) => m.topic === `plant/${PLC}/${tag}/set/result` && m.payload.id === id,
        6000,
        `result for ${id}`,
      );
      expect(bad.payload).to.deep.include({ ok: false, tag, id });
      expect(bad.payload.error.code, id).to.equal('INVALID_VALUE');
      expect(bad.payload.error.message).to.include(tag);
    }
    // Nothing reached the PLC: no write, and DB1 is byte for byte what it was (the program stands still).
    expect(written()).to.deep.equal([]);
    expect(db().equals(before), 'DB1 unchanged').to.equal(true);
  });

  it('loses no write across broker restarts: what the broker acknowledged while the gateway was away, and what the requester could not yet send, reaches the PLC in order and is answered', async () => {
    await helper.load(NODES, exampleFlow(plant, broker));
    const requester = await client({ clientId: 'requester', clean: false });
    await requester.mq.subscribeAsync(`plant/${PLC}/+/set/result`, { qos: 1 });
    await until(() => broker.connected(GATEWAY), 6000, 'the gateway connected to the broker');
    await requester.mq.publishAsync(`plant/${PLC}/pcHeartbeat/set`, JSON.stringify({ value: 1001, id: 'w1' }), { qos: 1 });
    await requester.next((m) => m.payload.id === 'w1', 6000, 'result for w1');

    // The broker restarts; the gateway stays away (its CONNECT is held) while the requester is back.
    broker.hold(GATEWAY);
    await broker.restart();
    await until(() => broker.connected('requester'), 6000, 'the requester reconnected');
    await until(() => broker.waitingFor(GATEWAY), 6000, 'the gateway trying to reconnect');
    expect(broker.connected(GATEWAY)).to.equal(false);
    // Acknowledged by the broker (PUBACK) while the gateway is away …
    await requester.mq.publishAsync(`plant/${PLC}/run/set`, JSON.stringify({ value: true, id: 'w2' }), { qos: 1 });
    await requester.mq.publishAsync(`plant/${PLC}/pcHeartbeat/set`, JSON.stringify({ value: 2002, id: 'w3' }), { qos: 1 });
    // … then the broker restarts again: they are only in its persistent store now.
    await broker.stop();
    // Published while the broker is down: the requester keeps it until a broker acknowledges it.
    const w4 = requester.mq.publishAsync(`plant/${PLC}/pcHeartbeat/set`, JSON.stringify({ value: 3003, id: 'w4' }), { qos: 1 });
    await broker.start();
    await w4;
    expect(written()).to.deep.equal([['pcHeartbeat', 1001]]);

    broker.release(GATEWAY);
    const results = [];
    for (const id of ['w2', 'w3', 'w4']) results.push(await requester.next((m) => m.payload.id === id, 10000, `result for ${id}`));
    expect(results.map((r) => r.payload.ok)).to.deep.equal([true, true, true]);
    // Each reached the PLC once, in the order they were sent.
    expect(written()).to.deep.equal([
      ['pcHeartbeat', 1001],
      ['run', true],
      ['pcHeartbeat', 2002],
      ['pcHeartbeat', 3003],
    ]);
    expect([db()[RUN_BYTE]! & 1, db().readInt16BE(PC_HEARTBEAT)]).to.deep.equal([1, 3003]);
    expect(plant.s7.connectionCount).to.equal(1);
  });
});
