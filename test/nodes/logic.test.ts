/** The nodes' pure helpers: tag tables, change detection with deadband, write requests, the life-sign watch. */
import { expect } from 'chai';
import * as path from 'node:path';
import { ROOT } from './support';

const tags = require(path.join(ROOT, 'nodes/shared/tags.js'));
const lifesign = require(path.join(ROOT, 'nodes/shared/lifesign.js'));

describe('nodes: tag tables', () => {
  it('defaults names to addresses and drops blank rows', () => {
    expect(tags.tagTable([{ name: ' a ', address: ' DB1,INT0 ' }, { name: '', address: 'M0.1' }, { name: 'x', address: '' }, null])).to.deep.equal([
      { name: 'a', address: 'DB1,INT0' },
      { name: 'M0.1', address: 'M0.1' },
    ]);
  });

  it('reads msg.tags as an address, an array or an object', () => {
    expect(tags.tagsOfMessage('MW2')).to.deep.equal([{ name: 'MW2', address: 'MW2' }]);
    expect(tags.tagsOfMessage(['MW2', { name: 'b', address: 'MW4' }])).to.deep.equal([{ name: 'MW2', address: 'MW2' }, { name: 'b', address: 'MW4' }]);
    expect(tags.tagsOfMessage({ c: 'MW6' })).to.deep.equal([{ name: 'c', address: 'MW6' }]);
    expect(tags.tagsOfMessage(undefined)).to.equal(undefined);
  });

  it('keeps table order in outcomes, with errors as plain data', () => {
    const err = Object.assign(new Error('boom'), { code: 'ACCESS_DENIED' });
    const list = tags.outcomes([{ name: 'b', address: 'B' }, { name: 'a', address: 'A' }], { A: { ok: true, value: 1 }, B: { ok: false, error: err } });
    expect(list).to.deep.equal([
      { name: 'b', address: 'B', ok: false, error: { code: 'ACCESS_DENIED', message: 'boom', address: 'B' } },
      { name: 'a', address: 'A', ok: true, value: 1 },
    ]);
  });
});

describe('nodes: change detection', () => {
  const good = (name: string, value: unknown) => ({ name, address: name, ok: true, value });

  it('reports the first read, then only moves beyond the deadband (measured from the last reported value)', () => {
    const f = new tags.ChangeFilter(0.5);
    expect(f.filter([good('t', 20)]).length).to.equal(1);
    expect(f.filter([good('t', 20.4)]).length).to.equal(0);
    expect(f.filter([good('t', 20.45)]).length).to.equal(0);
    expect(f.filter([good('t', 20.6)]).length).to.equal(1);
  });

  it('compares arrays, dates and bigints by value, and reports quality changes', () => {
    const f = new tags.ChangeFilter(0);
    f.filter([good('a', [1, 2]), good('d', new Date(5)), good('b', 10n)]);
    expect(f.filter([good('a', [1, 2]), good('d', new Date(5)), good('b', 10n)])).to.deep.equal([]);
    expect(f.filter([good('a', [1, 3]), good('d', new Date(6)), good('b', 11n)]).map((o: any) => o.name)).to.deep.equal(['a', 'd', 'b']);
    const bad = { name: 'b', address: 'b', ok: false, error: { code: 'TIMEOUT', message: 'x', address: 'b' } };
    expect(f.filter([bad]).length).to.equal(1);
    expect(f.filter([bad]).length).to.equal(0);
    expect(f.filter([good('b', 11n)]).length).to.equal(1);
  });
});

describe('nodes: write requests', () => {
  const table = [{ name: 'speed', address: 'DB1,INT0' }];

  it('maps names to addresses and keeps unknown keys as addresses', () => {
    expect(tags.writeRequest(table, { payload: { speed: 5, MW2: 7 } })).to.deep.equal({
      values: { 'DB1,INT0': 5, MW2: 7 },
      names: { 'DB1,INT0': 'speed', MW2: 'MW2' },
    });
  });

  it('takes msg.topic with a scalar or array payload', () => {
    expect(tags.writeRequest(table, { topic: 'speed', payload: 3 }).values).to.deep.equal({ 'DB1,INT0': 3 });
    expect(tags.writeRequest(table, { topic: 'DB1,INT0[2]', payload: [1, 2] }).values).to.deep.equal({ 'DB1,INT0[2]': [1, 2] });
  });

  it('refuses a payload without a target, an empty object, a missing value and a name and address of the same tag', () => {
    expect(() => tags.writeRequest(table, { payload: 5 })).to.throw(/msg.topic/).with.property('code', 'INVALID_VALUE');
    expect(() => tags.writeRequest(table, { payload: {} })).to.throw(/names no tag/);
    expect(() => tags.writeRequest(table, { payload: { speed: null } })).to.throw(/no value for "speed"/);
    expect(() => tags.writeRequest(table, { payload: { speed: 1, 'DB1,INT0': 2 } })).to.throw(/same address/);
  });
});

describe('nodes: life sign', () => {
  it('counts up and wraps at the maximum of the type; toggles booleans and numbers', () => {
    expect(lifesign.nextLifeSign('counter', 0, 'INT')).to.equal(1);
    expect(lifesign.nextLifeSign('counter', 32767, 'INT')).to.equal(0);
    expect(lifesign.nextLifeSign('counter', 255, 'BYTE')).to.equal(0);
    expect(lifesign.nextLifeSign('counter', 65534, 'WORD')).to.equal(65535);
    expect(lifesign.nextLifeSign('toggle', false, 'BOOL')).to.equal(true);
    expect(lifesign.nextLifeSign('toggle', 1, 'INT')).to.equal(0);
  });

  it('goes waiting → alive → lost (once) → restored on an injected clock', () => {
    let now = 1000;
    const w = new lifesign.LifeSignWatch({ timeout: 3000, now: () => now });
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
    const w = new lifesign.LifeSignWatch({ timeout: 100, now: () => now });
    w.observe(1);
    now = 101;
    expect(w.check()).to.equal('lost');
  });
});
