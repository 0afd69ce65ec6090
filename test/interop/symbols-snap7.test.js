'use strict';
// Reading and writing by symbol against snap7's server (an independent S7
// implementation): a table compiled by compileSymbols from the sources of
// test/fixtures/symbols/client/, snap7's DBs registered at the lengths those
// sources give, values put there by snap7's own client at the offsets the
// layout rules give by hand (docs/symbols.md); our client reads and writes
// them by name, and checks their lengths with snap7's block info.
const { expect } = require('chai');
const fs = require('node:fs');
const net = require('node:net');
const path = require('node:path');
const support = require('./support');
const { startSnap7Server, snap7Client, eventWithin } = support;
const dist = (file) => require(path.resolve(__dirname, '../../dist', file));

const FIXTURES = path.resolve(__dirname, '../fixtures/symbols/client');
const source = (name) => ({ name, content: fs.readFileSync(path.join(FIXTURES, name)) });
const PLANT = ['Motor.udt', 'Step.udt', 'Tank.db', 'Recipe.awl', 'Symbols.asc', 'Valve.udt', 'Field.db'];
const NUMBERS = { Tank: 1, Field: 4 };
/** The plant's sources compiled, with more sources (`{ name, content }`, numbered by `db`) when given. */
const compile = (more = [], db = {}) => support.plcwire.compileSymbols([...PLANT.map(source), ...more], { db: { ...NUMBERS, ...db } });

/** A bare ISO-on-TCP connection to `port` (COTP connect, setup communication): `ask(frame)` resolves the next answer, as sent. */
async function rawS7(port) {
  const { encodeConnectionRequest, encodeSetupCommunication } = dist('lib/s7/codec/index.js');
  const socket = net.connect(port, '127.0.0.1');
  await new Promise((resolve, reject) => socket.once('connect', resolve).once('error', reject));
  let pending = Buffer.alloc(0);
  const waiting = [];
  socket.on('data', (chunk) => {
    pending = Buffer.concat([pending, chunk]);
    while (pending.length >= 4 && pending.length >= pending.readUInt16BE(2)) {
      const n = pending.readUInt16BE(2);
      waiting.shift()?.(Buffer.from(pending.subarray(0, n)));
      pending = pending.subarray(n);
    }
  });
  const ask = (frame) =>
    new Promise((resolve) => {
      waiting.push(resolve);
      socket.write(frame);
    });
  await ask(encodeConnectionRequest({ sourceRef: 1, callingTsap: 0x0100, calledTsap: 0x0101, tpduSize: 0x0a }));
  await ask(encodeSetupCommunication(1, { maxAmqCalling: 1, maxAmqCalled: 1, pduSize: 480 }));
  return { ask, close: () => socket.destroy() };
}

