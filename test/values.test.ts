import { expect } from 'chai';
import { parseAddress } from '../lib/address';
import { PlcError, ProtocolError, ValueError } from '../lib/errors';
import type { DataTypeName } from '../lib/types';
import {
  decodeTag,
  tagDecoder,
  describeJsType,
  elementByteLength,
  encodeInto,
  encodeTag,
  tagByteLength,
  validateValue,
  writeSpan,
  type TagShape,
} from '../lib/values';

const hex = (b: Buffer) => b.toString('hex').toUpperCase();
const buf = (h: string) => Buffer.from(h.replace(/\s+/g, ''), 'hex');

/** A tag from a type spec: 'INT', 'INT[3]', 'STRING[4]', 'STRING[4][2]' (2 strings), 'BOOL[4]@6' (from bit 6). */
function shape(spec: string, address = `DB1.DBB0:${spec}`): TagShape {
  const m = /^([A-Z_0-9]+)(?:\[(\d+)\])?(?:\[(\d+)\])?(?:@(\d))?$/.exec(spec);
  if (!m) throw new Error(`bad spec ${spec}`);
  const type = m[1] as DataTypeName;
  const isString = type === 'STRING' || type === 'WSTRING';
  const stringLength = isString ? Number(m[2] ?? 254) : 0;
  const countText = isString ? m[3] : m[2];
  return {
    address,
    type,
    stringLength,
    count: countText === undefined ? 1 : Number(countText),
    isArray: countText !== undefined,
    bitOffset: Number(m[4] ?? 0),
  };
}

const ALL_TYPES: DataTypeName[] = [
  'BOOL',
  'BYTE',
  'WORD',
  'DWORD',
  'LWORD',
  'SINT',
  'USINT',
  'INT',
  'UINT',
  'DINT',
  'UDINT',
  'LINT',
  'ULINT',
  'REAL',
  'LREAL',
  'CHAR',
  'WCHAR',
  'STRING',
  'WSTRING',
  'S5TIME',
  'TIME',
  'LTIME',
  'DATE',
  'TIME_OF_DAY',
  'DATE_AND_TIME',
  'DTL',
  'COUNTER',
  'TIMER',
];

const utc = (iso: string) => new Date(iso);

/**
 * [type spec, value, big-endian bytes]: each encodes to exactly these bytes and
 * decodes back to the same value. Worked out by hand from the S7 type
 * definitions (IEEE 754, two's complement, BCD layouts in lib/values).
 */
