import { expect } from 'chai';
import fc from 'fast-check';
import { AddressError } from '../lib/errors';
import { formatAddress, parseAddress, parseTypeSpec } from '../lib/address';

type Expect = [area: string, db: number, byte: number, bit: number, type: string, count: number, isArray: boolean, strLen: number, bytes: number];

const ACCEPTED: Record<string, Expect> = {
  // nodes7 style
  'DB1,INT2': ['DB', 1, 2, 0, 'INT', 1, false, 0, 2],
  'DB1,X0.1': ['DB', 1, 0, 1, 'BOOL', 1, false, 0, 1],
  'DB1,X0.7.10': ['DB', 1, 0, 7, 'BOOL', 10, true, 0, 3],
  'DB1,REAL0.20': ['DB', 1, 0, 0, 'REAL', 20, true, 0, 80],
  'DB10,S20.30': ['DB', 10, 20, 0, 'STRING', 1, false, 30, 32],
  'DB10,STRING20.30.3': ['DB', 10, 20, 0, 'STRING', 3, true, 30, 96],
  'DB1,B4': ['DB', 1, 4, 0, 'BYTE', 1, false, 0, 1],
  'DB1,BYTE4.3': ['DB', 1, 4, 0, 'BYTE', 3, true, 0, 3],
  'DB1,C3': ['DB', 1, 3, 0, 'CHAR', 1, false, 0, 1],
  'DB1,W6': ['DB', 1, 6, 0, 'WORD', 1, false, 0, 2],
  'DB1,DW6': ['DB', 1, 6, 0, 'DWORD', 1, false, 0, 4],
  'DB1,I6': ['DB', 1, 6, 0, 'INT', 1, false, 0, 2],
  'DB1,DI6': ['DB', 1, 6, 0, 'DINT', 1, false, 0, 4],
  'DB1,R8': ['DB', 1, 8, 0, 'REAL', 1, false, 0, 4],
  'DB1,LREAL8': ['DB', 1, 8, 0, 'LREAL', 1, false, 0, 8],
  'DB1,LINT8': ['DB', 1, 8, 0, 'LINT', 1, false, 0, 8],
  'DB1,DTL0': ['DB', 1, 0, 0, 'DTL', 1, false, 0, 12],
  'DB1,WSTRING0.20': ['DB', 1, 0, 0, 'WSTRING', 1, false, 20, 44],
  'DB1,DT0': ['DB', 1, 0, 0, 'DATE_AND_TIME', 1, false, 0, 8],
  'db1,int2': ['DB', 1, 2, 0, 'INT', 1, false, 0, 2],
  ' DB1,INT2 ': ['DB', 1, 2, 0, 'INT', 1, false, 0, 2],
  MR4: ['M', 0, 4, 0, 'REAL', 1, false, 0, 4],
  MI4: ['M', 0, 4, 0, 'INT', 1, false, 0, 2],
  MW4: ['M', 0, 4, 0, 'WORD', 1, false, 0, 2],
  MB0: ['M', 0, 0, 0, 'BYTE', 1, false, 0, 1],
  MD4: ['M', 0, 4, 0, 'DWORD', 1, false, 0, 4],
  IW16: ['I', 0, 16, 0, 'WORD', 1, false, 0, 2],
  QD30: ['Q', 0, 30, 0, 'DWORD', 1, false, 0, 4],
  'M32.2': ['M', 0, 32, 2, 'BOOL', 1, false, 0, 1],
  'I0.1': ['I', 0, 0, 1, 'BOOL', 1, false, 0, 1],
  'E0.1': ['I', 0, 0, 1, 'BOOL', 1, false, 0, 1],
  AW2: ['Q', 0, 2, 0, 'WORD', 1, false, 0, 2],
  PIW256: ['PE', 0, 256, 0, 'WORD', 1, false, 0, 2],
  PEW256: ['PE', 0, 256, 0, 'WORD', 1, false, 0, 2],
  PQW4: ['PA', 0, 4, 0, 'WORD', 1, false, 0, 2],
  PIB0: ['PE', 0, 0, 0, 'BYTE', 1, false, 0, 1],
  PID4: ['PE', 0, 4, 0, 'DWORD', 1, false, 0, 4],
  T3: ['T', 0, 3, 0, 'TIMER', 1, false, 0, 2],
  C5: ['C', 0, 5, 0, 'COUNTER', 1, false, 0, 2],
  Z5: ['C', 0, 5, 0, 'COUNTER', 1, false, 0, 2],
  'T3:TIMER[4]': ['T', 0, 3, 0, 'TIMER', 4, true, 0, 8],
  // IEC / TIA style
  'DB1.DBX0.1': ['DB', 1, 0, 1, 'BOOL', 1, false, 0, 1],
  'DB1.DBB0': ['DB', 1, 0, 0, 'BYTE', 1, false, 0, 1],
  'DB1.DBW2': ['DB', 1, 2, 0, 'WORD', 1, false, 0, 2],
  'DB1.DBD4': ['DB', 1, 4, 0, 'DWORD', 1, false, 0, 4],
  '%MW4': ['M', 0, 4, 0, 'WORD', 1, false, 0, 2],
  '%I0.1': ['I', 0, 0, 1, 'BOOL', 1, false, 0, 1],
  '%DB1.DBX0.1': ['DB', 1, 0, 1, 'BOOL', 1, false, 0, 1],
  QB0: ['Q', 0, 0, 0, 'BYTE', 1, false, 0, 1],
  IB3: ['I', 0, 3, 0, 'BYTE', 1, false, 0, 1],
  'DB1.DBD4:REAL': ['DB', 1, 4, 0, 'REAL', 1, false, 0, 4],
  'DB1.DBD4:real': ['DB', 1, 4, 0, 'REAL', 1, false, 0, 4],
  'MW10:INT': ['M', 0, 10, 0, 'INT', 1, false, 0, 2],
  'DB1.DBB0:CHAR[10]': ['DB', 1, 0, 0, 'CHAR', 10, true, 0, 10],
  'DB1.DBB0:STRING[30]': ['DB', 1, 0, 0, 'STRING', 1, false, 30, 32],
  'DB1.DBB0:STRING[30][2]': ['DB', 1, 0, 0, 'STRING', 2, true, 30, 64],
  'DB1.DBX0.3:BOOL[4]': ['DB', 1, 0, 3, 'BOOL', 4, true, 0, 1],
  'DB1.DBX0.6:BOOL[4]': ['DB', 1, 0, 6, 'BOOL', 4, true, 0, 2],
  'DB1.DBB0:LREAL': ['DB', 1, 0, 0, 'LREAL', 1, false, 0, 8],
  'DB1.DBW0:S5TIME': ['DB', 1, 0, 0, 'S5TIME', 1, false, 0, 2],
  'DB1.DBD0:TIME': ['DB', 1, 0, 0, 'TIME', 1, false, 0, 4],
  'DB1.DBB0:DTL': ['DB', 1, 0, 0, 'DTL', 1, false, 0, 12],
  'DB1.DBW0:INT[10]': ['DB', 1, 0, 0, 'INT', 10, true, 0, 20],
  'DB65535.DBB65535': ['DB', 65535, 65535, 0, 'BYTE', 1, false, 0, 1],
  // S7-200 V area = DB1
  VB10: ['DB', 1, 10, 0, 'BYTE', 1, false, 0, 1],
  VW10: ['DB', 1, 10, 0, 'WORD', 1, false, 0, 2],
  VD10: ['DB', 1, 10, 0, 'DWORD', 1, false, 0, 4],
  'V10.1': ['DB', 1, 10, 1, 'BOOL', 1, false, 0, 1],
  'VD10:REAL': ['DB', 1, 10, 0, 'REAL', 1, false, 0, 4],
};

