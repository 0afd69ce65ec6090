/**
 * The examples beside the demo, as a new user meets them: `npm start` runs
 * (demo/start.js: the plant, Node-RED, the demo flow), and each example is
 * imported into that runtime on a tab of its own and deployed through the
 * admin API (POST /flows, deployment type "nodes", the way the editor's
 * Deploy does it), one after the other, each beside the demo and the
 * examples before it. Every plcwire node of every example reaches a link
 * that is up (no "bad connection", no "settings conflict"), every polling
 * read delivers values (a recorder is wired behind it), and the control
 * example reads the CPU in RUN. Statuses are heard as the editor hears them:
 * on the runtime's comms socket. The MQTT gateway example gets a broker
 * (aedes, as Mosquitto would be on 127.0.0.1:1883): a subscriber receives
 * the plant's values from it, and a guarded write through it starts and stops
 * the plant's motor. In the Sparkplug example a host sees the S7-300's alarms:
 * the tank's high level as Alarms/Event, and its DCMD acknowledgement. Only the ports change: the test's plant listens on free
 * ports instead of 10102, 12000/12001 and 14001, the broker instead of 1883.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { DataType } from '../lib/sparkplug/datatypes';
import type { DataSet } from '../lib/sparkplug/model';
import { TestBroker } from './support/mqtt-broker';
import { freePort } from './support/net';
import { SparkplugListener, type HeardMessage } from './support/sparkplug-listener';

const ROOT = path.resolve(__dirname, '../..');
/** Node-RED's own WebSocket library (the editor's comms use it), from Node-RED's dependencies. */
const WebSocket = require(require.resolve('ws', { paths: [path.dirname(require.resolve('node-red/package.json', { paths: [ROOT] }))] }));
const EXAMPLES = path.join(ROOT, 'examples');
const { demoFlow, DEMO_URLS } = require(path.join(ROOT, 'demo/flows.js')) as { demoFlow(urls: object): any[]; DEMO_URLS: any };
const mqtt = require('mqtt');
const MQTT_EXAMPLE = 'MQTT gateway - publish tags, guarded writes.json';
const S7PLUS_EXAMPLE = 'S7CommPlus optimized DB by name.json';

interface Demo {
  editor: string;
  /** The demo's plant (lib/plant), in this process: its memory is the S7-1200's. */
  plant: any;
  stop(): Promise<void>;
}

const files = fs
  .readdirSync(EXAMPLES)
  .filter((f) => f.endsWith('.json'))
  .sort();

/** The connection settings two connection nodes to one PLC must share (links.js): URL, sources, block numbers, strictness. */
function shared(n: any) {
  return { url: n.url, symbolSources: n.symbolSources ?? [], dbNumbers: n.dbNumbers ?? [], strictSymbols: !!n.strictSymbols };
}

