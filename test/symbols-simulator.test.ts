/**
 * The simulators built from DB sources (lib/sim/symbol-memory.ts): each data
 * block at its declared length, holding what a CPU holds after the download
 * (start values, STRING/WSTRING max-length headers, DTL/DT initial values),
 * as our client sees it over a real socket. snap7's view of the same bytes is
 * in test/interop/symbols-snap7-vs-server.test.js.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { FetchWriteClient } from '../lib/fetchwrite/client';
import { FetchWriteServer } from '../lib/fetchwrite/server';
import { S7Client } from '../lib/s7/client';
import { S7Server } from '../lib/s7/server';
import { compileSymbols } from '../lib/symbols/compile';
import { dataBlockImages, memoryFromSymbols } from '../lib/sim/symbol-memory';
import type { SymbolEntry, SymbolTable } from '../lib/symbols/model';
import type { DataTypeName, PlcValue } from '../lib/types';
import { parseUrl, type FetchWriteEndpoint, type S7Endpoint } from '../lib/url';

const FIXTURES = path.resolve(__dirname, '../../test/fixtures/symbols/cli');

/**
 * DB1 "Tank" of test/fixtures/symbols/cli/Tank.db after download, computed by
 * hand from the S7 standard-access layout rules (BOOLs packed from bit 0,
 * every member of 2 bytes or more, STRING, array and struct on an even byte,
 * a struct's length even) and the types' encodings.
 */
const TANK_HEX = [
  '41480000', //                   0 Level REAL 12.5
  '05', //                         4 Running (4.0) TRUE, Alarm (4.1) FALSE, Valve (4.2) TRUE
  '00', //                         5 (padding: Count is an INT)
  'fffe', //                       6 Count INT -2
  '0602414200000000', //           8 Name STRING[6] 'AB': max 6, length 2
  '0300000000', //                16 Note STRING[3], no start value: max 3, length 0
  '00', //                        21 (padding)
  '00030002004800e90000', //      22 Label WSTRING[3] 'Hé': max 3, length 2, UTF-16BE
  '07e80501040c1e0f00000000', //  32 Stamp DTL#2024-05-01-12:30:15 (a Wednesday: weekday 4)
  '07b201010500000000000000', //  44 Since DTL, no start value: DTL#1970-01-01-00:00:00 (a Thursday: 5)
  '000300040005', //              56 Set Array[1..3] of INT [3, 4, 5]
  '05', //                        62 Flags[0] and Flags[2] TRUE
  '02', //                        63 Flags[9] TRUE (bit 63.1)
  '3fc00000', //                  64 Motor.Speed REAL 1.5
  '01', //                        68 Motor.On TRUE (from the BEGIN section)
  '00', //                        69 (padding: the struct's length is even)
].join('');

/** The entries compileSymbols gives for Tank.db with `--db Tank=1`, written out by hand. */
function tankTable(): SymbolTable {
  const entries: SymbolEntry[] = [];
  const add = (
    name: string,
    type: string,
    dataType: DataTypeName | undefined,
    byte: number,
    size: number,
    extra: Partial<SymbolEntry> = {},
  ): void => {
    entries.push({
      name: `"Tank".${name}`,
      type,
      kind: 'elementary',
      ...(dataType ? { dataType } : {}),
      stringLength: 0,
      area: 'DB',
      db: 1,
      byte,
      bit: null,
      size,
      address: '',
      comment: '',
      ...extra,
    });
  };
  const initial = (value: PlcValue) => ({ initial: value });
  add('Level', 'REAL', 'REAL', 0, 4, initial(12.5));
  add('Running', 'BOOL', 'BOOL', 4, 1, { bit: 0, initial: true });
  add('Alarm', 'BOOL', 'BOOL', 4, 1, { bit: 1 });
  add('Valve', 'BOOL', 'BOOL', 4, 1, { bit: 2, initial: true });
  add('Count', 'INT', 'INT', 6, 2, initial(-2));
  add('Name', 'STRING[6]', 'STRING', 8, 8, { stringLength: 6, initial: 'AB' });
  add('Note', 'STRING[3]', 'STRING', 16, 5, { stringLength: 3 });
  add('Label', 'WSTRING[3]', 'WSTRING', 22, 10, { stringLength: 3, initial: 'Hé' });
  add('Stamp', 'DTL', 'DTL', 32, 12, initial(new Date(Date.UTC(2024, 4, 1, 12, 30, 15))));
  add('Since', 'DTL', 'DTL', 44, 12);
  add('Set', 'ARRAY[1..3] OF INT', 'INT', 56, 6, { kind: 'array', children: ['"Tank".Set[1]', '"Tank".Set[2]', '"Tank".Set[3]'] });
  [3, 4, 5].forEach((v, i) => add(`Set[${i + 1}]`, 'INT', 'INT', 56 + 2 * i, 2, initial(v)));
  add('Flags', 'ARRAY[0..9] OF BOOL', 'BOOL', 62, 2, { kind: 'array', bit: 0 });
  for (let i = 0; i < 10; i++)
    add(`Flags[${i}]`, 'BOOL', 'BOOL', 62 + (i >> 3), 1, { bit: i & 7, ...(i === 0 || i === 2 || i === 9 ? initial(true) : {}) });
  add('Motor', 'STRUCT', undefined, 64, 6, { kind: 'struct', children: ['"Tank".Motor.Speed', '"Tank".Motor.On'] });
  add('Motor.Speed', 'REAL', 'REAL', 64, 4, initial(1.5));
  add('Motor.On', 'BOOL', 'BOOL', 68, 1, { bit: 0, initial: true });
  const byName = new Map(entries.map((e) => [e.name, e]));
  return {
    entries,
    blocks: [{ name: 'Tank', db: 1, length: 70, file: 'Tank.db' }],
    types: [],
    lookup: (name) => byName.get(name),
    suggest: () => [],
  };
}

