/**
 * Reading and writing by name (docs/symbols.md, "Reading and writing by
 * name") end to end: a symbol table compiled by compileSymbols from the
 * sources of test/fixtures/symbols/client/, given to the client; the S7 and
 * FETCH/WRITE simulators built from the same sources.
 */
import { expect } from 'chai';
import { createClient } from '../lib/connect';
import { PlcError, TagErrors } from '../lib/errors';
import { FetchWriteClient } from '../lib/fetchwrite/client';
import { FetchWriteServer, type FetchWriteRequestEvent } from '../lib/fetchwrite/server';
import { S7Client } from '../lib/s7/client';
import { S7Server, type S7RequestEvent } from '../lib/s7/server';
import { compileSymbols } from '../lib/symbols';
import type { SymbolTable } from '../lib/symbols/model';
import type { PlcData, PlcStruct } from '../lib/types';
import { parseUrl, type FetchWriteEndpoint, type S7Endpoint } from '../lib/url';
import { compileClientSources } from './support/symbol-sources';

const FAST = { backoff: { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 } };

/** DB1 "Tank" (Tank.db with the UDTs "Motor" and "Step", 40 bytes), DB2 "Recipe" (Recipe.awl, numbered by Symbols.asc, 8 bytes). */
const PLANT = ['Motor.udt', 'Step.udt', 'Tank.db', 'Recipe.awl', 'Symbols.asc'];
/** DB3, a block whose name reads as an absolute address (flag word 10). */
const WITH_MW10 = [...PLANT, 'MW10.db'];

/**
 * Fills DB1/DB2 of a memory with known values at the offsets the layout
 * rules give by hand (docs/symbols.md): Level REAL 0, Count INT 4, Motor at
 * 6 (Run 6.0, Fault 6.1, Speed INT 8), Temps REAL[3] 10, Label STRING[8]
 * 22, Steps[0..1] of "Step" at 32 and 36 (Temp INT, On BOOL at +2).
 */
function fill(db1: Buffer, db2: Buffer): void {
  db1.writeFloatBE(12.5, 0);
  db1.writeInt16BE(-7, 4);
  db1[6] = 0b10; // Run false, Fault true
  db1.writeInt16BE(1500, 8);
  [1.5, 2.5, 3.5].forEach((v, i) => db1.writeFloatBE(v, 10 + 4 * i));
  db1[22] = 8;
  db1[23] = 3;
  db1.write('abc', 24, 'latin1');
  db1.writeInt16BE(21, 32);
  db1[34] = 1;
  db1.writeInt16BE(22, 36);
  db1[38] = 0;
  db2.writeFloatBE(80, 0);
  db2.writeInt16BE(2, 4);
  db2.writeInt16BE(99, 6);
}

const MOTOR = { Run: false, Fault: true, Speed: 1500 };
const STEPS = [
  { Temp: 21, On: true },
  { Temp: 22, On: false },
];

async function failure(p: Promise<unknown>): Promise<PlcError> {
  const outcome = await p.then(
    () => undefined,
    (e: unknown) => e,
  );
  if (!(outcome instanceof PlcError)) throw new Error(`expected a PlcError, got ${String(outcome)}`);
  return outcome;
}

