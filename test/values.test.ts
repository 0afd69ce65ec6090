import { expect } from 'chai';
import fc from 'fast-check';
import { parseAddress } from '../lib/address';
import { PlcError, ValueError } from '../lib/errors';
import type { DataTypeName } from '../lib/types';
import { decodeTag, encodeInto, encodeTag, tagByteLength, validateValue, writeSpan } from '../lib/values';

const hex = (b: Buffer) => b.toString('hex').toUpperCase();
const buf = (h: string) => Buffer.from(h.replace(/\s+/g, ''), 'hex');

/** [address, value, big-endian bytes] — S7 encodings checked by hand against the type definitions. */
const FIXTURES: [string, unknown, string][] = [
  ['DB1.DBB0', 0xab, 'AB'],
  ['DB1.DBB0:USINT', 200, 'C8'],
  ['DB1.DBB0:SINT', -2, 'FE'],
  ['DB1.DBW0', 0xbeef, 'BEEF'],
  ['DB1.DBW0:INT', -2, 'FFFE'],
  ['DB1.DBW0:INT', 1234, '04D2'],
  ['DB1.DBW0:UINT', 65535, 'FFFF'],
  ['DB1.DBD0', 0xdeadbeef, 'DEADBEEF'],
  ['DB1.DBD0:DINT', -1, 'FFFFFFFF'],
  ['DB1.DBD0:UDINT', 4294967295, 'FFFFFFFF'],
  ['DB1.DBD0:REAL', 1, '3F800000'],
  ['DB1.DBD0:REAL', -2.5, 'C0200000'],
  ['DB1.DBB0:LREAL', 1, '3FF0000000000000'],
  ['DB1.DBB0:LWORD', 0x0102030405060708n, '0102030405060708'],
  ['DB1.DBB0:LINT', -1n, 'FFFFFFFFFFFFFFFF'],
  ['DB1.DBB0:ULINT', 18446744073709551615n, 'FFFFFFFFFFFFFFFF'],
  ['DB1.DBB0:CHAR', 'A', '41'],
  ['DB1.DBW0:WCHAR', 'Ω', '03A9'],
  ['DB1.DBB0:CHAR[3]', ['a', 'b', 'c'], '616263'],
  ['DB1.DBB0:STRING[4]', 'hi', '0402 6869 0000'],
  ['DB1.DBB0:WSTRING[2]', 'é', '0002 0001 00E9 0000'],
  ['DB1.DBW0:S5TIME', 2000, '0200'], // 2 s = 200 × 10 ms (the finest exact base)
  ['DB1.DBW0:S5TIME', 9990000, '3999'],
  ['DB1.DBW0:S5TIME', 12300, '1123'], // 123 × 100 ms
  ['DB1.DBW0:S5TIME', 1230, '0123'],
  ['DB1.DBD0:TIME', -1000, 'FFFFFC18'],
  ['DB1.DBB0:LTIME', 1_000_000n, '00000000000F4240'],
  ['DB1.DBD0:TIME_OF_DAY', 3_600_000, '0036EE80'],
  ['DB1.DBW0:DATE', new Date('1990-01-02T00:00:00Z'), '0001'],
  ['DB1.DBW0:DATE', new Date('2024-02-29T00:00:00Z'), '30BD'], // 12477 days
  ['DB1.DBW0:DATE', new Date('1990-01-01T00:00:00Z'), '0000'],
  ['DB1.DBB0:DATE_AND_TIME', new Date('2024-05-17T13:45:30.123Z'), '24051713453012 36'],
  ['DB1.DBB0:DATE_AND_TIME', new Date('1999-12-31T23:59:59.999Z'), '99123123595999 96'],
  ['DB1.DBB0:DTL', new Date('2024-05-17T13:45:30.123Z'), '07E8 05 11 06 0D 2D 1E 0754D4C0'],
  ['C5', 123, '0123'],
  ['T3', 2000, '0200'],
  ['DB1.DBW0:INT[3]', [1, -1, 2], '0001FFFF0002'],
];

