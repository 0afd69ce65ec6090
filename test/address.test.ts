import { expect } from 'chai';
import { AddressError, ValueError } from '../lib/errors';
import { formatAddress, parseAddress, parseTypeSpec } from '../lib/address';

type Expect = [
  area: string,
  db: number,
  byte: number,
  bit: number,
  type: string,
  count: number,
  isArray: boolean,
  strLen: number,
  bytes: number,
];

export const ACCEPTED: Record<string, Expect> = {
  // nodes7 style, DB
  'DB1,INT2': ['DB', 1, 2, 0, 'INT', 1, false, 0, 2],
  'DB1,X0.1': ['DB', 1, 0, 1, 'BOOL', 1, false, 0, 1],
  'DB1,X0.1.8': ['DB', 1, 0, 1, 'BOOL', 8, true, 0, 2],
  'DB1,X0.7.10': ['DB', 1, 0, 7, 'BOOL', 10, true, 0, 3],
  'DB1,X0.0.8': ['DB', 1, 0, 0, 'BOOL', 8, true, 0, 1],
  'DB1,REAL0.20': ['DB', 1, 0, 0, 'REAL', 20, true, 0, 80],
  'DB1,REAL0.1': ['DB', 1, 0, 0, 'REAL', 1, true, 0, 4],
  'DB10,S20.30': ['DB', 10, 20, 0, 'STRING', 1, false, 30, 32],
  'DB10,STRING20': ['DB', 10, 20, 0, 'STRING', 1, false, 254, 256],
  'DB10,STRING20.30.3': ['DB', 10, 20, 0, 'STRING', 3, true, 30, 96],
  'DB1,B4': ['DB', 1, 4, 0, 'BYTE', 1, false, 0, 1],
  'DB1,BYTE4.3': ['DB', 1, 4, 0, 'BYTE', 3, true, 0, 3],
  'DB1,C3': ['DB', 1, 3, 0, 'CHAR', 1, false, 0, 1],
  'DB1,CHAR3.10': ['DB', 1, 3, 0, 'CHAR', 10, true, 0, 10],
  'DB1,W6': ['DB', 1, 6, 0, 'WORD', 1, false, 0, 2],
  'DB1,WORD6': ['DB', 1, 6, 0, 'WORD', 1, false, 0, 2],
  'DB1,DW6': ['DB', 1, 6, 0, 'DWORD', 1, false, 0, 4],
  'DB1,DWORD6': ['DB', 1, 6, 0, 'DWORD', 1, false, 0, 4],
  'DB1,I6': ['DB', 1, 6, 0, 'INT', 1, false, 0, 2],
  'DB1,DI6': ['DB', 1, 6, 0, 'DINT', 1, false, 0, 4],
  'DB1,DINT6': ['DB', 1, 6, 0, 'DINT', 1, false, 0, 4],
  'DB1,R8': ['DB', 1, 8, 0, 'REAL', 1, false, 0, 4],
  'DB1,LREAL8': ['DB', 1, 8, 0, 'LREAL', 1, false, 0, 8],
  'DB1,LINT8': ['DB', 1, 8, 0, 'LINT', 1, false, 0, 8],
  'DB1,ULINT8': ['DB', 1, 8, 0, 'ULINT', 1, false, 0, 8],
  'DB1,LWORD8': ['DB', 1, 8, 0, 'LWORD', 1, false, 0, 8],
  'DB1,SINT0': ['DB', 1, 0, 0, 'SINT', 1, false, 0, 1],
  'DB1,USINT0.4': ['DB', 1, 0, 0, 'USINT', 4, true, 0, 4],
  'DB1,UINT0': ['DB', 1, 0, 0, 'UINT', 1, false, 0, 2],
  'DB1,UDINT0': ['DB', 1, 0, 0, 'UDINT', 1, false, 0, 4],
  'DB1,WCHAR0': ['DB', 1, 0, 0, 'WCHAR', 1, false, 0, 2],
  'DB1,S5TIME0': ['DB', 1, 0, 0, 'S5TIME', 1, false, 0, 2],
  'DB1,S5.30': ['DB', 1, 5, 0, 'STRING', 1, false, 30, 32],
  'DB1,TIME4': ['DB', 1, 4, 0, 'TIME', 1, false, 0, 4],
  'DB1,LTIME8': ['DB', 1, 8, 0, 'LTIME', 1, false, 0, 8],
  'DB1,DATE0': ['DB', 1, 0, 0, 'DATE', 1, false, 0, 2],
  'DB1,TIME_OF_DAY4': ['DB', 1, 4, 0, 'TIME_OF_DAY', 1, false, 0, 4],
  'DB1,TOD4': ['DB', 1, 4, 0, 'TIME_OF_DAY', 1, false, 0, 4],
  'DB1,DATE_AND_TIME0': ['DB', 1, 0, 0, 'DATE_AND_TIME', 1, false, 0, 8],
  'DB1,DT0': ['DB', 1, 0, 0, 'DATE_AND_TIME', 1, false, 0, 8],
  'DB1,DTL0': ['DB', 1, 0, 0, 'DTL', 1, false, 0, 12],
  'DB1,DTL0.2': ['DB', 1, 0, 0, 'DTL', 2, true, 0, 24],
  'DB1,WSTRING0.20': ['DB', 1, 0, 0, 'WSTRING', 1, false, 20, 44],
  'DB1,COUNTER0': ['DB', 1, 0, 0, 'COUNTER', 1, false, 0, 2],
  'DB1,TIMER0': ['DB', 1, 0, 0, 'TIMER', 1, false, 0, 2],
  'db1,int2': ['DB', 1, 2, 0, 'INT', 1, false, 0, 2],
  ' DB1,INT2 ': ['DB', 1, 2, 0, 'INT', 1, false, 0, 2],
  '\tDB1,Real4\n': ['DB', 1, 4, 0, 'REAL', 1, false, 0, 4],
  // nodes7 style, other areas
  MR4: ['M', 0, 4, 0, 'REAL', 1, false, 0, 4],
  'MR4.3': ['M', 0, 4, 0, 'REAL', 3, true, 0, 12],
  MI4: ['M', 0, 4, 0, 'INT', 1, false, 0, 2],
  MDI4: ['M', 0, 4, 0, 'DINT', 1, false, 0, 4],
  MC3: ['M', 0, 3, 0, 'CHAR', 1, false, 0, 1],
  MW4: ['M', 0, 4, 0, 'WORD', 1, false, 0, 2],
  MB0: ['M', 0, 0, 0, 'BYTE', 1, false, 0, 1],
  MD4: ['M', 0, 4, 0, 'DWORD', 1, false, 0, 4],
  MB65535: ['M', 0, 65535, 0, 'BYTE', 1, false, 0, 1],
  IW16: ['I', 0, 16, 0, 'WORD', 1, false, 0, 2],
  QD30: ['Q', 0, 30, 0, 'DWORD', 1, false, 0, 4],
  'M32.2': ['M', 0, 32, 2, 'BOOL', 1, false, 0, 1],
  'MX32.2': ['M', 0, 32, 2, 'BOOL', 1, false, 0, 1],
  'I0.1': ['I', 0, 0, 1, 'BOOL', 1, false, 0, 1],
  'Q1.7': ['Q', 0, 1, 7, 'BOOL', 1, false, 0, 1],
  'E0.1': ['I', 0, 0, 1, 'BOOL', 1, false, 0, 1],
  EB2: ['I', 0, 2, 0, 'BYTE', 1, false, 0, 1],
  AW2: ['Q', 0, 2, 0, 'WORD', 1, false, 0, 2],
  'A4.0': ['Q', 0, 4, 0, 'BOOL', 1, false, 0, 1],
  PIW256: ['PE', 0, 256, 0, 'WORD', 1, false, 0, 2],
  PEW256: ['PE', 0, 256, 0, 'WORD', 1, false, 0, 2],
  PQW4: ['PA', 0, 4, 0, 'WORD', 1, false, 0, 2],
  PAW4: ['PA', 0, 4, 0, 'WORD', 1, false, 0, 2],
  PIB0: ['PE', 0, 0, 0, 'BYTE', 1, false, 0, 1],
  PID4: ['PE', 0, 4, 0, 'DWORD', 1, false, 0, 4],
  T3: ['T', 0, 3, 0, 'TIMER', 1, false, 0, 2],
  t3: ['T', 0, 3, 0, 'TIMER', 1, false, 0, 2],
  C5: ['C', 0, 5, 0, 'COUNTER', 1, false, 0, 2],
  Z5: ['C', 0, 5, 0, 'COUNTER', 1, false, 0, 2],
  '%T3': ['T', 0, 3, 0, 'TIMER', 1, false, 0, 2],
  'T3:TIMER[4]': ['T', 0, 3, 0, 'TIMER', 4, true, 0, 8],
  'C0:COUNTER[3]': ['C', 0, 0, 0, 'COUNTER', 3, true, 0, 6],
  T65535: ['T', 0, 65535, 0, 'TIMER', 1, false, 0, 2],
  // IEC / TIA style
  'DB1.DBX0.1': ['DB', 1, 0, 1, 'BOOL', 1, false, 0, 1],
  'DB1.DBB0': ['DB', 1, 0, 0, 'BYTE', 1, false, 0, 1],
  'DB1.DBW2': ['DB', 1, 2, 0, 'WORD', 1, false, 0, 2],
  'DB1.DBD4': ['DB', 1, 4, 0, 'DWORD', 1, false, 0, 4],
  'db1.dbd4': ['DB', 1, 4, 0, 'DWORD', 1, false, 0, 4],
  'DB01.DBW002': ['DB', 1, 2, 0, 'WORD', 1, false, 0, 2],
  '%MW4': ['M', 0, 4, 0, 'WORD', 1, false, 0, 2],
  '%I0.1': ['I', 0, 0, 1, 'BOOL', 1, false, 0, 1],
  '%DB1.DBX0.1': ['DB', 1, 0, 1, 'BOOL', 1, false, 0, 1],
  '%QB0': ['Q', 0, 0, 0, 'BYTE', 1, false, 0, 1],
  QB0: ['Q', 0, 0, 0, 'BYTE', 1, false, 0, 1],
  IB3: ['I', 0, 3, 0, 'BYTE', 1, false, 0, 1],
  'DB1.DBD4:REAL': ['DB', 1, 4, 0, 'REAL', 1, false, 0, 4],
  'DB1.DBD4:real': ['DB', 1, 4, 0, 'REAL', 1, false, 0, 4],
  'DB1.DBD4 : REAL': ['DB', 1, 4, 0, 'REAL', 1, false, 0, 4],
  'DB1.DBD4:R': ['DB', 1, 4, 0, 'REAL', 1, false, 0, 4],
  '%DB1.DBW2:INT': ['DB', 1, 2, 0, 'INT', 1, false, 0, 2],
  'MW10:INT': ['M', 0, 10, 0, 'INT', 1, false, 0, 2],
  'MD10:DINT': ['M', 0, 10, 0, 'DINT', 1, false, 0, 4],
  'MB1:SINT': ['M', 0, 1, 0, 'SINT', 1, false, 0, 1],
  'DB1.DBB0:CHAR[10]': ['DB', 1, 0, 0, 'CHAR', 10, true, 0, 10],
  'DB1.DBB0:STRING[30]': ['DB', 1, 0, 0, 'STRING', 1, false, 30, 32],
  'DB1.DBB0:STRING': ['DB', 1, 0, 0, 'STRING', 1, false, 254, 256],
  'DB1.DBW0:STRING[10]': ['DB', 1, 0, 0, 'STRING', 1, false, 10, 12],
  'DB1.DBB0:STRING[30][2]': ['DB', 1, 0, 0, 'STRING', 2, true, 30, 64],
  'DB1.DBB0:WSTRING[10]': ['DB', 1, 0, 0, 'WSTRING', 1, false, 10, 24],
  'DB1.DBX0.3:BOOL[4]': ['DB', 1, 0, 3, 'BOOL', 4, true, 0, 1],
  'DB1.DBX0.6:BOOL[4]': ['DB', 1, 0, 6, 'BOOL', 4, true, 0, 2],
  'DB1.DBX0.1:BOOL': ['DB', 1, 0, 1, 'BOOL', 1, false, 0, 1],
  'M0.3:BOOL[16]': ['M', 0, 0, 3, 'BOOL', 16, true, 0, 3],
  'DB1.DBB0:LREAL': ['DB', 1, 0, 0, 'LREAL', 1, false, 0, 8],
  'DB1.DBW0:LREAL': ['DB', 1, 0, 0, 'LREAL', 1, false, 0, 8],
  'DB1.DBW0:S5TIME': ['DB', 1, 0, 0, 'S5TIME', 1, false, 0, 2],
  'DB1.DBW0:WCHAR': ['DB', 1, 0, 0, 'WCHAR', 1, false, 0, 2],
  'DB1.DBW0:DATE': ['DB', 1, 0, 0, 'DATE', 1, false, 0, 2],
  'DB1.DBD0:TIME': ['DB', 1, 0, 0, 'TIME', 1, false, 0, 4],
  'DB1.DBD0:TOD': ['DB', 1, 0, 0, 'TIME_OF_DAY', 1, false, 0, 4],
  'DB1.DBB0:DTL': ['DB', 1, 0, 0, 'DTL', 1, false, 0, 12],
  'DB1.DBB0:DATE_AND_TIME': ['DB', 1, 0, 0, 'DATE_AND_TIME', 1, false, 0, 8],
  'DB1.DBW0:INT[10]': ['DB', 1, 0, 0, 'INT', 10, true, 0, 20],
  'DB1.DBW0:REAL[2]': ['DB', 1, 0, 0, 'REAL', 2, true, 0, 8],
  'DB1.DBW0:INT[1]': ['DB', 1, 0, 0, 'INT', 1, true, 0, 2],
  'DB65535.DBB65535': ['DB', 65535, 65535, 0, 'BYTE', 1, false, 0, 1],
  'DB1.DBW65534': ['DB', 1, 65534, 0, 'WORD', 1, false, 0, 2],
  // S7-200 V area = DB1
  VB10: ['DB', 1, 10, 0, 'BYTE', 1, false, 0, 1],
  VW10: ['DB', 1, 10, 0, 'WORD', 1, false, 0, 2],
  VD10: ['DB', 1, 10, 0, 'DWORD', 1, false, 0, 4],
  'V10.1': ['DB', 1, 10, 1, 'BOOL', 1, false, 0, 1],
  'VX10.1': ['DB', 1, 10, 1, 'BOOL', 1, false, 0, 1],
  vw10: ['DB', 1, 10, 0, 'WORD', 1, false, 0, 2],
  'VD10:REAL': ['DB', 1, 10, 0, 'REAL', 1, false, 0, 4],
  'VW10:INT': ['DB', 1, 10, 0, 'INT', 1, false, 0, 2],
};

