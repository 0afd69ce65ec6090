/**
 * A read node's push mode ("when the PLC reports a change"): the node's
 * table subscribed on an S7CommPlus client (client.subscribe()), each
 * notification turned into the table's per-tag outcomes, as a poll's are.
 * Subscribed when the link comes up and not yet subscribed (or on another
 * client: a new connection node); the client creates the subscription again
 * after a reconnect by itself. Nothing here is Node-RED's.
 */
import type { PlcError } from '../errors';
import type { TagRow } from '../tags/table';
import { outcomes, type TagOutcome } from './outcome';

/** What the push mode needs of a client: subscribe(), as the S7CommPlus client has it. */
interface PushClient {
  subscribe(tags: readonly string[], options?: { cycle?: number }): Promise<PushSubscription>;
}

interface PushSubscription {
  on(event: 'data', listener: (d: { results: Record<string, never> }) => void): unknown;
  on(event: 'lost' | 'error', listener: (err: PlcError) => void): unknown;
  on(event: 'active', listener: () => void): unknown;
  close(): Promise<void>;
}

/** True when `client` can have its PLC report changes (an s7plus:// client). */
export function canPush(client: unknown): client is PushClient {
  return typeof (client as Partial<PushClient> | undefined)?.subscribe === 'function';
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
  private client: PushClient | undefined;
  private sub: PushSubscription | undefined;
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
  linkUp(client: PushClient): void {
    if (this.closed || this.pending || this.addresses.length === 0) return;
    if (this.sub && this.client === client) return;
    const old = this.sub;
    this.sub = undefined;
    this.client = client;
    const pending = (old ? old.close() : Promise.resolve())
      .then(() => client.subscribe(this.addresses, { cycle: this.cycle }))
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