const FIXTURES: [string, unknown, string][] = [
  ['BOOL@3', true, '08'],
  ['BOOL', false, '00'],
  ['BYTE', 0xab, 'AB'],
  ['WORD', 0xbeef, 'BEEF'],
  ['DWORD', 0xdeadbeef, 'DEADBEEF'],
  ['LWORD', 0x0102030405060708n, '0102030405060708'],
  ['SINT', -128, '80'],
  ['SINT', 127, '7F'],
  ['SINT', -2, 'FE'],
  ['USINT', 200, 'C8'],
  ['INT', 1234, '04D2'],
  ['INT', -32768, '8000'],
  ['INT', 32767, '7FFF'],
  ['INT', -2, 'FFFE'],
  ['UINT', 65535, 'FFFF'],
  ['DINT', -2147483648, '80000000'],
  ['DINT', -1, 'FFFFFFFF'],
  ['UDINT', 4294967295, 'FFFFFFFF'],
  ['LINT', -(2n ** 63n), '8000000000000000'],
  ['LINT', -1n, 'FFFFFFFFFFFFFFFF'],
  ['ULINT', 2n ** 64n - 1n, 'FFFFFFFFFFFFFFFF'],
  ['REAL', 1, '3F800000'],
  ['REAL', -2.5, 'C0200000'],
  ['REAL', 3.4028234663852886e38, '7F7FFFFF'],
  ['REAL', 1.401298464324817e-45, '00000001'], // smallest denormal
  ['REAL', Infinity, '7F800000'],
  ['REAL', -Infinity, 'FF800000'],
  ['REAL', NaN, '7FC00000'],
  ['LREAL', 1, '3FF0000000000000'],
  ['LREAL', Math.PI, '400921FB54442D18'],
  ['CHAR', 'A', '41'],
  ['CHAR', 'é', 'E9'],
  ['WCHAR', 'Ω', '03A9'],
  ['WCHAR', '€', '20AC'],
  ['STRING[4]', 'hi', '04 02 6869 0000'],
  ['STRING[4]', '', '04 00 00000000'],
  ['STRING[3]', 'ÄÖü', '03 03 C4D6FC'],
  ['WSTRING[2]', 'é', '0002 0001 00E9 0000'],
  ['S5TIME', 0, '0000'],
  ['S5TIME', 10, '0001'], // 1 × 10 ms
  ['S5TIME', 990, '0099'],
  ['S5TIME', 1230, '0123'],
  ['S5TIME', 2000, '0200'], // 2 s = 200 × 10 ms, the finest base that holds it
  ['S5TIME', 10_000, '1100'], // 100 × 100 ms (1000 × 10 ms does not fit 3 digits)
  ['S5TIME', 12_300, '1123'],
  ['S5TIME', 100_000, '2100'], // 100 × 1 s
  ['S5TIME', 1_230_000, '3123'], // 123 × 10 s
  ['S5TIME', 9_990_000, '3999'], // 2h46m30s, the maximum
  ['TIMER', 2000, '0200'],
  ['TIMER', 9_990_000, '3999'],
  ['COUNTER', 0, '0000'],
  ['COUNTER', 123, '0123'],
  ['COUNTER', 999, '0999'],
  ['TIME', -1000, 'FFFFFC18'],
  ['TIME', 2147483647, '7FFFFFFF'], // T#24d20h31m23s647ms
  ['LTIME', 1_000_000n, '00000000000F4240'],
  ['LTIME', -1n, 'FFFFFFFFFFFFFFFF'],
  ['TIME_OF_DAY', 3_600_000, '0036EE80'],
  ['TIME_OF_DAY', 86_399_999, '05265BFF'],
  ['DATE', utc('1990-01-01T00:00:00Z'), '0000'],
  ['DATE', utc('1990-01-02T00:00:00Z'), '0001'],
  ['DATE', utc('2024-02-29T00:00:00Z'), '30BD'], // day 12477
  ['DATE', utc('2168-12-31T00:00:00Z'), 'FF62'], // D#2168-12-31, the maximum
  ['DATE_AND_TIME', utc('2024-05-17T13:45:30.123Z'), '24 05 17 13 45 30 12 36'], // Friday = 6
  ['DATE_AND_TIME', utc('1990-01-01T00:00:00Z'), '90 01 01 00 00 00 00 02'], // Monday = 2
  ['DATE_AND_TIME', utc('1999-12-31T23:59:59.999Z'), '99 12 31 23 59 59 99 96'],
  ['DATE_AND_TIME', utc('2089-12-31T23:59:59.999Z'), '89 12 31 23 59 59 99 97'], // Sunday = 1 … Saturday = 7
  ['DTL', utc('2024-05-17T13:45:30.123Z'), '07E8 05 11 06 0D 2D 1E 0754D4C0'],
  ['DTL', utc('1970-01-01T00:00:00Z'), '07B2 01 01 05 00 00 00 00000000'],
  ['DTL', utc('2262-04-11T23:47:16.854Z'), '08D6 04 0B 06 17 2F 10 32E70180'],
  // arrays
  ['INT[3]', [1, -1, 2], '0001 FFFF 0002'],
  ['REAL[2]', [1, -2.5], '3F800000 C0200000'],
  ['CHAR[3]', ['a', 'b', 'c'], '616263'],
  ['WCHAR[2]', ['Ω', 'a'], '03A9 0061'],
  ['STRING[2][2]', ['ab', 'c'], '0202 6162 0201 6300'],
  ['WSTRING[1][2]', ['a', ''], '0001 0001 0061 0001 0000 0000'],
  ['LINT[2]', [1n, -2n], '0000000000000001 FFFFFFFFFFFFFFFE'],
  ['S5TIME[2]', [10, 9_990_000], '0001 3999'],
  ['COUNTER[2]', [7, 42], '0007 0042'],
  ['DATE[2]', [utc('1990-01-01T00:00:00Z'), utc('1990-01-03T00:00:00Z')], '0000 0002'],
  [
    'DTL[2]',
    [utc('1970-01-01T00:00:00Z'), utc('2024-05-17T13:45:30.123Z')],
    '07B2 01 01 05 00 00 00 00000000 07E8 05 11 06 0D 2D 1E 0754D4C0',
  ],
  ['BOOL[4]@6', [false, true, false, true], '80 02'],
  ['BOOL[8]', [true, false, false, false, false, false, false, true], '81'],
];