export const REJECTED: Record<string, RegExp> = {
  '': /: empty address$/,
  '   ': /: empty address$/,
  'DB0,INT2': /DB0 is not a valid data block number \(1\.\.65535\)/,
  'DB0.DBW0': /DB0 is not a valid data block number/,
  'DB70000.DBW0': /DB70000 is not a valid data block number/,
  'DB99999999999999999999,INT0': /DB99999999999999999999 is not a valid data block number/,
  'DB1,X0.8': /bit 8 out of range \(0\.\.7\)/,
  'DB1.DBX0.9': /bit 9 out of range \(0\.\.7\)/,
  'M0.8': /bit 8 out of range/,
  'V0.08': /bit 8 out of range/,
  'DB1,FOO2': /unknown type "FOO"/,
  'DB1.DBD0:FOO': /unknown type "FOO"/,
  'DB1.DBD0:foo[2]': /unknown type "foo"/,
  MB70000: /offset 70000 out of range \(0\.\.65535\)/,
  'DB1,INT99999999999999999999': /offset 99999999999999999999 out of range/,
  T70000: /offset 70000 out of range/,
  'T65535:TIMER[2]': /ends at T65536, beyond T65535/,
  'DB1.DBW65534:INT[2]': /ends at byte 65537, beyond 65535/,
  'DB1.DBB65535:BOOL[1]': /BOOL needs a bit address/,
  'DB1.DBX65535.7:BOOL[2]': /ends at byte 65536/,
  'DB1,REAL0.0': /array length 0/,
  'DB1.DBW0:INT[0]': /array length 0/,
  'DB1,X0.1.0': /array length 0/,
  'DB1,REAL0.70000': /array length 70000 > 65535/,
  'DB1,S0.255': /STRING length 255 > 254/,
  'DB1.DBB0:STRING[255]': /STRING length 255 > 254/,
  'DB1.DBB0:STRING[0]': /STRING length 0 \(must be at least 1\)/,
  'DB1.DBB0:WSTRING[16383]': /WSTRING length 16383 > 16382/,
  'DB1.DBW2:REAL': /REAL needs a double word, DBW is a word$/,
  'MW10:DINT': /DINT needs a double word, MW is a word$/,
  'MD10:INT': /INT needs a word, MD is a double word$/,
  'DB1.DBB0:INT': /INT needs a word, DBB is a byte$/,
  'DB1.DBD0:WORD': /WORD needs a word, DBD is a double word$/,
  'VW0:CHAR': /CHAR needs a byte, VW is a word$/,
  'PIW0:REAL': /REAL needs a double word, PIW is a word$/,
  'DB1.DBX0': /a bit address needs \.<bit>, e\.g\. DBX0\.1/,
  'DB1,X0': /a bit address needs \.<bit>/,
  'DB1.DBW0.1': /DBW has no bit/,
  'VW10.1': /VW has no bit/,
  'DB1.DBX0.1:INT': /INT cannot start at a bit/,
  'DB1.DBW0:BOOL': /BOOL needs a bit address/,
  'DB1.DBB0:BOOL[8]': /BOOL needs a bit address/,
  'DB1,INT2:REAL': /drop the ":TYPE" override/,
  'MR4:INT': /"MR" names its type; drop the ":TYPE" override/,
  'DB1,INT2x': /unexpected "x" after "DB1,INT2"$/,
  MW4x: /unexpected "x" after "MW4"$/,
  'DB1.DBX0.1.2': /unexpected "\.2" after "DB1\.DBX0\.1"$/,
  'DB1.DBW2 4': /unexpected " 4" after "DB1\.DBW2"$/,
  'I0.1.2': /unexpected "\.2" after "I0\.1"$/,
  'DB1,INT2.3.4': /unexpected "\.4": INT takes one number after the offset/,
  'DB1, INT2': /expected DB<n>,<TYPE><byte>/,
  'DB1.FOO': /expected DB<n>\.DBX<byte>\.<bit>/,
  'DB1.DBW': /expected DB<n>\.DBX<byte>\.<bit>/,
  DB1: /expected DB<n>\.DBW<byte> \(IEC\) or DB<n>,<TYPE><byte> \(nodes7\)/,
  MW: /expected MB, MW, MD<byte> or M<byte>\.<bit>/,
  PIW: /expected PIB, PIW, PID<byte>/,
  M10: /expected a bit \(M10\.0\) or a width B, W or D \(MB10\)/,
  V10: /expected a bit \(V10\.0\) or a width B, W or D \(VB10\)/,
  TX: /expected a timer T<n> or a counter C<n>/,
  FOO: /not an S7 address/,
  '%%MW4': /not an S7 address/,
  ':REAL': /not an S7 address/,
  'P0.1': /not an S7 address/,
  'T3:COUNTER': /a timer is TIMER, not COUNTER/,
  'C5:TIMER': /a counter is COUNTER, not TIMER/,
  'DB1.DBW0:INT[2][3]': /only STRING and WSTRING take two brackets/,
  'MW4:': /"" is not a type/,
  'MW4:INT[]': /"INT\[\]" is not a type/,
  'MW4:INT:INT': /"INT:INT" is not a type/,
  '\u0131W16': /unexpected character "\u0131"/, // dotless i, which toUpperCase() would make an I
  'MW4\u0000': /unexpected character "\\u0000"/,
};

