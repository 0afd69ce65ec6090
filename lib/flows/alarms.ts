/**
 * The alarms node's plain logic (nodes/alarms.js is its Node-RED wrapper):
 * subscribes to a client's alarms through its driver's alarms port each
 * time the link comes up while it holds no subscription (the subscription
 * itself is made again by the client after a reconnect), passes every event
 * on, keeps the active / unacknowledged counts, and acknowledges on request.
 * Errors are told once per outage (lib/flows/outage.ts): a CPU that refuses
 * alarms is one Catch message, not one per reconnect. No Node-RED here.
 */
import { ackRefusal } from '../alarms/ack-guard';
import type { AlarmEvent, AlarmPort, AlarmSubscribeOptions, AlarmSubscription, PlcAlarm } from '../alarms/model';
import { alarmCounts, parseAlarmId } from '../alarms/show';
import { PlcError } from '../errors';
import type { PlcClient } from '../types';
import { OutageReports } from './outage';

/** What the feed needs of a client: its link's state and events, and its URL's safety settings. */
export type FeedClient = Pick<PlcClient, 'state' | 'on' | 'off'> & {
  readonly endpoint: { readonly readOnly?: boolean; readonly allow?: readonly string[] };
};

/** What the feed tells its node. */
export interface FeedHandlers {
  /** An event, in the order the PLC sent it. */
  event(e: AlarmEvent): void;
  /** The counts changed (after the subscription came up, and after every alarm event). */
  counts(c: { active: number; unacknowledged: number }): void;
  /** An error of the alarm service; `first`: the first of its outage (for Catch), else for the status only. */
  error(err: PlcError, first: boolean): void;
}

/** What an input message asks the alarms node for. */
export type AlarmRequest = { ack: number; signal8?: number } | { list: true };

/**
 * The request of a message: `msg.ack` (or `msg.payload.ack`) an alarm id
 * to acknowledge (number, or text as `plcwire ack` takes it), or
 * `msg.topic === 'list'` for the active alarms. Anything else is
 * INVALID_VALUE, saying what the node takes.
 */
export function requestOf(msg: { ack?: unknown; topic?: unknown; payload?: unknown }): AlarmRequest {
  const payload = msg.payload as { ack?: unknown; signal?: unknown } | null | undefined;
  const asked = msg.ack ?? (payload && typeof payload === 'object' ? payload.ack : undefined);
  if (asked !== undefined && asked !== null) {
    const id =
      typeof asked === 'number' && Number.isInteger(asked) && asked >= 0
        ? asked
        : parseAlarmId(typeof asked === 'string' || typeof asked === 'number' ? String(asked) : JSON.stringify(asked));
    const signal = payload && typeof payload === 'object' ? payload.signal : undefined;
    return typeof signal === 'number' ? { ack: id, signal8: signal } : { ack: id };
  }
  if (msg.topic === 'list') return { list: true };
  throw new PlcError(
    'INVALID_VALUE',
    'the alarms node takes msg.ack = <alarm id> (acknowledge it) or msg.topic = "list" (the active alarms)',
  );
}

export class AlarmFeed<C extends FeedClient> {
  private sub: AlarmSubscription | undefined;
  private trying = false;
  private closed = false;
  private readonly outage: OutageReports;
  private readonly onConnected = () => {
    this.outage.state('connected');
    this.attempt();
  };
  private readonly onDisconnected = () => this.outage.state('disconnected');

  constructor(
    private readonly client: C,
    private readonly port: AlarmPort<C>,
    private readonly options: AlarmSubscribeOptions,
    private readonly handlers: FeedHandlers,
  ) {
    this.outage = new OutageReports(() => client.state === 'connected');
    client.on('connected', this.onConnected);
    client.on('disconnected', this.onDisconnected);
    if (client.state === 'connected') this.attempt();
  }

  /** The alarms active now as the subscription knows them (empty before it came up). */
  get active(): readonly PlcAlarm[] {
    return this.sub?.active ?? [];
  }

  /** Whether the subscription is up. */
  get subscribed(): boolean {
    return this.sub !== undefined;
  }

  /** The PLC's active alarms, asked now. */
  list(): Promise<PlcAlarm[]> {
    return this.port.list(this.client);
  }

  /** Acknowledges alarm `id`: refused by the URL's readOnly and allow-list before anything is sent. */
  async acknowledge(id: number, signal8?: number): Promise<void> {
    const refusal = ackRefusal(id, this.client.endpoint.readOnly, this.client.endpoint.allow);
    if (refusal) throw refusal;
    await this.port.acknowledge(this.client, id, signal8 === undefined ? {} : { signal8 });
  }

  private report(err: unknown): void {
    const e = err instanceof PlcError ? err : new PlcError('PROTOCOL_ERROR', String((err as Error)?.message ?? err), { cause: err });
    this.handlers.error(e, this.outage.first());
  }

  private attempt(): void {
    if (this.sub || this.trying || this.closed) return;
    this.trying = true;
    this.port
      .subscribe(this.client, this.options, (e) => {
        this.handlers.event(e);
        if (e.type === 'alarm') this.handlers.counts(alarmCounts(this.active));
      })
      .then(async (sub) => {
        if (this.closed) return void (await sub.close().catch(() => undefined));
        this.sub = sub;
        sub.on('lost', (err: PlcError) => this.report(err));
        sub.on('error', (err: PlcError) => this.report(err));
        sub.on('active', () => this.handlers.counts(alarmCounts(sub.active)));
        this.handlers.counts(alarmCounts(sub.active));
      })
      .catch((err: unknown) => this.report(err))
      .finally(() => (this.trying = false));
  }

  /** Ends the subscription and stops listening to the client; always resolves. */
  async close(): Promise<void> {
    this.closed = true;
    this.client.off('connected', this.onConnected);
    this.client.off('disconnected', this.onDisconnected);
    this.outage.close();
    const sub = this.sub;
    this.sub = undefined;
    await sub?.close().catch(() => undefined);
  }
}
