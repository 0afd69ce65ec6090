/** The control node's plain logic, without Node-RED: actions, plain results, the diagnostics cursor. */
import { expect } from 'chai';
import { ACTIONS, actionOf, configuredAction, DiagnosticsCursor, isoOrNull, plainEntry, plainState } from '../lib/flows/control';
import type { DiagnosticEntry } from '../lib/s7/codec/diagnostics';

const entry = (ms: number, eventId: number, info1 = 0): DiagnosticEntry => ({
  time: new Date(ms),
  eventId,
  description: `event ${eventId}`,
  priority: 1,
  ob: 1,
  dataId: 0,
  info1,
  info2: 0,
  info3: 0,
});

describe('flows: control', () => {
  it('a configured action outside the list falls back to info', () => {
    expect(configuredAction('blocks')).to.equal('blocks');
    expect(configuredAction('reboot')).to.equal('info');
    expect(configuredAction(undefined)).to.equal('info');
    expect(ACTIONS).to.include.members(['stop', 'start', 'clock-sync']);
  });

  it('msg.action that is no string is an INVALID_VALUE error naming it; a topic that is no action is ignored', () => {
    expect(() => actionOf({ action: 3 }, 'info'))
      .to.throw(/"3" is not one of info, state/)
      .with.property('code', 'INVALID_VALUE');
    expect(actionOf({ action: null, topic: { a: 1 } }, 'clock')).to.equal('clock');
  });

  it('dates become ISO strings; a time stamp that is no date becomes null', () => {
    expect(isoOrNull(new Date(Date.UTC(2024, 0, 2, 3, 4, 5, 6)))).to.equal('2024-01-02T03:04:05.006Z');
    expect(isoOrNull(new Date(NaN))).to.equal(null);
    expect(isoOrNull('2024-01-02')).to.equal(null);
    const e = plainEntry(entry(0, 0x4302));
    expect(e).to.deep.equal({ ...entry(0, 0x4302), time: '1970-01-01T00:00:00.000Z' });
  });

  it('a CPU state as the node sends it: state in lower case, the mode as read', () => {
    const s = plainState({ mode: 'STOP', modeCode: 4, previousCode: 8, eventId: 0x4357, time: new Date(NaN) });
    expect(s).to.deep.equal({ state: 'stop', mode: 'STOP', modeCode: 4, previousCode: 8, eventId: 0x4357, time: null });
  });

  it('two entries that differ only in an info field are two entries', () => {
    const cursor = new DiagnosticsCursor();
    cursor.take([entry(1000, 5, 1)]);
    expect(cursor.take([entry(1000, 5, 2), entry(1000, 5, 1)]).map((e) => e.info1)).to.deep.equal([2]);
  });

  it('an empty buffer keeps what was reported last', () => {
    const cursor = new DiagnosticsCursor();
    cursor.take([entry(1000, 1)]);
    expect(cursor.take([])).to.deep.equal([]);
    expect(cursor.take([entry(1000, 1)])).to.deep.equal([]);
  });
});