const REJECTED: Record<string, RegExp> = {
  '': /empty address/,
  '   ': /empty address/,
  'DB0,INT2': /DB0 is not a valid data block number/,
  'DB70000.DBW0': /DB70000 is not a valid data block number/,
  'DB1,X0.8': /bit 8 out of range \(0\.\.7\)/,
  'DB1.DBX0.9': /bit 9 out of range/,
  'M0.8': /bit 8 out of range/,
  'DB1,FOO2': /unknown type "FOO"/,
  'DB1.DBD0:FOO': /unknown type "FOO"/,
  'MB70000': /offset 70000 out of range/,
  'DB1.DBB65535:INT': /INT needs a word/,
  'DB1.DBW65534:INT[2]': /beyond 65535/,
  'DB1,REAL0.0': /array length 0/,
  'DB1.DBW0:INT[0]': /array length 0/,
  'DB1,S0.255': /STRING length 255 out of range \(1\.\.254\)/,
  'DB1.DBB0:STRING[0]': /STRING length 0 out of range/,
  'DB1.DBW2:REAL': /REAL needs a double word \(D\), W is a word/,
  'MW10:DINT': /DINT needs a double word/,
  'MD10:INT': /INT needs a word/,
  'DB1.DBX0': /needs \.<bit>/,
  'DB1,X0': /needs \.<bit>/,
  'DB1.DBW0.1': /has no bit/,
  'DB1.DBX0.1:INT': /cannot start at a bit/,
  'DB1.DBW0:BOOL': /BOOL needs a bit address/,
  'DB1,INT2:REAL': /drop the ":TYPE" override/,
  'DB1,INT2x': /expected DB<n>,<TYPE><offset>/,
  'DB1.FOO': /expected DB<n>\.DBX/,
  MW: /not an S7 address/,
  M10: /expected a bit/,
  FOO: /not an S7 address/,
  'T3:COUNTER': /a timer is TIMER, not COUNTER/,
  'DB1,INT2.3.4': /too many dots/,
  'DB1.DBW0:INT[2][3]': /only STRING and WSTRING take two brackets/,
  'MW4:': /is not a type/,
};

