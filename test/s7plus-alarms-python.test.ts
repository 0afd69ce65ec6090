/**
 * s7commplus 0.3.0 (PyPI, MIT), a peer nobody here wrote, against our
 * S7-1500 simulator's Program_Alarms (issue #33): its read_alarms() (the
 * active-alarm Explore) and its alarm subscription with the notifications
 * of an alarm coming and going, texts included, the associated values in
 * their placeholders as its own decoder fills them. The package's server
 * emulator serves no alarms (server.py _handle_explore answers an Explore of
 * the alarm subsystem with its data-block list, no alarm object), so our
 * client is not run against it.
 */
import { expect } from 'chai';
import type { AlarmDefinition } from '../lib/alarms/model';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { openS7CommPlusClient, requireS7CommPlus, stopS7CommPlusPeers, type S7CommPlusPeerClient } from './support/s7commplus-peer';
import { startPlusSimulator, type PlusSimulator } from './support/s7plus-sim';

interface PeerAlarm {
  id: number;
  state: string;
  name: string;
  sequenceCounter: number;
  timestamp: number | null;
  values: string[];
  texts: Record<string, { alarm: string; info: string; additional: string[] }>;
}

const EN = 1033;
const DE = 1031;
const TANK: AlarmDefinition = {
  id: 7,
  kind: 'Program_Alarm',
  texts: { 'en-US': 'Tank level @1%5.1f@ m, count @2%d@, @3%s@', 'de-DE': 'Tankpegel @1%.1f@ m' },
  needsAck: true,
  priority: 5,
  trigger: '"Tank".Alarm',
  values: ['"Tank".Level', '"Tank".Count', '"Tank".Name'],
};
/** 300 more: their list (about 75 kB) takes more than one frame of 65535 bytes. */
const MANY: AlarmDefinition[] = Array.from({ length: 300 }, (_, i) => ({
  id: 2000 + i,
  kind: 'Program_Alarm',
  texts: { 'en-US': `Valve ${i} open too long` },
  needsAck: false,
  trigger: `M${300 + (i >> 3)}.${i & 7}`,
}));

describe('s7commplus 0.3.0 against our S7-1500 simulator: Program_Alarms', function () {
  this.timeout(60000);
  let python: string;
  let sim: PlusSimulator;
  let peer: S7CommPlusPeerClient | undefined;

  before(async function () {
    python = requireS7CommPlus(this);
    sim = await startPlusSimulator({ sources: SOURCES, db: DB_NUMBERS, alarms: [TANK, ...MANY] });
  });
  beforeEach(async () => {
    peer = openS7CommPlusClient(python);
    await peer.ok({ op: 'connect', port: sim.server.port, tls: true, fingerprint: sim.service.fingerprint! });
  });
  afterEach(async () => {
    await peer?.close();
    peer = undefined;
    sim.server.memory.writeBit('DB', 1, 6, 1, false);
    for (let b = 300; b < 338; b++) sim.server.memory.write('M', 0, b, Buffer.of(0));
  });
  after(async () => {
    await stopS7CommPlusPeers();
    await sim?.server.close();
  });

  it('read_alarms: none, then the Tank alarm with its values and both languages, its placeholders filled by the package', async () => {
    expect(await peer!.ok({ op: 'read_alarms' })).to.deep.equal([]);
    sim.server.memory.writeBit('DB', 1, 6, 1, true);
    const [alarm, ...rest] = (await peer!.ok({ op: 'read_alarms' })) as PeerAlarm[];
    expect(rest).to.deep.equal([]);
    expect(alarm).to.deep.include({ id: 7, state: 'coming', name: 'Program_Alarm_7' });
    // SD_1 REAL 12.5, SD_2 INT 7, SD_3 STRING[10] 'abc' (element 0: the type information).
    expect(alarm!.values.slice(0, 4)).to.deep.equal(['00000000', '41480000', '0007', '0a03616263']);
    expect(alarm!.texts[String(EN)]!.alarm).to.equal('Tank level  12.5 m, count 7, abc');
    expect(alarm!.texts[String(DE)]!.alarm).to.equal('Tankpegel 12.5 m');
    // A time stamp in nanoseconds since 1970, within a minute of now.
    expect(Math.abs(Number(alarm!.timestamp) / 1e6 - Date.now())).to.be.below(60_000);
  });

  it('read_alarms of 301 active alarms: an answer of several frames, every alarm in it', async () => {
    sim.server.memory.writeBit('DB', 1, 6, 1, true);
    for (let b = 300; b < 338; b++) sim.server.memory.write('M', 0, b, Buffer.of(0xff));
    const alarms = (await peer!.ok({ op: 'read_alarms', languages: [EN] })) as PeerAlarm[];
    expect(alarms.map((a) => a.id)).to.deep.equal([7, ...MANY.map((d) => d.id)]);
    expect(alarms.at(-1)!.texts[String(EN)]!.alarm).to.equal('Valve 299 open too long');
  });

  it('its alarm subscription: a notification as the alarm comes and one as it goes, texts in the language asked only', async () => {
    const id = (await peer!.ok({ op: 'alarm_subscribe', languages: [EN] })) as number;
    expect(id).to.be.a('number').above(0);
    sim.server.memory.writeBit('DB', 1, 6, 1, true);
    const coming = (await peer!.ok({ op: 'alarm_notification', languages: [EN], timeoutMs: 10000 })) as {
      subscription: number;
      alarms: PeerAlarm[];
    };
    expect(coming.subscription).to.equal(id);
    expect(coming.alarms.map((a) => [a.id, a.state])).to.deep.equal([[7, 'coming']]);
    expect(Object.keys(coming.alarms[0]!.texts)).to.deep.equal([String(EN)]);
    expect(coming.alarms[0]!.texts[String(EN)]!.alarm).to.equal('Tank level  12.5 m, count 7, abc');
    sim.server.memory.writeBit('DB', 1, 6, 1, false);
    const going = (await peer!.ok({ op: 'alarm_notification', languages: [EN], timeoutMs: 10000 })) as { alarms: PeerAlarm[] };
    expect(going.alarms.map((a) => [a.id, a.state, a.sequenceCounter])).to.deep.equal([
      [7, 'going', coming.alarms[0]!.sequenceCounter + 1],
    ]);
  });
});
