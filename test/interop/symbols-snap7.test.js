'use strict';
// Reading and writing by symbol against snap7's server (an independent S7
// implementation): DBs registered at known offsets, values put there by
// snap7's own client; our client reads and writes them by name, and checks
// their lengths with snap7's block info.
const { expect } = require('chai');
const support = require('./support');
const { startSnap7Server, snap7Client, eventWithin } = support;
const { symbolTable } = require('../../dist/test/support/symbol-table.js');

/** DB1 "Tank": Level REAL 0, Count INT 4, Motor { Run 6.0, Fault 6.1, Speed INT 8 }, Temps REAL[3] 10, Steps[0..1] { Temp INT, On BOOL } 22. */
const TANK = {
  name: 'Tank',
  db: 1,
  length: 30,
  members: [
    { name: 'Level', type: 'REAL', byte: 0 },
    { name: 'Count', type: 'INT', byte: 4 },
    {
      name: 'Motor',
      byte: 6,
      size: 4,
      struct: [
        { name: 'Run', type: 'BOOL', byte: 6, bit: 0 },
        { name: 'Fault', type: 'BOOL', byte: 6, bit: 1 },
        { name: 'Speed', type: 'INT', byte: 8 },
      ],
    },
    { name: 'Temps', type: 'REAL', byte: 10, count: 3 },
    {
      name: 'Steps',
      byte: 22,
      size: 4,
      count: 2,
      structArray: [
        { name: 'Temp', type: 'INT', byte: 22 },
        { name: 'On', type: 'BOOL', byte: 24, bit: 0 },
      ],
    },
  ],
};
const RECIPE = { name: 'Recipe', db: 2, length: 8, members: [{ name: 'Setpoint', type: 'REAL', byte: 0 }] };

