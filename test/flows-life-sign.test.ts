/** The life-sign exchange with a PLC program: counters, toggles, and the watch on an injected clock. */
import { expect } from 'chai';
import { LifeSignWatch, nextLifeSign } from '../lib';

describe('flows: life sign', () => {
  it('counts up and wraps at the maximum of the type; toggles booleans and numbers', () => {
    expect(nextLifeSign('counter', 0, 'INT')).to.equal(1);
    expect(nextLifeSign('counter', 32767, 'INT')).to.equal(0);
    expect(nextLifeSign('counter', 255, 'BYTE')).to.equal(0);
    expect(nextLifeSign('counter', 65534, 'WORD')).to.equal(65535);
    expect(nextLifeSign('toggle', false, 'BOOL')).to.equal(true);
    expect(nextLifeSign('toggle', 1, 'INT')).to.equal(0);
  });

  it('goes waiting → alive → lost (once) → restored on an injected clock', () => {
    let now = 1000;
    const w = new LifeSignWatch({ timeout: 3000, now: () => now });
    expect(w.observe(5)).to.equal(undefined); // first sight is no proof of life
    now += 500;
    expect(w.observe(6)).to.equal('alive');
    expect(w.observe(7)).to.equal(undefined);
    now += 3000;
    expect(w.check()).to.equal(undefined);
    now += 1;
    expect(w.check()).to.equal('lost');
    expect(w.check()).to.equal(undefined);
    expect(w.observe(7)).to.equal(undefined);
    now += 100;
    expect(w.observe(8)).to.equal('restored');
    expect(w.report('restored')).to.deep.equal({ event: 'restored', state: 'alive', changes: 3, losses: 1, age: 0, value: 8 });
  });

  it('is lost when nothing ever changes', () => {
    let now = 0;
    const w = new LifeSignWatch({ timeout: 100, now: () => now });
    w.observe(1);
    now = 101;
    expect(w.check()).to.equal('lost');
  });
});
