/**
 * A minimal Sparkplug host for the edge-node tests: an MQTT.js client that
 * subscribes to `spBv1.0/#`, decodes every message with the library's codec,
 * and keeps them in order with their MQTT QoS and retain flags, so tests
 * assert on what a broker really delivered. `next(match, ms)` waits (with a
 * deadline) for the next message after the ones already taken.
 */
import * as mqtt from 'mqtt';
import { decodePayload } from '../../lib/sparkplug/payload';
import type { SparkplugPayload } from '../../lib/sparkplug/model';
import { parseTopic, stateTopic, type ParsedTopic } from '../../lib/sparkplug/topics';

export interface Received {
  topic: string;
  parsed: ParsedTopic;
  qos: number;
  retain: boolean;
  payload: SparkplugPayload | undefined;
  raw: Buffer;
}

export class TestHost {
  readonly messages: Received[] = [];
  private taken = 0;
  private waiters: (() => void)[] = [];
  client!: mqtt.MqttClient;

  constructor(
    private readonly url: string,
    private readonly filter = 'spBv1.0/#',
  ) {}

  async connect(): Promise<void> {
    this.client = await mqtt.connectAsync(this.url, {
      clientId: `test-host-${process.pid}-${Math.random().toString(16).slice(2)}`,
      reconnectPeriod: 0,
      clean: true,
    });
    this.client.on('message', (topic, raw, packet) => {
      const parsed = parseTopic(topic);
      if (!parsed) return;
      this.messages.push({
        topic,
        parsed,
        qos: packet.qos,
        retain: packet.retain,
        payload: parsed.type === 'STATE' ? undefined : decodePayload(raw),
        raw,
      });
      for (const w of this.waiters.splice(0)) w();
    });
    await this.client.subscribeAsync(this.filter, { qos: 1 });
  }

  /** The next message (after those already taken) that `match` accepts; rejects after `ms`. Skipped ones are taken too. */
  async next(match: (m: Received) => boolean, ms = 5000, what = 'a matching message'): Promise<Received> {
    const deadline = Date.now() + ms;
    for (;;) {
      while (this.taken < this.messages.length) {
        const m = this.messages[this.taken++]!;
        if (match(m)) return m;
      }
      const left = deadline - Date.now();
      if (left <= 0) throw new Error(`no ${what} within ${ms} ms; got: ${this.messages.map((m) => m.topic).join(', ') || 'nothing'}`);
      await new Promise<void>((resolve) => {
        const timer = setTimeout(resolve, left);
        this.waiters.push(() => {
          clearTimeout(timer);
          resolve();
        });
      });
    }
  }

  /** The next message of a type ('NBIRTH', 'DDATA', …), optionally of a device. */
  nextOf(type: string, device?: string, ms = 5000): Promise<Received> {
    return this.next(
      (m) => m.parsed.type === type && (device === undefined || m.parsed.device === device),
      ms,
      `${type}${device ? ` of ${device}` : ''}`,
    );
  }

  /** Publishes the primary host's STATE, retained, QoS 1 (Sparkplug 3.0, section 4.2.1). */
  async state(host: string, online: boolean, timestamp = Date.now()): Promise<void> {
    await this.client.publishAsync(stateTopic(host), JSON.stringify({ online, timestamp }), { qos: 1, retain: true });
  }

  async close(): Promise<void> {
    for (const w of this.waiters.splice(0)) w();
    await this.client?.endAsync().catch(() => undefined);
  }
}