describe('values: byte-exact fixtures for every type', () => {
  for (const [spec, value, bytes] of FIXTURES) {
    const shown = value instanceof Date ? value.toISOString() : Array.isArray(value) ? `[${value.map(String)}]` : String(value);
    it(`${spec} ${shown} ⇄ ${bytes.replace(/\s+/g, '')}`, () => {
      const tag = shape(spec);
      const expected = buf(bytes);
      expect(hex(encodeTag(tag, value))).to.equal(hex(expected));
      expect(decodeTag(tag, expected)).to.deep.equal(value);
    });
  }

  it('covers all 28 types', () => {
    const covered = new Set(FIXTURES.map(([spec]) => /^[A-Z_0-9]+/.exec(spec)![0]));
    expect([...covered].sort()).to.deep.equal([...ALL_TYPES].sort());
  });

  it('decodes at an offset into a larger buffer', () => {
    expect(decodeTag(shape('INT'), buf('FFFF 04D2 FFFF'), 2)).to.equal(1234);
    expect(decodeTag(shape('BOOL[2]@7'), buf('00 80 01'), 1)).to.deep.equal([true, true]);
    // The poll path's decoders: the same values, one shared decoder per shape.
    expect(tagDecoder(shape('INT'))(buf('FFFF 04D2 FFFF'), 2)).to.equal(1234);
    expect(tagDecoder(shape('BOOL[2]@7'))(buf('00 80 01'), 1)).to.deep.equal([true, true]);
    expect(tagDecoder(shape('INT', 'DB1,INT2'))).to.equal(tagDecoder(shape('INT', 'DB9,INT40')));
    expect(tagDecoder(shape('BOOL@3'))).to.not.equal(tagDecoder(shape('BOOL@4')));
    expect(tagDecoder(shape('BOOL@3'))(buf('08'), 0)).to.equal(true);
    expect(tagDecoder(shape('BOOL@4'))(buf('08'), 0)).to.equal(false);
  });

  it('a 64-bit type accepts a safe-integer number on write and reads back a bigint', () => {
    expect(hex(encodeTag(shape('LINT'), -2))).to.equal('FFFFFFFFFFFFFFFE');
    expect(hex(encodeTag(shape('LTIME'), 1_000_000))).to.equal('00000000000F4240');
    expect(decodeTag(shape('ULINT'), encodeTag(shape('ULINT'), 2 ** 53 - 1))).to.equal(2n ** 53n - 1n);
  });

  it('REAL rounds to the nearest float32, like the PLC', () => {
    expect(hex(encodeTag(shape('REAL'), 0.1))).to.equal('3DCCCCCD');
    expect(decodeTag(shape('REAL'), buf('3DCCCCCD'))).to.equal(Math.fround(0.1));
    // just above FLOAT32_MAX but still rounding to it is not an overflow
    expect(hex(encodeTag(shape('REAL'), 3.4028235e38))).to.equal('7F7FFFFF');
  });

  it('integer types accept a bigint in range and write -0 as 0', () => {
    expect(hex(encodeTag(shape('INT'), -2n))).to.equal('FFFE');
    expect(hex(encodeTag(shape('DINT'), -0))).to.equal('00000000');
  });

  it('a CHAR array may be written as text, padded with NUL', () => {
    expect(hex(encodeTag(shape('CHAR[4]'), 'ab'))).to.equal('61620000');
    expect(hex(encodeTag(shape('WCHAR[2]'), 'Ω'))).to.equal('03A90000');
  });
});

