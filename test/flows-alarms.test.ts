/**
 * The alarms node's logic (lib/flows/alarms.ts) on a real S7 client over a
 * real socket to the simulator, its link going down and up: it subscribes
 * when the link is up, passes events on in order with the counts, tells a
 * refused subscription once per outage, and refuses an acknowledgement the
 * URL forbids before the port is asked. The port here is a stand-in of the
 * AlarmPort interface (the drivers' ports have their own tests), so what is
 * tested is the feed, not a protocol.
 */
import { expect } from 'chai';
import type { AlarmEvent, PlcAlarm } from '../lib/alarms/model';
import { createClient } from '../lib/connect';
import { PlcError } from '../lib/errors';
import { AlarmFeed, requestOf } from '../lib/flows/alarms';
import { S7Server } from '../lib/s7/server';
import { PlcMemory } from '../lib/sim/memory';
import type { S7Client } from '../lib/s7/client';
import { StandInPort } from './support/alarm-port';
import { until, waitFor } from './support/wait';

const alarm = (id: number, over: Partial<PlcAlarm> = {}): PlcAlarm => ({
  id,
  kind: 'ALARM_S',
  state: 'coming',
  needsAck: true,
  acknowledged: false,
  values: [],
  ...over,
});

describe('flows: the alarms feed', function () {
  this.timeout(20000);
  let server: S7Server;
  let port: number;
  const memory = new PlcMemory();
  const closers: (() => Promise<unknown>)[] = [];

  beforeEach(async () => {
    server = new S7Server({ port: 0, memory, profile: 's7-300' });
    port = await server.listen();
  });

  afterEach(async () => {
    for (const close of closers.splice(0).reverse()) await close();
    await server.close();
  });

  function client(extra = '') {
    const c = createClient(`s7://127.0.0.1:${port}?rack=0&slot=2&timeout=1000${extra}`) as S7Client;
    c.on('error', () => {});
    closers.push(() => c.close());
    return c;
  }

  function recorder() {
    const events: AlarmEvent[] = [];
    const counts: { active: number; unacknowledged: number }[] = [];
    const errors: { err: PlcError; first: boolean }[] = [];
    return {
      events,
      counts,
      errors,
      handlers: {
        event: (e: AlarmEvent) => events.push(e),
        counts: (c: any) => counts.push(c),
        error: (err: PlcError, first: boolean) => errors.push({ err, first }),
      },
    };
  }

  it('subscribes once the link is up, passes events on in order, and counts after each', async () => {
    const c = client();
    const stand = new StandInPort();
    const r = recorder();
    const feed = new AlarmFeed(c, stand, { mode: true }, r.handlers);
    closers.push(() => feed.close());
    expect(stand.attempts, 'nothing before the link is up').to.equal(0);
    c.start();
    await until(() => feed.subscribed, 5000, 'subscribed');
    expect(stand.options[0]).to.deep.include({ mode: true });
    expect(r.counts.at(-1)).to.deep.equal({ active: 0, unacknowledged: 0 });
    const sub = stand.subs[0]!;
    const at = new Date();
    sub.active = [alarm(1001)];
    sub.push({ type: 'alarm', change: 'coming', alarm: alarm(1001), at });
    sub.push({ type: 'mode', from: 'RUN', to: 'STOP', at });
    sub.active = [alarm(1001, { acknowledged: true })];
    sub.push({ type: 'alarm', change: 'acknowledged', alarm: alarm(1001, { acknowledged: true }), at });
    expect(r.events.map((e) => (e.type === 'alarm' ? e.change : e.type))).to.deep.equal(['coming', 'mode', 'acknowledged']);
    expect(r.counts.slice(1)).to.deep.equal([
      { active: 1, unacknowledged: 1 },
      { active: 1, unacknowledged: 0 },
    ]);
    expect(feed.active).to.have.length(1);
  });

  it('tells a refused subscription once per outage, and tries again on the next connection', async () => {
    const c = client();
    const stand = new StandInPort();
    stand.refuse = new PlcError('NOT_SUPPORTED', 'this CPU serves no alarms');
    const r = recorder();
    const feed = new AlarmFeed(c, stand, {}, r.handlers);
    closers.push(() => feed.close());
    c.start();
    await until(() => r.errors.length === 1, 5000, 'the first refusal');
    expect(r.errors[0]).to.deep.include({ first: true });
    expect(r.errors[0]!.err.code).to.equal('NOT_SUPPORTED');
    // The PLC goes away and comes back: the feed tries again, and the same outage is not told twice.
    const lost = waitFor(c, 'disconnected', 5000);
    await server.close();
    await lost;
    server = new S7Server({ port, memory, profile: 's7-300' });
    await server.listen();
    await until(() => stand.attempts === 2 && r.errors.length === 2, 10000, 'the second attempt');
    expect(r.errors[1]).to.deep.include({ first: false });
    expect(feed.subscribed).to.equal(false);
    // Now the PLC serves alarms: the next connection subscribes.
    stand.refuse = undefined;
    const again = waitFor(c, 'disconnected', 5000);
    await server.close();
    await again;
    server = new S7Server({ port, memory, profile: 's7-300' });
    await server.listen();
    await until(() => feed.subscribed, 10000, 'subscribed after the CPU serves alarms');
  });

  it('refuses an acknowledgement the URL forbids before the port is asked; allows what the allow-list names', async () => {
    const stand = new StandInPort();
    const readOnly = new AlarmFeed(client('&readOnly=true'), stand, {}, recorder().handlers);
    closers.push(() => readOnly.close());
    const err = await readOnly.acknowledge(1001).then(
      () => undefined,
      (e: unknown) => e,
    );
    expect(err).to.be.instanceOf(PlcError).with.property('code', 'WRITE_NOT_ALLOWED');
    expect((err as Error).message).to.contain('read-only');
    const listed = new AlarmFeed(client('&allow=ALARM1001,DB1'), stand, {}, recorder().handlers);
    closers.push(() => listed.close());
    await listed.acknowledge(1001);
    const other = await listed.acknowledge(1002).then(
      () => undefined,
      (e: unknown) => e,
    );
    expect(other).to.be.instanceOf(PlcError).with.property('code', 'WRITE_NOT_ALLOWED');
    expect(stand.acks).to.deep.equal([1001]);
  });

  it('closes its subscription and leaves no listener on the client', async () => {
    const c = client();
    const before = c.listenerCount('connected') + c.listenerCount('disconnected');
    const stand = new StandInPort();
    const feed = new AlarmFeed(c, stand, {}, recorder().handlers);
    c.start();
    await until(() => feed.subscribed, 5000, 'subscribed');
    await feed.close();
    expect(stand.subs[0]!.closed).to.equal(true);
    expect(c.listenerCount('connected') + c.listenerCount('disconnected')).to.equal(before);
    expect(feed.subscribed).to.equal(false);
  });

  it('reads what a message asks for: msg.ack, msg.payload.ack with its signal, topic "list"', () => {
    expect(requestOf({ ack: 1001 })).to.deep.equal({ ack: 1001 });
    expect(requestOf({ ack: '16#3E9' })).to.deep.equal({ ack: 1001 });
    expect(requestOf({ payload: { ack: 7, signal: 3 } })).to.deep.equal({ ack: 7, signal8: 3 });
    expect(requestOf({ topic: 'list' })).to.deep.equal({ list: true });
    expect(() => requestOf({ payload: 'hello' }))
      .to.throw(PlcError, 'msg.ack = <alarm id>')
      .with.property('code', 'INVALID_VALUE');
    expect(() => requestOf({ ack: 'twelve' })).to.throw(PlcError, 'alarm id "twelve"');
  });
});
