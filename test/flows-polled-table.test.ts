/** A tag table made ready for polling: the address list, the message builders, and change detection by row. */
import { expect } from 'chai';
import { ChangeFilter, PolledTable, type TagOutcome } from '../lib';

/** The key-by-key loop the builders stand for (what a read node built before them). */
function byLoop(tags: { name: string; address: string }[], values: Record<string, unknown>) {
  const payload: Record<string, unknown> = {};
  const quality: Record<string, string> = {};
  const addresses: Record<string, string> = {};
  for (const t of tags) {
    payload[t.name] = values[t.address];
    quality[t.name] = 'good';
    addresses[t.name] = t.address;
  }
  return { payload, quality, addresses };
}

describe('flows: polled tables', () => {
  const tags = [
    { name: 'speed', address: 'DB1,INT0' },
    { name: 'level "a"', address: 'DB1.DBD4:REAL' },
    { name: 'again', address: 'DB1,INT0' },
    { name: 'list', address: 'MW10:INT[2]' },
  ];
  const values = { 'DB1,INT0': 7, 'DB1.DBD4:REAL': 1.5, 'MW10:INT[2]': [1, 2] };

  it('reads each address once, in table order, from one array, and marks the rows that repeat one', () => {
    const table = new PolledTable(tags);
    expect(table.addresses).to.deep.equal(['DB1,INT0', 'DB1.DBD4:REAL', 'MW10:INT[2]']);
    expect(table.addresses).to.equal(table.addresses);
    expect(table.repeated).to.deep.equal([false, false, true, false]);
    expect(table.rowValues(values)).to.deep.equal([7, 1.5, 7, [1, 2]]);
  });

  it('builds payload, quality and addresses as the key-by-key loop does, in the same key order', () => {
    const table = new PolledTable(tags);
    const loop = byLoop(tags, values);
    for (const [built, expected] of [
      [table.payload(values), loop.payload],
      [table.goodQuality(), loop.quality],
      [table.addressesByName(), loop.addresses],
    ] as const) {
      expect(built).to.deep.equal(expected);
      expect(Object.keys(built)).to.deep.equal(Object.keys(expected));
    }
  });

  it('returns new objects on every call: a flow may change what it received', () => {
    const table = new PolledTable(tags);
    const one = table.goodQuality();
    one.speed = 'bad';
    expect(table.goodQuality().speed).to.equal('good');
    expect(table.payload(values)).not.to.equal(table.payload(values));
    expect(table.addressesByName()).not.to.equal(table.addressesByName());
  });

  it('keeps the last row of a name given twice, and a name that is special in an object literal as a plain key', () => {
    const twice = [
      { name: 'x', address: 'MW0' },
      { name: 'x', address: 'MW2' },
      { name: '__proto__', address: 'MW4' },
    ];
    const table = new PolledTable(twice);
    const payload = table.payload({ MW0: 1, MW2: 2, MW4: 3 });
    expect(Object.getPrototypeOf(payload)).to.equal(Object.prototype);
    expect(Object.getOwnPropertyDescriptor(payload, '__proto__')!.value).to.equal(3);
    expect(payload.x).to.equal(2);
    expect(table.addressesByName().x).to.equal('MW2');
    expect(table.slots).to.deep.equal([0, 0, 1]);
  });

  it('builds the same without code generation', () => {
    const original = globalThis.Function;
    (globalThis as { Function: unknown }).Function = function () {
      throw new EvalError('code generation from strings disallowed');
    };
    let table: PolledTable;
    try {
      table = new PolledTable(tags);
    } finally {
      (globalThis as { Function: unknown }).Function = original;
    }
    const loop = byLoop(tags, values);
    expect(table.payload(values)).to.deep.equal(loop.payload);
    expect(table.goodQuality()).to.deep.equal(loop.quality);
    expect(table.rowValues(values)).to.deep.equal([7, 1.5, 7, [1, 2]]);
  });
});

describe('flows: change detection by row', () => {
  const tags = [
    { name: 'a', address: 'MW0' },
    { name: 'b', address: 'MW2:INT[2]' },
  ];

  it('reports the first read, then rows that changed beyond the deadband, with the memory filter() has by name', () => {
    const table = new PolledTable(tags);
    const f = new ChangeFilter(0.5);
    expect(f.changedRows(table, [10, [1, 2]])).to.deep.equal([0, 1]);
    expect(f.changedRows(table, [10.4, [1, 2]])).to.deep.equal([]);
    expect(f.changedRows(table, [10.6, [1, 2]])).to.deep.equal([0]);
    const bad: TagOutcome = { name: 'a', address: 'MW0', ok: false, error: { code: 'TIMEOUT', message: 'late', address: 'MW0' } };
    expect(f.filter([bad])).to.deep.equal([bad]);
    expect(f.changedRows(table, [10.6, [1, 2]])).to.deep.equal([0]);
    expect(f.filter([{ name: 'b', address: 'MW2:INT[2]', ok: true, value: [1, 2] }])).to.deep.equal([]);
  });

  it('remembers a copy of what it reported: a reported array changed in place is no change', () => {
    const table = new PolledTable(tags);
    const f = new ChangeFilter();
    const list = [1, 2];
    f.changedRows(table, [0, list]);
    list[0] = 99;
    expect(f.changedRows(table, [0, [1, 2]])).to.deep.equal([]);
    expect(f.changedRows(table, [0, [99, 2]])).to.deep.equal([1]);
  });

  it('forgets everything on clear()', () => {
    const table = new PolledTable(tags);
    const f = new ChangeFilter();
    f.changedRows(table, [0, [1]]);
    f.clear();
    expect(f.changedRows(table, [0, [1]])).to.deep.equal([0, 1]);
  });
});
