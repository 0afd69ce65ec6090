import { expect } from 'chai';
import fc from 'fast-check';
import { AddressError } from '../lib/errors';
import { parseFreeportAddress } from '../lib/freeport/address';

describe('freeport addresses ST<station>,<TYPE><byte>[.<bit>]', () => {
  const pick = (a: string) => {
    const t = parseFreeportAddress(a);
    return [t.station, t.type, t.byteOffset, t.bitOffset, t.count, t.isArray, t.byteLength];
  };

  it('parses the types of a 4-byte data area', () => {
    expect(pick('ST5,DWORD0')).to.deep.equal([5, 'DWORD', 0, 0, 1, false, 4]);
    expect(pick('ST5,BYTE1')).to.deep.equal([5, 'BYTE', 1, 0, 1, false, 1]);
    expect(pick('ST5,INT2')).to.deep.equal([5, 'INT', 2, 0, 1, false, 2]);
    expect(pick('ST5,REAL0')).to.deep.equal([5, 'REAL', 0, 0, 1, false, 4]);
    expect(pick('ST5,X0.3')).to.deep.equal([5, 'BOOL', 0, 3, 1, false, 1]);
    expect(pick('ST5,B0.4')).to.deep.equal([5, 'BYTE', 0, 0, 4, true, 4]);
    expect(pick('ST255,INT0.2')).to.deep.equal([255, 'INT', 0, 0, 2, true, 4]);
    expect(pick(' st12 , dint0 ')).to.deep.equal([12, 'DINT', 0, 0, 1, false, 4]);
    expect(pick('ST0,CHAR3')).to.deep.equal([0, 'CHAR', 3, 0, 1, false, 1]);
  });

  it('keeps the address as written and names the station area for allow-lists', () => {
    const t = parseFreeportAddress('ST5,X0.3');
    expect(t.address).to.equal('ST5,X0.3');
    expect(t.area).to.equal('ST');
  });

  it('refuses what does not fit, naming the address and the problem', () => {
    const cases: [string, RegExp][] = [
      ['ST5,DWORD1', /DWORD at byte 1 ends at byte 4, past the station's 4-byte data area/],
      ['ST5,B1.4', /BYTE\[4\] at byte 1 ends at byte 4/],
      ['ST5,BYTE4', /ends at byte 4/],
      ['ST5,X0.8', /bit 8 does not exist/],
      ['ST5,X0', /a bit needs its number/],
      ['ST256,BYTE0', /station 256 is beyond the highest address 255/],
      ['ST5,LREAL0', /unknown type "LREAL"/],
      ['ST5,B0.0', /at least one element/],
      ['DB1,INT0', /expected ST<station>/],
      ['ST5', /expected ST<station>/],
      ['', /expected ST<station>/],
    ];
    for (const [address, problem] of cases) {
      expect(() => parseFreeportAddress(address), address)
        .to.throw(AddressError, problem)
        .with.property('message')
        .that.includes(`"${address}"`);
    }
  });

  it('follows the profile: a wider DA allows higher stations, a larger area longer tags', () => {
    expect(parseFreeportAddress('ST4095,BYTE0', { maxStation: 4095 }).station).to.equal(4095);
    expect(parseFreeportAddress('ST1,REAL4', { dataBytes: 8 }).byteOffset).to.equal(4);
  });

  it('throws nothing but AddressError on any input', () => {
    fc.assert(
      fc.property(fc.oneof(fc.string(), fc.stringMatching(/^ST\d{1,4},[A-Z]{1,6}\d{1,2}(\.\d{1,2})?$/)), (s) => {
        try {
          const t = parseFreeportAddress(s);
          expect(t.byteOffset + t.byteLength).to.be.at.most(4);
        } catch (err) {
          expect(err).to.be.instanceOf(AddressError);
        }
      }),
      { numRuns: 1000 },
    );
  });
});