async function api(base: string, method: string, route: string, body?: unknown, headers: Record<string, string> = {}): Promise<any> {
  const res = await fetch(`${base}${route}`, {
    method,
    headers: { 'content-type': 'application/json', 'Node-RED-API-Version': 'v2', ...headers },
    body: body === undefined ? undefined : JSON.stringify(body),
  });
  const text = await res.text();
  if (!res.ok) throw new Error(`${method} ${route}: ${res.status} ${text}`);
  return text && /^[[{]/.test(text) ? JSON.parse(text) : text;
}

/** Waits for `check` (which throws while its condition does not hold) to pass, until `ms` have passed; then its last error. */
async function eventually<T>(check: () => Promise<T>, ms: number, what: string): Promise<T> {
  const deadline = Date.now() + ms;
  for (;;) {
    try {
      return await check();
    } catch (err) {
      if (Date.now() > deadline) throw new Error(`${what} within ${ms} ms: ${(err as Error).message}`, { cause: err });
      await new Promise((r) => setTimeout(r, 200));
    }
  }
}

describe('examples: each imported into the running `npm start` demo and deployed', function () {
  this.timeout(240_000);
  let demo: Demo;
  let broker: TestBroker;
  let ports: { s7: number; fetch: number; write: number; freeport: number; mqtt: number };
  let comms: any;
  /** The S7-1200's certificate fingerprint as the connection dialog's Get certificate shows it (from the runtime). */
  let pinned: string;
  /** Every node status the runtime published, by node id, as the editor hears them (its comms socket, topic status/<id>). */
  const statusOf: Record<string, { text?: string; fill?: string; shape?: string }[]> = {};

  before(async () => {
    const { startDemo } = require(path.join(ROOT, 'demo/start.js')) as { startDemo(o: object): Promise<Demo> };
    const [port, s7, fetchPort, write, freeport] = await Promise.all([freePort(), freePort(), freePort(), freePort(), freePort()]);
    broker = new TestBroker();
    await broker.start();
    ports = { s7, fetch: fetchPort, write, freeport, mqtt: broker.port };
    // The motor standing, as `plcwire demo` starts it: the gateway's write starts it.
    demo = await startDemo({
      port,
      plantPorts: { s7, fetch: fetchPort, write, freeport },
      quiet: true,
      log: () => undefined,
      feedMotor: 'stopped',
    });
    comms = new WebSocket(`${demo.editor.replace(/^http/, 'ws')}comms`);
    await new Promise((resolve, reject) => {
      comms.once('open', resolve);
      comms.once('error', reject);
    });
    comms.on('message', (data: Buffer) => {
      const list = JSON.parse(data.toString());
      for (const m of Array.isArray(list) ? list : [list]) {
        const id = /^status\/(.+)$/.exec(m.topic ?? '')?.[1];
        if (id) (statusOf[id] = statusOf[id] ?? []).push(m.data ?? {});
      }
    });
    comms.send(JSON.stringify({ subscribe: 'status/#' }));
    // An s7plus:// connection in an example trusts no certificate: a user presses Get certificate and Pin, as here.
    const cert = await api(demo.editor, 'POST', 'plcwire/s7plus/certificate', { url: `s7plus://127.0.0.1:${s7}` });
    expect(cert.ok, JSON.stringify(cert)).to.equal(true);
    pinned = cert.fingerprint;
    expect(pinned).to.equal(demo.plant.s7plus.fingerprint);
  });
  after(async () => {
    comms?.close();
    await demo?.stop();
    await broker?.stop();
  });

  it("every example's connection agrees with the demo's connection to the same PLC (ports, settings, sources)", () => {
    const demoConns = demoFlow(DEMO_URLS).filter((n) => n.type === 'plcwire-connection');
    for (const f of files) {
      const flow = JSON.parse(fs.readFileSync(path.join(EXAMPLES, f), 'utf8'));
      for (const conn of flow.filter((n: any) => n.type === 'plcwire-connection')) {
        // The same PLC: scheme, host and port (the demo has two s7:// CPUs, the S7-1200 and the S7-300).
        const plc = conn.url.split('?')[0];
        const theirs = demoConns.find((n) => n.url.split('?')[0] === plc);
        expect(theirs, `${f}: the demo has a connection to ${plc}`).to.not.equal(undefined);
        expect(shared(conn), `${f}: ${conn.id}`).to.deep.equal(shared(theirs));
      }
    }
  });

  /** The example on a tab of its own, its ports the test plant's, with a recorder behind every polling read. */
  function imported(f: string, i: number): { nodes: any[]; plcwire: string[]; polls: string[] } {
    const flow = JSON.parse(fs.readFileSync(path.join(EXAMPLES, f), 'utf8')) as any[];
    const tab = `ex${i}.tab`;
    // Get certificate, Pin: the dialog adds the fingerprint to an s7plus:// URL without one (nodes/connection.html buildUrl).
    const pin = (url: string) => (/^s7plus:\/\/[^?]*$/.test(url) ? `${url}?fingerprint=${pinned}` : url);
    const port = (url: string) =>
      pin(url)
        .replace(':10102', `:${ports.s7}`)
        .replace('fetchPort=12000', `fetchPort=${ports.fetch}`)
        .replace('writePort=12001', `writePort=${ports.write}`)
        .replace(':14001', `:${ports.freeport}`)
        .replace(':10103', `:${demo.plant.ports.s7classic}`);
    const configs = new Set(['plcwire-connection', 'mqtt-broker', 'plcwire-sparkplug-edge']);
    const plcwire = flow.filter((n) => n.type.startsWith('plcwire-') && !configs.has(n.type)).map((n) => n.id);
    const polls = flow.filter((n) => n.type === 'plcwire-read' && Number(n.interval) > 0).map((n) => n.id);
    const alarms = flow.filter((n) => n.type === 'plcwire-alarms').map((n) => n.id);
    const nodes: any[] = [{ id: tab, type: 'tab', label: f }];
    for (const n of flow) {
      if (n.type === 'plcwire-connection') nodes.push({ ...n, url: port(n.url) });
      else if (n.type === 'mqtt-broker') nodes.push({ ...n, port: String(ports.mqtt) });
      else if (n.type === 'plcwire-sparkplug-edge') nodes.push({ ...n, brokers: `mqtt://127.0.0.1:${ports.mqtt}` });
      else if (alarms.includes(n.id)) nodes.push({ ...n, z: tab, wires: [[...(n.wires?.[0] ?? []), `${n.id}.probe`]] });
      else if (polls.includes(n.id)) nodes.push({ ...n, z: tab, wires: [[...(n.wires?.[0] ?? []), `${n.id}.probe`]] });
      else nodes.push({ ...n, z: tab });
    }
    for (const [k, id] of polls.entries())
      nodes.push({
        id: `${id}.probe`,
        type: 'function',
        z: tab,
        x: 900,
        y: 100 + 40 * k,
        func: `const all = global.get('plcwireValues') || {};\n(all[${JSON.stringify(id)}] = all[${JSON.stringify(id)}] || []).push(msg.payload);\nglobal.set('plcwireValues', all);\nreturn null;`,
        outputs: 0,
        wires: [],
      });
    // Behind every alarms node: its events' topics, in order (alarm/257/coming, …).
    for (const [k, id] of alarms.entries())
      nodes.push({
        id: `${id}.probe`,
        type: 'function',
        z: tab,
        x: 900,
        y: 400 + 40 * k,
        func: `const all = global.get('plcwireAlarmTopics') || {};\n(all[${JSON.stringify(id)}] = all[${JSON.stringify(id)}] || []).push(msg.topic);\nglobal.set('plcwireAlarmTopics', all);\nreturn null;`,
        outputs: 0,
        wires: [],
      });
    return { nodes, plcwire, polls };
  }

  /** A global context value of the runtime, as the context sidebar reads it. */
  async function globalContext(key: string): Promise<any> {
    const res = await api(demo.editor, 'GET', `context/global/${key}`);
    const stored = res?.memory ?? res;
    // Nothing stored yet: no msg, or the sidebar's text "(undefined)".
    if (!stored || stored.msg === undefined || stored.msg === '(undefined)') return undefined;
    return JSON.parse(stored.msg);
  }

  /**
   * The MQTT gateway beside the demo, as a consumer on another machine meets it: every tag of the plant on
   * plant/tank/<tag> with the plant's values, and a write through the allow-list that starts the plant's motor
   * (and one more that stops it again), while a member the plant computes is refused.
   */
  async function mqttGateway(): Promise<void> {
    const db = (): Buffer => demo.plant.memory.area('DB', 1);
    const latest: Record<string, any> = {};
    const results: Record<string, any> = {};
    const consumer = await mqtt.connectAsync(broker.url, { reconnectPeriod: 100, connectTimeout: 5000 });
    try {
      consumer.on('message', (topic: string, payload: Buffer) => {
        const body = JSON.parse(payload.toString());
        const tag = /^plant\/tank\/([^/]+)$/.exec(topic)?.[1];
        if (tag) latest[tag] = body;
        if (/^plant\/tank\/[^/]+\/set\/result$/.test(topic)) results[body.id] = body;
      });
      await consumer.subscribeAsync('plant/tank/#', { qos: 1 });
      const tags = ['level', 'temperature', 'heater', 'run', 'running', 'speed', 'parts'];
      await eventually(
        async () => {
          const missing = tags.filter((t) => latest[t]?.quality !== 'good');
          if (missing.length) throw new Error(`not yet: ${missing.join(', ')} (${JSON.stringify(latest)})`);
        },
        30_000,
        'every plant tag published on plant/tank/<tag>',
      );
      // The plant's values, by name: the motor stands (nothing has started it), so its members hold still.
      expect(db()[4]! & 1, 'the demo starts with the motor stopped').to.equal(0);
      expect(latest.level).to.include({ address: '"Plant".Level' });
      expect(latest.level.value).to.be.within(0, 100);
      expect(latest.temperature.value).to.be.within(19.9, 60);
      expect([latest.run.value, latest.running.value, latest.speed.value]).to.deep.equal([false, false, 0]);
      expect(latest.parts.value).to.equal(db().readInt32BE(8));
      // A member the plant computes is refused, and the level goes on as the plant makes it.
      await consumer.publishAsync('plant/tank/level/set', JSON.stringify({ value: 0, id: 'level' }), { qos: 1 });
      await eventually(async () => expect(results.level?.error?.code).to.equal('NOT_WRITABLE'), 15_000, 'the level write refused');
      // The run command through the allow-list: acknowledged by the PLC, the plant's motor turns, the gateway publishes it.
      await consumer.publishAsync('plant/tank/run/set', JSON.stringify({ value: true, id: 'start' }), { qos: 1 });
      await eventually(async () => expect(results.start).to.deep.include({ ok: true, tag: 'run' }), 15_000, 'the start acknowledged');
      expect(db()[4]! & 1, '"Plant".MotorRun in the PLC').to.equal(1);
      await eventually(
        async () => expect([latest.running.value, latest.speed.value > 0]).to.deep.equal([true, true]),
        15_000,
        'the motor turning, published',
      );
      await consumer.publishAsync('plant/tank/run/set', JSON.stringify({ value: false, id: 'stop' }), { qos: 1 });
      await eventually(async () => expect(results.stop).to.deep.include({ ok: true, tag: 'run' }), 15_000, 'the stop acknowledged');
      await eventually(
        async () => expect([latest.running.value, latest.speed.value]).to.deep.equal([false, 0]),
        15_000,
        'the motor standing again, published',
      );
    } finally {
      await consumer.endAsync(true);
    }
  }

  /**
   * The S7CommPlus example: its poll reads the optimized DB "Tank" by name with the values the plant's process keeps
   * (no source file: the names are the PLC's), and its inject writes "Tank".Setpoint by name into the PLC.
   */
  async function optimizedByName(): Promise<void> {
    const latest = async () => ((await globalContext('plcwireValues')) ?? {})['s7plus.read']?.at(-1);
    const first = await latest();
    expect(first).to.have.keys(['phase', 'setpoint', 'drive', 'levels']);
    expect(first.setpoint).to.equal(demo.plant.tank.snapshot().setpoint);
    expect(first.phase).to.be.oneOf(['Filling', 'Draining']);
    expect(first.drive).to.have.keys(['Running', 'Speed', 'Current']);
    expect(first.levels).to.have.length(5);
    for (const v of first.levels) expect(v).to.be.within(0, 100);
    await api(demo.editor, 'POST', 'inject/s7plus.inject.setpoint');
    await eventually(async () => expect(demo.plant.tank.snapshot().setpoint).to.equal(45), 15_000, '"Tank".Setpoint written in the PLC');
    await eventually(async () => expect((await latest()).setpoint).to.equal(45), 15_000, 'the poll reading the new setpoint');
    await api(demo.editor, 'POST', 'inject/s7plus.inject.back');
    await eventually(async () => expect(demo.plant.tank.snapshot().setpoint).to.equal(42.5), 15_000, 'the setpoint back at 42.5');
  }

  /**
   * The S7-300 alarms example (issue #33): the plant's program raises the tank's high level, the alarms node sends it
   * as it comes, and the example's inject acknowledges it in the CPU (the node sends the acknowledged event).
   */
  async function classicAlarms(): Promise<void> {
    const topics = async (): Promise<string[]> => ((await globalContext('plcwireAlarmTopics')) ?? {})['almex.alarms'] ?? [];
    const flag = () => (demo.plant.memory.area('M')[10] & 1) !== 0;
    // A fresh coming: the level well below the limit (the program clears the flag), then above it.
    demo.plant.memory.area('DB', 1).writeFloatBE(50, 0);
    await eventually(async () => expect(flag(), 'M10.0 cleared').to.equal(false), 10_000, 'the high-level flag cleared');
    const before = (await topics()).length;
    demo.plant.memory.area('DB', 1).writeFloatBE(89, 0);
    await eventually(async () => expect((await topics()).slice(before)).to.include('alarm/257/coming'), 15_000, 'the ALARM_SQ coming');
    await api(demo.editor, 'POST', 'inject/almex.inject.ack');
    await eventually(
      async () => expect((await topics()).slice(before)).to.include('alarm/257/acknowledged'),
      15_000,
      'the acknowledgement',
    );
  }

  /**
   * The Sparkplug example (issue #34): every PLC of the demo is a device with typed, named metrics; a host writes the
   * permitted tag (the plant's motor) with DCMD; the S7-300 device publishes its PLC's alarms, the S7-1200's (PUT/GET)
   * does not; a host sees the tank's high level come as Alarms/Event and a row of Alarms/Active, and acknowledges it.
   */
  async function sparkplugAlarms(): Promise<void> {
    const listener = new SparkplugListener(broker.url);
    try {
      await listener.ready();
      // The births went out before this host subscribed: it asks for them again, as a host does.
      await listener.publish('spBv1.0/Plant/NCMD/Edge1', {
        timestamp: Date.now(),
        metrics: [{ name: 'Node Control/Rebirth', datatype: DataType.Boolean, value: true }],
      });
      const birth = await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'S7-300', 20_000, 0, "the S7-300's DBIRTH");
      const tank = await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Tank', 20_000, 0, "the Tank's DBIRTH");
      expect(birth.payload!.metrics.map((m) => m.name)).to.include.members([
        'Level',
        'Alarms/Active',
        'Alarms/Event',
        'Alarms/Acknowledge',
      ]);
      expect(tank.payload!.metrics.filter((m) => m.name?.startsWith('Alarms/'))).to.deep.equal([]);
      // Every PLC of the demo is a device, its metrics named and typed from the PLC (the Done of issue #34).
      const typed = (m: HeardMessage) =>
        Object.fromEntries(m.payload!.metrics.filter((x) => !x.name?.startsWith('Alarms/')).map((x) => [x.name, x.datatype]));
      expect(typed(tank)).to.deep.equal({
        Level: DataType.Float,
        Temperature: DataType.Float,
        MotorRun: DataType.Boolean,
        Parts: DataType.Int32,
      });
      expect(typed(birth)).to.deep.equal({ Level: DataType.Float, Temperature: DataType.Float, MotorRunning: DataType.Boolean });
      const cp = await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'CP', 20_000, 0, "the CP's DBIRTH");
      expect(typed(cp)).to.deep.equal({ Level: DataType.Float, Speed: DataType.Int16, MotorRunning: DataType.Boolean });
      const stations = await listener.waitFor((m) => m.type === 'DBIRTH' && m.device === 'Stations', 20_000, 0, "the Stations' DBIRTH");
      expect(typed(stations)).to.deep.equal({ Level: DataType.Float, Parts: DataType.Int32 });
      for (const b of [tank, birth, cp, stations]) {
        expect(
          b.payload!.metrics.every((m) => typeof m.timestamp === 'number' && m.alias !== undefined),
          b.device,
        ).to.equal(true);
        expect(b.payload!.metrics.find((m) => m.name === 'Level')!.value, `${b.device}: the plant's level`).to.be.within(0, 100);
      }

      // The host writes the permitted tag: the plant's motor starts, and the next DDATA says so; then it stops it again.
      const tankNames = new Map(tank.payload!.metrics.map((m) => [m.alias, m.name]));
      const motorIs = (on: boolean) => (m: HeardMessage) =>
        m.type === 'DDATA' &&
        m.device === 'Tank' &&
        m.payload!.metrics.some((x) => tankNames.get(x.alias) === 'MotorRun' && x.value === on);
      for (const on of [true, false]) {
        const from = listener.heard.length;
        await listener.publish('spBv1.0/Plant/DCMD/Edge1/Tank', {
          timestamp: Date.now(),
          metrics: [{ name: 'MotorRun', datatype: DataType.Boolean, value: on }],
        });
        await listener.waitFor(motorIs(on), 20_000, from, `DDATA MotorRun ${on}`);
        expect(demo.plant.memory.area('DB', 1)[4]! & 1, '"Plant".MotorRun in the PLC').to.equal(on ? 1 : 0);
      }
      const names = new Map(birth.payload!.metrics.map((m) => [m.alias, m.name]));
      const named = (m: HeardMessage) => m.payload!.metrics.map((x) => ({ ...x, name: x.name ?? names.get(x.alias) }));

      // A fresh coming, as classicAlarms makes one: the level well below the limit, then above it.
      const flag = () => (demo.plant.memory.area('M')[10] & 1) !== 0;
      demo.plant.memory.area('DB', 1).writeFloatBE(50, 0);
      await eventually(async () => expect(flag(), 'M10.0 cleared').to.equal(false), 10_000, 'the high-level flag cleared');
      const from = listener.heard.length;
      demo.plant.memory.area('DB', 1).writeFloatBE(89, 0);
      const coming = (m: HeardMessage) =>
        m.type === 'DDATA' &&
        m.device === 'S7-300' &&
        named(m).some((x) => x.name === 'Alarms/Event' && /"change":"coming"/.test(String(x.value)) && /"id":257\b/.test(String(x.value)));
      await listener.waitFor(coming, 20_000, from, 'DDATA Alarms/Event: alarm 257 coming');

      const beforeAck = listener.heard.length;
      await listener.publish('spBv1.0/Plant/DCMD/Edge1/S7-300', {
        timestamp: Date.now(),
        metrics: [{ name: 'Alarms/Acknowledge', datatype: DataType.UInt32, value: 257 }],
      });
      const acknowledged = (m: HeardMessage) => {
        if (m.type !== 'DDATA' || m.device !== 'S7-300') return false;
        const t = named(m).find((x) => x.name === 'Alarms/Active')?.value as DataSet | undefined;
        return !!t?.rows.some((r) => r[t.columns.indexOf('Id')] === 257 && r[t.columns.indexOf('Acknowledged')] === true);
      };
      await listener.waitFor(acknowledged, 20_000, beforeAck, 'DDATA Alarms/Active: alarm 257 acknowledged');
    } finally {
      await listener.close();
    }
  }

  /**
   * A node whose link is up: green, or a yellow dot; an alarms node's counts are up in every colour (a red dot
   * "1/1 unacked" is an alarm waiting for an operator, not a link down).
   */
  const up = (s: any) => s.fill === 'green' || (s.fill === 'yellow' && s.shape === 'dot') || unacked(s);
  const unacked = (s: any) => s.fill === 'red' && s.shape === 'dot' && /^\d+\/\d+ unacked$/.test(s.text ?? '');

  for (const [i, f] of files.entries()) {
    it(`"${f}": deploys beside the demo; every plcwire node's link is up, every poll delivers values`, async () => {
      const { nodes, plcwire, polls } = imported(f, i);
      const { flows, rev } = await api(demo.editor, 'GET', 'flows');
      await api(demo.editor, 'POST', 'flows', { flows: [...flows, ...nodes], rev }, { 'Node-RED-Deployment-Type': 'nodes' });

      const statuses = await eventually(
        async () => {
          const all = statusOf;
          const notUp = plcwire.filter((id) => !(all[id] ?? []).some(up));
          if (notUp.length)
            throw new Error(
              `heard ${Object.keys(all).length} nodes; not up: ${notUp.map((id) => `${id} ${JSON.stringify(all[id] ?? [])}`).join('; ')}`,
            );
          return all;
        },
        30_000,
        'every plcwire node up',
      );
      for (const id of plcwire) {
        const red = statuses[id]!.filter((s) => s.fill === 'red' && s.shape === 'dot' && !unacked(s));
        expect(red, `${f}: ${id} never showed bad connection or settings conflict`).to.deep.equal([]);
      }
      await eventually(
        async () => {
          const values = (await globalContext('plcwireValues')) ?? {};
          const silent = polls.filter((id) => !(values[id] ?? []).some((v: unknown) => v !== null && v !== undefined));
          if (silent.length) throw new Error(`no value from ${silent.join(', ')}`);
        },
        30_000,
        'a value from every poll',
      );
      if (f === MQTT_EXAMPLE) await mqttGateway();
      if (f === S7PLUS_EXAMPLE) await optimizedByName();
      if (f === 'S7-300 alarms - events, acknowledge.json') await classicAlarms();
      if (f === 'Sparkplug B - each PLC a device.json') await sparkplugAlarms();
      if (f === 'S7 PLC control.json') {
        await api(demo.editor, 'POST', 'inject/ctlex.inject.state');
        await eventually(
          async () => {
            const s = statusOf['ctlex.control'] ?? [];
            if (!s.some((x) => /RUN/.test(x.text ?? ''))) throw new Error(JSON.stringify(s));
          },
          20_000,
          'the control node reads the CPU in RUN',
        );
      }
    });
  }
});
