/**
 * A stand-in of the AlarmPort interface (lib/alarms/model.ts) for the tests of
 * what sits on top of a driver's port (the CLI, the alarms node's feed): the
 * test pushes events and sets the active list; the drivers' own ports are
 * tested against their simulators.
 */
import { EventEmitter } from 'node:events';
import type { AlarmEvent, AlarmPort, AlarmSubscribeOptions, AlarmSubscription, PlcAlarm } from '../../lib/alarms/model';
import type { PlcError } from '../../lib/errors';

/** Shaped as an AlarmSubscription (its `on`/`off` are EventEmitter's, cast where handed out). */
class StandInSubscription extends EventEmitter {
  active: PlcAlarm[] = [];
  closed = false;
  constructor(readonly push: (e: AlarmEvent) => void) {
    super();
  }
  close(): Promise<void> {
    this.closed = true;
    return Promise.resolve();
  }
}

export class StandInPort<C = unknown> implements AlarmPort<C> {
  subs: StandInSubscription[] = [];
  refuse: PlcError | undefined;
  acks: number[] = [];
  attempts = 0;
  options: AlarmSubscribeOptions[] = [];
  /** The active list `list()` answers. */
  active: PlcAlarm[] = [];
  list(): Promise<PlcAlarm[]> {
    return Promise.resolve(this.active);
  }
  subscribe(_client: C, options: AlarmSubscribeOptions, listener: (e: AlarmEvent) => void): Promise<AlarmSubscription> {
    this.attempts++;
    this.options.push(options);
    if (this.refuse) return Promise.reject(this.refuse);
    const sub = new StandInSubscription(listener);
    this.subs.push(sub);
    return Promise.resolve(sub as unknown as AlarmSubscription);
  }
  acknowledge(_client: C, id: number): Promise<void> {
    this.acks.push(id);
    return Promise.resolve();
  }
}