describe('value codecs', () => {
  for (const [address, value, bytes] of FIXTURES) {
    it(`${address} ${String(value)} ⇄ ${bytes.replace(/\s+/g, '')}`, () => {
      const tag = parseAddress(address);
      const expected = buf(bytes);
      const encoded = encodeTag(tag, value);
      expect(hex(encoded)).to.equal(hex(expected));
      expect(decodeTag(tag, expected)).to.deep.equal(value);
    });
  }

  it('S5TIME picks the finest time base that holds the value exactly, and decodes every base', () => {
    const tag = parseAddress('MW0:S5TIME');
    expect(hex(encodeTag(tag, 990))).to.equal('0099'); // 99 × 10 ms
    expect(hex(encodeTag(tag, 10_000))).to.equal('1100'); // 100 × 100 ms
    expect(decodeTag(tag, buf('2005'))).to.equal(5000); // 5 × 1 s
    expect(decodeTag(tag, buf('3010'))).to.equal(100_000); // 10 × 10 s
    expect(() => encodeTag(tag, 12_345)).to.throw(ValueError, /cannot be represented exactly/);
  });

  it('a BOOL array writes only its bits and keeps the neighbours', () => {
    const tag = parseAddress('DB1.DBX0.6:BOOL[4]');
    expect(tagByteLength(tag)).to.equal(2);
    const target = buf('FF00');
    encodeInto(tag, [false, true, false, true], target);
    // bits 6,7 of byte 0 → 0,1 ; bits 0,1 of byte 1 → 0,1
    expect(hex(target)).to.equal('BF02');
    expect(decodeTag(tag, target)).to.deep.equal([false, true, false, true]);
  });

  it('a single bit leaves the other seven alone', () => {
    const tag = parseAddress('DB1,X0.3');
    const target = buf('F7');
    encodeInto(tag, true, target);
    expect(hex(target)).to.equal('FF');
    encodeInto(tag, false, target);
    expect(hex(target)).to.equal('F7');
  });

  it('writing a STRING keeps the max-length byte the PLC holds and sends only length and characters', () => {
    const tag = parseAddress('DB1,S0.10');
    const plc = buf('0A03 616263 00000000000000');
    encodeInto(tag, 'xy', plc);
    expect(hex(plc.subarray(0, 4))).to.equal('0A027879');
    expect(writeSpan(tag, 'xy')).to.deep.equal({ start: 1, data: buf('027879') });
    const w = parseAddress('DB1,WSTRING0.4');
    expect(writeSpan(w, 'a')).to.deep.equal({ start: 2, data: buf('00010061') });
  });

  it('a corrupt STRING length from the PLC is clamped, never read past the string', () => {
    const tag = parseAddress('DB1,S0.4');
    expect(decodeTag(tag, buf('04FF 61626364'))).to.equal('abcd');
    expect(decodeTag(tag, buf('02FF 61626364'))).to.equal('ab');
  });

  const BAD: [string, unknown, RegExp][] = [
    ['DB1,INT2', 40000, /40000 is out of range for INT \(-32768\.\.32767\)/],
    ['DB1,INT2', 1.5, /not an integer/],
    ['DB1,INT2', '5', /expected a number for INT, got "5"/],
    ['DB1,INT2', NaN, /not an integer/],
    ['DB1.DBB0', -1, /out of range for BYTE/],
    ['DB1.DBD0:REAL', 1e39, /overflows REAL/],
    ['DB1.DBB0:LINT', 2 ** 60, /not a safe integer/],
    ['DB1.DBB0:ULINT', -1n, /out of range for ULINT/],
    ['DB1,S0.4', 'hello', /5 characters do not fit STRING\[4\]/],
    ['DB1,S0.4', 'ΩΩ', /outside latin-1/],
    ['DB1.DBB0:CHAR', 'ab', /one character/],
    ['DB1.DBW0:INT[3]', [1, 2], /expected an array of 3 INT, got 2 elements/],
    ['DB1.DBW0:INT[3]', 5, /expected an array of 3 INT/],
    ['DB1,X0.1', 1, /expected a boolean/],
    ['DB1.DBW0:DATE', new Date('2024-01-01T12:00:00Z'), /not a UTC midnight/],
    ['DB1.DBB0:DATE_AND_TIME', new Date('2090-01-01T00:00:00Z'), /out of range for DATE_AND_TIME \(1990-01-01\.\.2089-12-31\)/],
    ['DB1.DBB0:DTL', new Date('invalid'), /Invalid Date/],
    ['DB1.DBB0:DTL', '2024-01-01', /expected a Date/],
    ['DB1.DBD0:TIME_OF_DAY', 86_400_000, /out of range/],
    ['C5', 1000, /out of range for COUNTER \(0\.\.999\)/],
  ];
  for (const [address, value, message] of BAD) {
    it(`rejects ${String(value)} for ${address} with a ValueError naming the tag`, () => {
      const tag = parseAddress(address);
      const target = Buffer.alloc(tagByteLength(tag), 0x55);
      let error: unknown;
      try {
        encodeInto(tag, value, target);
      } catch (err) {
        error = err;
      }
      expect(error).to.be.instanceOf(ValueError);
      expect((error as ValueError).tag).to.equal(address);
      expect((error as ValueError).message).to.match(message).and.include(address);
      expect(target.every((b) => b === 0x55), 'nothing written').to.equal(true);
    });
  }

  it('decoding too few bytes is a ProtocolError', () => {
    expect(() => decodeTag(parseAddress('DB1,REAL0'), buf('3F80'))).to.throw(PlcError, /4 bytes expected, 2 received/);
  });

  const TYPES: [string, fc.Arbitrary<unknown>][] = [
    ['DB1.DBB0', fc.integer({ min: 0, max: 255 })],
    ['DB1.DBB0:SINT', fc.integer({ min: -128, max: 127 })],
    ['DB1.DBW0:INT', fc.integer({ min: -32768, max: 32767 })],
    ['DB1.DBW0:UINT', fc.integer({ min: 0, max: 65535 })],
    ['DB1.DBD0:DINT', fc.integer()],
    ['DB1.DBD0:UDINT', fc.integer({ min: 0, max: 2 ** 32 - 1 })],
    ['DB1.DBB0:LINT', fc.bigInt({ min: -(2n ** 63n), max: 2n ** 63n - 1n })],
    ['DB1.DBB0:ULINT', fc.bigInt({ min: 0n, max: 2n ** 64n - 1n })],
    ['DB1.DBB0:LWORD', fc.bigInt({ min: 0n, max: 2n ** 64n - 1n })],
    ['DB1.DBD0:REAL', fc.float({ noNaN: true }).map((f) => Math.fround(f))],
    ['DB1.DBB0:LREAL', fc.double({ noNaN: true })],
    ['DB1.DBB0:CHAR', fc.integer({ min: 0, max: 255 }).map((c) => String.fromCharCode(c))],
    ['DB1.DBW0:WCHAR', fc.integer({ min: 0, max: 0xffff }).map((c) => String.fromCharCode(c))],
    ['DB1.DBB0:STRING[20]', fc.string({ unit: fc.integer({ min: 0, max: 255 }).map((c) => String.fromCharCode(c)), maxLength: 20 })],
    ['DB1.DBB0:WSTRING[20]', fc.string({ unit: 'binary', maxLength: 10 }).filter((s) => s.length <= 20)],
    ['DB1.DBW0:S5TIME', fc.tuple(fc.integer({ min: 0, max: 999 }), fc.constantFrom(10, 100, 1000, 10000)).map(([u, b]) => u * b)],
    ['DB1.DBD0:TIME', fc.integer()],
    ['DB1.DBB0:LTIME', fc.bigInt({ min: -(2n ** 63n), max: 2n ** 63n - 1n })],
    ['DB1.DBD0:TIME_OF_DAY', fc.integer({ min: 0, max: 86_399_999 })],
    ['DB1.DBW0:DATE', fc.integer({ min: 0, max: 65378 }).map((d) => new Date(Date.UTC(1990, 0, 1) + d * 86_400_000))],
    ['DB1.DBB0:DATE_AND_TIME', fc.date({ min: new Date('1990-01-01T00:00:00Z'), max: new Date('2089-12-31T23:59:59.999Z'), noInvalidDate: true })],
    ['DB1.DBB0:DTL', fc.date({ min: new Date('1970-01-01T00:00:00Z'), max: new Date('2262-04-11T00:00:00Z'), noInvalidDate: true })],
    ['C0', fc.integer({ min: 0, max: 999 })],
    ['DB1.DBX0.5:BOOL[13]', fc.array(fc.boolean(), { minLength: 13, maxLength: 13 })],
    ['DB1.DBD0:REAL[5]', fc.array(fc.float({ noNaN: true }).map((f) => Math.fround(f)), { minLength: 5, maxLength: 5 })],
  ];

  it('property: decode(encode(v)) is v for every type over its valid domain', () => {
    for (const [address, arb] of TYPES) {
      const tag = parseAddress(address);
      fc.assert(
        fc.property(arb, (v) => {
          validateValue(tag, v);
          const back = decodeTag(tag, encodeTag(tag, v));
          if (typeof v === 'number' && Object.is(v, -0)) expect(Object.is(back, -0) || back === 0).to.equal(true);
          else expect(back, address).to.deep.equal(v);
        }),
        { numRuns: 300 },
      );
    }
  });

  it('property: decoding arbitrary bytes never throws for any type', () => {
    const addresses = [...TYPES.map(([a]) => a), 'DB1,S0.254', 'DB1,WSTRING0.100', 'T0', 'DB1.DBB0:DTL[3]'];
    for (const address of addresses) {
      const tag = parseAddress(address);
      fc.assert(
        fc.property(fc.uint8Array({ minLength: tag.byteLength, maxLength: tag.byteLength + 4 }), (bytes) => {
          decodeTag(tag, Buffer.from(bytes));
        }),
        { numRuns: 300 },
      );
    }
  });
});