describe('values: sizes and the JavaScript mapping', () => {
  it('elementByteLength of every type', () => {
    const sizes: Record<DataTypeName, number> = {
      BOOL: 1,
      BYTE: 1,
      CHAR: 1,
      SINT: 1,
      USINT: 1,
      WORD: 2,
      INT: 2,
      UINT: 2,
      WCHAR: 2,
      S5TIME: 2,
      DATE: 2,
      COUNTER: 2,
      TIMER: 2,
      DWORD: 4,
      DINT: 4,
      UDINT: 4,
      REAL: 4,
      TIME: 4,
      TIME_OF_DAY: 4,
      LWORD: 8,
      LINT: 8,
      ULINT: 8,
      LREAL: 8,
      LTIME: 8,
      DATE_AND_TIME: 8,
      DTL: 12,
      STRING: 32,
      WSTRING: 64,
    };
    for (const type of ALL_TYPES) expect(elementByteLength(type, 30), type).to.equal(sizes[type]);
    expect(elementByteLength('STRING', 254)).to.equal(256);
    expect(elementByteLength('WSTRING')).to.equal(4);
  });

  it('tagByteLength: arrays multiply, BOOL counts the bytes its bits touch', () => {
    expect(tagByteLength(shape('STRING[10][3]'))).to.equal(36);
    expect(tagByteLength(shape('DTL[2]'))).to.equal(24);
    expect(tagByteLength(shape('BOOL@7'))).to.equal(1);
    expect(tagByteLength(shape('BOOL[2]@7'))).to.equal(2);
    expect(tagByteLength(shape('BOOL[16]'))).to.equal(2);
    expect(tagByteLength(shape('BOOL[17]'))).to.equal(3);
  });

  it('describeJsType names the JS type of every PLC type', () => {
    expect(describeJsType('INT')).to.match(/^number -32768\.\.32767/);
    for (const t of ['LWORD', 'LINT', 'ULINT', 'LTIME'] as const) expect(describeJsType(t), t).to.match(/^bigint/);
    for (const t of ['DATE', 'DATE_AND_TIME', 'DTL'] as const) expect(describeJsType(t), t).to.match(/^Date/);
    for (const t of ['S5TIME', 'TIME', 'TIME_OF_DAY', 'TIMER'] as const) expect(describeJsType(t), t).to.match(/^number of ms/);
    expect(describeJsType('BOOL')).to.equal('boolean');
    for (const t of ALL_TYPES) expect(describeJsType(t), t).to.be.a('string').and.not.equal('');
  });
});

