/**
 * A Sparkplug B 3.0 edge node whose devices are PLCs (Sparkplug 3.0, chapter
 * 5 "Operational Behavior"): one MQTT session at a time to the first broker
 * of its list that works, with the NDEATH as its Will; births after the
 * primary host's STATE says it is online; each PLC a device whose metrics
 * are its tags; DDATA by exception; DDEATH when a PLC's link is lost and a
 * DBIRTH when it is back; rebirth on request; DCMD writes to the tags the
 * options make writable; store-and-forward while there is no session.
 *
 * docs/sparkplug.md lists each rule of the specification with its test.
 */
import * as mqtt from 'mqtt';
import { PlcError, toPlcError } from '../errors';
import { EventEmitterBase, type TypedEvents } from '../client/events';
import { BdSeqStore } from './bdseq';
import { BrokerErrors, brokerName, checkBrokers } from './brokers';
import { checkNodeCommand, executeCommand } from './commands';
import { SparkplugDevice } from './device';
import { HostStateTracker, parseHostState } from './host-state';
import { ndeathPayload, nbirthPayload } from './messages';
import type { SparkplugMetric, SparkplugPayload } from './model';
import type { EdgeNodeEvents, EdgeNodeState, SparkplugEdgeNodeOptions } from './options';
import { decodePayload, encodePayload } from './payload';
import { DevicePush } from './push';
import { ForwardStore } from './store';
import { UnconfirmedData } from './unconfirmed';
import { checkId, parseTopic, stateTopic, topicOf, type MessageType } from './topics';

// EdgeNodeEvents' listener methods (lib/client/events.ts), merged into the class, as BaseClient does.
/* eslint-disable @typescript-eslint/no-unsafe-declaration-merging, @typescript-eslint/no-empty-object-type */
export interface SparkplugEdgeNode extends TypedEvents<EdgeNodeEvents> {}
/* eslint-enable @typescript-eslint/no-empty-object-type */

export class SparkplugEdgeNode extends EventEmitterBase {
  readonly group: string;
  readonly node: string;
  private readonly options: SparkplugEdgeNodeOptions;
  private readonly devices: SparkplugDevice[] = [];
  private readonly bdSeqStore: BdSeqStore;
  private readonly store: ForwardStore;
  /** DDATA the broker has not confirmed (by a PINGRESP) yet: stored again when a session ends without our DISCONNECT. */
  private readonly unconfirmed: UnconfirmedData;
  private readonly host = new HostStateTracker();
  private readonly brokerErrors = new BrokerErrors((e) => this.report(e));
  /** Devices born in this session. */
  private readonly born = new Set<string>();
  private readonly unsubscribers: (() => void)[] = [];
  private readonly pushes = new Map<SparkplugDevice, DevicePush>();
  private client: mqtt.MqttClient | undefined;
  private brokerIndex = 0;
  private bdSeq: number | undefined;
  private seq = 0;
  private nodeBorn = false;
  private stopped = true;
  private state: EdgeNodeState = 'stopped';
  private pollTimer: NodeJS.Timeout | undefined;
  private reconnectTimer: NodeJS.Timeout | undefined;
  private polling: Promise<void> | undefined;

  constructor(options: SparkplugEdgeNodeOptions) {
    super();
    checkBrokers(options.brokers);
    this.group = checkId('group', options.group);
    this.node = checkId('edge node', options.node);
    if (options.primaryHost !== undefined) checkId('primary host', options.primaryHost);
    const interval = options.interval ?? 1000;
    if (!(interval >= 10)) throw new PlcError('INVALID_VALUE', `the poll interval must be at least 10 ms, got ${options.interval}`);
    this.options = options;
    let alias = 0;
    const names = new Set<string>();
    for (const d of options.devices) {
      checkId('device', d.name);
      if (names.has(d.name)) throw new PlcError('INVALID_VALUE', `two devices are named "${d.name}"`);
      names.add(d.name);
      const device: SparkplugDevice = new SparkplugDevice(d, alias, options.deadbands?.[d.name], {
        alarmsChanged: () => this.afterRead(device),
        error: (e) => this.report(e, device.name),
      });
      alias = device.endAlias;
      this.devices.push(device);
    }
    this.bdSeqStore = new BdSeqStore(options.stateDir, this.group, this.node);
    this.store = new ForwardStore(options.buffer, `${encodeURIComponent(this.group)}.${encodeURIComponent(this.node)}`);
    this.unconfirmed = new UnconfirmedData(options.buffer?.count ?? 10_000);
  }
  /* eslint-enable @typescript-eslint/no-unsafe-declaration-merging */

