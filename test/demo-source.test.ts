/**
 * The demo plant's DB1 as a PLC source (lib/plant/source.ts, demo/Plant.db):
 * the file a user opens is the text the library ships, written the way TIA
 * Portal's "Generate source from blocks" writes it, and a standard-access
 * data block the parser reads as the programmer declared it.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { DEMO_SYMBOLS, DEMO_TAGS } from '../lib/plant/process';
import { PLANT_DB_NUMBERS, PLANT_SOURCE } from '../lib/plant/source';
import type { DataBlockDecl, TypeRef } from '../lib/symbols/model';
import { parseBlockSource } from '../lib/symbols/source-parser';

const ROOT = path.resolve(__dirname, '../..');
const FILE = path.join(ROOT, 'demo/Plant.db');

describe('demo plant: DB1 as a TIA source', () => {
  it('demo/Plant.db is the shipped source as TIA writes a file: UTF-8 with a BOM, CRLF line ends', () => {
    const bytes = fs.readFileSync(FILE);
    expect([...bytes.subarray(0, 3)]).to.deep.equal([0xef, 0xbb, 0xbf]);
    const text = bytes.subarray(3).toString('utf8');
    expect(text.split('\r\n').length).to.be.greaterThan(10);
    expect(text.replace(/\r\n/g, '')).to.not.include('\n');
    expect(text.replace(/\r\n/g, '\n')).to.equal(PLANT_SOURCE.content);
    expect(path.basename(FILE)).to.equal(PLANT_SOURCE.name);
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
});
