/**
 * The session that carries a client's subscriptions: a second S7CommPlus
 * connection, opened the way the client opens its own (same URL, trust and
 * password), kept by its own supervisor (reconnect with backoff), on which
 * nothing is ever written: public reports say a write on a session that
 * carries a subscription resets it (docs/s7commplus.md, "Subscriptions").
 *
 * On each new session every subscription is created again (CreateObject of a
 * Subscription object in the session's container); notifications are routed
 * by subscription id and change counter; credits are renewed before they run
 * out, so notifications never stop; the last subscription's close deletes
 * the container and ends the session. Facts: s7commplus (MIT), client.py
 * (create_subscription, delete_subscription, resubscribe), subscription.py
 * (SubscriptionRegistry.route: the credit rule), connection.py
 * (send_subscription_credit).
 */
import { EventEmitter } from 'node:events';
import { ConnectionError, PlcError, toPlcError } from '../../errors';
import type { LinkSupervisor } from '../../link/supervisor';
import type { SymbolTable } from '../../symbols/model';
import type { Tag } from '../../types';
import { type Notification, decodeNotification, subscriptionObject } from '../codec/subscription';
import { ProtocolVersion } from '../constants';
import { subscriptionCreateAsk, subscriptionDeleteAsk } from './asks';
import { isNamed } from './names';
import {
  CREDIT_LIMIT,
  GOODBYE_MS,
  creditRunningOut,
  grantCredit,
  pushedSessionSupervisor,
  type PushedSessionWiring,
} from './pushed-session';
import type { S7PlusSession } from './session';
import { S7PlusSubscription, type Plan, type SubscribeOptions, type SubscriptionChange } from './subscription';

/** s7commplus names its first subscription object's relation 0x7FFFC001 and counts up (client.py). */
const FIRST_RELATION_ID = 0x7fffc001;
/** Notifications of an unknown subscription id kept for when its CreateObject answer has been read. */
const MAX_ORPHANS = 16;
/** What the client gives its push link. */
export interface PushWiring extends PushedSessionWiring {
  /** The PLC's names as a table, browsed on `session` (reads only). */
  browse(session: S7PlusSession): Promise<SymbolTable>;
  parse(address: string): Tag;
}

/** A subscription created on the live session. */
interface Live {
  sub: S7PlusSubscription;
  id: number;
  changeCounter: number;
  /** The credit limit last granted. */
  credit: number;
}

export class PushLink extends EventEmitter {
  private readonly supervisor: LinkSupervisor<S7PlusSession>;
  private readonly subs = new Set<S7PlusSubscription>();
  private readonly live = new Map<number, Live>();
  /** Subscriptions waiting for their first creation, with their subscribe() promise. */
  private readonly first = new Map<S7PlusSubscription, { resolve(): void; reject(err: PlcError): void }>();
  /** Notifications of ids not (yet) known, the newest few. */
  private orphans: Notification[] = [];
  private table: { session: S7PlusSession; table: Promise<SymbolTable> } | undefined;
  /** One creation or deletion at a time on the session. */
  private work: Promise<unknown> = Promise.resolve();
  private changeCounter = 1;
  private relationId = FIRST_RELATION_ID;
  private closed = false;
  private ending: Promise<void> = Promise.resolve();

  constructor(private readonly wiring: PushWiring) {
    super();
    this.supervisor = pushedSessionSupervisor(wiring, 'subscriptions', this, (data) => this.route(data));
    this.on('connected', () => this.createAll());
    this.on('disconnected', (err: PlcError) => this.sessionGone(err));
    this.on('reconnecting', ({ error }: { error: PlcError }) => this.failFirst(error));
  }

  /** The state of the subscriptions' own link. */
  get state(): string {
    return this.supervisor.state;
  }

  /** True once it closed (the client's close(), or its last subscription's): a new subscription needs a new link. */
  get done(): boolean {
    return this.closed;
  }