describe('interop: reading and writing by symbol against snap7 server', function () {
  this.timeout(20000);
  const table = compile();
  /** Fresh zeros for each DB, at the lengths the sources declare: DB1 "Tank" 40, DB2 "Recipe" 8, DB4 "Field" 34. */
  const zeros = () => ({ db: Object.fromEntries(table.blocks.map((b) => [b.db, Buffer.alloc(b.length)])) });
  let peer;
  let them;
  let plc;

  // One snap7 server and client for the suite, as the other interop suites keep theirs; each test starts from zeros.
  before(async () => {
    expect(table.blocks.map((b) => [b.name, b.db, b.length]).sort()).to.deep.equal([
      ['Field', 4, 34],
      ['Recipe', 2, 8],
      ['Tank', 1, 40],
    ]);
    peer = await startSnap7Server(zeros());
    them = await snap7Client(peer.port);
  });

  after(() => {
    them?.close();
    peer?.stop();
  });

  beforeEach(() => peer.reset(zeros()));

  afterEach(async () => {
    await plc?.close();
    plc = undefined;
  });

  const connect = (symbols = table, query = '') =>
    support.plcwire.connect(`s7://127.0.0.1:${peer.port}?rack=0&slot=1&timeout=5000${query}`, { symbols });

  it('reads by name the values snap7 wrote at the offsets, and a struct read equals its member reads', async () => {
    // DB1 "Tank" by hand: Level REAL 0, Count INT 4, Motor at 6 (Run 6.0, Fault 6.1, Speed INT 8), Temps REAL[3] 10,
    // Label STRING[8] 22, Steps[0..1] of "Step" at 32 and 36 (Temp INT, On BOOL at +2).
    const db1 = Buffer.alloc(40);
    db1.writeFloatBE(12.5, 0);
    db1.writeInt16BE(-7, 4);
    db1[6] = 0b10;
    db1.writeInt16BE(1500, 8);
    [1.5, 2.5, 3.5].forEach((v, i) => db1.writeFloatBE(v, 10 + 4 * i));
    db1.set([8, 3, 0x61, 0x62, 0x63], 22);
    db1.writeInt16BE(21, 32);
    db1[34] = 1;
    db1.writeInt16BE(22, 36);
    await them.call('DBWrite', 1, 0, 40, db1);
    const db2 = Buffer.alloc(8);
    db2.writeFloatBE(80, 0);
    db2.writeInt16BE(2, 4);
    await them.call('DBWrite', 2, 0, 8, db2);
    plc = await connect();
    const names = [
      '"Tank".Level',
      '"Tank".Count',
      '"Tank".Motor.Run',
      '"Tank".Motor.Fault',
      '"Tank".Motor.Speed',
      '"Tank".Temps',
      '"Tank".Label',
    ];
    expect(await plc.read([...names, 'Recipe.Setpoint', '"Recipe".Mode'])).to.deep.equal({
      '"Tank".Level': 12.5,
      '"Tank".Count': -7,
      '"Tank".Motor.Run': false,
      '"Tank".Motor.Fault': true,
      '"Tank".Motor.Speed': 1500,
      '"Tank".Temps': [1.5, 2.5, 3.5],
      '"Tank".Label': 'abc',
      'Recipe.Setpoint': 80,
      '"Recipe".Mode': 2,
    });
    const struct = await plc.read(['"Tank".Motor', '"Tank".Steps', '"Tank"']);
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
    const single = await plc.read(names);
    expect(struct['"Tank"']).to.deep.equal({
      Level: single['"Tank".Level'],
      Count: single['"Tank".Count'],
      Motor: { Run: single['"Tank".Motor.Run'], Fault: single['"Tank".Motor.Fault'], Speed: single['"Tank".Motor.Speed'] },
      Temps: single['"Tank".Temps'],
      Label: single['"Tank".Label'],
      Steps: struct['"Tank".Steps'],
    });
  });

  it('writes by name (a struct with members missing too) to the offsets snap7 reads back', async () => {
    const start = Buffer.alloc(40);
    start[6] = 0b10; // Fault set, kept by a write of Run and Speed
    await them.call('DBWrite', 1, 0, 40, start);
    plc = await connect();
    await plc.write({
      '"Tank".Level': -2.25,
      '"Tank".Motor': { Run: true, Speed: 42 },
      '"Tank".Steps': [undefined, { On: true }],
      '"Tank".Label': 'xyz',
      '"Recipe".Setpoint': 80,
    });
    const db1 = await them.call('DBRead', 1, 0, 40);
    expect(db1.readFloatBE(0)).to.equal(-2.25);
    expect(db1[6]).to.equal(0b11);
    expect(db1.readInt16BE(8)).to.equal(42);
    expect([db1[34], db1[38]]).to.deep.equal([0, 1]);
    expect(db1.subarray(23, 27).toString('latin1')).to.equal('\x03xyz');
    expect((await them.call('DBRead', 2, 0, 4)).readFloatBE(0)).to.equal(80);
  });

  describe('layout corners, by name and by hand at the offsets docs/symbols.md gives (DB4 "Field")', () => {
    /** Bytes no member owns, filled with 0xA5: a tool that packs members without the S7 padding reads them. */
    const PAD = 0xa5;

    it('a STRING[11] then an INT: the string takes 13 bytes, the INT starts on the next even byte, 14', async () => {
      const db4 = Buffer.alloc(34);
      db4.set([11, 5, ...Buffer.from('PUMP1', 'latin1')], 0);
      db4[13] = PAD;
      db4.writeInt16BE(1234, 14);
      await them.call('DBWrite', 4, 0, 34, db4);
      plc = await connect();
      expect(await plc.read(['"Field".Id', '"Field".After'])).to.deep.equal({ '"Field".Id': 'PUMP1', '"Field".After': 1234 });
      await plc.write({ '"Field".Id': 'VALVE-22', '"Field".After': -300 });
      const bytes = await them.call('DBRead', 4, 0, 16);
      const byHand = { id: bytes.toString('latin1', 2, 2 + bytes[1]), max: bytes[0], after: bytes.readInt16BE(14), pad: bytes[13] };
      expect(byHand).to.deep.equal({ id: 'VALVE-22', max: 11, after: -300, pad: PAD });
      expect(await plc.read(['"Field".Id', '"Field".After'])).to.deep.equal({ '"Field".Id': byHand.id, '"Field".After': byHand.after });
    });

    it('a BOOL after a BOOL array: the array holds bits 16.0-16.2, the BOOL is on the next even byte, 18.0', async () => {
      const db4 = Buffer.alloc(34);
      db4[16] = 0b101 | (PAD & 0xf8); // Flags T, F, T; bits 16.3-16.7 are no member's
      db4[17] = PAD;
      await them.call('DBWrite', 4, 0, 34, db4);
      plc = await connect();
      expect(await plc.read(['"Field".Flags', '"Field".Ready'])).to.deep.equal({
        '"Field".Flags': [true, false, true],
        '"Field".Ready': false,
      });
      await plc.write({ '"Field".Ready': true, '"Field".Flags[1]': true });
      const bytes = await them.call('DBRead', 4, 16, 3);
      const byHand = { flags: [0, 1, 2].map((bit) => ((bytes[0] >> bit) & 1) === 1), ready: (bytes[2] & 1) === 1 };
      expect(byHand).to.deep.equal({ flags: [true, true, true], ready: true });
      expect([bytes[0] & 0xf8, bytes[1], bytes[2] & 0xfe]).to.deep.equal([PAD & 0xf8, PAD, 0]);
      expect(await plc.read(['"Field".Flags', '"Field".Ready'])).to.deep.equal({
        '"Field".Flags': byHand.flags,
        '"Field".Ready': byHand.ready,
      });
    });

    it('an array of a UDT ending in a BOOL: each "Valve" (REAL, BOOL) padded to 6 bytes, at 20 and 26; what follows at 32', async () => {
      const db4 = Buffer.alloc(34);
      db4.writeFloatBE(12.5, 20);
      db4[24] = 1;
      db4[25] = PAD;
      db4.writeFloatBE(80, 26);
      db4[31] = PAD;
      db4.writeInt16BE(7, 32);
      await them.call('DBWrite', 4, 0, 34, db4);
      plc = await connect();
      const got = await plc.read(['"Field".Valves', '"Field".Tail', '"Field".Valves[1].Position', '"Field".Valves[1].Open']);
      expect(got).to.deep.equal({
        '"Field".Valves': [
          { Position: 12.5, Open: true },
          { Position: 80, Open: false },
        ],
        '"Field".Tail': 7,
        '"Field".Valves[1].Position': 80,
        '"Field".Valves[1].Open': false,
      });
      await plc.write({ '"Field".Valves': [{ Open: false }, { Position: -1.5, Open: true }], '"Field".Tail': -5 });
      const bytes = await them.call('DBRead', 4, 20, 14);
      const valve = (at) => ({ Position: bytes.readFloatBE(at), Open: (bytes[at + 4] & 1) === 1 });
      const byHand = { valves: [valve(0), valve(6)], tail: bytes.readInt16BE(12) };
      expect(byHand).to.deep.equal({
        valves: [
          { Position: 12.5, Open: false },
          { Position: -1.5, Open: true },
        ],
        tail: -5,
      });
      expect([bytes[5], bytes[11]]).to.deep.equal([PAD, PAD]);
      expect(await plc.read(['"Field".Valves', '"Field".Tail'])).to.deep.equal({
        '"Field".Valves': byHand.valves,
        '"Field".Tail': byHand.tail,
      });
    });
  });

  it("checks the layout with snap7's block info: layoutOk, and layoutMismatch for sources newer than the PLC's block", async () => {
    plc = await connect(table, '&strictSymbols=true');
    const [ok] = await eventWithin(plc, 'layoutOk', 5000);
    expect(ok.checks.map((c) => [c.db, c.status, c.actual]).sort()).to.deep.equal([
      [1, 'ok', 40],
      [2, 'ok', 8],
      [4, 'ok', 34],
    ]);
    await plc.close();
    // Tank.db with a member added at its end, not yet downloaded: 42 bytes declared, snap7's DB1 has 40.
    const grown = fs
      .readFileSync(path.join(FIXTURES, 'Tank.db'), 'latin1')
      .replace('Steps : Array[0..1] of "Step";', '$&\r\n      Extra : Int;');
    const newer = support.plcwire.compileSymbols(
      [...PLANT.filter((f) => f !== 'Tank.db').map(source), { name: 'Tank.db', content: grown }],
      {
        db: NUMBERS,
      },
    );
    plc = await connect(newer, '&strictSymbols=true');
    const checks = await plc.checkLayout();
    expect(checks.find((c) => c.db === 1)).to.deep.equal({ block: 'Tank', db: 1, declared: 42, actual: 40, status: 'mismatch' });
    const r = await plc.readDetailed(['"Tank".Level', 'DB1.DBD0:REAL', '"Recipe".Mode']);
    expect(r['"Tank".Level'].ok === false && r['"Tank".Level'].error.code).to.equal('LAYOUT_MISMATCH');
    expect([r['DB1.DBD0:REAL'].ok, r['"Recipe".Mode'].ok]).to.deep.equal([true, true]);
  });

  it("snap7's answer to block info of a DB it does not have, as recorded in test/fixtures/s7-userdata.ts: a TPKT frame 78 bytes longer than its S7 lengths, its header left over from earlier answers", async () => {
    const { encodeUserdataRequest, decodeUserdata } = dist('lib/s7/codec/index.js');
    const { encodeBlockInfoRequest, decodeBlockInfo } = dist('lib/s7/codec/blocks.js');
    const { SNAP7 } = dist('test/fixtures/s7-userdata.js');
    const blockInfo = (db) => encodeUserdataRequest(3, 3, encodeBlockInfoRequest(0x41, db));
    const raw = await rawS7(peer.port);
    try {
      const first = await raw.ask(blockInfo(9));
      // What snap7 writes on that path: the S7 data length 4, the error D2 09, the item 0A 00 0000, then 78 zeros.
      expect([first.length, first.readUInt16BE(2), first.readUInt16BE(15), first.readUInt16BE(27)]).to.deep.equal([111, 111, 4, 0xd209]);
      expect(first.subarray(29).equals(Buffer.concat([Buffer.from('0a000000', 'hex'), Buffer.alloc(78)]))).to.equal(true);
      // The rest of its header is left from earlier answers of the process (the fixture is the first of a fresh one): never a frame.
      expect(() => decodeUserdata(first)).to.throw(/S7 protocol id|S7 lengths/);
      expect(first.subarray(29).equals(SNAP7.blockInfoMissingFirst.subarray(29))).to.equal(true);
      const known = await raw.ask(blockInfo(2));
      expect(decodeBlockInfo(decodeUserdata(known).data)).to.deep.include({ type: 'DB', number: 2, mc7Size: 8 });
      const after = await raw.ask(blockInfo(9));
      expect(after.toString('hex')).to.equal(SNAP7.blockInfoMissingAfterAnswer.toString('hex'));
      expect(() => decodeUserdata(after)).to.throw(/S7 lengths \(header 10 \+ parameters 12 \+ data 4\) do not match the PDU \(104\)/);
    } finally {
      raw.close();
    }
  });

  it("a DB snap7 does not have: a mismatch with actual null from snap7's block list, asked without its block info; the link stays up", async () => {
    const ghost = {
      name: 'Ghost.db',
      content:
        'DATA_BLOCK "Ghost"\r\n{ S7_Optimized_Access := \'FALSE\' }\r\nVERSION : 0.1\r\n   STRUCT\r\n      X : Int;\r\n   END_STRUCT;\r\nBEGIN\r\nEND_DATA_BLOCK\r\n',
    };
    plc = await connect(compile([ghost], { Ghost: 9 }));
    const disconnects = [];
    plc.on('disconnected', (e) => disconnects.push(e));
    const [event] = await eventWithin(plc, 'layoutMismatch', 5000);
    expect(event).to.deep.equal({ block: 'Ghost', db: 9, declared: 2, actual: null });
    const checks = await plc.checkLayout();
    expect(checks.map((c) => [c.db, c.status, c.actual]).sort()).to.deep.equal([
      [1, 'ok', 40],
      [2, 'ok', 8],
      [4, 'ok', 34],
      [9, 'mismatch', null],
    ]);
    expect([plc.state, disconnects.length]).to.deep.equal(['connected', 0]);
    expect(await plc.read(['"Recipe".Setpoint'])).to.deep.equal({ '"Recipe".Setpoint': 0 });
  });
});
