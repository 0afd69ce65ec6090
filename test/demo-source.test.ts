/**
 * The demo plant's DB1 as a PLC source (lib/plant/source.ts, demo/Plant.db; its optimized DB2, demo/Tank.db):
 * the file a user opens is the text the library ships, written the way TIA
 * Portal's "Generate source from blocks" writes it, and a standard-access
 * data block the parser reads as the programmer declared it.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { formatAddress, parseAddress } from '../lib/address';
import { connect } from '../lib/connect';
import { startPlant } from '../lib/plant/plant';
import { DEMO_SYMBOLS, DEMO_TAGS, DemoProcess, THERMAL } from '../lib/plant/process';
import { PLANT_DB_NUMBERS, PLANT_SOURCE, TANK_DB_NUMBERS, TANK_SOURCE } from '../lib/plant/source';
import { PlcMemory } from '../lib/sim/memory';
import { compileSymbols } from '../lib/symbols';
import { dataBlockImages } from '../lib/sim/symbol-memory';
import type { DataBlockDecl, TypeRef } from '../lib/symbols/model';
import { parseBlockSource } from '../lib/symbols/source-parser';

/** An address in one spelling, so that `DB1.DBD0:REAL` and `DB1,REAL0` compare equal. */
const canonical = (address: string) => formatAddress(parseAddress(address));

const ROOT = path.resolve(__dirname, '../..');
const FILE = path.join(ROOT, 'demo/Plant.db');

