/**
 * The demo raises alarms (issue #33): the tank's high level, set by the plant's program, comes as an ALARM_SQ on the
 * classic S7-300 (the level its associated value, acknowledged by the operator) and as a Program_Alarm on the
 * S7-1200 (texts in en-US and de-DE with the level in the placeholder). Real clients over real sockets.
 */
import { expect } from 'chai';
import type { AlarmEvent, AlarmSubscription } from '../lib/alarms/model';
import type { S7PlusClient } from '../lib';
import { createClient } from '../lib/connect';
import { DEMO_ALARM_IDS, DEMO_HIGH_LEVEL } from '../lib/plant/alarms';
import { startPlant, type Plant } from '../lib/plant/plant';
import { S7Client } from '../lib/s7/client';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { until } from './support/wait';

describe('demo plant alarms: the tank high level (issue #33)', function () {
  this.timeout(30_000);
  let plant: Plant;
  const closers: (() => Promise<unknown>)[] = [];

  beforeEach(async () => {
    plant = await startPlant({ ports: { s7: 0, fetch: 0, write: 0, freeport: 0 }, periodMs: 50 });
  });

  afterEach(async () => {
    for (const close of closers.splice(0).reverse()) await close().catch(() => undefined);
    await plant.close();
  });

  /** The level just below the limit: the program (filling) crosses it within a few cycles. */
  const nearHigh = () => plant.memory.area('DB', 1)!.writeFloatBE(DEMO_HIGH_LEVEL.above - 0.5, 0);
  /** Well below the clearing level: the program clears the flag in its next cycle. */
  const low = () => plant.memory.write('DB', 1, 0, Buffer.from([0x42, 0x48, 0, 0])); // 50.0

  it('the program sets M10.0 at 85 % and clears it below 80 % (hysteresis)', async () => {
    const flag = () => (plant.memory.area('M')![DEMO_HIGH_LEVEL.byte]! & 1) !== 0;
    nearHigh();
    await until(flag, 5000, 'the high-level flag set');
    expect(plant.process.snapshot().level).to.be.at.least(DEMO_HIGH_LEVEL.above);
    low();
    await until(() => !flag(), 5000, 'the high-level flag cleared');
  });

  it('classic S7-300: an ALARM_SQ with the level, listed, acknowledged, going', async () => {
    const client = new S7Client(parseUrl(`${plant.urls.s7classic}&timeout=5000`) as S7Endpoint);
    await client.connect();
    closers.push(() => client.close());
    const events: AlarmEvent[] = [];
    const sub: AlarmSubscription = await client.subscribeAlarms({}, (e) => events.push(e));
    closers.push(() => sub.close());
    nearHigh();
    await until(() => events.some((e) => e.type === 'alarm' && e.change === 'coming'), 10_000, 'the coming ALARM_SQ');
    const coming = events.find((e) => e.type === 'alarm' && e.change === 'coming');
    if (coming?.type !== 'alarm') throw new Error('no alarm event');
    expect(coming.alarm).to.include({ id: DEMO_ALARM_IDS.classic, kind: 'ALARM_SQ', needsAck: true, acknowledged: false });
    expect(coming.alarm.values[0]!.type).to.equal('REAL');
    expect(coming.alarm.values[0]!.value as number).to.be.within(DEMO_HIGH_LEVEL.above, DEMO_HIGH_LEVEL.above + 2);
    const listed = await client.alarms();
    expect(listed.map((a) => a.id)).to.deep.equal([DEMO_ALARM_IDS.classic]);
    await client.acknowledge(DEMO_ALARM_IDS.classic);
    await until(() => events.some((e) => e.type === 'alarm' && e.change === 'acknowledged'), 10_000, 'the acknowledged event');
    low();
    await until(() => events.some((e) => e.type === 'alarm' && e.change === 'going'), 10_000, 'the going ALARM_SQ');
  });

  it('S7-1200: a Program_Alarm with texts in en-US and de-DE, the level in the placeholder', async () => {
    const client = createClient(`${plant.urls.s7plus}&timeout=5000`) as S7PlusClient;
    await client.connect();
    closers.push(() => client.close());
    const events: AlarmEvent[] = [];
    const sub = await client.subscribeAlarms({ languages: ['en-US', 'de-DE'] }, (e) => events.push(e));
    closers.push(() => sub.close());
    nearHigh();
    await until(() => events.some((e) => e.type === 'alarm' && e.change === 'coming'), 10_000, 'the coming Program_Alarm');
    const coming = events.find((e) => e.type === 'alarm' && e.change === 'coming');
    if (coming?.type !== 'alarm') throw new Error('no alarm event');
    expect(coming.alarm).to.include({ id: DEMO_ALARM_IDS.program, kind: 'Program_Alarm', needsAck: true });
    const level = coming.alarm.values[0]!.value as number;
    expect(level).to.be.within(DEMO_HIGH_LEVEL.above, DEMO_HIGH_LEVEL.above + 2);
    expect(coming.alarm.texts?.['en-US']?.text).to.equal(`Tank level high: ${level.toFixed(1)} %`);
    expect(coming.alarm.texts?.['de-DE']?.text).to.equal(`Tankfüllstand hoch: ${level.toFixed(1)} %`);
    const active = await client.alarms({ languages: ['en-US'] });
    expect(active.map((a) => a.id)).to.deep.equal([DEMO_ALARM_IDS.program]);
    low();
    await until(() => events.some((e) => e.type === 'alarm' && e.change === 'going'), 10_000, 'the going Program_Alarm');
  });
});
