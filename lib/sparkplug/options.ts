/** What a SparkplugEdgeNode takes (its options) and tells (its events), lib/sparkplug/edge-node.ts. */
import type * as mqtt from 'mqtt';
import type { PlcError } from '../errors';
import type { SparkplugDeviceOptions } from './device';
import type { SparkplugPayload } from './model';
import type { BufferOptions } from './store';
import type { MessageType } from './topics';

export interface SparkplugEdgeNodeOptions {
  /** MQTT brokers in order of preference (`mqtt://host:1883`, `mqtts://…`): one session at a time, the next on failure or host offline. */
  brokers: readonly string[];
  /** The Sparkplug group id. */
  group: string;
  /** The Sparkplug edge node id. */
  node: string;
  devices: readonly SparkplugDeviceOptions[];
  /** The primary host application's id: births wait for its STATE online; its offline moves to the next broker. */
  primaryHost?: string;
  /** Poll interval in ms (default 1000). */
  interval?: number;
  /** Where bdSeq is kept across restarts (without it, bdSeq starts at 0 with every process). */
  stateDir?: string;
  /** Store-and-forward bounds while there is no Sparkplug session. */
  buffer?: BufferOptions;
  /** Per device, per metric: a numeric change at or under it is not reported. */
  deadbands?: Readonly<Record<string, Readonly<Record<string, number>>>>;
  /** false: poll every device, even those whose PLC can push its changes (S7CommPlus subscriptions); default true. */
  push?: boolean;
  /**
   * The sample time asked of a PLC that pushes (ms): how often it looks for
   * changes to report. Default the poll interval, at most 1000 ms: a slow
   * poll must not make report by exception slow.
   */
  pushCycle?: number;
  /** Delay before the next CONNECT after a session ended or failed, in ms (default 1000). */
  reconnectDelay?: number;
  /** MQTT client id (default `plcwire-<group>-<node>`). */
  clientId?: string;
  /** Further MQTT.js options: username, password, TLS (ca, cert, key), connectTimeout, keepalive, protocolVersion (4 or 5). */
  mqtt?: Omit<mqtt.IClientOptions, 'will' | 'clean' | 'reconnectPeriod' | 'clientId'>;
}

export type EdgeNodeState = 'connecting' | 'waiting-for-host' | 'online' | 'stopped';

export interface EdgeNodeStatus {
  state: EdgeNodeState;
  /** The broker of the session (or being connected to). */
  broker?: string;
  bdSeq?: number;
}

/** A message the edge node published (the payload as it was encoded). */
export interface PublishedMessage {
  topic: string;
  type: MessageType;
  device?: string;
  payload: SparkplugPayload;
}

/** A DCMD metric written to the PLC. */
export interface CommandDone {
  device: string;
  metric: string;
  value: unknown;
}

export interface EdgeNodeEvents {
  status: [status: EdgeNodeStatus];
  /**
   * Only emitted when someone listens: refused commands, failed writes, a broker's errors, dropped buffered
   * data, a PLC's alarm service failing. `device`: the device it concerns, if one.
   */
  error: [error: PlcError, device?: string];
  publish: [message: PublishedMessage];
  command: [done: CommandDone];
  /** Buffered values dropped at the store-and-forward bound (the running total in `stats.dropped`). */
  dropped: [count: number];
}