describe('values: bits, strings and read-modify-write', () => {
  it('a BOOL array writes only its bits and keeps the neighbours', () => {
    const tag = shape('BOOL[4]@6');
    const target = buf('FF00');
    encodeInto(tag, [false, true, false, true], target);
    expect(hex(target)).to.equal('BF02'); // bits 6,7 of byte 0 → 0,1; bits 0,1 of byte 1 → 0,1
    expect(decodeTag(tag, target)).to.deep.equal([false, true, false, true]);
  });

  it('a single bit leaves the other seven alone, at an offset', () => {
    const tag = shape('BOOL@3');
    const target = buf('AA F7 55');
    encodeInto(tag, true, target, 1);
    expect(hex(target)).to.equal('AAFF55');
    encodeInto(tag, false, target, 1);
    expect(hex(target)).to.equal('AAF755');
  });

  it('writing a STRING keeps the max-length byte the PLC holds and sends only length and characters', () => {
    const tag = shape('STRING[10]', 'DB1,S0.10');
    const plc = buf('FE03 616263 00000000000000');
    encodeInto(tag, 'xy', plc);
    expect(hex(plc)).to.equal('FE027879' + '00'.repeat(8));
    expect(writeSpan(tag, 'xy')).to.deep.equal({ start: 1, data: buf('027879') });
    expect(writeSpan(tag, '')).to.deep.equal({ start: 1, data: buf('00') });
  });

  it('writing a WSTRING keeps the max-length word', () => {
    const tag = shape('WSTRING[4]');
    const plc = buf('0010 0004 0041004200430044');
    encodeInto(tag, 'é', plc);
    expect(hex(plc)).to.equal('0010000100E9000000000000');
    expect(writeSpan(tag, 'a')).to.deep.equal({ start: 2, data: buf('00010061') });
  });

  it('writing an array of strings keeps every max-length byte', () => {
    const tag = shape('STRING[2][2]');
    const plc = buf('09 00 0000 08 00 0000');
    encodeInto(tag, ['a', 'bc'], plc);
    expect(hex(plc)).to.equal('090161000802' + '6263');
    expect(writeSpan(tag, ['a', 'bc'])).to.deep.equal({ start: 0, data: buf('0201 6100 0202 6263') });
  });

  it('writeSpan of other types is the whole encoded tag; BOOL is refused (drivers write bits)', () => {
    expect(writeSpan(shape('INT[2]'), [1, 2])).to.deep.equal({ start: 0, data: buf('00010002') });
    expect(() => writeSpan(shape('BOOL'), true)).to.throw(TypeError, /bit by bit/);
  });

  it('writeSpan validates: a too-long STRING is a ValueError naming the tag and the limit', () => {
    expect(() => writeSpan(shape('STRING[3]', 'DB1,S0.3'), 'abcd')).to.throw(
      ValueError,
      /"DB1,S0\.3": 4 characters do not fit STRING\[3\] \(at most 3\)/,
    );
  });

  it('encodeTag of a BOOL sets the bits in zero bytes', () => {
    expect(hex(encodeTag(shape('BOOL[3]@7'), [true, true, true]))).to.equal('8003');
  });
});

