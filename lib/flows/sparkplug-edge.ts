/**
 * The Node-RED side of a Sparkplug B edge node (nodes/sparkplug-edge.js and
 * nodes/sparkplug-device.js): the edge-node config node holds one
 * SparkplugEdgeHub, each device node adds its PLC (a plcwire connection's
 * client and its tag table). The hub builds the SparkplugEdgeNode once the
 * flows have started, with every device the deploy gave it, and builds it
 * anew (NDEATH, then births with the next bdSeq) when a device comes or goes
 * later. What it does reaches the nodes as status and errors.
 */
import { EventEmitter } from 'node:events';
import type * as mqtt from 'mqtt';
import { driverOf, schemesOffering } from '../drivers';
import { PlcError } from '../errors';
import type { PlcClient } from '../types';
import type { SymbolTable } from '../symbols/model';
import { ALARM_METRICS } from '../sparkplug/alarms';
import { SparkplugEdgeNode } from '../sparkplug/edge-node';
import type { EdgeNodeStatus } from '../sparkplug/options';
import type { SparkplugDeviceOptions } from '../sparkplug/device';
import { tagTable } from './tag-list';

/** The edge-node config node's settings, as the editor stores them (text fields). */
export interface EdgeHubConfig {
  /** One broker URL a line (or comma-separated), in order of preference. */
  brokers: string;
  group: string;
  node: string;
  primaryHost?: string;
  stateDir?: string;
  /** Store-and-forward bound: most values kept (text from the editor; default 10000). */
  buffer?: string | number;
  /** A directory where store-and-forward keeps its values too, so a restarted edge node forwards them. */
  bufferDir?: string;
  interval?: string | number;
  username?: string;
  password?: string;
  /** What Node-RED's tls-config node gives (addTLSOptions): the CA, a client certificate and key, whether to verify the broker. */
  tls?: Pick<mqtt.IClientOptions, 'ca' | 'cert' | 'key' | 'servername' | 'rejectUnauthorized' | 'ALPNProtocols'> & { passphrase?: string };
}

/** One device node's PLC. */
export interface HubDevice {
  name: string;
  client: PlcClient;
  /** The device node's tag table: rows of { name, address }; each name a metric. */
  tags: unknown;
  /** Metric names a host may write (comma-separated text or a list). */
  writable?: string | readonly string[];
  symbols?: SymbolTable;
  /** A numeric change at or under it is not reported (every metric of the device). */
  deadband?: number;
  /** The PLC's alarms as the device's `Alarms/…` metrics (its connection's protocol must report alarms). */
  alarms?: boolean;
  /** A host may acknowledge them with DCMD `Alarms/Acknowledge` (with `alarms`). */
  acknowledge?: boolean;
}

/** The list of a text field: one item a line or comma-separated, blanks dropped. */
function listOf(text: unknown): string[] {
  if (Array.isArray(text)) return text.map((t) => String(t).trim()).filter((t) => t !== '');
  return (typeof text === 'string' ? text : '')
    .split(/[\n,]/)
    .map((t) => t.trim())
    .filter((t) => t !== '');
}

function wholeNumber(field: string, raw: unknown, fallback: number, min: number): number {
  if (raw === undefined || raw === null || raw === '') return fallback;
  const n = Number(raw);
  if (!Number.isInteger(n) || n < min)
    throw new PlcError('INVALID_VALUE', `${field} must be a whole number ≥ ${min}, got ${JSON.stringify(raw)}`);
  return n;
}

/** The device's options for the edge node; a bad row or writable name is a PlcError naming the device and the tag. */
function deviceOptions(device: HubDevice): SparkplugDeviceOptions {
  const rows = tagTable(device.tags);
  if (rows.length === 0) throw new PlcError('INVALID_VALUE', `Sparkplug device ${device.name} has no tags`);
  if (device.alarms && !driverOf(device.client).alarms) {
    throw new PlcError(
      'NOT_SUPPORTED',
      `Sparkplug device ${device.name}: its connection (${device.client.protocol}://) reports no alarms (${schemesOffering('alarms')} do)`,
    );
  }
  if (device.acknowledge && !device.alarms)
    throw new PlcError(
      'INVALID_VALUE',
      `Sparkplug device ${device.name}: hosts can acknowledge alarms only when the device publishes them`,
    );
  return {
    name: device.name,
    client: device.client,
    tags: Object.fromEntries(rows.map((r) => [r.name, r.address])),
    writable: [...listOf(device.writable), ...(device.acknowledge ? [ALARM_METRICS.acknowledge] : [])],
    ...(device.alarms ? { alarms: true } : {}),
    ...(device.symbols ? { symbols: device.symbols } : {}),
  };
}

