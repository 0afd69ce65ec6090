/**
 * A client's events typed by event maps (issue #31): EventEmitter's listener
 * methods narrowed to the maps' events and arguments, so that
 * `client.on('conected', …)` or a listener of another event's argument does
 * not compile. The emitter at run time is Node's own.
 *
 * Every client has the events of one map (ClientEvents, lib/types.ts) and a
 * driver's client may add its own (`Own`) as a second overload. The first
 * overload is the same in every client, so a union of clients (AnyClient)
 * can still call `on('connected', …)`: TypeScript calls a union's method
 * through the signatures all its members share.
 */
import { EventEmitter } from 'node:events';

/** Event name → the listener's arguments. */
export type EventMap<E> = { [K in keyof E]: unknown[] };

/** No events of its own. */
export type NoEvents = Record<never, never>;

type Listener<A> = (...args: A extends unknown[] ? A : never) => void;

/** The listener methods of an emitter of the events `E` and, for a driver's client, its `Own` ones. */
export interface TypedEvents<E extends EventMap<E>, Own extends EventMap<Own> = NoEvents> {
  on<K extends keyof E>(event: K, listener: Listener<E[K]>): void;
  on<K extends keyof Own>(event: K, listener: Listener<Own[K]>): void;
  once<K extends keyof E>(event: K, listener: Listener<E[K]>): void;
  once<K extends keyof Own>(event: K, listener: Listener<Own[K]>): void;
  off<K extends keyof E>(event: K, listener: Listener<E[K]>): void;
  off<K extends keyof Own>(event: K, listener: Listener<Own[K]>): void;
  removeListener<K extends keyof E>(event: K, listener: Listener<E[K]>): void;
  removeListener<K extends keyof Own>(event: K, listener: Listener<Own[K]>): void;
  removeAllListeners(event?: keyof E | keyof Own): void;
  listenerCount(event: keyof E | keyof Own): number;
}

/** The methods TypedEvents types; the rest of EventEmitter (emit, setMaxListeners, …) stays as Node types it. */
type Narrowed =
  | 'on'
  | 'once'
  | 'off'
  | 'removeListener'
  | 'removeAllListeners'
  | 'listenerCount'
  | 'addListener'
  | 'prependListener'
  | 'prependOnceListener';

/**
 * EventEmitter as a base class whose listener methods a subclass declares
 * (by merging TypedEvents into its interface): at run time Node's EventEmitter.
 */
export const EventEmitterBase = EventEmitter as unknown as new () => Omit<EventEmitter, Narrowed>;
