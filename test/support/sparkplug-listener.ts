/**
 * A plain MQTT.js subscriber to spBv1.0/# that decodes each Sparkplug B message
 * with our codec (lib/sparkplug/payload.ts) and keeps it, in order, with a
 * deadline-bound wait for the one a test expects. STATE payloads are kept as
 * text.
 */
import { decodePayload } from '../../lib/sparkplug/payload';
import type { SparkplugPayload } from '../../lib/sparkplug/model';
import { encodePayload } from '../../lib/sparkplug/payload';

const mqtt = require('mqtt');

export interface HeardMessage {
  topic: string;
  /** NBIRTH, DDATA, ..., or STATE. */
  type: string;
  device?: string;
  payload?: SparkplugPayload;
  /** STATE's payload. */
  text?: string;
  retain: boolean;
}

export class SparkplugListener {
  readonly heard: HeardMessage[] = [];
  private readonly client: any;
  private readonly waiters = new Set<() => void>();
  private readonly subscribed: Promise<void>;

  /** `options`: further MQTT.js options (a TLS broker's ca, a user and password). */
  constructor(url: string, topic = 'spBv1.0/#', options: Record<string, unknown> = {}) {
    this.client = mqtt.connect(url, { reconnectPeriod: 200, connectTimeout: 5000, ...options });
    this.client.on('error', () => undefined);
    this.subscribed = new Promise((resolve) => this.client.on('connect', () => this.client.subscribe(topic, { qos: 1 }, () => resolve())));
    this.client.on('message', (t: string, bytes: Buffer, packet: { retain: boolean }) => {
      const parts = t.split('/');
      const msg: HeardMessage =
        parts[1] === 'STATE'
          ? { topic: t, type: 'STATE', text: bytes.toString('utf8'), retain: packet.retain }
          : { topic: t, type: parts[2]!, ...(parts[4] ? { device: parts[4] } : {}), payload: decodePayload(bytes), retain: packet.retain };
      this.heard.push(msg);
      this.waiters.forEach((w) => w());
    });
  }

  ready(): Promise<void> {
    return this.subscribed;
  }

  /** The first message from index `from` on that satisfies `match`, or a rejection after `ms`. */
  waitFor(match: (m: HeardMessage) => boolean, ms = 20_000, from = 0, what = 'a matching message'): Promise<HeardMessage> {
    return new Promise((resolve, reject) => {
      const check = () => {
        const hit = this.heard.slice(from).find(match);
        if (hit) {
          clearTimeout(timer);
          this.waiters.delete(check);
          resolve(hit);
        }
      };
      const timer = setTimeout(() => {
        this.waiters.delete(check);
        reject(new Error(`no ${what} within ${ms} ms; heard: ${this.heard.map((m) => m.topic).join(', ')}`));
      }, ms);
      this.waiters.add(check);
      check();
    });
  }

  /** Publishes a Sparkplug payload (a command) or text (STATE) as a host would. */
  async publish(topic: string, payload: SparkplugPayload | string, options: { qos?: 0 | 1; retain?: boolean } = {}): Promise<void> {
    const bytes = typeof payload === 'string' ? payload : encodePayload(payload);
    await this.client.publishAsync(topic, bytes, { qos: options.qos ?? 0, retain: options.retain ?? false });
  }

  close(): Promise<void> {
    return this.client.endAsync(true);
  }
}