describe('address parser', () => {
  for (const [address, e] of Object.entries(ACCEPTED)) {
    it(`parses ${JSON.stringify(address)}`, () => {
      const t = parseAddress(address);
      expect([t.area, t.dbNumber, t.byteOffset, t.bitOffset, t.type, t.count, t.isArray, t.stringLength, t.byteLength]).to.deep.equal(e);
      expect(t.address).to.equal(address);
      expect(Object.isFrozen(t)).to.equal(true);
    });
  }

  for (const [address, problem] of Object.entries(REJECTED)) {
    it(`rejects ${JSON.stringify(address)} naming the problem`, () => {
      let error: unknown;
      try {
        parseAddress(address);
      } catch (err) {
        error = err;
      }
      expect(error).to.be.instanceOf(AddressError);
      const e = error as AddressError;
      expect(e.code).to.equal('INVALID_ADDRESS');
      expect(e.tag).to.equal(address);
      expect(e.message).to.include(`"${address}"`);
      expect(e.message).to.match(problem);
    });
  }

  it('parses type specs on their own (the editor uses it)', () => {
    expect(parseTypeSpec('real[20]', 'x')).to.deep.equal({ type: 'REAL', count: 20, isArray: true, stringLength: 0 });
    expect(parseTypeSpec('STRING[30]', 'x')).to.deep.equal({ type: 'STRING', count: 1, isArray: false, stringLength: 30 });
    expect(parseTypeSpec('TOD', 'x').type).to.equal('TIME_OF_DAY');
  });

  it('formats every accepted address canonically, and the canonical form parses to the same tag', () => {
    for (const address of Object.keys(ACCEPTED)) {
      const t = parseAddress(address);
      const canonical = formatAddress(t);
      const back = parseAddress(canonical);
      expect({ ...back, address: '' }, `${address} → ${canonical}`).to.deep.equal({ ...t, address: '' });
    }
    expect(formatAddress(parseAddress('DB1,REAL0.20'))).to.equal('DB1.DBB0:REAL[20]');
    expect(formatAddress(parseAddress('M32.2'))).to.equal('M32.2');
    expect(formatAddress(parseAddress('DB10,S20.30'))).to.equal('DB10.DBB20:STRING[30]');
  });

  it('property: any string gives a tag or an AddressError, never anything else', () => {
    const alphabet = fc.constantFrom(...'DBXWIRSTCMQVPAEZ%,.:[]0123456789 _-'.split(''));
    fc.assert(
      fc.property(fc.oneof(fc.string(), fc.string({ unit: alphabet, maxLength: 24 })), (s) => {
        try {
          const t = parseAddress(s);
          expect(t.byteLength).to.be.greaterThan(0);
        } catch (err) {
          if (!(err instanceof AddressError)) throw err;
        }
      }),
      { numRuns: 5000 },
    );
  });

  it('property: generated valid tags survive format → parse', () => {
    const tagArb = fc.record({
      area: fc.constantFrom('DB', 'M', 'I', 'Q', 'PE', 'PA'),
      db: fc.integer({ min: 1, max: 65535 }),
      byte: fc.integer({ min: 0, max: 60000 }),
      bit: fc.integer({ min: 0, max: 7 }),
      type: fc.constantFrom('BOOL', 'BYTE', 'INT', 'REAL', 'LREAL', 'STRING', 'WORD', 'DTL', 'CHAR', 'S5TIME'),
      count: fc.integer({ min: 1, max: 20 }),
      isArray: fc.boolean(),
      strLen: fc.integer({ min: 1, max: 254 }),
    });
    fc.assert(
      fc.property(tagArb, (g) => {
        const prefix = g.area === 'DB' ? `DB${g.db}.DB` : g.area === 'PE' ? 'PI' : g.area === 'PA' ? 'PQ' : g.area;
        const spec = g.type === 'STRING' ? `STRING[${g.strLen}]` : g.type;
        const arr = g.isArray ? `[${g.count}]` : '';
        const size: Record<string, string> = { INT: 'W', WORD: 'W', S5TIME: 'W', REAL: 'D' };
        const width = !g.isArray && size[g.type] ? size[g.type] : 'B';
        const address = g.type === 'BOOL' ? `${prefix}X${g.byte}.${g.bit}${g.isArray ? `:BOOL${arr}` : ''}` : `${prefix}${width}${g.byte}:${spec}${arr}`;
        const t = parseAddress(address);
        const back = parseAddress(formatAddress(t));
        expect({ ...back, address: '' }).to.deep.equal({ ...t, address: '' });
      }),
      { numRuns: 2000 },
    );
  });
});