describe('reading and writing by symbol (S7 simulator)', function () {
  this.timeout(10000);
  let server: S7Server;
  let client: S7Client;
  let table: SymbolTable;
  let requests: S7RequestEvent[];
  const reads = () => requests.filter((r) => r.kind === 'read');
  const writes = () => requests.filter((r) => r.kind === 'write');

  beforeEach(async () => {
    table = compileClientSources(...WITH_MW10);
    server = new S7Server({ port: 0, profile: 's7-300', symbols: table });
    await server.listen();
    fill(server.memory.area('DB', 1)!, server.memory.area('DB', 2)!);
    client = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?rack=0&slot=2&timeout=1500`) as S7Endpoint, { ...FAST, symbols: table });
    await client.connect();
    requests = [];
    server.on('request', (r: S7RequestEvent) => requests.push(r));
  });

  afterEach(async () => {
    await client.close();
    await server.close();
  });

  it('reads elementary symbols keyed as given, from the offsets of the table', async () => {
    const names = [
      '"Tank".Level',
      '"Tank".Count',
      '"Tank".Motor.Speed',
      '"Tank".Motor.Fault',
      '"Tank".Temps',
      '"Tank".Label',
      '"Recipe".Mode',
    ];
    expect(await client.read(names)).to.deep.equal({
      '"Tank".Level': 12.5,
      '"Tank".Count': -7,
      '"Tank".Motor.Speed': 1500,
      '"Tank".Motor.Fault': true,
      '"Tank".Temps': [1.5, 2.5, 3.5],
      '"Tank".Label': 'abc',
      '"Recipe".Mode': 2,
    });
  });

  it('resolves a name as the table does (another case, unquoted) and keys it as written', async () => {
    expect(await client.read(['"TANK".level', 'Recipe.Setpoint'])).to.deep.equal({ '"TANK".level': 12.5, 'Recipe.Setpoint': 80 });
  });

  it('writes elementary symbols to the offsets of the table', async () => {
    await client.write({ '"Tank".Motor.Run': true, '"Tank".Level': -1.25, '"Recipe".Spare': 7, '"Tank".Label': 'xy' });
    const db1 = server.memory.area('DB', 1)!;
    expect(db1[6]).to.equal(0b11);
    expect(db1.readFloatBE(0)).to.equal(-1.25);
    expect(server.memory.area('DB', 2)!.readInt16BE(6)).to.equal(7);
    expect(db1.toString('latin1', 24, 24 + db1[23]!)).to.equal('xy');
  });

  it('reads a whole struct, an array of structs and a whole DB as objects, each in one item of one request', async () => {
    const got = await client.read<PlcData>(['"Tank".Motor']);
    expect(got).to.deep.equal({ '"Tank".Motor': MOTOR });
    expect(reads().map((r) => r.items)).to.deep.equal([1]);
    requests = [];
    expect(await client.read<PlcData>(['"Tank".Steps'])).to.deep.equal({ '"Tank".Steps': STEPS });
    expect(reads().map((r) => r.items)).to.deep.equal([1]);
    requests = [];
    const tank = (await client.read<PlcStruct>(['"Tank"']))['"Tank"']!;
    expect(reads().map((r) => r.items)).to.deep.equal([1]);
    expect(tank).to.deep.equal({ Level: 12.5, Count: -7, Motor: MOTOR, Temps: [1.5, 2.5, 3.5], Label: 'abc', Steps: STEPS });
    // The block named as the table's names are: any case, quotes optional; its bytes are the declared length.
    expect((await client.read<PlcData>(['tank'])).tank).to.deep.equal(tank);
    expect(client.tag('"Recipe"')).to.include({ dbNumber: 2, byteOffset: 0, count: 8 });
  });

  it('a struct read equals the reads of its members', async () => {
    const members = await client.read(['"Tank".Motor.Run', '"Tank".Motor.Fault', '"Tank".Motor.Speed']);
    const struct = (await client.read<PlcStruct>(['"Tank".Motor']))['"Tank".Motor']!;
    expect(struct).to.deep.equal({
      Run: members['"Tank".Motor.Run'],
      Fault: members['"Tank".Motor.Fault'],
      Speed: members['"Tank".Motor.Speed'],
    });
  });

  it('mixes symbols, structs and absolute addresses in one call, packed into one request', async () => {
    const got = await client.read<PlcData>(['"Tank".Level', 'DB1.DBW4', '"Tank".Motor', 'DB2,REAL0', '"Recipe".Mode']);
    expect(got).to.deep.equal({ '"Tank".Level': 12.5, 'DB1.DBW4': 0xfff9, '"Tank".Motor': MOTOR, 'DB2,REAL0': 80, '"Recipe".Mode': 2 });
    expect(reads()).to.have.length(1);
    await client.write({ '"Tank".Count': 5, 'DB2.DBW6': 6 });
    expect(writes()).to.have.length(1);
    expect(await client.read(['DB1.DBW4:INT', '"Recipe".Spare'])).to.deep.equal({ 'DB1.DBW4:INT': 5, '"Recipe".Spare': 6 });
  });

  it('readDetailed gives a struct its object and an unknown name its error, naming the closest names', async () => {
    const results = await client.readDetailed<PlcData>(['"Tank".Levle', '"Tank".Motor', '"Tank".Motor.Sped']);
    expect(results['"Tank".Motor']).to.deep.equal({ ok: true, value: MOTOR });
    const levle = results['"Tank".Levle']!;
    expect(levle.ok).to.equal(false);
    if (levle.ok) return;
    expect(levle.error.code).to.equal('INVALID_ADDRESS');
    expect(levle.error.tag).to.equal('"Tank".Levle');
    expect(levle.error.message).to.match(/^unknown symbol "Tank"\.Levle; did you mean "Tank"\.Level/);
    const sped = results['"Tank".Motor.Sped']!;
    expect(!sped.ok && sped.error.message).to.match(/did you mean "Tank"\.Motor\.Speed/);
  });

  it('read() of an unknown name rejects with TagErrors that keep the good values', async () => {
    const err = await failure(client.read(['"Tank".Level', '"Tank".Nothing_like_it']));
    expect(err).to.be.instanceOf(TagErrors);
    expect((err as TagErrors).results['"Tank".Level']).to.deep.equal({ ok: true, value: 12.5 });
    expect((err as TagErrors).errors['"Tank".Nothing_like_it']!.message).to.equal(
      'unknown symbol "Tank".Nothing_like_it; "Tank" has no such member (its members: Level, Count, Motor, Temps, Label, Steps)',
    );
  });

  it('an unquoted text that is neither an address nor a name keeps the address error', async () => {
    const results = await client.readDetailed(['DB1.DBW', 'QQQQQQQQ']);
    expect(!results['DB1.DBW']!.ok && results['DB1.DBW']!.error.message).to.match(/^invalid address "DB1\.DBW"/);
    expect(!results.QQQQQQQQ!.ok && results.QQQQQQQQ!.error.code).to.equal('INVALID_ADDRESS');
  });

  it('an absolute address comes before a symbol of the same spelling; quoted, the name is the symbol', async () => {
    server.memory.area('M')!.writeUInt16BE(0x1234, 10);
    server.memory.area('DB', 3)!.writeUInt16BE(0x4321, 0);
    expect(await client.read<PlcData>(['MW10', '"MW10"'])).to.deep.equal({ MW10: 0x1234, '"MW10"': { Word: 0x4321 } });
  });

  it('writes a struct from an object: the members given, each its own item; the others keep their value', async () => {
    const db1 = server.memory.area('DB', 1)!;
    db1[6] = 0b10;
    await client.write({ '"Tank".Motor': { Run: true, Speed: 42 } });
    expect(db1[6]).to.equal(0b11); // Fault kept
    expect(db1.readInt16BE(8)).to.equal(42);
    expect(writes().map((w) => w.items)).to.deep.equal([2]);
    await client.write({ '"Tank".Steps': [undefined, { Temp: -3 }] });
    expect([db1.readInt16BE(32), db1.readInt16BE(36), db1[34]]).to.deep.equal([21, -3, 1]);
    await client.write({ '"Tank"': { Motor: { Fault: false }, Count: 9 } });
    expect([db1[6], db1.readInt16BE(4)]).to.deep.equal([0b01, 9]);
  });

  it('refuses a struct value with members its type does not have, naming them, and writes nothing of it', async () => {
    const before = Buffer.from(server.memory.area('DB', 1)!);
    const results = await client.writeDetailed({ '"Tank".Motor': { Run: true, Speeed: 1, Colour: 'red' }, '"Recipe".Mode': 3 });
    const motor = results['"Tank".Motor']!;
    expect(motor.ok).to.equal(false);
    if (motor.ok) return;
    expect(motor.error.code).to.equal('INVALID_VALUE');
    expect(motor.error.tag).to.equal('"Tank".Motor');
    expect(motor.error.message).to.contain('no members "Speeed", "Colour" (its members: Run, Fault, Speed)');
    expect(results['"Recipe".Mode']).to.deep.equal({ ok: true, value: undefined });
    expect(server.memory.area('DB', 1)!.equals(before)).to.equal(true);
  });

  it('refuses a struct given a value that is not an object, or a member value that does not fit, before sending', async () => {
    const results = await client.writeDetailed({
      '"Tank".Motor': 5,
      '"Tank".Steps': [{ Temp: 1 }],
      '"Recipe"': { Mode: 70000, Spare: 1 },
    });
    expect(Object.values(results).map((r) => !r.ok && r.error.code)).to.deep.equal(['INVALID_VALUE', 'INVALID_VALUE', 'INVALID_VALUE']);
    expect(!results['"Recipe"']!.ok && results['"Recipe"']!.error.message).to.contain('"Recipe".Mode');
    expect(writes()).to.have.length(0);
    expect(server.memory.area('DB', 2)!.readInt16BE(6)).to.equal(99);
  });

  it('prepare() takes symbols and structs: polling them plans once', async () => {
    const poll = client.prepare(['"Tank".Level', '"Tank".Motor', 'DB2.DBW4']);
    const plans = client.stats.plansMade;
    for (let i = 0; i < 3; i++) {
      expect(await poll.read<PlcData>()).to.deep.equal({ '"Tank".Level': 12.5, '"Tank".Motor': MOTOR, 'DB2.DBW4': 2 });
      expect((await poll.readDetailed<PlcData>())['"Tank".Motor']).to.deep.equal({ ok: true, value: MOTOR });
    }
    expect(client.stats.plansMade - plans).to.be.at.most(1);
    expect(() => client.prepare(['"Tank".Levle'])).to.throw(PlcError, /did you mean "Tank"\.Level/);
  });

  it('write allow-lists take symbols: a struct admits its members', async () => {
    const guarded = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?rack=0&slot=2`) as S7Endpoint, {
      symbols: table,
      allow: ['"Tank".Motor'],
    });
    try {
      await guarded.connect();
      const results = await guarded.writeDetailed({ '"Tank".Motor.Speed': 1, '"Tank".Motor': { Run: true }, '"Tank".Level': 1 });
      const outcome = (key: string) => results[key]!.ok || (!results[key]!.ok && results[key]!.error.code);
      expect(['"Tank".Motor.Speed', '"Tank".Motor', '"Tank".Level'].map(outcome)).to.deep.equal([true, true, 'WRITE_NOT_ALLOWED']);
    } finally {
      await guarded.close();
    }
  });
});

