/**
 * A burst of classic alarms (issue #33): 1,000 alarms coming within a second reach a subscriber complete and in the
 * order the CPU raised them, and a link loss in the middle of a burst loses none of them (the active list read again
 * after the reconnect reports what came meanwhile, `during: 'outage'`).
 */
import { expect } from 'chai';
import type { AlarmDefinition, AlarmEvent } from '../lib/alarms/model';
import { S7Client } from '../lib/s7/client';
import { S7Server } from '../lib/s7/server';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { until, waitFor } from './support/wait';

const N = 1000;
const DEFINITIONS: AlarmDefinition[] = Array.from({ length: N }, (_, i) => ({
  id: 0x10000 + i,
  kind: 'ALARM_S' as const,
  texts: { 'en-US': `Alarm ${i}` },
  needsAck: false,
  trigger: `DB1.DBX${i >> 3}.${i & 7}`,
  values: ['MW0:INT'],
}));

describe('S7 classic alarms: a burst of 1,000 (issue #33)', function () {
  this.timeout(60000);
  const open: { close(): Promise<void> }[] = [];

  afterEach(async () => {
    for (const x of open.splice(0).reverse()) await x.close();
  });

  async function start() {
    const server = new S7Server({ port: 0, profile: 's7-400', alarms: DEFINITIONS, layout: { dbs: { 1: N / 8 } } });
    await server.listen();
    open.push(server);
    const client = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?slot=2&timeout=5000`) as S7Endpoint);
    open.push(client);
    await client.connect();
    const events: AlarmEvent[] = [];
    const sub = await client.subscribeAlarms({}, (e) => events.push(e));
    open.push(sub);
    return { server, client, events, sub };
  }

  const ids = (events: readonly AlarmEvent[]) => events.map((e) => (e.type === 'alarm' ? e.alarm.id - 0x10000 : -1));

  it('1,000 alarms raised within a second reach the subscriber complete and in order', async () => {
    const { server, events, sub } = await start();
    const t0 = process.hrtime.bigint();
    for (let i = 0; i < N; i++) server.memory.writeBit('DB', 1, i >> 3, i & 7, true);
    const raisedMs = Number(process.hrtime.bigint() - t0) / 1e6;
    await until(() => events.length === N, 10000, `${N} events`);
    const receivedMs = Number(process.hrtime.bigint() - t0) / 1e6;
    console.log(`      ${N} alarms raised in ${raisedMs.toFixed(0)} ms, all received after ${receivedMs.toFixed(0)} ms`);
    expect(raisedMs).to.be.lessThan(1000);
    expect(ids(events)).to.deep.equal(Array.from({ length: N }, (_, i) => i));
    expect(events.every((e) => e.type === 'alarm' && e.change === 'coming')).to.equal(true);
    expect(sub.active).to.have.length(N);
  });

  it('a link loss in the middle of a burst loses nothing: what came while the link was down is reported after the reconnect', async () => {
    const { server, events, sub } = await start();
    for (let i = 0; i < N / 2; i++) server.memory.writeBit('DB', 1, i >> 3, i & 7, true);
    const lost = waitFor(sub as never, 'lost', 5000);
    server.faults.dropConnections();
    for (let i = N / 2; i < N; i++) server.memory.writeBit('DB', 1, i >> 3, i & 7, true);
    await lost;
    await waitFor(sub as never, 'active', 20000);
    // Every alarm came once: live before the loss, or reported as came during the outage.
    const seen = new Set(ids(events));
    expect(seen.size).to.equal(N);
    const outage = events.filter((e) => e.type === 'alarm' && 'during' in e);
    expect(outage.length).to.be.greaterThanOrEqual(N / 2);
    expect(sub.active).to.have.length(N);
  });
});
