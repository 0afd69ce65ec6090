/**
 * A read node's push mode ("when the PLC reports a change"): the node's
 * table subscribed through the client's driver (its subscribe port in
 * lib/drivers.ts: an S7CommPlus client's client.subscribe()), each
 * notification turned into the table's per-tag outcomes, as a poll's are.
 * Subscribed when the link comes up and not yet subscribed (or on another
 * client: a new connection node); the client creates the subscription again
 * after a reconnect by itself. Nothing here is Node-RED's.
 */
import type { AnyClient } from '../connect';
import { driverOf } from '../drivers';
import type { PlcError } from '../errors';
import type { PlcClient, TagSubscription } from '../types';
import type { TagRow } from '../tags/table';
import { outcomes, type TagOutcome } from './outcome';

export { refusedForGood } from '../errors';

/** True when `client` can have its PLC report changes: its driver offers the subscribe port (s7plus://, s7:// on S7-300/400). */
export function canPush(client: PlcClient | undefined): client is PlcClient {
  return client !== undefined && driverOf(client).subscribe !== undefined;
}

export interface ReadPushEvents {
  /** The outcomes of a notification, one per row of the table. */
  outcomes(list: TagOutcome[]): void;
  /** Subscribed (again): the next outcomes carry every value. */
  active(): void;
  /** The subscription's link went (it is created again when it is back), or subscribing failed (tried again on the next link up). */
  failed(err: PlcError): void;
}

export class ReadPush {
  private readonly addresses: string[];
  private client: PlcClient | undefined;
  private sub: TagSubscription | undefined;
  private pending: Promise<unknown> | undefined;
  private closed = false;

  constructor(
    private readonly tags: readonly TagRow[],
    private readonly cycle: number,
    private readonly events: ReadPushEvents,
  ) {
    this.addresses = [...new Set(tags.map((t) => t.address))];
  }

  /** The link is up on `client`: subscribes unless it is subscribed on it already (or subscribing). */
  linkUp(client: PlcClient): void {
    if (this.closed || this.pending || this.addresses.length === 0) return;
    if (this.sub && this.client === client) return;
    const old = this.sub;
    this.sub = undefined;
    this.client = client;
    const pending = (old ? old.close() : Promise.resolve())
      .then(() => driverOf(client).subscribe!(client as AnyClient, this.addresses, { cycle: this.cycle }))
      .then(
        async (sub) => {
          if (this.closed) return sub.close();
          this.sub = sub;
          sub.on('data', (d) => this.events.outcomes(outcomes(this.tags, d.results)));
          sub.on('active', () => this.events.active());
          sub.on('lost', (err) => this.events.failed(err));
          sub.on('error', (err) => this.events.failed(err));
          this.events.active();
        },
        (err: PlcError) => {
          if (!this.closed) this.events.failed(err);
        },
      )
      .finally(() => {
        if (this.pending === pending) this.pending = undefined;
      });
    this.pending = pending;
  }

  /** Ends the subscription. Always resolves. */
  async close(): Promise<void> {
    this.closed = true;
    await this.pending?.catch(() => undefined);
    await this.sub?.close();
    this.sub = undefined;
  }
}