describe('demo plant: DB1 as a TIA source', () => {
  for (const [file, source] of [
    [FILE, PLANT_SOURCE],
    [path.join(ROOT, 'demo/Tank.db'), TANK_SOURCE],
  ] as const) {
    it(`demo/${source.name} is the shipped source as TIA writes a file: UTF-8 with a BOM, CRLF line ends`, () => {
      const bytes = fs.readFileSync(file);
      expect([...bytes.subarray(0, 3)]).to.deep.equal([0xef, 0xbb, 0xbf]);
      const text = bytes.subarray(3).toString('utf8');
      expect(text.split('\r\n').length).to.be.greaterThan(10);
      expect(text.replace(/\r\n/g, '')).to.not.include('\n');
      expect(text.replace(/\r\n/g, '\n')).to.equal(source.content);
      expect(path.basename(file)).to.equal(source.name);
    });
  }

  it('demo/Tank.db (the README\'s example of an optimized source) declares the optimized DB "Tank" the demo CPU serves as DB2, needing no other file', () => {
    const [tank, ...others] = parseBlockSource({ name: 'Tank.db', content: fs.readFileSync(path.join(ROOT, 'demo/Tank.db')) });
    expect(others).to.deep.equal([]);
    expect(tank).to.include({ kind: 'db', name: 'Tank', optimized: true });
    const table = compileSymbols([TANK_SOURCE], { db: TANK_DB_NUMBERS });
    expect(table.blocks.map((b) => ({ name: b.name, db: b.db, length: b.length }))).to.deep.equal([{ name: 'Tank', db: 2, length: null }]);
  });

  it('declares one global DB "Plant" with standard access, numbered by PLANT_DB_NUMBERS, a member for every demo tag', () => {
    const file = parseBlockSource({ name: 'Plant.db', content: fs.readFileSync(FILE) });
    expect(file).to.deep.equal(parseBlockSource(PLANT_SOURCE));
    expect(file).to.have.length(1);
    const plant = file[0] as DataBlockDecl;
    expect(plant).to.include({ kind: 'db', name: 'Plant', optimized: false });
    expect(plant.attributes.S7_Optimized_Access).to.equal('FALSE');
    expect(Object.keys(PLANT_DB_NUMBERS)).to.deep.equal([plant.name]);
    const body = plant.body as Extract<TypeRef, { kind: 'struct' }>;
    const members = body.members.map((m) => `"${plant.name}".${m.name}`);
    expect(members).to.have.members(Object.values(DEMO_SYMBOLS));
    expect(Object.keys(DEMO_SYMBOLS)).to.deep.equal(Object.keys(DEMO_TAGS));
    // A real programmer's DB: every member says what it is.
    for (const m of body.members) expect(m.comment, m.name).to.match(/\w{3,}/);
  });

  it('compiles to exactly the offsets the process uses: every name of DEMO_SYMBOLS is the address of DEMO_TAGS, in a block of 20 bytes', () => {
    const table = compileSymbols([PLANT_SOURCE], { db: PLANT_DB_NUMBERS });
    expect(table.blocks.map((b) => ({ name: b.name, db: b.db, length: b.length }))).to.deep.equal([{ name: 'Plant', db: 1, length: 20 }]);
    for (const [key, name] of Object.entries(DEMO_SYMBOLS)) {
      const entry = table.lookup(name);
      expect(entry, name).to.not.equal(undefined);
      expect(entry!.name).to.equal(name);
      expect(canonical(entry!.address!), name).to.equal(canonical(DEMO_TAGS[key as keyof typeof DEMO_TAGS]));
    }
    // No member the process does not know: the table is the plant's memory map, nothing beside it.
    expect(table.entries.map((e) => e.name)).to.have.members(Object.values(DEMO_SYMBOLS));
  });

  it('its start values are those the process starts from on blank memory: level 20 %, temperature at ambient, the rest 0', () => {
    const table = compileSymbols([PLANT_SOURCE], { db: PLANT_DB_NUMBERS });
    const initial = Object.fromEntries(table.entries.map((e) => [e.name, e.initial]));
    expect(initial).to.deep.equal({
      ...Object.fromEntries(Object.values(DEMO_SYMBOLS).map((n) => [n, undefined])),
      [DEMO_SYMBOLS.level]: 20,
      [DEMO_SYMBOLS.temperature]: THERMAL.ambient,
    });
    const blank = new PlcMemory();
    new DemoProcess(blank).start().stop();
    // The first 20 bytes of a process started on blank memory are the bytes the source's start values give.
    expect(blank.area('DB', 1)!.subarray(0, 20).toString('hex')).to.equal(dataBlockImages(table).get(1)!.toString('hex'));
  });

  it('the demo plant serves DB1 as the source declares it, 20 bytes, to S7 and FETCH/WRITE alike; beside it only the optimized DB2 "Tank", which PUT/GET refuses', async () => {
    const plant = await startPlant({ ports: { s7: 0, fetch: 0, write: 0, freeport: 0 } });
    const s7 = await connect(plant.urls.s7);
    try {
      plant.process.stop();
      expect(plant.memory.dataBlockNumbers()).to.deep.equal([1, 2]);
      expect(plant.memory.area('DB', 1)!.length).to.equal(20);
      expect([...plant.s7plus.model.optimizedDbs]).to.deep.equal([2]);
      const r = await s7.readDetailed(['DB1.DBW12:INT', 'DB2.DBB0:BYTE']);
      expect(r['DB1.DBW12:INT']!.ok).to.equal(true);
      expect(r['DB2.DBB0:BYTE']!.ok, 'DB2 over PUT/GET').to.equal(false);
      expect(plant.symbols.blocks).to.deep.equal(compileSymbols([PLANT_SOURCE], { db: PLANT_DB_NUMBERS }).blocks);
      // The CP serves the CPU's memory.
      expect(plant.fetchwrite.memory).to.equal(plant.memory);
    } finally {
      await s7.close();
      await plant.close();
    }
  });

  it('a client given the source reads the plant by name over S7 and FETCH/WRITE, the values the process holds, and a write by name starts the motor', async () => {
    const plant = await startPlant({ ports: { s7: 0, fetch: 0, write: 0, freeport: 0 } });
    const symbols = compileSymbols([PLANT_SOURCE], { db: PLANT_DB_NUMBERS });
    const clients = [await connect(plant.urls.s7, { symbols }), await connect(plant.urls.fetchwrite, { symbols })];
    try {
      plant.process.stop();
      for (let i = 0; i < 25; i++) plant.process.step();
      const held = plant.process.snapshot();
      const names = [DEMO_SYMBOLS.level, DEMO_SYMBOLS.parts, DEMO_SYMBOLS.plcHeartbeat, DEMO_SYMBOLS.temperature, DEMO_SYMBOLS.heater];
      for (const client of clients) {
        expect(await client.read(names), client.protocol).to.deep.equal({
          [DEMO_SYMBOLS.level]: held.level,
          [DEMO_SYMBOLS.parts]: held.parts,
          [DEMO_SYMBOLS.plcHeartbeat]: held.heartbeat,
          [DEMO_SYMBOLS.temperature]: held.temperature,
          [DEMO_SYMBOLS.heater]: held.heater,
        });
      }
      expect(held.heartbeat).to.be.greaterThan(0);
      await clients[1]!.write({ [DEMO_SYMBOLS.run]: true });
      expect(plant.memory.area('DB', 1)![4]! & 0x01).to.equal(1);
      for (let i = 0; i < 5; i++) plant.process.step();
      expect(await clients[0]!.read([DEMO_SYMBOLS.running, DEMO_SYMBOLS.speed])).to.deep.equal({
        [DEMO_SYMBOLS.running]: true,
        [DEMO_SYMBOLS.speed]: plant.process.snapshot().speed,
      });
      expect(plant.process.snapshot().speed).to.be.greaterThan(0);
    } finally {
      for (const c of clients) await c.close();
      await plant.close();
    }
  });
});