  /** What the node did so far. */
  get stats(): { buffered: number; dropped: number; bdSeq: number | undefined; state: EdgeNodeState } {
    return { buffered: this.store.count, dropped: this.store.dropped, bdSeq: this.bdSeq, state: this.state };
  }

  /** Starts polling the PLCs and connecting to the brokers. */
  start(): void {
    if (!this.stopped) return;
    this.stopped = false;
    for (const device of this.devices) {
      const down = (error: PlcError): void => this.deviceDown(device, error);
      device.client.on('disconnected', down);
      this.unsubscribers.push(() => device.client.off('disconnected', down));
      const alarms = device.alarms;
      if (alarms) {
        const open = (): void => alarms.open();
        device.client.on('connected', open);
        this.unsubscribers.push(() => device.client.off('connected', open));
        open();
      }
      if (this.options.push === false) continue;
      const push = new DevicePush(
        device,
        this.options.pushCycle ?? Math.min(this.options.interval ?? 1000, 1000),
        () => this.afterRead(device),
        (e) => this.report(e, device.name),
      );
      if (!push.available) continue;
      this.pushes.set(device, push);
      const open = (): void => void push.open();
      device.client.on('connected', open);
      this.unsubscribers.push(() => device.client.off('connected', open));
      open();
    }
    this.connect();
    this.schedulePoll(0);
  }

  /** Publishes NDEATH (tck-id-operational-behavior-edge-node-intentional-disconnect-ndeath), disconnects, stops polling. Always resolves. */
  async stop(): Promise<void> {
    if (this.stopped) return;
    this.stopped = true;
    clearTimeout(this.pollTimer);
    clearTimeout(this.reconnectTimer);
    for (const off of this.unsubscribers.splice(0)) off();
    await this.polling?.catch(() => undefined);
    await Promise.all([...this.pushes.values()].map((p) => p.close()));
    this.pushes.clear();
    const client = this.client;
    this.client = undefined;
    this.nodeBorn = false;
    this.born.clear();
    // The NDEATH's PUBACK confirms every data message before it; without it they are kept (on disk, with buffer.dir).
    let confirmed = false;
    if (client) {
      if (client.connected && this.bdSeq !== undefined) {
        confirmed = await client
          .publishAsync(topicOf('NDEATH', this.group, this.node), encodePayload(ndeathPayload(this.bdSeq)), { qos: 1, retain: false })
          .then(
            () => true,
            () => false,
          );
      }
      await client.endAsync().catch(() => undefined);
      client.removeAllListeners();
    }
    for (const run of this.unconfirmed.take()) if (!confirmed) this.store.add(run.device, run.metrics);
    await Promise.all(this.devices.map((d) => d.close()));
    this.setState('stopped');
  }

  /** Sends NBIRTH and the DBIRTHs again, with the same bdSeq (as on a host's Node Control/Rebirth). */
  rebirth(): void {
    if (!this.nodeBorn) return;
    this.birth();
  }

  // ------------------------------------------------------------------ the MQTT session

  private connect(): void {
    if (this.stopped) return;
    const url = this.options.brokers[this.brokerIndex]!;
    const bdSeq = this.bdSeqStore.next();
    this.bdSeq = bdSeq;
    this.setState('connecting', url);
    const client = mqtt.connect(url, {
      connectTimeout: 5000,
      // A PINGRESP confirms the QoS 0 data sent before it (unconfirmed.ts): every 10 s, and a dead path is seen in 15 s.
      keepalive: 10,
      ...this.options.mqtt,
      clientId: this.options.clientId ?? `plcwire-${this.group}-${this.node}`,
      clean: true,
      reconnectPeriod: 0,
      will: { topic: topicOf('NDEATH', this.group, this.node), payload: encodePayload(ndeathPayload(bdSeq)), qos: 1, retain: false },
    });
    this.client = client;
    client.on('connect', () => void this.sessionStarted(client));
    client.on('message', (topic, payload) => this.received(client, topic, payload));
    client.on('packetsend', (p) => p.cmd === 'pingreq' && this.unconfirmed.pingSent());
    client.on('packetreceive', (p) => p.cmd === 'pingresp' && this.unconfirmed.pingAnswered());
    client.on('error', (err) => this.brokerErrors.take(url, err));
    client.on('close', () => this.sessionEnded(client));
  }