  /** A new subscription: resolves once the PLC created it; rejects (and forgets it) when it cannot be. */
  subscribe(
    tags: readonly string[],
    options: SubscribeOptions,
    listener?: (change: SubscriptionChange) => void,
  ): Promise<S7PlusSubscription> {
    if (this.closed) return Promise.reject(new ConnectionError('CLOSED', `${this.wiring.name}: the client was closed`));
    let sub: S7PlusSubscription;
    try {
      sub = new S7PlusSubscription({ name: this.wiring.name, parse: this.wiring.parse, remove: (s) => this.remove(s) }, tags, options);
    } catch (err) {
      return Promise.reject(err);
    }
    if (listener) sub.on('change', listener);
    const created = new Promise<void>((resolve, reject) => this.first.set(sub, { resolve, reject }));
    this.subs.add(sub);
    const session = this.supervisor.session;
    if (session?.alive) void this.queue(() => this.create(sub, session));
    else this.supervisor.start();
    return created.then(
      () => {
        // After the caller's continuation (a microtask) has added its listeners.
        setImmediate(() => sub.release());
        return sub;
      },
      (err: PlcError) => {
        this.subs.delete(sub);
        return this.idle().then(() => Promise.reject(err));
      },
    );
  }

  /** Ends every subscription and the session. Always resolves. */
  async close(): Promise<void> {
    if (this.closed) return this.ending;
    this.closed = true;
    const subs = [...this.subs];
    this.subs.clear();
    this.failFirst(new ConnectionError('CLOSED', `${this.wiring.name}: the client was closed`));
    for (const s of subs) void s.close();
    this.ending = this.goodbye();
    return this.ending;
  }

  private queue<R>(fn: () => Promise<R>): Promise<R> {
    const next = this.work.then(fn, fn);
    this.work = next.catch(() => {});
    return next;
  }

  private createAll(): void {
    const session = this.supervisor.session;
    if (!session) return;
    for (const sub of this.subs) void this.queue(() => this.create(sub, session));
  }

  /** Creates `sub` on `session`: its items planned on the session's table, CreateObject, registered for routing. */
  private async create(sub: S7PlusSubscription, session: S7PlusSession): Promise<void> {
    if (!this.subs.has(sub) || !session.alive || session !== this.supervisor.session) return;
    try {
      // A PLC that named no container when the session was created has nowhere to create one (s7commplus client.py create_subscription).
      if (session.subscriptionContainerId === 0)
        throw new PlcError('NOT_SUPPORTED', `${this.wiring.name} offers no subscription container: it cannot report changes; poll instead`);
      const needsTable = sub.tags.some((t) => isNamed(this.wiring.parse(t)));
      const plan = sub.planWith(needsTable ? await this.tableOf(session) : undefined);
      const { id, changeCounter } = await this.createObject(session, sub, plan);
      if (!this.subs.has(sub) || session !== this.supervisor.session) return;
      const live: Live = { sub, id, changeCounter, credit: CREDIT_LIMIT };
      this.live.set(id, live);
      sub.activated(plan);
      const early = this.orphans.filter((n) => n.subscriptionId === id);
      this.orphans = this.orphans.filter((n) => n.subscriptionId !== id);
      for (const n of early) this.deliver(live, n);
      this.settleFirst(sub);
    } catch (err) {
      const e = toPlcError(err, 'PROTOCOL_ERROR');
      // A link error: the supervisor reconnects and creates it again.
      if (!session.alive) return;
      if (!this.settleFirst(sub, e)) sub.failed(e);
    }
  }

  private async createObject(session: S7PlusSession, sub: S7PlusSubscription, plan: Plan): Promise<{ id: number; changeCounter: number }> {
    const changeCounter = this.changeCounter;
    const relationId = this.relationId;
    this.changeCounter = (this.changeCounter % 0xff) + 1;
    this.relationId = (this.relationId + 1) >>> 0;
    const object = subscriptionObject({ relationId, cycleMs: sub.cycle, creditLimit: CREDIT_LIMIT, changeCounter, items: plan.items });
    const body = await session.request(subscriptionCreateAsk(session.subscriptionContainerId, object));
    const id = body.objectIds[0];
    if (body.returnValue !== 0n || id === undefined) {
      throw new PlcError(
        'PLC_ERROR',
        `${this.wiring.name} refused the subscription of ${sub.tags.join(', ')} (0x${body.returnValue.toString(16)})`,
        {
          tag: sub.tags[0],
          plcCode: Number(body.returnValue & 0xffffn),
        },
      );
    }
    return { id, changeCounter };
  }

