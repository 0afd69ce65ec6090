/**
 * Alarms as the CLI, the alarms node and the dashboard show them
 * (lib/alarms/show.ts): ids as users type them, texts by language, one line
 * per alarm and per event, plain data for messages and JSON.
 */
import { expect } from 'chai';
import type { AlarmEvent, PlcAlarm } from '../lib/alarms/model';
import { alarmCounts, alarmLine, alarmText, eventLine, eventTopic, parseAlarmId, plainEvent } from '../lib/alarms/show';
import { PlcError } from '../lib/errors';

const CAME = new Date('2026-12-03T10:00:00.000Z');

const tankHigh = (over: Partial<PlcAlarm> = {}): PlcAlarm => ({
  id: 1001,
  kind: 'ALARM_S',
  state: 'coming',
  needsAck: true,
  acknowledged: false,
  coming: CAME,
  values: [{ type: 'REAL', value: 95.5 }],
  texts: { 'en-US': { text: 'Tank high level: 95.5 %' }, 'de-DE': { text: 'Tank Füllstand hoch: 95,5 %' } },
  ...over,
});

describe('alarms: as people and flows see them', () => {
  it('parses ids in decimal, 16#hex and 0x hex, and refuses anything else naming it', () => {
    expect(parseAlarmId('1001')).to.equal(1001);
    expect(parseAlarmId('16#3E9')).to.equal(1001);
    expect(parseAlarmId('0x3e9')).to.equal(1001);
    expect(parseAlarmId(' 4294967295 ')).to.equal(0xffffffff);
    for (const bad of ['', '12x', '-1', '4294967296', '16#', '1.5', '0x1FFFFFFFF']) {
      expect(() => parseAlarmId(bad), bad)
        .to.throw(PlcError, `alarm id "${bad}" is not a number`)
        .with.property('code', 'INVALID_VALUE');
    }
  });

  it('takes the text in the language asked for, by its language part too, else the first the PLC sent', () => {
    expect(alarmText(tankHigh(), 'de-DE')).to.equal('Tank Füllstand hoch: 95,5 %');
    expect(alarmText(tankHigh(), 'DE')).to.equal('Tank Füllstand hoch: 95,5 %');
    expect(alarmText(tankHigh(), 'fr-FR')).to.equal('Tank high level: 95.5 %');
    expect(alarmText(tankHigh())).to.equal('Tank high level: 95.5 %');
    expect(alarmText(tankHigh({ texts: undefined }))).to.equal(undefined);
  });

  it('shows an alarm on one line: id, source, state, acknowledgement, priority, time, text and values', () => {
    expect(alarmLine(tankHigh({ priority: 3 }))).to.equal(
      '1001 ALARM_S coming unacknowledged priority 3 came 2026-12-03T10:00:00.000Z "Tank high level: 95.5 %" (REAL 95.5)',
    );
    const going = tankHigh({
      kind: 'ALARM_8',
      signal: 3,
      state: 'going',
      acknowledged: true,
      going: new Date('2026-12-03T10:05:00.000Z'),
      texts: undefined,
      values: [{ type: 'STRING', value: 'low' }],
    });
    expect(alarmLine(going)).to.equal(
      '1001 ALARM_8 signal 3 going acknowledged came 2026-12-03T10:00:00.000Z went 2026-12-03T10:05:00.000Z (STRING "low")',
    );
    expect(alarmLine(tankHigh({ needsAck: false, values: [], texts: undefined, coming: undefined }))).to.equal(
      '1001 ALARM_S coming no acknowledgement needed',
    );
  });

  it('shows events with their time first, the outage ones marked', () => {
    const at = new Date('2026-12-03T10:00:01.000Z');
    const coming: AlarmEvent = { type: 'alarm', change: 'coming', alarm: tankHigh({ texts: undefined, values: [] }), at };
    expect(eventLine(coming)).to.equal('2026-12-03T10:00:01.000Z coming 1001 ALARM_S coming unacknowledged came 2026-12-03T10:00:00.000Z');
    const missed: AlarmEvent = { ...coming, during: 'outage' };
    expect(eventLine(missed)).to.match(/^2026-12-03T10:00:01.000Z coming \(while the link was down\) 1001 /);
    expect(eventLine({ type: 'mode', from: 'STOP', to: 'RUN', at })).to.equal('2026-12-03T10:00:01.000Z mode STOP -> RUN');
    expect(eventLine({ type: 'diagnostic', id: 0x4302, text: 'Mode transition', state: 'coming', at, raw: '' })).to.equal(
      '2026-12-03T10:00:01.000Z diagnostic 16#4302 coming Mode transition',
    );
  });

  it('gives messages plain data: ISO strings, no Date, that survive a JSON round trip unchanged', () => {
    const e: AlarmEvent = { type: 'alarm', change: 'coming', alarm: tankHigh(), at: CAME };
    const plain = plainEvent(e);
    expect(plain).to.deep.equal(JSON.parse(JSON.stringify(plain)));
    expect(plain).to.deep.include({ type: 'alarm', change: 'coming', at: '2026-12-03T10:00:00.000Z' });
    expect((plain as { alarm: { coming: string } }).alarm.coming).to.equal('2026-12-03T10:00:00.000Z');
    expect(eventTopic(plain)).to.equal('alarm/1001/coming');
    expect(eventTopic({ type: 'diagnostic', id: 17154, text: '', at: CAME, raw: '' })).to.equal('diagnostic/17154');
  });

  it('counts the active alarms and those that wait for an operator', () => {
    const list = [tankHigh(), tankHigh({ id: 2, acknowledged: true }), tankHigh({ id: 3, needsAck: false })];
    expect(alarmCounts(list)).to.deep.equal({ active: 3, unacknowledged: 1 });
    expect(alarmCounts([])).to.deep.equal({ active: 0, unacknowledged: 0 });
  });
});