describe('reading and writing by symbol (FETCH/WRITE simulator)', function () {
  this.timeout(10000);
  let server: FetchWriteServer;
  let client: FetchWriteClient;
  let jobs: FetchWriteRequestEvent[];

  beforeEach(async () => {
    const symbols = compileClientSources(...PLANT);
    server = new FetchWriteServer({ port: 0, symbols });
    const { fetchPort } = await server.listen();
    fill(server.memory.area('DB', 1)!, server.memory.area('DB', 2)!);
    client = new FetchWriteClient(parseUrl(`fetchwrite://127.0.0.1?port=${fetchPort}&timeout=1500`) as FetchWriteEndpoint, {
      ...FAST,
      symbols,
    });
    await client.connect();
    jobs = [];
    server.on('request', (r: FetchWriteRequestEvent) => jobs.push(r));
  });

  afterEach(async () => {
    await client.close();
    await server.close();
  });

  it('reads symbols, structs and addresses, one fetch per DB', async () => {
    const got = await client.read<PlcData>(['"Tank".Level', '"Tank".Motor', '"Tank".Steps', 'DB1.DBW4:INT', '"Recipe".Mode']);
    expect(got).to.deep.equal({
      '"Tank".Level': 12.5,
      '"Tank".Motor': MOTOR,
      '"Tank".Steps': STEPS,
      'DB1.DBW4:INT': -7,
      '"Recipe".Mode': 2,
    });
    expect(jobs.filter((j) => j.kind === 'fetch')).to.have.length(2);
  });

  it('writes symbols and a struct with members missing', async () => {
    await client.write({ '"Tank".Motor': { Speed: -5 }, '"Recipe".Setpoint': 1.5 });
    const db1 = server.memory.area('DB', 1)!;
    expect([db1.readInt16BE(8), db1[6]]).to.deep.equal([-5, 0b10]);
    expect(server.memory.area('DB', 2)!.readFloatBE(0)).to.equal(1.5);
  });
});