describe('values: decoding what a PLC (or a broken peer) sends', () => {
  it('a STRING actual length beyond the declared or the PLC max length is clamped, never read past the string', () => {
    const tag = shape('STRING[4]');
    expect(decodeTag(tag, buf('04FF 61626364'))).to.equal('abcd');
    expect(decodeTag(tag, buf('02FF 61626364'))).to.equal('ab');
    expect(decodeTag(tag, buf('FE03 61626364'))).to.equal('abc');
    expect(decodeTag(tag, buf('0003 61626364')), 'a zero max byte is ignored').to.equal('abc');
    expect(decodeTag(tag, buf('0000 00000000')), 'a never-written string').to.equal('');
  });

  it('a WSTRING actual length beyond the max is clamped', () => {
    expect(decodeTag(shape('WSTRING[2]'), buf('0002 FFFF 0041 0042'))).to.equal('AB');
    expect(decodeTag(shape('WSTRING[2]'), buf('0001 0002 0041 0042'))).to.equal('A');
  });

  it('S5TIME and COUNTER: unused high bits are ignored, a non-BCD nibble reads as 9', () => {
    expect(decodeTag(shape('S5TIME'), buf('C200'))).to.equal(2000);
    expect(decodeTag(shape('S5TIME'), buf('200A'))).to.equal(9000);
    expect(decodeTag(shape('COUNTER'), buf('F123'))).to.equal(123);
    expect(decodeTag(shape('COUNTER'), buf('0FFF'))).to.equal(999);
  });

  it('DATE_AND_TIME and DTL whose fields are no real date decode to an Invalid Date (a never-written DB)', () => {
    for (const [spec, bytes] of [
      ['DATE_AND_TIME', '00 00 00 00 00 00 00 00'], // month 0
      ['DATE_AND_TIME', '24 02 30 00 00 00 00 00'], // 30 February
      ['DATE_AND_TIME', '24 0A 01 00 00 00 00 00'], // not BCD
      ['DATE_AND_TIME', '24 01 01 24 00 00 00 00'], // hour 24
      ['DTL', '0000 00 00 00 00 00 00 00000000'],
      ['DTL', '07E8 01 01 00 00 3C 00 00000000'], // second 60
      ['DTL', '07E8 01 01 00 00 00 00 3B9ACA00'], // 1e9 ns
    ] as const) {
      const d = decodeTag(shape(spec), buf(bytes)) as Date;
      expect(d, `${spec} ${bytes}`).to.be.instanceOf(Date);
      expect(Number.isNaN(d.getTime()), `${spec} ${bytes}`).to.equal(true);
    }
  });

  it('DTL: the weekday byte is not trusted, nanoseconds are truncated to ms, a year below 100 stays itself', () => {
    expect(decodeTag(shape('DTL'), buf('07E8 05 11 01 0D 2D 1E 0754D4C0'))).to.deep.equal(utc('2024-05-17T13:45:30.123Z'));
    expect(decodeTag(shape('DTL'), buf('07E8 05 11 06 0D 2D 1E 0754D4C1'))).to.deep.equal(utc('2024-05-17T13:45:30.123Z'));
    expect((decodeTag(shape('DTL'), buf('0032 01 01 01 00 00 00 00000000')) as Date).getUTCFullYear()).to.equal(50);
  });

  it('DATE beyond the documented maximum still decodes (u16 days)', () => {
    expect(decodeTag(shape('DATE'), buf('FFFF'))).to.deep.equal(utc('2169-06-06T00:00:00Z'));
  });

  it('too few bytes is a ProtocolError naming the tag', () => {
    let error: unknown;
    try {
      decodeTag(shape('REAL', 'DB1,REAL0'), buf('3F80'));
    } catch (err) {
      error = err;
    }
    expect(error).to.be.instanceOf(ProtocolError);
    expect((error as PlcError).message).to.equal('DB1,REAL0: 4 bytes expected, 2 received');
    expect((error as PlcError).tag).to.equal('DB1,REAL0');
    expect(() => decodeTag(shape('INT'), buf('0001'), 1)).to.throw(ProtocolError, /2 bytes expected, 1 received/);
    expect(() => decodeTag(shape('BOOL[9]'), buf('FF'))).to.throw(ProtocolError, /2 bytes expected/);
  });
});