function rejection(address: string): AddressError {
  try {
    parseAddress(address);
  } catch (err) {
    expect(err).to.be.instanceOf(AddressError);
    return err as AddressError;
  }
  throw new Error(`${JSON.stringify(address)} was accepted`);
}

describe('address parser: accepted addresses', () => {
  for (const [address, e] of Object.entries(ACCEPTED)) {
    it(`parses ${JSON.stringify(address)}`, () => {
      const t = parseAddress(address);
      expect([t.area, t.dbNumber, t.byteOffset, t.bitOffset, t.type, t.count, t.isArray, t.stringLength, t.byteLength]).to.deep.equal(e);
      expect(t.address).to.equal(address);
      expect(Object.isFrozen(t)).to.equal(true);
    });
  }
});

describe('address errors quote the address once', () => {
  it('a TIA name in its own quotes is shown as written, not quoted again', () => {
    expect(rejection('"Plant".Level').message).to.match(/^invalid address "Plant"\.Level: not an S7 address/);
    expect(rejection('DB1.DBW').message).to.match(/^invalid address "DB1\.DBW": /);
    expect(rejection('"').message).to.match(/^invalid address "\\"": /);
    expect(new ValueError('"Plant".Level', 'too big').message).to.equal('invalid value for "Plant".Level: too big');
    expect(new ValueError('DB1,INT2', 'too big').message).to.equal('invalid value for "DB1,INT2": too big');
  });

  it('a tag name where only addresses are known says so, and that the sources are given to the connection', () => {
    for (const name of ['"Plant".Level', 'Plant.Level', 'Tank', 'Motor.Speed', '"Motor 1".Speed', 'Tank.Set[2]']) {
      const e = rejection(name);
      expect(e.code).to.equal('INVALID_ADDRESS');
      expect(e.message, name).to.match(/; it looks like a tag name: .*DB sources or symbol table.*given to the connection as its symbols$/);
    }
    expect(rejection('"Plant".Level').message).to.match(/^invalid address "Plant"\.Level: not an S7 address \(e\.g\. [^)]*\); it looks/);
    // Not a name: no hint.
    for (const address of ['DB1.DBW', '12', 'DB1,FOO2', 'Q?'])
      expect(rejection(address).message, address).to.not.match(/looks like a tag name/);
  });
});

