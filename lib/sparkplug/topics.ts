/**
 * Sparkplug topics (Sparkplug 3.0, chapter 4 "Topics and Messages"):
 * `spBv1.0/<group_id>/<message_type>/<edge_node_id>[/<device_id>]` and the
 * primary host's `spBv1.0/STATE/<host_id>`. An id is UTF-8 without the MQTT
 * separators and wildcards `/`, `+`, `#` (section 4.1.1).
 */
import { PlcError } from '../errors';

/** The namespace element of Sparkplug B (section 4.1.1.1). */
export const NAMESPACE = 'spBv1.0';

type NodeMessageType = 'NBIRTH' | 'NDEATH' | 'NDATA' | 'NCMD';
type DeviceMessageType = 'DBIRTH' | 'DDEATH' | 'DDATA' | 'DCMD';
export type MessageType = NodeMessageType | DeviceMessageType;

const MESSAGE_TYPES: ReadonlySet<string> = new Set(['NBIRTH', 'NDEATH', 'NDATA', 'NCMD', 'DBIRTH', 'DDEATH', 'DDATA', 'DCMD']);

/** Throws INVALID_VALUE unless `id` can be a group, edge node, device or host id. */
export function checkId(kind: string, id: string): string {
  if (typeof id !== 'string' || id === '') throw new PlcError('INVALID_VALUE', `a Sparkplug ${kind} id must be a non-empty string`);
  const bad = /[/+#]/.exec(id);
  if (bad)
    throw new PlcError(
      'INVALID_VALUE',
      `the Sparkplug ${kind} id "${id}" holds "${bad[0]}": ids cannot hold "/", "+" or "#" (they separate and match MQTT topic levels)`,
    );
  return id;
}

/** The topic of an edge node's message (N…) or of a device's (D…, with `device`). */
export function topicOf(type: MessageType, group: string, node: string, device?: string): string {
  const base = `${NAMESPACE}/${group}/${type}/${node}`;
  return type.startsWith('D') ? `${base}/${device}` : base;
}

/** The primary host application's STATE topic (section 4.2.1). */
export function stateTopic(host: string): string {
  return `${NAMESPACE}/STATE/${host}`;
}

/** A Sparkplug topic's parts, or undefined for a topic that is not one. */
export interface ParsedTopic {
  type: MessageType | 'STATE';
  group?: string;
  node?: string;
  device?: string;
  host?: string;
}

export function parseTopic(topic: string): ParsedTopic | undefined {
  const parts = topic.split('/');
  if (parts[0] !== NAMESPACE) return undefined;
  if (parts[1] === 'STATE' && parts.length === 3) return { type: 'STATE', host: parts[2]! };
  if (parts.length < 4 || !MESSAGE_TYPES.has(parts[2]!)) return undefined;
  const type = parts[2] as MessageType;
  const isDevice = type.startsWith('D');
  if (parts.length !== (isDevice ? 5 : 4)) return undefined;
  return { type, group: parts[1]!, node: parts[3]!, ...(isDevice ? { device: parts[4]! } : {}) };
}
