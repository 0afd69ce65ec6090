/**
 * One Catch message per outage (lib/flows/outage.ts, issue #26): the first error of an outage is reported, the ones
 * after it are not, until the link has stayed connected for the stable time; a link that flaps is one outage. The
 * stable time runs on a clock the test holds.
 */
import { expect } from 'chai';
import { OutageReports, type StableTimer } from '../lib/flows/outage';

/** A stable timer the test fires by hand; `running` is the timers started and not cancelled. */
function handTimer() {
  const running = new Set<{ fire: () => void; ms: number }>();
  const timer: StableTimer = {
    start(fire, ms) {
      const t = { fire, ms };
      running.add(t);
      return () => running.delete(t);
    },
  };
  const fireAll = () => {
    const due = [...running];
    running.clear();
    for (const t of due) t.fire();
  };
  return { timer, running, fireAll };
}

describe('flows: one report per outage', () => {
  it('reports the first error only, and again after the link stayed connected for the stable time', () => {
    let connected = false;
    const clock = handTimer();
    const outage = new OutageReports(() => connected, 5000, clock.timer);
    expect(outage.first()).to.equal(true);
    expect(outage.first()).to.equal(false);
    outage.state('reconnecting');
    expect(outage.first()).to.equal(false);
    connected = true;
    outage.state('connected');
    expect([...clock.running].map((t) => t.ms)).to.deep.equal([5000]);
    outage.state('connected');
    expect(clock.running.size, 'one timer per stretch of connection').to.equal(1);
    clock.fireAll();
    expect(outage.first()).to.equal(true);
    expect(outage.first()).to.equal(false);
  });

  it('a link that comes up and drops within the stable time stays one outage', () => {
    let connected = false;
    const clock = handTimer();
    const outage = new OutageReports(() => connected, 5000, clock.timer);
    expect(outage.first()).to.equal(true);
    for (let i = 0; i < 5; i++) {
      connected = true;
      outage.state('connected');
      connected = false;
      outage.state('reconnecting');
    }
    expect(clock.running.size, 'each short connection stopped its timer').to.equal(0);
    expect(outage.first()).to.equal(false);
  });

  it('a stable timer that fires while the link is down again does not end the outage; close() stops the timer', () => {
    let connected = true;
    const clock = handTimer();
    const outage = new OutageReports(() => connected, 5000, clock.timer);
    expect(outage.first()).to.equal(true);
    outage.state('connected');
    connected = false; // down, but not yet told
    clock.fireAll();
    expect(outage.first()).to.equal(false);
    connected = true;
    outage.state('connected');
    outage.close();
    expect(clock.running.size).to.equal(0);
  });

  it('without an error there is no outage to end: connecting starts no timer', () => {
    const clock = handTimer();
    const outage = new OutageReports(() => true, 5000, clock.timer);
    outage.state('connected');
    expect(clock.running.size).to.equal(0);
    expect(outage.first()).to.equal(true);
  });
});