describe('simulators built from DB sources', function () {
  this.timeout(20000);

  it('the fixture hex covers the 70 bytes Tank.db declares', () => {
    expect(TANK_HEX).to.have.length(140);
  });

  it('a data block holds the start values, string headers and DTL initial values a CPU holds after download', () => {
    const images = dataBlockImages(tankTable());
    expect([...images.keys()]).to.deep.equal([1]);
    expect(images.get(1)!.toString('hex')).to.equal(TANK_HEX);
  });

  it('the data block compiled from Tank.db holds the same bytes', () => {
    const table = compileSymbols([{ name: 'Tank.db', content: fs.readFileSync(path.join(FIXTURES, 'Tank.db')) }], { db: { Tank: 1 } });
    expect(table.blocks.map((b) => [b.db, b.length])).to.deep.equal([[1, 70]]);
    expect(dataBlockImages(table).get(1)!.toString('hex')).to.equal(TANK_HEX);
  });

  it('a start value that does not fit its member names the member', () => {
    const table = tankTable();
    const bad = { ...table, entries: table.entries.map((e) => (e.name === '"Tank".Count' ? { ...e, initial: 40000 } : e)) };
    expect(() => dataBlockImages(bad)).to.throw(/"Tank"\.Count/);
  });

  it("the memory has only the sources' data blocks, and the layout's other areas", () => {
    const memory = memoryFromSymbols(tankTable(), { flags: 16 });
    expect(memory.dataBlockNumbers()).to.deep.equal([1]);
    expect(memory.area('DB', 1)!.toString('hex')).to.equal(TANK_HEX);
    expect(memory.area('M')!.length).to.equal(16);
    expect(memory.check('DB', 1, 69, 1)).to.equal(undefined);
    expect(memory.check('DB', 1, 70, 1)).to.equal('OUT_OF_RANGE');
  });

  describe('S7Server({ symbols })', () => {
    let server: S7Server;
    let client: S7Client;

    beforeEach(async () => {
      server = new S7Server({ port: 0, profile: 's7-300', symbols: tankTable() });
      const port = await server.listen();
      client = new S7Client(parseUrl(`s7://127.0.0.1:${port}?rack=0&slot=2`) as S7Endpoint);
      await client.connect();
    });

    afterEach(async () => {
      await client.close();
      await server.close();
    });

    it('our client reads the start values by address', async () => {
      const values = await client.read([
        'DB1.DBD0:REAL',
        'DB1.DBX4.0',
        'DB1.DBX4.1',
        'DB1.DBW6:INT',
        'DB1.DBB8:STRING[6]',
        'DB1.DBB16:STRING[3]',
        'DB1.DBB22:WSTRING[3]',
        'DB1.DBB32:DTL',
        'DB1.DBB44:DTL',
        'DB1,INT56.3',
        'DB1,X62.0.10',
        'DB1.DBD64:REAL',
        'DB1.DBX68.0',
      ]);
      expect(values).to.deep.equal({
        'DB1.DBD0:REAL': 12.5,
        'DB1.DBX4.0': true,
        'DB1.DBX4.1': false,
        'DB1.DBW6:INT': -2,
        'DB1.DBB8:STRING[6]': 'AB',
        'DB1.DBB16:STRING[3]': '',
        'DB1.DBB22:WSTRING[3]': 'Hé',
        'DB1.DBB32:DTL': new Date(Date.UTC(2024, 4, 1, 12, 30, 15)),
        'DB1.DBB44:DTL': new Date(Date.UTC(1970, 0, 1)),
        'DB1,INT56.3': [3, 4, 5],
        'DB1,X62.0.10': [true, false, true, false, false, false, false, false, false, true],
        'DB1.DBD64:REAL': 1.5,
        'DB1.DBX68.0': true,
      });
    });

    it('a write of a STRING keeps the max-length header the download put there', async () => {
      await client.write({ 'DB1.DBB16:STRING[3]': 'xyz' });
      expect(server.memory.area('DB', 1)!.subarray(16, 21).toString('hex')).to.equal('030378797a');
    });

    it('block info reports the declared length; a DB the sources do not declare does not exist', async () => {
      const info = await client.blockInfo('DB', 1);
      expect(info.mc7Size).to.equal(70);
      expect(await client.listBlocksOfType('DB')).to.deep.equal([1]);
      const results = await client.readDetailed(['DB2.DBB0', 'DB1.DBB70']);
      expect(results['DB2.DBB0']!.ok ? undefined : results['DB2.DBB0']!.error.code).to.equal('OBJECT_DOES_NOT_EXIST');
      expect(results['DB1.DBB70']!.ok ? undefined : results['DB1.DBB70']!.error.code).to.equal('ADDRESS_OUT_OF_RANGE');
    });
  });

  it('FetchWriteServer({ symbols }) serves the same bytes', async () => {
    const server = new FetchWriteServer({ port: 0, symbols: tankTable() });
    const { fetchPort } = await server.listen();
    const client = new FetchWriteClient(parseUrl(`fetchwrite://127.0.0.1?port=${fetchPort}`) as FetchWriteEndpoint);
    try {
      await client.connect();
      expect(await client.read(['DB1,B0.70'])).to.deep.equal({ 'DB1,B0.70': [...Buffer.from(TANK_HEX, 'hex')] });
    } finally {
      await client.close();
      await server.close();
    }
  });
});