/** [type spec, address, value, message]: each is a ValueError naming the address, and nothing is written. */
const BAD: [string, string, unknown, RegExp][] = [
  ['INT', 'DB1,INT2', 40000, /"DB1,INT2": 40000 is out of range for INT \(-32768\.\.32767\)$/],
  ['INT', 'DB1,INT2', -32769, /-32769 is out of range for INT/],
  ['INT', 'DB1,INT2', 1.5, /1\.5 is not an integer \(INT\)/],
  ['INT', 'DB1,INT2', NaN, /NaN is not an integer/],
  ['INT', 'DB1,INT2', Infinity, /Infinity is not an integer/],
  ['INT', 'DB1,INT2', '5', /expected a number for INT, got "5"/],
  ['INT', 'DB1,INT2', null, /expected a number for INT, got null/],
  ['INT', 'DB1,INT2', undefined, /got undefined/],
  ['INT', 'DB1,INT2', true, /expected a number for INT, got true/],
  ['INT', 'DB1,INT2', [1], /got an array of 1/],
  ['INT', 'DB1,INT2', 40000n, /40000n is out of range for INT/],
  ['BYTE', 'MB0', -1, /-1 is out of range for BYTE \(0\.\.255\)/],
  ['SINT', 'MB0:SINT', 128, /out of range for SINT \(-128\.\.127\)/],
  ['USINT', 'MB0:USINT', 256, /out of range for USINT/],
  ['WORD', 'MW0', 65536, /out of range for WORD/],
  ['UINT', 'MW0:UINT', -1, /out of range for UINT/],
  ['DWORD', 'MD0', 2 ** 32, /out of range for DWORD/],
  ['DINT', 'MD0:DINT', 2 ** 31, /out of range for DINT/],
  ['UDINT', 'MD0:UDINT', -1, /out of range for UDINT/],
  ['REAL', 'DB1,REAL0', 1e39, /1e\+39 overflows REAL/],
  ['REAL', 'DB1,REAL0', -3.5e38, /overflows REAL/],
  ['REAL', 'DB1,REAL0', '1.5', /expected a number for REAL/],
  ['LREAL', 'DB1.DBB0:LREAL', 1n, /expected a number for LREAL, got 1n/],
  ['LINT', 'DB1.DBB0:LINT', 2 ** 60, /is not a safe integer; pass a bigint for LINT/],
  ['LINT', 'DB1.DBB0:LINT', 2n ** 63n, /out of range for LINT/],
  ['LINT', 'DB1.DBB0:LINT', 1.5, /not a safe integer/],
  ['ULINT', 'DB1.DBB0:ULINT', -1n, /-1n is out of range for ULINT/],
  ['LWORD', 'DB1.DBB0:LWORD', 2n ** 64n, /out of range for LWORD/],
  ['LWORD', 'DB1.DBB0:LWORD', '1', /expected a bigint or an integer number for LWORD/],
  ['LTIME', 'DB1.DBB0:LTIME', 0.5, /not a safe integer/],
  ['STRING[4]', 'DB1,S0.4', 'hello', /5 characters do not fit STRING\[4\] \(at most 4\)/],
  ['STRING[4]', 'DB1,S0.4', 'ΩΩ', /outside latin-1, which STRING\[4\] cannot hold/],
  ['STRING[4]', 'DB1,S0.4', 42, /expected a string for STRING\[4\], got 42/],
  ['WSTRING[2]', 'DB1.DBB0:WSTRING[2]', 'abc', /3 UTF-16 units do not fit WSTRING\[2\]/],
  ['WSTRING[2]', 'DB1.DBB0:WSTRING[2]', '😀!', /3 UTF-16 units/],
  ['CHAR', 'DB1.DBB0:CHAR', 'ab', /expected one character for CHAR, got "ab"/],
  ['CHAR', 'DB1.DBB0:CHAR', '', /expected one character/],
  ['CHAR', 'DB1.DBB0:CHAR', 'Ω', /not a latin-1 character/],
  ['WCHAR', 'DB1.DBW0:WCHAR', '😀', /surrogate pair/],
  ['INT[3]', 'DB1,INT0.3', [1, 2], /expected an array of 3 INT, got 2 elements/],
  ['INT[3]', 'DB1,INT0.3', 5, /expected an array of 3 INT, got 5/],
  ['INT[3]', 'DB1,INT0.3', [1, 40000, 3], /element 1: 40000 is out of range for INT/],
  ['CHAR[2]', 'DB1.DBB0:CHAR[2]', 'abc', /3 characters do not fit CHAR\[2\]/],
  ['STRING[2][2]', 'DB1.DBB0:STRING[2][2]', ['ab', 'abc'], /element 1: 3 characters do not fit STRING\[2\]/],
  ['BOOL', 'DB1,X0.1', 1, /expected a boolean for BOOL, got 1/],
  ['BOOL', 'DB1,X0.1', 'true', /expected a boolean/],
  ['BOOL[3]', 'DB1,X0.0.3', [true, 0, false], /element 1: expected a boolean/],
  ['BOOL[3]', 'DB1,X0.0.3', [true], /expected an array of 3 BOOL/],
  ['S5TIME', 'MW0:S5TIME', 12_345, /12345 ms cannot be represented exactly in S5TIME/],
  ['S5TIME', 'MW0:S5TIME', 9_990_001, /out of range for S5TIME \(0\.\.9990000\)/],
  ['S5TIME', 'MW0:S5TIME', -10, /out of range for S5TIME/],
  ['TIMER', 'T3', 10_001, /cannot be represented exactly in TIMER/],
  ['COUNTER', 'C5', 1000, /1000 is out of range for COUNTER \(0\.\.999\)/],
  ['COUNTER', 'C5', 1.5, /not an integer/],
  ['TIME', 'MD0:TIME', 2 ** 31, /out of range for TIME/],
  ['TIME_OF_DAY', 'MD0:TOD', 86_400_000, /out of range for TIME_OF_DAY \(0\.\.86399999\)/],
  ['TIME_OF_DAY', 'MD0:TOD', -1, /out of range/],
  ['DATE', 'MW0:DATE', utc('2024-01-01T12:00:00Z'), /not a UTC midnight/],
  ['DATE', 'MW0:DATE', utc('1989-12-31T00:00:00Z'), /out of range for DATE \(1990-01-01\.\.2168-12-31\)/],
  ['DATE', 'MW0:DATE', utc('2169-01-01T00:00:00Z'), /out of range for DATE/],
  ['DATE', 'MW0:DATE', 0, /expected a Date for DATE, got 0/],
  ['DATE_AND_TIME', 'DB1.DBB0:DT', utc('2090-01-01T00:00:00Z'), /out of range for DATE_AND_TIME \(1990-01-01\.\.2089-12-31\)/],
  ['DATE_AND_TIME', 'DB1.DBB0:DT', utc('1989-12-31T23:59:59.999Z'), /out of range for DATE_AND_TIME/],
  ['DTL', 'DB1.DBB0:DTL', new Date('invalid'), /Invalid Date for DTL/],
  ['DTL', 'DB1.DBB0:DTL', '2024-01-01', /expected a Date for DTL, got "2024-01-01"/],
  ['DTL', 'DB1.DBB0:DTL', utc('1969-12-31T23:59:59.999Z'), /out of range for DTL/],
  ['DTL', 'DB1.DBB0:DTL', utc('2262-04-11T23:47:16.855Z'), /out of range for DTL/],
];