describe('interop: reading and writing by symbol against snap7 server', function () {
  this.timeout(20000);
  let peer;
  let them;
  let plc;

  // One snap7 server and client for the suite, as the other interop suites keep theirs; each test starts from zeros.
  before(async () => {
    peer = await startSnap7Server({ db: { 1: Buffer.alloc(30), 2: Buffer.alloc(8) } });
    them = await snap7Client(peer.port);
  });

  after(() => {
    them?.close();
    peer?.stop();
  });

  beforeEach(() => peer.reset({ db: { 1: Buffer.alloc(30), 2: Buffer.alloc(8) } }));

  afterEach(async () => {
    await plc?.close();
    plc = undefined;
  });

  const connect = (table, query = '') =>
    support.plcwire.connect(`s7://127.0.0.1:${peer.port}?rack=0&slot=1&timeout=5000${query}`, { symbols: table });

  it('reads by name the values snap7 wrote at the offsets, and a struct read equals its member reads', async () => {
    const db1 = Buffer.alloc(30);
    db1.writeFloatBE(12.5, 0);
    db1.writeInt16BE(-7, 4);
    db1[6] = 0b10;
    db1.writeInt16BE(1500, 8);
    [1.5, 2.5, 3.5].forEach((v, i) => db1.writeFloatBE(v, 10 + 4 * i));
    db1.writeInt16BE(21, 22);
    db1[24] = 1;
    db1.writeInt16BE(22, 26);
    await them.call('DBWrite', 1, 0, 30, db1);
    plc = await connect(symbolTable([TANK, RECIPE]));
    const names = ['"Tank".Level', '"Tank".Count', '"Tank".Motor.Run', '"Tank".Motor.Fault', '"Tank".Motor.Speed', '"Tank".Temps'];
    expect(await plc.read(names)).to.deep.equal({
      '"Tank".Level': 12.5,
      '"Tank".Count': -7,
      '"Tank".Motor.Run': false,
      '"Tank".Motor.Fault': true,
      '"Tank".Motor.Speed': 1500,
      '"Tank".Temps': [1.5, 2.5, 3.5],
    });
    const struct = await plc.read(['"Tank".Motor', '"Tank".Steps']);
    expect(struct['"Tank".Motor']).to.deep.equal({ Run: false, Fault: true, Speed: 1500 });
    expect(struct['"Tank".Steps']).to.deep.equal([
      { Temp: 21, On: true },
      { Temp: 22, On: false },
    ]);
    const members = await plc.read(['"Tank".Steps[0].Temp', '"Tank".Steps[0].On', '"Tank".Steps[1].Temp', '"Tank".Steps[1].On']);
    expect(struct['"Tank".Steps']).to.deep.equal([
      { Temp: members['"Tank".Steps[0].Temp'], On: members['"Tank".Steps[0].On'] },
      { Temp: members['"Tank".Steps[1].Temp'], On: members['"Tank".Steps[1].On'] },
    ]);
  });

  it('writes by name (a struct with members missing too) to the offsets snap7 reads back', async () => {
    const start = Buffer.alloc(30);
    start[6] = 0b10; // Fault set, kept by a write of Run and Speed
    await them.call('DBWrite', 1, 0, 30, start);
    plc = await connect(symbolTable([TANK, RECIPE]));
    await plc.write({
      '"Tank".Level': -2.25,
      '"Tank".Motor': { Run: true, Speed: 42 },
      '"Tank".Steps': [undefined, { On: true }],
      '"Recipe".Setpoint': 80,
    });
    const db1 = await them.call('DBRead', 1, 0, 30);
    expect(db1.readFloatBE(0)).to.equal(-2.25);
    expect(db1[6]).to.equal(0b11);
    expect(db1.readInt16BE(8)).to.equal(42);
    expect([db1[24], db1[28]]).to.deep.equal([0, 1]);
    expect((await them.call('DBRead', 2, 0, 4)).readFloatBE(0)).to.equal(80);
  });

  it("checks the layout with snap7's block info: layoutOk, and layoutMismatch for a DB of another length", async () => {
    plc = await connect(symbolTable([TANK, RECIPE]), '&strictSymbols=true');
    const [ok] = await eventWithin(plc, 'layoutOk', 5000);
    expect(ok.checks.map((c) => [c.db, c.status, c.actual])).to.deep.equal([
      [1, 'ok', 30],
      [2, 'ok', 8],
    ]);
    await plc.close();
    const longer = { ...TANK, length: 28 };
    plc = await connect(symbolTable([longer, RECIPE]), '&strictSymbols=true');
    const checks = await plc.checkLayout();
    expect(checks[0]).to.deep.equal({ block: 'Tank', db: 1, declared: 28, actual: 30, status: 'mismatch' });
    const r = (await plc.readDetailed(['"Tank".Level', 'DB1.DBD0:REAL']))['"Tank".Level'];
    expect(r.ok === false && r.error.code).to.equal('LAYOUT_MISMATCH');
  });

  it("a DB snap7 does not have: a mismatch with actual null from snap7's block list, asked without its block info; the link stays up", async () => {
    const missing = { name: 'Ghost', db: 9, length: 4, members: [{ name: 'X', type: 'INT', byte: 0 }] };
    plc = await connect(symbolTable([RECIPE, missing]));
    const disconnects = [];
    plc.on('disconnected', (e) => disconnects.push(e));
    const [event] = await eventWithin(plc, 'layoutMismatch', 5000);
    expect(event).to.deep.equal({ block: 'Ghost', db: 9, declared: 4, actual: null });
    const checks = await plc.checkLayout();
    expect(checks.map((c) => [c.db, c.status, c.actual])).to.deep.equal([
      [2, 'ok', 8],
      [9, 'mismatch', null],
    ]);
    expect([plc.state, disconnects.length]).to.deep.equal(['connected', 0]);
    expect(await plc.read(['"Recipe".Setpoint'])).to.deep.equal({ '"Recipe".Setpoint': 0 });
  });
});