describe('symbols and the protocols', () => {
  it('freeport refuses a symbol table, saying why', () => {
    let err: unknown;
    try {
      createClient('freeport+tcp://127.0.0.1:4001', { symbols: compileClientSources('Recipe.awl', 'Symbols.asc') });
    } catch (e) {
      err = e;
    }
    expect(err).to.be.instanceOf(PlcError);
    expect((err as PlcError).code).to.equal('NOT_SUPPORTED');
    expect((err as PlcError).message).to.contain("reaches only each station's data area");
  });

  it('createClient passes symbols and the URL strictSymbols to S7 and FETCH/WRITE clients', async () => {
    const symbols = compileClientSources('Recipe.awl', 'Symbols.asc');
    const s7 = createClient('s7://127.0.0.1:1?strictSymbols=true', { symbols });
    const fw = createClient('fetchwrite://127.0.0.1?port=1', { symbols });
    expect(s7.tag('"Recipe".Mode')).to.include({ address: '"Recipe".Mode', area: 'DB', dbNumber: 2, byteOffset: 4, type: 'INT' });
    expect(fw.tag('"Recipe".Setpoint')).to.include({ dbNumber: 2, byteOffset: 0, type: 'REAL' });
    expect((s7 as unknown as { strictSymbols: boolean }).strictSymbols).to.equal(true);
    await Promise.all([s7.close(), fw.close()]);
  });
});

