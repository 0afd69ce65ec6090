/**
 * `plcwire watch` on an s7plus:// URL (or s7:// to an S7-300/400: its cyclic data): the PLC reports changes
 * (client.subscribe()), so a change shows within the subscription's cycle
 * whatever `--interval` says. Tags that cannot be subscribed (a name the PLC
 * does not have, an item the PLC does not report) are polled every
 * `--interval` ms instead, and stderr says which and why.
 */
import type { AnyClient } from '../connect';
import { driverOf } from '../drivers';
import { TagErrors, type PlcError, type TagResult } from '../errors';
import type { SubscriptionNotice, TagSubscription } from '../types';

/** How `client` has its PLC report changes: its driver's subscribe port (lib/drivers.ts), bound to it; undefined without one. */
export function subscriberOf(client: AnyClient): Subscriber | undefined {
  const subscribe = driverOf(client).subscribe;
  return subscribe && ((tags, options) => subscribe(client, tags, options));
}

/** Subscribes tags on one client. */
type Subscriber = (tags: readonly string[], options: { cycle: number }) => Promise<TagSubscription>;

export interface PushWatch {
  /** Ends the subscription. Always resolves. */
  stop(): Promise<void>;
}

export interface PushWatchOptions {
  /** The PLC's sampling cycle, ms (`--cycle`). */
  cycle: number;
  /** The poll interval of the tags that fall back to polling, for the message. */
  interval: number;
  /** A line for stderr. */
  report(line: string): void;
  /** Results to print (the watch prints the changed ones). */
  print(results: Record<string, TagResult<unknown>>): void;
  /** These tags are polled from now on. */
  poll(tags: readonly string[]): void;
}

/**
 * Subscribes `addresses` once the client is connected (again on a later
 * connection while it has not succeeded); the subscription itself is created
 * again by the client after a reconnect.
 */
export function watchPushed(client: AnyClient, subscribe: Subscriber, addresses: readonly string[], o: PushWatchOptions): PushWatch {
  let sub: TagSubscription | undefined;
  let trying = false;
  let stopped = false;
  const polled = new Set<string>();
  const fallBack = (tags: readonly string[], why: (tag: string) => string) => {
    const fresh = tags.filter((t) => !polled.has(t));
    if (fresh.length === 0) return;
    fresh.forEach((t) => polled.add(t));
    for (const t of fresh) o.report(`${t} cannot be subscribed (${why(t)}): polled every ${o.interval} ms instead`);
    o.poll([...polled]);
  };
  const onData = (d: SubscriptionNotice) => {
    const shown: Record<string, TagResult<unknown>> = {};
    const refused: string[] = [];
    for (const t of d.changed) {
      const r = d.results[t]!;
      if (!r.ok && r.error.code === 'NOT_SUPPORTED') refused.push(t);
      else shown[t] = r;
    }
    if (refused.length > 0) fallBack(refused, (t) => (d.results[t] as { error: PlcError }).error.message);
    o.print(shown);
  };
  const trySubscribe = async (tags: readonly string[]): Promise<void> => {
    try {
      const s = await subscribe(tags, { cycle: o.cycle });
      if (stopped) return void (await s.close());
      sub = s;
      s.on('data', onData);
      s.on('lost', (err: PlcError) => o.report(`subscription lost: ${err.message}`));
      s.on('active', () => o.report(`subscribed again to ${tags.length} tag(s)`));
      s.on('error', (err: PlcError) => o.report(`subscription: ${err.message}`));
      // The cycle the PLC was asked for: an S7-300/400's is rounded to its time base (lib/s7/client/cyclic.ts).
      const cycle = (s as { cycle?: number }).cycle ?? o.cycle;
      o.report(`subscribed to ${tags.length} tag(s): the PLC reports changes every ${cycle} ms`);
    } catch (err) {
      if (!(err instanceof TagErrors)) throw err;
      const failed = Object.keys(err.errors);
      fallBack(failed, (t) => err.errors[t]!.message);
      const rest = tags.filter((t) => !failed.includes(t));
      if (rest.length > 0) await trySubscribe(rest);
    }
  };
  const attempt = () => {
    if (sub || trying || stopped) return;
    trying = true;
    trySubscribe(addresses)
      .catch((err: Error) => o.report(`subscribing failed: ${err.message} (tried again on the next connection)`))
      .finally(() => (trying = false));
  };
  client.on('connected', attempt);
  if (client.state === 'connected') attempt();
  return {
    async stop() {
      stopped = true;
      client.off('connected', attempt);
      await sub?.close();
    },
  };
}
