/**
 * Compiled with the tests (tsconfig includes test/**), never run: a client's
 * events are typed (ClientEvents, and a driver's own: S7ClientEvents,
 * S7PlusClientEvents). A line marked @ts-expect-error must not compile; if it
 * did, the build fails.
 */
import { connect, createClient, type AnyClient } from '../../lib';
import type { ItemLimitEvent } from '../../lib/s7/client/client';
import type { PlcError } from '../../lib/errors';
import type { ProgramChange } from '../../lib/s7plus/client/program';
import type { LayoutOkEvent, LinkState, ReconnectingEvent } from '../../lib/types';

export async function typedClientEvents(): Promise<void> {
  const s7 = createClient('s7://192.168.0.1');
  const s7plus = createClient('s7plus://10.0.0.2?fingerprint=00');
  const fw = createClient('fetchwrite://10.0.0.5');
  const serial = createClient('freeport+tcp://10.0.0.7:4001');

  // Every client's events, each listener with its own argument's type.
  for (const client of [s7, s7plus, fw, serial] as const) {
    client.on('state', (s: LinkState) => void s);
    client.once('disconnected', (err: PlcError) => void err.code);
    client.on('reconnecting', (e: ReconnectingEvent) => void e.delay);
    client.on('layoutOk', (e: LayoutOkEvent) => void e.checks);
    client.off('connected', () => {});
  }
  // A driver's own events.
  s7.on('itemLimit', (e: ItemLimitEvent) => void e.limit);
  s7plus.on('itemLimit', (e) => void e.was);
  s7plus.on('programChanged', (c: ProgramChange) => void c);
  s7plus.on('insecure', (e) => void e.certificate);

  // @ts-expect-error -- a misspelt event does not compile: S7Client,
  s7.on('conected', () => {});
  // @ts-expect-error -- S7PlusClient,
  s7plus.on('conected', () => {});
  // @ts-expect-error -- FetchWriteClient,
  fw.on('conected', () => {});
  // @ts-expect-error -- FreeportClient,
  serial.once('conected', () => {});
  // @ts-expect-error -- nor a listener of another event's argument,
  s7.on('state', (e: ItemLimitEvent) => void e.limit);
  // @ts-expect-error -- nor another driver's event (FETCH/WRITE has no item limit),
  fw.on('itemLimit', () => {});
  // @ts-expect-error -- nor one the S7 client does not emit.
  s7.on('programChanged', () => {});

  // Any client (the CLI's view): every client's events, still checked.
  const any: AnyClient = await connect(process.argv[2] ?? 's7://h');
  any.on('connected', () => {});
  any.on('disconnected', (err: PlcError) => void err.message);
  any.off('connected', () => {});
  // @ts-expect-error -- a misspelt event does not compile on any client either.
  any.on('conected', () => {});
  // @ts-expect-error -- nor one a single driver adds.
  any.on('itemLimit', () => {});
}
