/**
 * A device fed by its PLC's own pushes where the driver has a subscribe port
 * (lib/drivers.ts; S7CommPlus today): the PLC reports its tags' changes, so
 * the edge node's poll of that device stands down while the subscription is
 * active. Without the port, while the subscription is not active, or once
 * the PLC refused it for good (refusedForGood), the device is polled.
 */
import { driverOf } from '../drivers';
import { refusedForGood, toPlcError, type PlcError } from '../errors';
import type { PlcValue, SubscriptionNotice, TagSubscription } from '../types';
import type { TagResult } from '../errors';
import type { SparkplugDevice } from './device';

export class DevicePush {
  private subscription: TagSubscription | undefined;
  private opening = false;
  private closed = false;
  /** The PLC refused the subscription for what it is (an S7-1200/1500 asked for cyclic data over s7://): polled for good. */
  private refused = false;
  /** True while the PLC pushes this device's values (the poll skips it). */
  active = false;

  constructor(
    private readonly device: SparkplugDevice,
    private readonly cycle: number,
    private readonly onData: () => void,
    private readonly onError: (error: PlcError) => void,
  ) {}

  /** Whether the device's driver can push at all (and its PLC has not refused it). */
  get available(): boolean {
    return !this.refused && driverOf(this.device.client).subscribe !== undefined;
  }

  /** Subscribes once the client is connected (again, after a failed attempt); a no-op without the port or once open. */
  async open(): Promise<void> {
    const subscribe = driverOf(this.device.client).subscribe;
    if (!subscribe || this.refused || this.subscription || this.opening || this.closed || this.device.client.state !== 'connected') return;
    this.opening = true;
    try {
      const sub = await subscribe(
        this.device.client as never,
        this.device.metrics.map((m) => m.address),
        { cycle: this.cycle },
      );
      if (this.closed) return void (await sub.close());
      this.subscription = sub;
      this.active = true;
      sub.on('data', (d: SubscriptionNotice) => {
        this.active = true;
        this.device.take(d.results as Record<string, TagResult<PlcValue>>);
        this.onData();
      });
      sub.on('active', () => (this.active = true));
      sub.on('lost', () => (this.active = false));
      sub.on('error', (err) => this.onError(err));
    } catch (err) {
      const e = toPlcError(err);
      // A CPU without the service is polled, as a driver without the port is: not an error of the device.
      if (refusedForGood(e)) this.refused = true;
      else this.onError(e);
    } finally {
      this.opening = false;
    }
  }

  async close(): Promise<void> {
    this.closed = true;
    this.active = false;
    const sub = this.subscription;
    this.subscription = undefined;
    await sub?.close().catch(() => undefined);
  }
}
