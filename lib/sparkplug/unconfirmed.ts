/**
 * Data messages the broker has not confirmed yet. DDATA goes with QoS 0
 * (tck-id-topics-ddata-mqtt), so the broker acknowledges nothing; when the
 * path to it dies without a close (a cable pulled, a broker's host lost),
 * MQTT.js writes on into the socket until its keepalive timeout (1.5 ×
 * keepalive) and what it wrote meanwhile never arrives. A PINGRESP proves the
 * broker has read everything sent before the PINGREQ it answers: one TCP
 * stream, read in order, and a PINGRESP is the answer to a PINGREQ (MQTT
 * 3.1.1, sections 3.12 and 3.13). So the edge node keeps what it sent since the
 * oldest PINGREQ not answered yet; when a session ends without its own
 * DISCONNECT, that goes back into store-and-forward and is sent again, as
 * historical data, after the next births: delivered at least once, never lost
 * (a host may see a value twice, with the same timestamp).
 */
import type { SparkplugMetric } from './model';

interface Sent {
  device: string;
  metrics: SparkplugMetric[];
}

export class UnconfirmedData {
  private sent: Sent[] = [];
  /** Messages counted since the start: `sent[0]` is message number `first`. */
  private first = 0;
  /** The message count at each PINGREQ not answered yet, oldest first. */
  private pings: number[] = [];
  private values = 0;

  /** `max`: most metric values kept (the store-and-forward bound); beyond it the oldest are forgotten. */
  constructor(private readonly max: number) {}

  /** Metric values kept now. */
  get count(): number {
    return this.values;
  }

  /** A data message was handed to the socket. */
  data(device: string, metrics: SparkplugMetric[]): void {
    this.sent.push({ device, metrics });
    this.values += metrics.length;
    while (this.values > this.max && this.sent.length > 0) this.forget(1);
  }

  /** A PINGREQ was handed to the socket. */
  pingSent(): void {
    this.pings.push(this.first + this.sent.length);
  }

  /** A PINGRESP came: everything sent before the oldest open PINGREQ reached the broker. */
  pingAnswered(): void {
    const upTo = this.pings.shift();
    if (upTo !== undefined && upTo > this.first) this.forget(Math.min(upTo - this.first, this.sent.length));
  }

  /** What was not confirmed, oldest first; forgets it and the open PINGREQs (a new session counts anew). */
  take(): Sent[] {
    const out = this.sent;
    this.first += out.length;
    this.sent = [];
    this.pings = [];
    this.values = 0;
    return out;
  }

  private forget(n: number): void {
    for (const s of this.sent.splice(0, n)) this.values -= s.metrics.length;
    this.first += n;
  }
}