  private async sessionStarted(client: mqtt.MqttClient): Promise<void> {
    this.brokerErrors.reset();
    const subscriptions: Record<string, { qos: 1 }> = { [topicOf('NCMD', this.group, this.node)]: { qos: 1 } };
    for (const device of this.devices) {
      if (device.commandable) subscriptions[topicOf('DCMD', this.group, this.node, device.name)] = { qos: 1 };
    }
    if (this.options.primaryHost !== undefined) subscriptions[stateTopic(this.options.primaryHost)] = { qos: 1 };
    try {
      await client.subscribeAsync(subscriptions);
    } catch (err) {
      // No session without the command subscriptions: end it, the next CONNECT tries again.
      this.report(toPlcError(err, 'CONNECTION_LOST'));
      client.end(true);
      return;
    }
    if (client !== this.client) return;
    if (this.options.primaryHost === undefined) this.birth();
    else if (!this.nodeBorn) this.setState('waiting-for-host');
  }

  private sessionEnded(client: mqtt.MqttClient): void {
    if (client !== this.client) return;
    client.removeAllListeners();
    client.on('error', () => undefined);
    this.client = undefined;
    // Ended without our DISCONNECT: what the broker did not confirm is sent again after the next births.
    for (const run of this.unconfirmed.take()) this.buffer(run.device, run.metrics);
    this.nodeBorn = false;
    this.born.clear();
    this.host.unknown();
    if (this.stopped) return;
    this.brokerIndex = (this.brokerIndex + 1) % this.options.brokers.length;
    this.setState('connecting', this.options.brokers[this.brokerIndex]);
    this.reconnectTimer = setTimeout(() => this.connect(), this.options.reconnectDelay ?? 1000);
  }

  /** Leaves this broker for the next (the primary host is offline on it): NDEATH, then DISCONNECT (tck-id-message-flow-edge-node-birth-publish-phid-offline). */
  private leave(client: mqtt.MqttClient): void {
    if (this.nodeBorn && this.bdSeq !== undefined) this.publish('NDEATH', undefined, ndeathPayload(this.bdSeq), 1);
    this.unconfirmed.take(); // the DISCONNECT goes after them on the same stream: the broker reads them all
    this.nodeBorn = false;
    this.born.clear();
    client.end(false, () => undefined);
  }

  private received(client: mqtt.MqttClient, topic: string, bytes: Buffer): void {
    if (client !== this.client) return;
    const parsed = parseTopic(topic);
    if (!parsed) return;
    if (parsed.type === 'STATE') {
      if (parsed.host !== this.options.primaryHost) return; // tck-id-message-flow-edge-node-birth-publish-phid-wait-id
      const state = parseHostState(bytes);
      if (!state)
        return this.report(
          new PlcError('PROTOCOL_ERROR', `STATE of primary host ${parsed.host} is not {"online": boolean, "timestamp": number}`),
        );
      const transition = this.host.take(state);
      if (transition === 'online' && !this.nodeBorn) this.birth();
      else if (transition === 'offline') this.leave(client);
      return;
    }
    let payload: SparkplugPayload;
    try {
      payload = decodePayload(bytes);
    } catch (err) {
      return this.report(toPlcError(err, 'PROTOCOL_ERROR'));
    }
    if (parsed.type === 'DCMD') return void this.deviceCommand(parsed.device!, payload);
    if (parsed.type !== 'NCMD') return;
    const { rebirth, errors } = checkNodeCommand(payload);
    for (const e of errors) this.report(e);
    if (rebirth) this.rebirth();
  }

  private async deviceCommand(name: string, payload: SparkplugPayload): Promise<void> {
    const device = this.devices.find((d) => d.name === name);
    if (!device) return this.report(new PlcError('INVALID_ADDRESS', `DCMD for unknown device ${name}`));
    const { done, errors } = await executeCommand(device, payload);
    for (const error of errors) this.report(error, name);
    for (const d of done) this.emit('command', { device: name, metric: d.metric, value: d.value });
    if (done.length > 0) this.schedulePoll(0);
  }

  // ------------------------------------------------------------------ births, data, deaths

  private birth(): void {
    if (!this.client || this.bdSeq === undefined) return;
    this.nodeBorn = false;
    this.born.clear();
    this.seq = 0;
    this.publish('NBIRTH', undefined, nbirthPayload(this.bdSeq));
    this.nodeBorn = true;
    for (const device of this.devices) {
      device.forgetReported();
      this.deviceBirth(device, false);
    }
    this.setState('online', this.options.brokers[this.brokerIndex]);
    // Every DBIRTH before any DDATA (tck-id-payloads-dbirth-order); then what the born devices kept, in order.
    this.forward((d) => this.born.has(d));
    for (const device of this.devices) if (this.born.has(device.name)) this.lateAlarms(device);
  }