/**
 * Events: `status` (EdgeNodeStatus), `error` (PlcError, and the device it concerns if one), `publish`
 * (PublishedMessage), `command` (CommandDone), as the edge node's.
 */
export class SparkplugEdgeHub extends EventEmitter {
  private readonly devices = new Map<string, HubDevice>();
  private node: SparkplugEdgeNode | undefined;
  private started = false;
  private building: Promise<void> = Promise.resolve();
  /** The last status, for a device node that comes later. */
  status: EdgeNodeStatus = { state: 'stopped' };

  constructor(private readonly config: EdgeHubConfig) {
    super();
    if (listOf(config.brokers).length === 0) throw new PlcError('INVALID_VALUE', 'the Sparkplug edge node needs at least one broker URL');
  }

  /** Adds a device (a second one of the same name is refused); after start(), the edge node is built anew. */
  add(device: HubDevice): void {
    if (this.devices.has(device.name))
      throw new PlcError('INVALID_VALUE', `two Sparkplug device nodes are named "${device.name}" on one edge node`);
    deviceOptions(device); // its mistakes are the device node's, now
    this.devices.set(device.name, device);
    if (this.started) this.rebuild();
  }

  remove(name: string): void {
    if (this.devices.delete(name) && this.started) this.rebuild();
  }

  /** Builds and starts the edge node with the devices so far (the flows have started). */
  start(): void {
    if (this.started) return;
    this.started = true;
    this.rebuild();
  }

  /** Sends NBIRTH and the DBIRTHs again. */
  rebirth(): void {
    this.node?.rebirth();
  }

  get stats(): SparkplugEdgeNode['stats'] | undefined {
    return this.node?.stats;
  }

  /** Stops the edge node (NDEATH before the disconnect). Always resolves. */
  async close(): Promise<void> {
    this.started = false;
    await this.building;
    const node = this.node;
    this.node = undefined;
    await node?.stop();
  }

  private rebuild(): void {
    this.building = this.building.then(async () => {
      const old = this.node;
      this.node = undefined;
      await old?.stop();
      if (!this.started || this.devices.size === 0) return;
      try {
        this.node = this.build();
        this.node.start();
      } catch (err) {
        const error = err instanceof PlcError ? err : new PlcError('INVALID_VALUE', (err as Error).message);
        if (this.listenerCount('error') > 0) this.emit('error', error);
      }
    });
  }

  private build(): SparkplugEdgeNode {
    const c = this.config;
    const node = new SparkplugEdgeNode({
      brokers: listOf(c.brokers),
      group: String(c.group ?? '').trim(),
      node: String(c.node ?? '').trim(),
      devices: [...this.devices.values()].map(deviceOptions),
      interval: wholeNumber('the poll interval', c.interval, 1000, 10),
      buffer: {
        count: wholeNumber('the store-and-forward bound', c.buffer, 10_000, 0),
        ...(c.bufferDir?.trim() ? { dir: c.bufferDir.trim() } : {}),
      },
      deadbands: Object.fromEntries(
        [...this.devices.values()]
          .filter((d) => (d.deadband ?? 0) > 0)
          .map((d) => [d.name, Object.fromEntries(tagTable(d.tags).map((r) => [r.name, d.deadband!]))]),
      ),
      ...(c.primaryHost?.trim() ? { primaryHost: c.primaryHost.trim() } : {}),
      ...(c.stateDir?.trim() ? { stateDir: c.stateDir.trim() } : {}),
      mqtt: { ...c.tls, ...(c.username ? { username: c.username, ...(c.password ? { password: c.password } : {}) } : {}) },
    });
    node.on('status', (s) => {
      this.status = s;
      this.emit('status', s);
    });
    node.on('error', (e, device) => this.listenerCount('error') > 0 && this.emit('error', e, ...(device !== undefined ? [device] : [])));
    node.on('publish', (m) => this.emit('publish', m));
    node.on('command', (d) => this.emit('command', d));
    return node;
  }
}
