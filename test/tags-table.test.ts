/** Tag tables as people keep them in spreadsheets: CSV import with a type column, export, duplicate names. */
import { expect } from 'chai';
import { parseAddress, parseFreeportAddress } from '../lib';
import { addressWithType, duplicateNames, parseCsv, tagsFromCsv, tagsToCsv } from '../lib/tags/table';

describe('tag tables: CSV', () => {
  it('splits comma, semicolon and tab separated text, with quoted fields, CRLF and a byte-order mark', () => {
    expect(parseCsv('a,b\r\n"c,1","d ""x"""\n')).to.deep.equal([
      ['a', 'b'],
      ['c,1', 'd "x"'],
    ]);
    // A semicolon file (German spreadsheets) keeps the commas of nodes7 addresses unquoted.
    expect(parseCsv('\uFEFFspeed;DB1,INT6\nlevel;DB1,REAL8')).to.deep.equal([
      ['speed', 'DB1,INT6'],
      ['level', 'DB1,REAL8'],
    ]);
    expect(parseCsv('speed\tDB1.DBW6\tINT')).to.deep.equal([['speed', 'DB1.DBW6', 'INT']]);
    expect(parseCsv('"multi\nline",x\n\n  \n')).to.deep.equal([['multi\nline', 'x']]);
  });

  it("reads name,address,type; the type column becomes the address's :TYPE", () => {
    const { tags, problems } = tagsFromCsv('speed,DB1.DBW6,INT\nlevel,DB1.DBD8,Real\nflag,M0.1,\n');
    expect(tags).to.deep.equal([
      { name: 'speed', address: 'DB1.DBW6:INT' },
      { name: 'level', address: 'DB1.DBD8:Real' },
      { name: 'flag', address: 'M0.1' },
    ]);
    expect(parseAddress(tags[0]!.address).type).to.equal('INT');
    expect(problems).to.deep.equal([]);
  });

  it('takes columns from a header row in any order, and skips it', () => {
    const { tags } = tagsFromCsv('Type;Address;Name\nINT;DB1.DBW6;speed\nWORD;DB1.DBW8;status\n');
    expect(tags).to.deep.equal([
      { name: 'speed', address: 'DB1.DBW6:INT' },
      { name: 'status', address: 'DB1.DBW8' },
    ]);
    expect(tagsFromCsv('name,address\nx,MW2\n').tags).to.deep.equal([{ name: 'x', address: 'MW2' }]);
  });

  it('reads one column as addresses and two as name,address', () => {
    expect(tagsFromCsv('MW2\nMW4\n').tags).to.deep.equal([
      { name: '', address: 'MW2' },
      { name: '', address: 'MW4' },
    ]);
    expect(tagsFromCsv('a,"DB1,INT2"\nb,\n').tags).to.deep.equal([{ name: 'a', address: 'DB1,INT2' }]);
  });

  it('keeps an address that names its type when the type column agrees, and says so when it does not', () => {
    const { tags, problems } = tagsFromCsv('a;DB1,INT6;INT\nb;DB1,INT8;REAL\nc;MW2:INT;WORD\nd;DB1.DBB0;STRING[10]\n');
    expect(tags).to.deep.equal([
      { name: 'a', address: 'DB1,INT6' },
      { name: 'b', address: 'DB1,INT8' },
      { name: 'c', address: 'MW2:INT' },
      { name: 'd', address: 'DB1.DBB0:STRING[10]' },
    ]);
    expect(problems.map((p) => [p.line, p.code, p.name])).to.deep.equal([
      [2, 'TYPE_MISMATCH', 'b'],
      [3, 'TYPE_MISMATCH', 'c'],
    ]);
    expect(problems[0]!.message).to.equal('"DB1,INT8" is INT, the type column says REAL');
  });

  it('names an unknown type', () => {
    const { tags, problems } = tagsFromCsv('x,DB1.DBW0,INTEGER\n');
    expect(tags).to.deep.equal([{ name: 'x', address: 'DB1.DBW0' }]);
    expect(problems).to.have.length(1);
    expect(problems[0]).to.include({ line: 1, code: 'INVALID_TYPE', name: 'x' });
    expect(problems[0]!.message).to.include('INTEGER');
  });

  it('checks the type against the parser it is given (freeport station addresses)', () => {
    const parse = (a: string) => parseFreeportAddress(a);
    expect(addressWithType('ST5,INT2', 'INT', parse)).to.deep.equal({ address: 'ST5,INT2' });
    expect(addressWithType('ST5,BYTE1', 'INT', parse)).to.deep.equal({
      address: 'ST5,BYTE1',
      problem: { code: 'TYPE_MISMATCH', message: '"ST5,BYTE1" is BYTE, the type column says INT' },
    });
  });

  it('flags names that occur twice (a row without a name is named by its address), with the line of each', () => {
    const { problems } = tagsFromCsv('name,address\nspeed,MW2\nlevel,MW4\nspeed,MW6\n,MW8\nMW8,MW10\n');
    expect(problems.map((p) => [p.line, p.code, p.name])).to.deep.equal([
      [4, 'DUPLICATE_NAME', 'speed'],
      [6, 'DUPLICATE_NAME', 'MW8'],
    ]);
    expect(problems[0]!.message).to.equal('"speed" is also the name on line 2');
  });

  it('exports what it imports', () => {
    const tags = [
      { name: 'a', address: 'DB1,INT2' },
      { name: 'say "hi"', address: 'DB1.DBW6:INT' },
      { name: '', address: 'M0.1' },
    ];
    const csv = tagsToCsv(tags);
    expect(csv).to.equal('name,address\r\na,"DB1,INT2"\r\n"say ""hi""",DB1.DBW6:INT\r\n,M0.1\r\n');
    expect(tagsFromCsv(csv).tags).to.deep.equal(tags);
  });
});

describe('tag tables: duplicate names', () => {
  it('lists each name given to more than one row, with the rows', () => {
    expect(
      duplicateNames([
        { name: 'a', address: 'MW0' },
        { name: 'b', address: 'MW2' },
        { name: ' a ', address: 'MW4' },
        { name: '', address: 'MW6' },
        { name: 'MW6', address: 'MW8' },
      ]),
    ).to.deep.equal([
      { name: 'a', rows: [0, 2] },
      { name: 'MW6', rows: [3, 4] },
    ]);
    expect(
      duplicateNames([
        { name: 'A', address: 'MW0' },
        { name: 'a', address: 'MW0' },
      ]),
    ).to.deep.equal([]);
  });
});
