import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { deflateRawSync } from 'node:zlib';
import { SourceError } from '../lib/errors';
import type { SymbolTableRow } from '../lib/symbols/model';
import { readSymbolTable } from '../lib/symbols/symbol-files';

/** The fixtures and the script that wrote them (make-fixtures.py says how). */
const FIXTURES = path.resolve(__dirname, '../../test/fixtures/symbols/tables');
const fixture = (name: string): Uint8Array => fs.readFileSync(path.join(FIXTURES, name));

/** name → address, the comparison most tests make. */
const addresses = (rows: readonly SymbolTableRow[]) => Object.fromEntries(rows.map((r) => [r.name, r.address]));

function sourceError(run: () => unknown): SourceError {
  try {
    run();
  } catch (err) {
    expect(err).to.be.instanceOf(SourceError);
    expect((err as SourceError).code).to.equal('INVALID_SOURCE');
    return err as SourceError;
  }
  throw new Error('expected a SourceError');
}

/** Windows-1252 bytes of a text of Latin-1 letters (what STEP 7 writes). */
const cp1252 = (text: string) => Buffer.from(text, 'latin1');

// ---------------------------------------------------------------- a zip writer for the hostile workbooks

const CRC_TABLE = Array.from({ length: 256 }, (_, n) => {
  let c = n;
  for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  return c >>> 0;
});
function crc32(data: Buffer): number {
  let c = 0xffffffff;
  for (const b of data) c = CRC_TABLE[(c ^ b) & 0xff]! ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

interface Part {
  name: string;
  data: Buffer;
  /** 0 stored, 8 deflated (the default). */
  method?: number;
  /** The inflated size the directory claims; the real one unless given. */
  declaredSize?: number;
  flags?: number;
}

function zip(parts: readonly Part[]): Buffer {
  const locals: Buffer[] = [];
  const central: Buffer[] = [];
  let offset = 0;
  for (const p of parts) {
    const method = p.method ?? 8;
    const body = method === 8 ? deflateRawSync(p.data) : p.data;
    const name = Buffer.from(p.name, 'utf8');
    const local = Buffer.alloc(30);
    local.writeUInt32LE(0x04034b50, 0);
    local.writeUInt16LE(20, 4);
    local.writeUInt16LE(p.flags ?? 0, 6);
    local.writeUInt16LE(method, 8);
    local.writeUInt32LE(crc32(p.data), 14);
    local.writeUInt32LE(body.length, 18);
    local.writeUInt32LE(p.declaredSize ?? p.data.length, 22);
    local.writeUInt16LE(name.length, 26);
    const entry = Buffer.alloc(46);
    entry.writeUInt32LE(0x02014b50, 0);
    entry.writeUInt16LE(20, 4);
    entry.writeUInt16LE(20, 6);
    entry.writeUInt16LE(p.flags ?? 0, 8);
    entry.writeUInt16LE(method, 10);
    entry.writeUInt32LE(crc32(p.data), 16);
    entry.writeUInt32LE(body.length, 20);
    entry.writeUInt32LE(p.declaredSize ?? p.data.length, 24);
    entry.writeUInt16LE(name.length, 28);
    entry.writeUInt32LE(offset, 42);
    locals.push(local, name, body);
    central.push(entry, name);
    offset += local.length + name.length + body.length;
  }
  const directory = Buffer.concat(central);
  const end = Buffer.alloc(22);
  end.writeUInt32LE(0x06054b50, 0);
  end.writeUInt16LE(parts.length, 8);
  end.writeUInt16LE(parts.length, 10);
  end.writeUInt32LE(directory.length, 12);
  end.writeUInt32LE(offset, 16);
  return Buffer.concat([...locals, directory, end]);
}

const WORKBOOK =
  '<workbook xmlns="http://schemas.openxmlformats.org/spreadsheetml/2006/main" xmlns:r="http://schemas.openxmlformats.org/officeDocument/2006/relationships">' +
  '<sheets><sheet name="PLC Tags" sheetId="1" r:id="rId1"/></sheets></workbook>';
const RELS =
  '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">' +
  '<Relationship Id="rId1" Type="http://schemas.openxmlformats.org/officeDocument/2006/relationships/worksheet" Target="worksheets/sheet1.xml"/></Relationships>';

/** A one-sheet workbook of inline-string cells. */
function workbook(rows: readonly (readonly string[])[], sheet: Partial<Part> = {}, extra: Part[] = []): Buffer {
  const cells = rows
    .map((row, r) => {
      const cs = row.map((text, c) => `<c r="${String.fromCharCode(65 + c)}${r + 1}" t="inlineStr"><is><t>${text}</t></is></c>`);
      return `<row r="${r + 1}">${cs.join('')}</row>`;
    })
    .join('');
  const xml = `<worksheet xmlns="http://schemas.openxmlformats.org/spreadsheetml/2006/main"><sheetData>${cells}</sheetData></worksheet>`;
  return zip([
    { name: 'xl/workbook.xml', data: Buffer.from(WORKBOOK) },
    { name: 'xl/_rels/workbook.xml.rels', data: Buffer.from(RELS) },
    { name: 'xl/worksheets/sheet1.xml', data: Buffer.from(xml), ...sheet },
    ...extra,
  ]);
}

const HEADER = ['Name', 'Path', 'Data Type', 'Logical Address', 'Comment'];

// ---------------------------------------------------------------- the tests

describe('symbol tables (lib/symbols/symbol-files.ts)', () => {
  describe('STEP 7 .sdf (Windows-1252, German mnemonics)', () => {
    const rows = readSymbolTable({ name: 'Symbole.sdf', content: fixture('step7-de.sdf') });

    it('reads every row with its address in our syntax, its type only where the address does not say it', () => {
      expect(addresses(rows)).to.deep.equal({
        Not_Aus: 'I0.0',
        Motor_ein: 'Q4.0',
        Störung: 'M1.7',
        Zähler_Byte: 'MB2',
        Drehzahl: 'MW10:INT',
        Temperatur: 'MD20:REAL',
        Eingänge_1: 'IB1',
        Schalter: 'IW2',
        Sollwert: 'QW6:INT',
        Zeitstempel: 'ID8:DINT',
        Füllstand: 'PIW256:INT',
        Ventil_Ausgang: 'PQW512',
        Verzögerung: 'T5',
        Stückzahl: 'C5',
        Rezept: 'DB10',
        Regler: 'FB3',
        Berechnung: 'FC1',
        Motor_Typ: 'UDT1',
        Zyklus: 'OB1',
      });
    });

    it('keeps the data type and the comment (umlauts decoded from Windows-1252), and where each row stands', () => {
      const füllstand = rows.find((r) => r.name === 'Füllstand')!;
      expect(füllstand).to.deep.equal({
        name: 'Füllstand',
        address: 'PIW256:INT',
        dataType: 'INT',
        comment: 'Füllstand Behälter',
        at: { file: 'Symbole.sdf', line: 11, column: 1 },
      });
      expect(rows[0]!.comment).to.equal('Not-Aus-Taster (Öffner)');
      expect(rows.find((r) => r.name === 'Rezept')!.dataType).to.equal('DB 10');
      expect(rows.find((r) => r.name === 'Temperatur')!.comment).to.equal('°C');
    });

    it('reads the same table given as text', () => {
      const text = Buffer.from(fixture('step7-de.sdf')).toString('latin1');
      expect(readSymbolTable({ name: 'x.SDF', content: text })).to.deep.equal(rows.map((r) => ({ ...r, at: { ...r.at, file: 'x.SDF' } })));
    });
  });

  describe('STEP 7 .asc (fixed width, English mnemonics)', () => {
    const rows = readSymbolTable({ name: 'Symbols.asc', content: fixture('step7-en.asc') });

    it('reads every record', () => {
      expect(addresses(rows)).to.deep.equal({
        'Start button': 'I0.0',
        Lamp: 'Q4.1',
        'Level raw': 'IW64:INT',
        Flow: 'QD8:REAL',
        Counts: 'ID12:DINT',
        Valve: 'QB3',
        'Analog in': 'PIW256:INT',
        'Analog out': 'PQW512:INT',
        'Batch counter': 'C5',
        Delay: 'T7',
        'Cycle time': 'MW30:S5TIME',
        Tank: 'DB1',
      });
      expect(rows[2]!.comment).to.equal('Füllstand (raw)');
      expect(rows[2]!.at).to.deep.equal({ file: 'Symbols.asc', line: 3, column: 5 });
    });

    it('reads records whose trailing spaces an editor has cut', () => {
      const text = '126,Lamp                    Q       4.1 BOOL\r\n\r\n126,Speed                   MW     10   INT';
      expect(addresses(readSymbolTable({ name: 'a.asc', content: text }))).to.deep.equal({ Lamp: 'Q4.1', Speed: 'MW10:INT' });
    });

    it('refuses a record that does not start with 126, naming its line', () => {
      const err = sourceError(() =>
        readSymbolTable({ name: 'a.asc', content: '126,Lamp                    Q       4.1 BOOL\r\nLamp2 Q 4.2 BOOL\r\n' }),
      );
      expect(err.message).to.equal('a.asc:2:1: expected an ASC symbol record starting with "126,"');
    });

    it('names the column of a bad address in a record', () => {
      const err = sourceError(() => readSymbolTable({ name: 'a.asc', content: '126,Lamp                    X       4.1 BOOL' }));
      expect(err.message).to.match(/^a\.asc:1:29: symbol "Lamp": "X {7}4\.1" is not an address a symbol table holds/);
    });
  });

  describe('STEP 7 .seq (assignment list)', () => {
    it('reads TAB address TAB symbol TAB comment, without a data type', () => {
      const rows = readSymbolTable({ name: 'Symbole.seq', content: fixture('step7.seq') });
      expect(addresses(rows)).to.deep.equal({
        Not_Aus: 'I0.0',
        Motor_ein: 'Q4.0',
        Drehzahl: 'MW10',
        'green_phase_ped.': 'T2',
        Rezept: 'DB10',
      });
      expect(rows[2]).to.deep.equal({
        name: 'Drehzahl',
        address: 'MW10',
        dataType: '',
        comment: 'Drehzahl in 1/min',
        at: { file: 'Symbole.seq', line: 3, column: 8 },
      });
    });

    it('takes LF or CRLF line ends and a comment written with a semicolon', () => {
      const rows = readSymbolTable({ name: 's.seq', content: '\tE 0.1\tTaster\t;Taster 1\n\tA 0.0\tLampe\r\n' });
      expect(rows.map((r) => [r.name, r.address, r.comment, r.at.line])).to.deep.equal([
        ['Taster', 'I0.1', 'Taster 1', 1],
        ['Lampe', 'Q0.0', '', 2],
      ]);
    });
  });

  describe('the address mnemonics', () => {
    const one = (address: string, type = '') => readSymbolTable({ name: 't.sdf', content: `"S","${address}","${type}",""` })[0]!.address;

    it('reads the German and the English families alike', () => {
      const pairs: [string, string, string][] = [
        ['E 1.2', 'I 1.2', 'I1.2'],
        ['EB 3', 'IB 3', 'IB3'],
        ['EW 4', 'IW 4', 'IW4'],
        ['ED 8', 'ID 8', 'ID8'],
        ['A 1.2', 'Q 1.2', 'Q1.2'],
        ['AB 3', 'QB 3', 'QB3'],
        ['AW 4', 'QW 4', 'QW4'],
        ['AD 8', 'QD 8', 'QD8'],
        ['PEB 256', 'PIB 256', 'PIB256'],
        ['PEW 256', 'PIW 256', 'PIW256'],
        ['PED 256', 'PID 256', 'PID256'],
        ['PAB 256', 'PQB 256', 'PQB256'],
        ['PAW 256', 'PQW 256', 'PQW256'],
        ['PAD 256', 'PQD 256', 'PQD256'],
        ['Z 5', 'C 5', 'C5'],
      ];
      for (const [german, english, ours] of pairs) {
        expect(one(german), german).to.equal(ours);
        expect(one(english), english).to.equal(ours);
      }
      expect(one('M 0.0')).to.equal('M0.0');
      expect(one('MB 1')).to.equal('MB1');
      expect(one('T 5')).to.equal('T5');
    });

    it("adds the type where it is not the address's own, and checks that it fits", () => {
      expect(one('MW 10', 'INT')).to.equal('MW10:INT');
      expect(one('MW 10', 'WORD')).to.equal('MW10');
      expect(one('MD 20', 'REAL')).to.equal('MD20:REAL');
      expect(one('MD 20', 'DWORD')).to.equal('MD20');
      expect(one('I 0.0', 'BOOL')).to.equal('I0.0');
      expect(one('MW 4', 'S5TIME')).to.equal('MW4:S5TIME');
      expect(one('MD 4', 'TIME_OF_DAY')).to.equal('MD4:TIME_OF_DAY');
      expect(one('MD 4', 'Tod')).to.equal('MD4:TIME_OF_DAY');
      expect(one('MB 0', 'CHAR')).to.equal('MB0:CHAR');
      expect(one('T 5', 'TIMER')).to.equal('T5');
      expect(one('Z 5', 'COUNTER')).to.equal('C5');
    });

    it("reads TIA's % form and addresses without spaces, in any case", () => {
      expect(one('%MW10', 'Int')).to.equal('MW10:INT');
      expect(one('%i0.7', 'Bool')).to.equal('I0.7');
      expect(one('%IX1.3', 'Bool')).to.equal('I1.3');
      expect(one('mw  010', 'int')).to.equal('MW10:INT');
      expect(one('db 007')).to.equal('DB7');
    });

    it('refuses what a symbol table cannot hold, naming symbol, line and column', () => {
      const bad = (address: string, type: string) =>
        sourceError(() => readSymbolTable({ name: 't.sdf', content: `"Ok","M 0.0","BOOL",""\r\n"Speed","${address}","${type}",""` }))
          .message;
      expect(bad('MW 10', 'DINT')).to.equal(
        't.sdf:2:9: symbol "Speed": invalid address "MW10:DINT": DINT needs a double word, MW is a word',
      );
      expect(bad('M 0.0', 'INT')).to.equal(
        't.sdf:2:9: symbol "Speed": invalid address "M0.0:INT": INT cannot start at a bit; use a B, W or D address',
      );
      expect(bad('M 0.8', 'BOOL')).to.equal('t.sdf:2:9: symbol "Speed": invalid address "M0.8": bit 8 out of range (0..7)');
      expect(bad('MW 10', 'Motor')).to.equal(
        't.sdf:2:17: symbol "Speed": "Motor" is not a data type an address can have (e.g. BOOL, INT, REAL)',
      );
      expect(bad('MW 10.1', 'INT')).to.match(/^t\.sdf:2:9: symbol "Speed": "MW 10\.1" is not a STEP 7 address/);
      expect(bad('M 10', 'INT')).to.match(/^t\.sdf:2:9: symbol "Speed": "M 10" is not a STEP 7 address/);
      expect(bad('DB1.DBW2', 'INT')).to.match(/^t\.sdf:2:9: symbol "Speed": "DB1\.DBW2" is not an address a symbol table holds/);
      expect(bad('', 'INT')).to.equal('t.sdf:2:9: symbol "Speed": no address');
      expect(bad('MW 70000', 'INT')).to.match(/^t\.sdf:2:9: symbol "Speed": invalid address "MW70000:INT": offset 70000 out of range/);
    });

    it('refuses a row without a name, or with control characters in it', () => {
      expect(sourceError(() => readSymbolTable({ name: 't.sdf', content: '"","M 0.0","BOOL",""' })).message).to.equal(
        't.sdf:1:1: a row without a symbol name',
      );
      expect(sourceError(() => readSymbolTable({ name: 't.sdf', content: '"A\u0007","M 0.0","BOOL",""' })).message).to.match(
        /^t\.sdf:1:1: symbol "A\\u0007": unexpected control character/,
      );
      expect(sourceError(() => readSymbolTable({ name: 't.sdf', content: '"lonely"' })).message).to.match(
        /^t\.sdf:1:1: expected "Symbol","Address"/,
      );
    });
  });

  describe('TIA Portal .csv', () => {
    const expected = {
      'Start button': 'I0.0',
      'Motor on': 'Q0.1',
      'Speed setpoint': 'MW10:INT',
      Temperature: 'MD20:REAL',
      Füllstand: 'IW64:INT',
      'Status word': 'MW12',
      'Run time': 'MD24:TIME',
      Flags: 'MB3',
      'Big counter': 'MB40:LINT',
    };
    const utf8 = Buffer.from(fixture('tia-tags.csv'));

    it('reads the PLC tag table columns from UTF-8 with BOM, separated by semicolons, other columns ignored', () => {
      const rows = readSymbolTable({ name: 'PLCTags.csv', content: utf8 });
      expect(addresses(rows)).to.deep.equal(expected);
      expect(rows[4]).to.deep.equal({
        name: 'Füllstand',
        address: 'IW64:INT',
        dataType: 'Int',
        comment: 'Füllstand Behälter',
        at: { file: 'PLCTags.csv', line: 6, column: 1 },
      });
    });

    it('reads the same table as UTF-16 (LE and BE, with BOM), as Windows-1252 and comma-separated', () => {
      const text = utf8.subarray(3).toString('utf8');
      const le = Buffer.concat([Buffer.from([0xff, 0xfe]), Buffer.from(text, 'utf16le')]);
      const be = Buffer.from(le);
      be.swap16();
      expect(addresses(readSymbolTable({ name: 'a.csv', content: le }))).to.deep.equal(expected);
      expect(addresses(readSymbolTable({ name: 'a.csv', content: be }))).to.deep.equal(expected);
      const latin = readSymbolTable({ name: 'a.csv', content: cp1252(text) });
      expect(latin[4]!.comment).to.equal('Füllstand Behälter');
      const comma = text.replace(/;/g, ',');
      expect(addresses(readSymbolTable({ name: 'a.csv', content: comma }))).to.deep.equal(expected);
      expect(addresses(readSymbolTable({ name: 'a.csv', content: text.replace(/;/g, '\t') }))).to.deep.equal(expected);
    });

    it('finds the columns by their titles in any order, German titles too', () => {
      const csv = 'Kommentar;Logische Adresse;Datentyp;Name\r\n"Motor ""A""; links";%Q0.0;Bool;Motor A\r\n';
      expect(readSymbolTable({ name: 'v.csv', content: csv })).to.deep.equal([
        { name: 'Motor A', address: 'Q0.0', dataType: 'Bool', comment: 'Motor "A"; links', at: { file: 'v.csv', line: 2, column: 33 } },
      ]);
    });

    it('names line and column of a row that does not read', () => {
      const csv = 'Name,Data Type,Logical Address\nA,Bool,%I0.0\nB,Int,%MX10\n';
      expect(sourceError(() => readSymbolTable({ name: 'v.csv', content: csv })).message).to.equal(
        'v.csv:3:7: symbol "B": "%MX10" is not a STEP 7 address (e.g. I 0.0, MW 10, QD 4)',
      );
      const quoted = 'Name,Data Type,Logical Address,Comment\nA,Bool,%I0.0,"two\r\nlines"\n"C",Real,"%MW4"\n';
      expect(sourceError(() => readSymbolTable({ name: 'v.csv', content: quoted })).message).to.equal(
        'v.csv:4:10: symbol "C": invalid address "MW4:REAL": REAL needs a double word, MW is a word',
      );
    });

    it('refuses a table without its header row', () => {
      expect(sourceError(() => readSymbolTable({ name: 'v.csv', content: 'A,Bool,%I0.0\n' })).message).to.equal(
        'v.csv:1:1: expected a header row with the columns Name and Logical Address (as TIA Portal exports a PLC tag table)',
      );
    });
  });

  describe('TIA Portal .xlsx', () => {
    it('reads the sheet "PLC Tags" of a workbook zipped by another writer (shared and inline strings, empty cells)', () => {
      const rows = readSymbolTable({ name: 'PLCTags.xlsx', content: fixture('PLCTags.xlsx') });
      expect(addresses(rows)).to.deep.equal({
        'Start button': 'I0.0',
        'Motor on': 'Q0.1',
        'Speed setpoint': 'MW10:INT',
        Temperature: 'MD20:REAL',
        Füllstand: 'IW64:INT',
        'Status word': 'MW12',
        'Run time': 'MD24:TIME',
        Flags: 'MB3',
        'Big counter': 'MB40:LINT',
      });
      expect(rows[0]).to.deep.equal({
        name: 'Start button',
        address: 'I0.0',
        dataType: 'Bool',
        comment: 'Green button',
        at: { file: 'PLCTags.xlsx', line: 2, column: 1 },
      });
      expect(rows[1]!.comment).to.equal('');
      expect(rows[2]!.comment).to.equal('rpm'); // the inline string cell
      expect(rows[3]!.comment).to.equal('Tank <1> & "2"');
    });

    it('names the row and the column (D for Logical Address) of a bad cell', () => {
      const bytes = workbook([HEADER, ['A', 'T', 'Bool', '%I0.0', ''], ['B', 'T', 'DInt', '%MW10', '']]);
      expect(sourceError(() => readSymbolTable({ name: 'W.xlsx', content: bytes })).message).to.equal(
        'W.xlsx:3:4: symbol "B": invalid address "MW10:DINT": DINT needs a double word, MW is a word',
      );
    });

    it('finds the tag sheet by its columns when it is not named "PLC Tags", and reads cells written out of order or without references', () => {
      const xml =
        '<x:worksheet xmlns:x="http://schemas.openxmlformats.org/spreadsheetml/2006/main"><x:sheetData>' +
        '<x:row><x:c t="inlineStr"><x:is><x:t>Logical Address</x:t></x:is></x:c><x:c t="inlineStr"><x:is><x:t>Name</x:t></x:is></x:c></x:row>' +
        '<x:row r="5"><x:c r="B5" t="str"><x:v>Lamp &amp; horn</x:v></x:c><x:c r="A5" t="str"><x:v>%Q0.0</x:v></x:c></x:row>' +
        '</x:sheetData></x:worksheet>';
      const book = zip([
        { name: 'xl/workbook.xml', data: Buffer.from(WORKBOOK.replace('PLC Tags', 'Tabelle1')) },
        { name: 'xl/_rels/workbook.xml.rels', data: Buffer.from(RELS) },
        { name: 'xl/worksheets/sheet1.xml', data: Buffer.from(xml), method: 0 },
      ]);
      expect(readSymbolTable({ name: 'w.xlsx', content: book })).to.deep.equal([
        { name: 'Lamp & horn', address: 'Q0.0', dataType: '', comment: '', at: { file: 'w.xlsx', line: 5, column: 2 } },
      ]);
    });

    it('refuses a workbook without a tag sheet (naming its sheets), or a "PLC Tags" sheet without its header', () => {
      expect(sourceError(() => readSymbolTable({ name: 'w.xlsx', content: workbook([['Something', 'else']]) })).message).to.equal(
        'w.xlsx:1:1: expected a header row with the columns Name and Logical Address (as TIA Portal exports a PLC tag table)',
      );
      const unnamed = zip([
        { name: 'xl/workbook.xml', data: Buffer.from(WORKBOOK.replace('PLC Tags', 'Sheet1')) },
        { name: 'xl/_rels/workbook.xml.rels', data: Buffer.from(RELS) },
        {
          name: 'xl/worksheets/sheet1.xml',
          data: Buffer.from('<worksheet><sheetData><row r="1"><c r="A1" t="inlineStr"><is><t>x</t></is></c></row></sheetData></worksheet>'),
        },
      ]);
      expect(sourceError(() => readSymbolTable({ name: 'w.xlsx', content: unnamed })).message).to.equal(
        'w.xlsx:1:1: no sheet "PLC Tags" nor one with Name and Logical Address columns (sheets: "Sheet1")',
      );
    });

    it('refuses an .xlsx given as text', () => {
      expect(sourceError(() => readSymbolTable({ name: 'w.xlsx', content: 'PK…' })).message).to.equal(
        'w.xlsx:1:1: an .xlsx file must be given as bytes (a Uint8Array), not as text',
      );
    });
  });

  describe('empty tables', () => {
    it('are empty in every format', () => {
      for (const name of ['e.sdf', 'e.asc', 'e.seq', 'e.csv']) {
        expect(readSymbolTable({ name, content: '' }), name).to.deep.equal([]);
        expect(readSymbolTable({ name, content: '\r\n\r\n' }), name).to.deep.equal([]);
        expect(readSymbolTable({ name, content: new Uint8Array(0) }), name).to.deep.equal([]);
      }
      expect(readSymbolTable({ name: 'e.csv', content: '\uFEFFName;Path;Data Type;Logical Address;Comment\r\n' })).to.deep.equal([]);
      expect(readSymbolTable({ name: 'e.xlsx', content: workbook([HEADER]) })).to.deep.equal([]);
      expect(readSymbolTable({ name: 'e.xlsx', content: workbook([]) })).to.deep.equal([]);
    });
  });

  describe('unknown and hostile files', () => {
    it('refuses an unknown extension', () => {
      expect(sourceError(() => readSymbolTable({ name: 'tags.txt', content: 'x' })).message).to.equal(
        'tags.txt:1:1: not a symbol table: expected a .sdf, .asc, .seq (STEP 7), .xlsx or .csv (TIA Portal) file',
      );
    });

    it('answers random bytes in every format with rows or a SourceError, never anything else', () => {
      // A fixed pseudo-random sequence (xorshift), so a failure repeats.
      let state = 0x2545f491;
      const random = (n: number) =>
        Uint8Array.from({ length: n }, () => {
          state ^= state << 13;
          state ^= state >>> 17;
          state ^= state << 5;
          return state & 0xff;
        });
      for (let i = 0; i < 200; i++) {
        const bytes = random(1 + ((i * 37) % 2000));
        for (const ext of ['sdf', 'asc', 'seq', 'csv', 'xlsx']) {
          try {
            expect(readSymbolTable({ name: `r.${ext}`, content: bytes })).to.be.an('array');
          } catch (err) {
            expect(err, `${ext} #${i}`).to.be.instanceOf(SourceError);
          }
        }
      }
    });

    it('refuses every truncation of a real workbook with a SourceError', () => {
      const whole = fixture('PLCTags.xlsx');
      for (let end = 0; end < whole.length; end += 7) {
        try {
          readSymbolTable({ name: 't.xlsx', content: whole.subarray(0, end) });
          expect.fail(`a workbook cut at ${end} of ${whole.length} bytes was read`);
        } catch (err) {
          expect(err, `cut at ${end}`).to.be.instanceOf(SourceError);
        }
      }
    });

    it('refuses a zip bomb: a part that claims a huge size, or lies and inflates past the cap', () => {
      const zeros = Buffer.alloc(80 * 1024 * 1024);
      const claimed = workbook([HEADER], { declaredSize: 0xfffffff0 });
      expect(sourceError(() => readSymbolTable({ name: 'b.xlsx', content: claimed })).message).to.equal(
        `b.xlsx:1:1: not a readable .xlsx workbook: xl/worksheets/sheet1.xml would inflate to ${0xfffffff0} bytes (at most 67108864)`,
      );
      const lying = zip([
        { name: 'xl/workbook.xml', data: Buffer.from(WORKBOOK) },
        { name: 'xl/_rels/workbook.xml.rels', data: Buffer.from(RELS) },
        { name: 'xl/worksheets/sheet1.xml', data: zeros, declaredSize: 100 },
      ]);
      expect(lying.length).to.be.below(200_000);
      expect(sourceError(() => readSymbolTable({ name: 'b.xlsx', content: lying })).message).to.equal(
        'b.xlsx:1:1: not a readable .xlsx workbook: xl/worksheets/sheet1.xml inflates past 67108864 bytes',
      );
    });

    it('refuses encrypted parts, unknown compression, damaged deflate data and dangling shared strings', () => {
      const message = (bytes: Buffer) => sourceError(() => readSymbolTable({ name: 'h.xlsx', content: bytes })).message;
      expect(message(workbook([HEADER], { flags: 1 }))).to.equal(
        'h.xlsx:1:1: not a readable .xlsx workbook: xl/worksheets/sheet1.xml is encrypted',
      );
      const book = workbook([HEADER]);
      // The sheet's method field in its directory entry: 12 (bzip2).
      const bzip = Buffer.from(book);
      const entry = bzip.lastIndexOf(Buffer.from('xl/worksheets/sheet1.xml')) - 46;
      bzip.writeUInt16LE(12, entry + 10);
      expect(message(bzip)).to.equal('h.xlsx:1:1: not a readable .xlsx workbook: xl/worksheets/sheet1.xml uses zip compression method 12');
      const garbage = zip([
        { name: 'xl/workbook.xml', data: Buffer.from(WORKBOOK) },
        { name: 'xl/_rels/workbook.xml.rels', data: Buffer.from(RELS) },
        { name: 'xl/worksheets/sheet1.xml', data: Buffer.from([0xff, 0xff, 0xff, 0xff]), method: 0 },
      ]);
      const damaged = Buffer.from(garbage);
      damaged.writeUInt16LE(8, damaged.lastIndexOf(Buffer.from('xl/worksheets/sheet1.xml')) - 46 + 10);
      expect(message(damaged)).to.match(/^h\.xlsx:1:1: not a readable \.xlsx workbook: xl\/worksheets\/sheet1\.xml does not inflate/);
      const dangling = zip([
        { name: 'xl/workbook.xml', data: Buffer.from(WORKBOOK) },
        { name: 'xl/_rels/workbook.xml.rels', data: Buffer.from(RELS) },
        {
          name: 'xl/worksheets/sheet1.xml',
          data: Buffer.from('<worksheet><sheetData><row r="1"><c r="A1" t="s"><v>3</v></c></row></sheetData></worksheet>'),
        },
      ]);
      expect(message(dangling)).to.equal(
        'h.xlsx:1:1: not a readable .xlsx workbook: h.xlsx (sheet "PLC Tags"): cell A1 names shared string 3 of 0',
      );
      expect(message(zip([{ name: 'hello.txt', data: Buffer.from('hi') }]))).to.equal(
        'h.xlsx:1:1: not a readable .xlsx workbook: it has no xl/workbook.xml',
      );
    });
  });
});