  private tableOf(session: S7PlusSession): Promise<SymbolTable> {
    if (this.table?.session !== session) {
      const table = this.wiring.browse(session);
      const kept = { session, table };
      this.table = kept;
      table.catch(() => {
        if (this.table === kept) this.table = undefined;
      });
    }
    return this.table!.table;
  }

  /** A notification: to its subscription (an unknown id or an old change counter is dropped), then credits if they run low. */
  private route(data: Buffer): void {
    let n: Notification;
    try {
      n = decodeNotification(data);
    } catch (err) {
      const session = this.supervisor.session;
      if (session) this.supervisor.lost(session, toPlcError(err, 'PROTOCOL_ERROR'));
      return;
    }
    const live = this.live.get(n.subscriptionId);
    if (!live) {
      // The first notification can come in the same read as the CreateObject answer, before the id is known here.
      if (this.orphans.push(n) > MAX_ORPHANS) this.orphans.shift();
      return;
    }
    this.deliver(live, n);
  }

  private deliver(live: Live, n: Notification): void {
    if (live.changeCounter !== n.changeCounter) return;
    try {
      live.sub.notified(n);
    } catch (err) {
      // A listener's own error is the application's, not the PLC's: it must not drop the link as a protocol error.
      process.nextTick(() => {
        throw err;
      });
    }
    if (creditRunningOut(live.credit, n.creditTick)) this.grant(live);
  }

  private grant(live: Live): void {
    const session = this.supervisor.session;
    if (!session?.alive) return;
    live.credit = grantCredit(session, live.id, live.credit);
  }

  private sessionGone(err: PlcError): void {
    this.live.clear();
    this.orphans = [];
    this.table = undefined;
    for (const sub of this.subs) sub.lost(err);
  }

  private settleFirst(sub: S7PlusSubscription, err?: PlcError): boolean {
    const waiter = this.first.get(sub);
    if (!waiter) return false;
    this.first.delete(sub);
    if (err) waiter.reject(err);
    else waiter.resolve();
    return true;
  }

  /** The link failed before some subscriptions were ever created: their subscribe() rejects with why. */
  private failFirst(err: PlcError): void {
    for (const sub of [...this.first.keys()]) this.settleFirst(sub, err);
  }

  /** A subscription's close: the others go on; the last one ends the session. */
  private remove(sub: S7PlusSubscription): Promise<void> {
    if (!this.subs.delete(sub)) return Promise.resolve();
    this.settleFirst(sub, new PlcError('CLOSED', `${this.wiring.name}: the subscription was closed`));
    for (const [id, live] of this.live) if (live.sub === sub) this.live.delete(id);
    if (this.subs.size === 0) return this.idle();
    // The PLC deletes a session's subscriptions together (its container: client.py delete_subscription); the others are created again.
    const session = this.supervisor.session;
    if (!session?.alive) return Promise.resolve();
    return this.queue(async () => {
      await this.deleteContainer(session);
      this.live.clear();
      for (const other of this.subs) await this.create(other, session);
    }).catch(() => {
      // A link that went meanwhile: the others are created again on the next session.
    });
  }

  /** No subscription left: the session ends, the link stops (a later subscribe() starts it again). */
  private idle(): Promise<void> {
    if (this.subs.size > 0 || this.closed) return Promise.resolve();
    this.ending = this.goodbye();
    return this.ending;
  }

  private async goodbye(): Promise<void> {
    await this.work;
    // A subscribe() while the last one was going keeps the link.
    if (this.subs.size > 0 && !this.closed) return;
    // From here on the client opens a new link for a new subscription.
    this.closed = true;
    const session = this.supervisor.session;
    if (session?.alive) {
      await this.deleteContainer(session).catch(() => {});
      await session.goodbye(Math.min(this.wiring.timeout, GOODBYE_MS));
    }
    await this.supervisor.close();
    this.live.clear();
    this.table = undefined;
  }

  private async deleteContainer(session: S7PlusSession): Promise<void> {
    const ac = new AbortController();
    const timer = setTimeout(() => ac.abort(), Math.min(this.wiring.timeout, GOODBYE_MS));
    try {
      await session.request(subscriptionDeleteAsk(session.subscriptionContainerId, session.version === ProtocolVersion.V1), {
        signal: ac.signal,
      });
    } finally {
      clearTimeout(timer);
    }
  }
}