describe('address parser: rejected addresses', () => {
  for (const [address, problem] of Object.entries(REJECTED)) {
    it(`rejects ${JSON.stringify(address)} naming the problem`, () => {
      const e = rejection(address);
      expect(e.code).to.equal('INVALID_ADDRESS');
      expect(e.tag).to.equal(address);
      expect(e.message).to.include(`invalid address "${address}": `);
      expect(e.message).to.match(problem);
    });
  }

  it('rejects input that is not text with an AddressError', () => {
    for (const input of [undefined, null, 42, {}, ['MW4']]) {
      expect(() => parseAddress(input as unknown as string), String(input)).to.throw(AddressError, /must be text/);
    }
  });

  it('quotes only the start of an overlong input', () => {
    const e = rejection('M'.repeat(100_000));
    expect(e.message).to.match(/longer than 256 characters$/);
    expect(e.message.length).to.be.lessThan(120);
  });
});

describe('address parser: type specs', () => {
  it('parses type specs on their own (the editor uses them)', () => {
    expect(parseTypeSpec('real[20]', 'x')).to.deep.equal({ type: 'REAL', count: 20, isArray: true, stringLength: 0 });
    expect(parseTypeSpec(' INT ', 'x')).to.deep.equal({ type: 'INT', count: 1, isArray: false, stringLength: 0 });
    expect(parseTypeSpec('STRING[30]', 'x')).to.deep.equal({ type: 'STRING', count: 1, isArray: false, stringLength: 30 });
    expect(parseTypeSpec('STRING', 'x')).to.deep.equal({ type: 'STRING', count: 1, isArray: false, stringLength: 254 });
    expect(parseTypeSpec('wstring[8][3]', 'x')).to.deep.equal({ type: 'WSTRING', count: 3, isArray: true, stringLength: 8 });
    expect(parseTypeSpec('CHAR[10]', 'x')).to.deep.equal({ type: 'CHAR', count: 10, isArray: true, stringLength: 0 });
    expect(parseTypeSpec('TOD', 'x').type).to.equal('TIME_OF_DAY');
    expect(parseTypeSpec('S5TIME', 'x').type).to.equal('S5TIME');
  });

  it('names the address it was given in its errors', () => {
    expect(() => parseTypeSpec('FOO', 'DB1.DBW0:FOO')).to.throw(AddressError, 'invalid address "DB1.DBW0:FOO": unknown type "FOO"');
    expect(() => parseTypeSpec('constructor', 'x')).to.throw(AddressError, 'unknown type "constructor"');
    expect(() => parseTypeSpec('__proto__', 'x')).to.throw(AddressError, 'unknown type "__proto__"');
  });
});