  /** A DBIRTH, and with `data` what the device kept (forward()). A device not ready is born later, from afterRead. */
  private deviceBirth(device: SparkplugDevice, data = true): void {
    if (!this.nodeBorn || this.born.has(device.name) || !device.complete || device.client.state !== 'connected') return;
    this.publish('DBIRTH', device.name, { timestamp: Date.now(), seq: this.nextSeq(), metrics: device.birth() });
    this.born.add(device.name);
    if (!data) return;
    this.forward((d) => d === device.name);
    this.lateAlarms(device);
  }

  private deviceDown(device: SparkplugDevice, _error: PlcError): void {
    if (!this.born.delete(device.name)) return;
    device.alarms?.died();
    this.publish('DDEATH', device.name, { timestamp: Date.now(), seq: this.nextSeq(), metrics: [] });
  }

  /** After the DBIRTHs: what the devices `which` accepts kept while there was no session, as historical DDATA, oldest first. */
  private forward(which: (device: string) => boolean): void {
    for (const run of this.store.take(which))
      this.publish('DDATA', run.device, { timestamp: Date.now(), seq: this.nextSeq(), metrics: run.metrics });
  }

  /** After a device's birth and what it kept: the alarm events its PLC reported before the birth (the device down), in order. */
  private lateAlarms(device: SparkplugDevice): void {
    const late = device.changes();
    if (late.length > 0) this.publish('DDATA', device.name, { timestamp: Date.now(), seq: this.nextSeq(), metrics: late });
  }

  private nextSeq(): number {
    this.seq = (this.seq + 1) % 256;
    return this.seq;
  }

  private publish(type: MessageType, device: string | undefined, payload: SparkplugPayload, qos: 0 | 1 = 0): void {
    const client = this.client;
    if (!client) return;
    const topic = topicOf(type, this.group, this.node, device);
    client.publish(topic, encodePayload(payload), { qos, retain: false });
    if (type === 'DDATA') this.unconfirmed.data(device!, payload.metrics);
    this.emit('publish', { topic, type, ...(device !== undefined ? { device } : {}), payload });
  }

  // ------------------------------------------------------------------ polling

  private schedulePoll(delay: number): void {
    if (this.stopped) return;
    clearTimeout(this.pollTimer);
    this.pollTimer = setTimeout(() => {
      if (this.polling) return this.schedulePoll(5);
      this.polling = this.pollAll().finally(() => {
        this.polling = undefined;
        this.schedulePoll(this.options.interval ?? 1000);
      });
    }, delay);
  }

  private async pollAll(): Promise<void> {
    await Promise.all(this.devices.map((d) => this.pollDevice(d)));
  }

  private async pollDevice(device: SparkplugDevice): Promise<void> {
    device.alarms?.open(true); // again, after a subscription attempt that failed on a link that stayed up
    if (this.pushes.get(device)?.active && this.born.has(device.name)) return;
    try {
      await device.poll();
    } catch (err) {
      return this.deviceDown(device, toPlcError(err));
    }
    this.afterRead(device);
  }

  /** Births or reports a device after new values came in (a poll or a push). */
  private afterRead(device: SparkplugDevice): void {
    if (this.stopped) return;
    if (device.client.state !== 'connected')
      return this.deviceDown(device, new PlcError('NOT_CONNECTED', `${device.name} is not connected`));
    if (this.nodeBorn && !this.born.has(device.name)) return this.deviceBirth(device);
    if (this.born.has(device.name)) {
      const changes = device.changes();
      if (changes.length > 0) this.publish('DDATA', device.name, { timestamp: Date.now(), seq: this.nextSeq(), metrics: changes });
      return;
    }
    if (device.hasReported) this.buffer(device.name, device.changes());
  }

  private buffer(device: string, metrics: SparkplugMetric[]): void {
    if (metrics.length === 0) return;
    const dropped = this.store.add(device, metrics);
    if (dropped > 0) {
      this.emit('dropped', dropped);
      this.report(
        new PlcError('QUEUE_FULL', `store-and-forward full: dropped ${dropped} of the oldest values (${this.store.dropped} in all)`),
      );
    }
  }

  private setState(state: EdgeNodeState, broker?: string): void {
    this.state = state;
    const shown = broker !== undefined ? { broker: brokerName(broker) } : {};
    this.emit('status', { state, ...shown, ...(this.bdSeq !== undefined ? { bdSeq: this.bdSeq } : {}) });
  }

  private report(error: PlcError, device?: string): void {
    if (this.listenerCount('error') > 0) this.emit('error', error, ...(device !== undefined ? [device] : []));
  }
}
