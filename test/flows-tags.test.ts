/** What flows do with tags: tag tables, outcomes, change detection with deadband, write requests, failure messages. */
import { expect } from 'chai';
import { ChangeFilter, errorInfo, outcomes, PlcError, tagFailure, tagsOfMessage, tagTable, writeRequest } from '../lib';

describe('flows: tag tables', () => {
  it('defaults names to addresses and drops blank rows', () => {
    expect(
      tagTable([{ name: ' a ', address: ' DB1,INT0 ' }, { name: '', address: 'M0.1' }, { name: 'x', address: '' }, null]),
    ).to.deep.equal([
      { name: 'a', address: 'DB1,INT0' },
      { name: 'M0.1', address: 'M0.1' },
    ]);
  });

  it('reads msg.tags as an address, an array or an object', () => {
    expect(tagsOfMessage('MW2')).to.deep.equal([{ name: 'MW2', address: 'MW2' }]);
    expect(tagsOfMessage(['MW2', { name: 'b', address: 'MW4' }])).to.deep.equal([
      { name: 'MW2', address: 'MW2' },
      { name: 'b', address: 'MW4' },
    ]);
    expect(tagsOfMessage({ c: 'MW6' })).to.deep.equal([{ name: 'c', address: 'MW6' }]);
    expect(tagsOfMessage(undefined)).to.equal(undefined);
  });

  it('keeps table order in outcomes, with errors as plain data', () => {
    const err = Object.assign(new Error('boom'), { code: 'ACCESS_DENIED' }) as unknown as PlcError;
    const list = outcomes(
      [
        { name: 'b', address: 'B' },
        { name: 'a', address: 'A' },
      ],
      { A: { ok: true, value: 1 }, B: { ok: false, error: err } },
    );
    expect(list).to.deep.equal([
      { name: 'b', address: 'B', ok: false, error: { code: 'ACCESS_DENIED', message: 'boom', address: 'B' } },
      { name: 'a', address: 'A', ok: true, value: 1 },
    ]);
  });
});

describe('flows: change detection', () => {
  const good = (name: string, value: unknown) => ({ name, address: name, ok: true as const, value });

  it('reports the first read, then only moves beyond the deadband (measured from the last reported value)', () => {
    const f = new ChangeFilter(0.5);
    expect(f.filter([good('t', 20)]).length).to.equal(1);
    expect(f.filter([good('t', 20.4)]).length).to.equal(0);
    expect(f.filter([good('t', 20.45)]).length).to.equal(0);
    expect(f.filter([good('t', 20.6)]).length).to.equal(1);
  });

  it('compares arrays, dates and bigints by value, and reports quality changes', () => {
    const f = new ChangeFilter(0);
    f.filter([good('a', [1, 2]), good('d', new Date(5)), good('b', 10n)]);
    expect(f.filter([good('a', [1, 2]), good('d', new Date(5)), good('b', 10n)])).to.deep.equal([]);
    expect(f.filter([good('a', [1, 3]), good('d', new Date(6)), good('b', 11n)]).map((o) => o.name)).to.deep.equal(['a', 'd', 'b']);
    const bad = { name: 'b', address: 'b', ok: false as const, error: { code: 'TIMEOUT', message: 'x', address: 'b' } };
    expect(f.filter([bad]).length).to.equal(1);
    expect(f.filter([bad]).length).to.equal(0);
    expect(f.filter([good('b', 11n)]).length).to.equal(1);
  });

  it('compares a struct read by name member by member, with the deadband, nested structs and arrays of structs too', () => {
    const f = new ChangeFilter(0.5);
    const motor = (speed: number, run: boolean) => ({ Run: run, Speed: speed, Drive: { Temp: 40 } });
    expect(f.filter([good('m', motor(10, true)), good('s', [{ x: 1 }, { x: 2 }])]).length).to.equal(2);
    // A new object each poll with the same members is no change; one within the deadband neither.
    expect(f.filter([good('m', motor(10.4, true)), good('s', [{ x: 1 }, { x: 2 }])])).to.deep.equal([]);
    expect(f.filter([good('m', motor(10, false))]).map((o) => o.name)).to.deep.equal(['m']);
    expect(f.filter([good('m', { ...motor(10, false), Drive: { Temp: 41 } })]).length).to.equal(1);
    expect(f.filter([good('s', [{ x: 1 }, { x: 3 }])]).length).to.equal(1);
    // The reported value is a copy: a flow changing it in place does not hide the next change.
    const sent = (f.filter([good('t', { a: 1 })])[0] as { value: { a: number } }).value;
    sent.a = 2;
    expect(f.filter([good('t', { a: 2 })]).length).to.equal(1);
  });
});

describe('flows: write requests', () => {
  const table = [{ name: 'speed', address: 'DB1,INT0' }];

  it('maps names to addresses and keeps unknown keys as addresses', () => {
    expect(writeRequest(table, { payload: { speed: 5, MW2: 7 } })).to.deep.equal({
      values: { 'DB1,INT0': 5, MW2: 7 },
      names: { 'DB1,INT0': 'speed', MW2: 'MW2' },
    });
  });

  it('takes msg.topic with a scalar or array payload', () => {
    expect(writeRequest(table, { topic: 'speed', payload: 3 }).values).to.deep.equal({ 'DB1,INT0': 3 });
    expect(writeRequest(table, { topic: 'DB1,INT0[2]', payload: [1, 2] }).values).to.deep.equal({ 'DB1,INT0[2]': [1, 2] });
  });

  it('refuses a payload without a target, an empty object, a missing value and a name and address of the same tag', () => {
    expect(() => writeRequest(table, { payload: 5 }))
      .to.throw(/msg.topic/)
      .with.property('code', 'INVALID_VALUE');
    expect(() => writeRequest(table, { payload: {} })).to.throw(/names no tag/);
    expect(() => writeRequest(table, { payload: { speed: null } })).to.throw(/no value for "speed"/);
    expect(() => writeRequest(table, { payload: { speed: 1, 'DB1,INT0': 2 } })).to.throw(/same address/);
  });
});

describe('flows: failure messages', () => {
  const error = (code: string, message: string, address: string) => ({ code, message, address });

  it('names the first failed tag by name and address, its message, how many more failed, and carries its code and name', () => {
    const err = tagFailure('read', [
      { name: 'speed', error: error('ACCESS_DENIED', 'denied', 'DB1,INT0') },
      { name: 'MW2', error: error('TIMEOUT', 'late', 'MW2') },
    ]);
    expect(err).to.be.instanceOf(PlcError);
    expect(err.message).to.equal('read "speed" (DB1,INT0): denied (+1)');
    expect(err).to.include({ code: 'ACCESS_DENIED', tag: 'speed' });
  });

  it('names a tag known by its address once, for reads and writes alike', () => {
    expect(tagFailure('write', [{ name: 'MW2', error: error('TIMEOUT', 'late', 'MW2') }]).message).to.equal('write "MW2": late');
  });

  it('turns errors into plain data, PLC_ERROR when they have no code', () => {
    expect(errorInfo(Object.assign(new Error('x'), { code: 'TIMEOUT' }), 'MW2')).to.deep.equal({
      code: 'TIMEOUT',
      message: 'x',
      address: 'MW2',
    });
    expect(errorInfo('odd', 'MW4')).to.deep.equal({ code: 'PLC_ERROR', message: 'odd', address: 'MW4' });
  });
});