describe('reading and writing by symbol: a table compiled from TIA sources (S7 simulator)', function () {
  this.timeout(10000);
  const SOURCE = [
    'TYPE "Motor"',
    'VERSION : 0.1',
    '   STRUCT',
    '      Run : Bool;',
    '      Fault : Bool;',
    '      Speed : Int;',
    '   END_STRUCT;',
    'END_TYPE',
    '',
    'DATA_BLOCK "Tank"',
    "{ S7_Optimized_Access := 'FALSE' }",
    'VERSION : 0.1',
    'NON_RETAIN',
    '   STRUCT',
    '      Level : Real;',
    '      Motor : "Motor";',
    '      Pumps : Array[1..2] of "Motor";',
    '      Label : String[8];',
    '   END_STRUCT;',
    'BEGIN',
    'END_DATA_BLOCK',
  ].join('\n');

  it('reads and writes members, UDT instances and arrays of them at the offsets the layout gives; the layout check matches', async () => {
    const table = compileSymbols([{ name: 'Tank.db', content: SOURCE }], { db: { Tank: 1 } });
    const server = new S7Server({ port: 0, profile: 's7-300', symbols: table });
    await server.listen();
    const client = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?rack=0&slot=2&strictSymbols=true`) as S7Endpoint, {
      symbols: table,
    });
    try {
      const ok = new Promise((resolve) => client.once('layoutOk', resolve));
      await client.connect();
      await ok;
      // Values put by absolute address at the entries' offsets, read back by name.
      const speed = table.lookup('"Tank".Pumps[2].Speed')!;
      const speedAddress = speed.address!;
      await client.write({
        [speedAddress]: 1234,
        [table.lookup('"Tank".Motor.Fault')!.address!]: true,
        [table.lookup('"Tank".Level')!.address!]: 2.5,
      });
      expect(await client.read<PlcData>(['"Tank".Level', '"Tank".Motor', '"Tank".Pumps'])).to.deep.equal({
        '"Tank".Level': 2.5,
        '"Tank".Motor': { Run: false, Fault: true, Speed: 0 },
        '"Tank".Pumps': [
          { Run: false, Fault: false, Speed: 0 },
          { Run: false, Fault: false, Speed: 1234 },
        ],
      });
      await client.write({ '"Tank".Pumps': [{ Run: true }, undefined], '"Tank".Label': 'ok' });
      expect(await client.read([table.lookup('"Tank".Pumps[1].Run')!.address!, speedAddress, '"Tank".Label'])).to.deep.equal({
        [table.lookup('"Tank".Pumps[1].Run')!.address!]: true,
        [speedAddress]: 1234,
        '"Tank".Label': 'ok',
      });
    } finally {
      await client.close();
      await server.close();
    }
  });
});
