/**
 * What the two kinds of pushed data share (push.ts: tag subscriptions,
 * alarms.ts: the alarm subscription): a session of their own, opened the way
 * the client opens its own and kept by its own supervisor, on which nothing
 * is written; and the credit rule that keeps the PLC sending. Facts:
 * s7commplus (MIT) client.py create_subscription (credit_limit=10),
 * subscription.py SubscriptionRegistry.route (credit_step=5, ticks modulo
 * 255), connection.py send_subscription_credit.
 */
import type { EventEmitter } from 'node:events';
import type { PlcError } from '../../errors';
import type { BackoffOptions } from '../../link/backoff';
import { LinkSupervisor } from '../../link/supervisor';
import { ProtocolVersion } from '../constants';
import { creditTell } from './asks';
import type { S7PlusSession } from './session';

/** Credits granted at creation: what real S7-1500 CPUs accepted. */
export const CREDIT_LIMIT = 10;
/** Credits added each time; renewed once this few remain, so a round trip never leaves the PLC without. */
const CREDIT_STEP = 5;
/** The credit tick counts modulo 255. */
const TICKS = 255;
/** The DeleteObject at the end waits this long at most. */
export const GOODBYE_MS = 2000;

/** What the client gives a session of pushed data. */
export interface PushedSessionWiring {
  name: string;
  timeout: number;
  backoff?: BackoffOptions;
  random?: () => number;
  /** Opens a session the way the client opens its own, with these hooks for loss and notifications. */
  open(
    signal: AbortSignal,
    hooks: { lost(session: S7PlusSession, err: PlcError): void; notify(data: Buffer): void },
  ): Promise<S7PlusSession>;
}

/** The supervisor of a pushed-data session (`what`: "subscriptions", "alarms"), its notifications to `route`, its events on `events`. */
export function pushedSessionSupervisor(
  wiring: PushedSessionWiring,
  what: string,
  events: EventEmitter,
  route: (data: Buffer) => void,
): LinkSupervisor<S7PlusSession> {
  const supervisor: LinkSupervisor<S7PlusSession> = new LinkSupervisor<S7PlusSession>({
    name: `${wiring.name} (${what})`,
    connectTimeout: wiring.timeout,
    open: (signal) => wiring.open(signal, { lost: (session, err) => supervisor.lost(session, err), notify: route }),
    events,
    ...(wiring.backoff ? { backoff: wiring.backoff } : {}),
    ...(wiring.random ? { random: wiring.random } : {}),
  });
  return supervisor;
}

/** Whether a notification at `creditTick` leaves so few of `credit` that more must be granted now. */
export function creditRunningOut(credit: number, creditTick: number): boolean {
  return (credit - creditTick + TICKS) % TICKS <= CREDIT_STEP;
}

/** Grants the subscription `id` more credits on `session` (a tell: only a lost link fails it); the new limit. */
export function grantCredit(session: S7PlusSession, id: number, credit: number): number {
  const next = (credit + CREDIT_STEP) % TICKS || CREDIT_STEP;
  session.tell(creditTell({ subscriptionId: id, creditLimit: next, v1: session.version === ProtocolVersion.V1 })).catch(() => {});
  return next;
}
