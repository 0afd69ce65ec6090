/**
 * Compiled with the tests (tsconfig includes test/**), never run: a
 * subscription's events are typed (S7PlusSubscriptionEvents). A line marked
 * @ts-expect-error must not compile; if it did, the build fails.
 */
import { connect } from '../../lib';
import type { PlcError } from '../../lib/errors';
import type { SubscriptionChange, SubscriptionData, SubscriptionState } from '../../lib/s7plus/client/subscription';

export async function typedSubscriptionEvents(): Promise<void> {
  const plc = await connect('s7plus://10.0.0.2?fingerprint=00');
  const sub = await plc.subscribe(['"Tank".Level'], { cycle: 100 });
  // Each event's listener gets its own argument's type.
  sub.on('change', (c: SubscriptionChange) => void c.tag);
  sub.on('data', (d: SubscriptionData) => void d.changed);
  sub.on('state', (s: SubscriptionState) => void s);
  sub.once('lost', (err: PlcError) => void err.code);
  sub.on('active', () => {});
  sub.on('closed', () => {});
  // @ts-expect-error -- a misspelt event does not compile.
  sub.on('chnage', () => {});
  // @ts-expect-error -- nor a listener of another event's argument.
  sub.on('change', (d: SubscriptionData) => void d.initial);
  // @ts-expect-error -- nor an event emitted with the wrong argument.
  sub.emit('state', 'flowing');
}