describe('values: strict validation', () => {
  for (const [spec, address, value, message] of BAD) {
    const shown = typeof value === 'string' ? JSON.stringify(value) : value instanceof Date ? value.toJSON() : String(value);
    it(`rejects ${shown} for ${address} (${spec}) with a ValueError naming the tag, writing nothing`, () => {
      const tag = shape(spec, address);
      const target = Buffer.alloc(tagByteLength(tag), 0x55);
      let error: unknown;
      try {
        encodeInto(tag, value, target);
      } catch (err) {
        error = err;
      }
      expect(error).to.be.instanceOf(ValueError);
      expect((error as ValueError).code).to.equal('INVALID_VALUE');
      expect((error as ValueError).tag).to.equal(address);
      expect((error as ValueError).message)
        .to.include(`"${address}"`)
        .and.match(message);
      expect(
        target.every((b) => b === 0x55),
        'nothing written',
      ).to.equal(true);
      expect(() => encodeTag(tag, value)).to.throw(ValueError);
      expect(() => validateValue(tag, value)).to.throw(ValueError);
    });
  }
});

describe('values: with tags from the address parser', () => {
  it('nodes7 and IEC addresses encode and decode through the parsed tag', () => {
    expect(hex(encodeTag(parseAddress('DB1,INT2'), 1234))).to.equal('04D2');
    expect(hex(encodeTag(parseAddress('DB1.DBD4:REAL'), 1))).to.equal('3F800000');
    expect(decodeTag(parseAddress('DB10,S20.5'), buf('0503 616263 0000'))).to.equal('abc');
    expect(decodeTag(parseAddress('DB1,X0.1.3'), buf('0A'))).to.deep.equal([true, false, true]);
    expect(hex(encodeTag(parseAddress('T3'), 2000))).to.equal('0200');
    expect(hex(encodeTag(parseAddress('C5'), 123))).to.equal('0123');
    expect(() => validateValue(parseAddress('DB1,INT2'), 40000)).to.throw(
      ValueError,
      'invalid value for "DB1,INT2": 40000 is out of range for INT (-32768..32767)',
    );
  });
});