describe('address formatter', () => {
  const CANONICAL: Record<string, string> = {
    'DB1,REAL0.20': 'DB1.DBB0:REAL[20]',
    'DB1,INT2': 'DB1.DBW2:INT',
    'db1,x0.1': 'DB1.DBX0.1',
    'DB1,X0.1.8': 'DB1.DBX0.1:BOOL[8]',
    'DB10,S20.30': 'DB10.DBB20:STRING[30]',
    'DB10,STRING20.30.3': 'DB10.DBB20:STRING[30][3]',
    'DB1,C3': 'DB1.DBB3:CHAR',
    'DB1,LREAL8': 'DB1.DBB8:LREAL',
    'DB1,DTL0': 'DB1.DBB0:DTL',
    'DB1.DBW2': 'DB1.DBW2',
    'DB1.DBD4:REAL': 'DB1.DBD4:REAL',
    '%mw4': 'MW4',
    'M32.2': 'M32.2',
    'E0.1': 'I0.1',
    AW2: 'QW2',
    PEW256: 'PIW256',
    PAW4: 'PQW4',
    MR4: 'MD4:REAL',
    VW10: 'DB1.DBW10',
    'V10.1': 'DB1.DBX10.1',
    Z5: 'C5',
    'T3:TIMER[4]': 'T3:TIMER[4]',
    'DB1.DBW0:TIMER': 'DB1.DBW0:TIMER',
  };
  for (const [address, canonical] of Object.entries(CANONICAL)) {
    it(`formats ${address} as ${canonical}`, () => {
      expect(formatAddress(parseAddress(address))).to.equal(canonical);
    });
  }

  it('formats every accepted address to a form that parses back to the same tag', () => {
    for (const address of Object.keys(ACCEPTED)) {
      const t = parseAddress(address);
      const canonical = formatAddress(t);
      expect({ ...parseAddress(canonical), address: '' }, `${address} → ${canonical}`).to.deep.equal({ ...t, address: '' });
      expect(formatAddress(parseAddress(canonical)), 'canonical is a fixed point').to.equal(canonical);
    }
  });
});
