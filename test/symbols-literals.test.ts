import { expect } from 'chai';
import { SourceError } from '../lib/errors';
import { literalValue } from '../lib/symbols/literals';
import type { DataBlockDecl, Literal } from '../lib/symbols/model';
import { parseBlockSource } from '../lib/symbols/source-parser';
import type { DataTypeName, PlcScalar } from '../lib/types';

const AT = { file: 'Tank.db', line: 7, column: 12 };

function lit(text: string): Literal {
  return { text, at: AT };
}

function valueOf(text: string, type: DataTypeName, stringLength = 0): PlcScalar {
  return literalValue(lit(text), type, stringLength);
}

function refusal(text: string, type: DataTypeName, stringLength = 0): SourceError {
  try {
    valueOf(text, type, stringLength);
  } catch (err) {
    expect(err, text).to.be.instanceOf(SourceError);
    return err as SourceError;
  }
  expect.fail(`${text} was accepted for ${type}`);
}

const utc = (...f: [number, number, number, number?, number?, number?, number?]) => {
  const d = new Date(0);
  d.setUTCFullYear(f[0], f[1] - 1, f[2]);
  d.setUTCHours(f[3] ?? 0, f[4] ?? 0, f[5] ?? 0, f[6] ?? 0);
  return d;
};

describe('symbols: start-value literals (literalValue)', () => {
  const accepted: [text: string, type: DataTypeName, value: PlcScalar, stringLength?: number][] = [
    // BOOL
    ['TRUE', 'BOOL', true],
    ['false', 'BOOL', false],
    ['1', 'BOOL', true],
    ['0', 'BOOL', false],
    ['BOOL#TRUE', 'BOOL', true],
    ['BOOL#0', 'BOOL', false],
    // integers, every radix and STEP 7 form
    ['12', 'INT', 12],
    ['-32768', 'INT', -32768],
    ['+5', 'SINT', 5],
    ['1_000', 'DINT', 1000],
    ['INT#5', 'INT', 5],
    ['INT#-5', 'INT', -5],
    ['DINT#16#7FFF_FFFF', 'DINT', 0x7fffffff],
    ['16#FF', 'BYTE', 255],
    ['16#ff', 'BYTE', 255],
    ['2#1010', 'BYTE', 10],
    ['2#1010_0101', 'WORD', 0xa5],
    ['8#17', 'BYTE', 15],
    ['-16#80', 'SINT', -128],
    ['B#16#FF', 'BYTE', 255],
    ['W#16#FF', 'WORD', 255],
    ['W#16#FFFF', 'WORD', 65535],
    ['W#2#1111', 'WORD', 15],
    ['DW#16#FFFF0000', 'DWORD', 0xffff0000],
    ['LW#16#FFFF_FFFF_FFFF_FFFF', 'LWORD', 2n ** 64n - 1n],
    ['L#10', 'DINT', 10],
    ['L#-2147483648', 'DINT', -2147483648],
    ['B#(1, 2)', 'WORD', 0x0102],
    ['B#(1,2,3,4)', 'DWORD', 0x01020304],
    ['C#12', 'WORD', 0x12],
    ['C#999', 'COUNTER', 999],
    ['12', 'COUNTER', 12],
    ['65535', 'UINT', 65535],
    ['4294967295', 'UDINT', 4294967295],
    ['-9223372036854775808', 'LINT', -(2n ** 63n)],
    ['LINT#9223372036854775807', 'LINT', 2n ** 63n - 1n],
    ['ULINT#18446744073709551615', 'ULINT', 2n ** 64n - 1n],
    ['USINT#255', 'USINT', 255],
    // reals
    ['1.5', 'REAL', 1.5],
    ['1.5E3', 'REAL', 1500],
    ['-1.0', 'REAL', -1],
    ['1.000000e+000', 'REAL', 1],
    ['2.500000e+001', 'REAL', 25],
    ['-3.4e38', 'REAL', -3.4e38],
    ['REAL#1.5', 'REAL', 1.5],
    ['LREAL#-2.25E-3', 'LREAL', -2.25e-3],
    ['5', 'REAL', 5],
    ['INT#5', 'REAL', 5],
    ['1e300', 'LREAL', 1e300],
    // characters and strings
    ["'a'", 'CHAR', 'a'],
    ["CHAR#'a'", 'CHAR', 'a'],
    ["WCHAR#'a'", 'WCHAR', 'a'],
    ["'$''", 'CHAR', "'"],
    ["''''", 'CHAR', "'"],
    ["'$41'", 'CHAR', 'A'],
    ["'abc'", 'STRING', 'abc', 20],
    ["''", 'STRING', '', 20],
    ["'it''s'", 'STRING', "it's", 20],
    ["'$$ $' $L $N $P $R $T $l $t'", 'STRING', "$ ' \n \n \f \r \t \n \t", 30],
    ["'$41$62'", 'STRING', 'Ab', 20],
    ["STRING#'x'", 'STRING', 'x', 1],
    ["CHAR#'x'", 'STRING', 'x', 5],
    ["WSTRING#'Grüße'", 'WSTRING', 'Grüße', 10],
    ["'Ω'", 'WSTRING', 'Ω', 10],
    // durations
    ['T#5s', 'TIME', 5000],
    ['T#1S', 'TIME', 1000],
    ['T#1h2m3s4ms', 'TIME', 3_723_004],
    ['TIME#1d', 'TIME', 86_400_000],
    ['T#1d_2h_3m', 'TIME', 93_780_000],
    ['T#-5s', 'TIME', -5000],
    ['T#1.5s', 'TIME', 1500],
    ['T#0ms', 'TIME', 0],
    ['T#24d20h31m23s647ms', 'TIME', 2_147_483_647],
    ['LT#1s', 'LTIME', 1_000_000_000n],
    ['LT#1d2h3m4s5ms6us7ns', 'LTIME', 93_784_005_006_007n],
    ['LTIME#-5us', 'LTIME', -5000n],
    ['LT#2ns', 'LTIME', 2n],
    ['S5T#1S', 'S5TIME', 1000],
    ['S5T#2s', 'S5TIME', 2000],
    ['S5TIME#2h46m30s', 'S5TIME', 9_990_000],
    ['S5T#10ms', 'S5TIME', 10],
    ['S5T#1S', 'TIMER', 1000],
    // dates and times of day
    ['D#2024-01-31', 'DATE', utc(2024, 1, 31)],
    ['DATE#1990-01-01', 'DATE', utc(1990, 1, 1)],
    ['TOD#12:00:00.5', 'TIME_OF_DAY', 43_200_500],
    ['TOD#23:59:59.999', 'TIME_OF_DAY', 86_399_999],
    ['TIME_OF_DAY#0:0:0', 'TIME_OF_DAY', 0],
    ['DT#2024-01-31-12:00:00', 'DATE_AND_TIME', utc(2024, 1, 31, 12)],
    ['DT#90-1-1-0:0:0.000', 'DATE_AND_TIME', utc(1990, 1, 1)],
    ['DT#89-12-31-23:59:59.999', 'DATE_AND_TIME', utc(2089, 12, 31, 23, 59, 59, 999)],
    ['DATE_AND_TIME#2000-02-29-01:02:03.4', 'DATE_AND_TIME', utc(2000, 2, 29, 1, 2, 3, 400)],
    ['DTL#2024-01-31-12:00:00', 'DTL', utc(2024, 1, 31, 12)],
    ['DTL#1970-01-01-00:00:00.123456789', 'DTL', utc(1970, 1, 1, 0, 0, 0, 123)],
  ];
  for (const [text, type, expected, stringLength] of accepted) {
    it(`${text} for ${type} is ${typeof expected === 'bigint' ? `${expected}n` : expected instanceof Date ? expected.toISOString() : JSON.stringify(expected)}`, () => {
      const got = valueOf(text, type, stringLength ?? (type === 'STRING' || type === 'WSTRING' ? 254 : 0));
      expect(typeof got).to.equal(typeof expected);
      if (expected instanceof Date) expect((got as Date).toISOString()).to.equal(expected.toISOString());
      else expect(got).to.equal(expected);
    });
  }

  const refused: [text: string, type: DataTypeName, message: RegExp, stringLength?: number][] = [
    ['300', 'SINT', /^Tank\.db:7:12: start value 300 does not fit SINT \(-128\.\.127\)$/],
    ['-1', 'BYTE', /start value -1 does not fit BYTE \(0\.\.255\)/],
    ['16#1FF', 'BYTE', /start value 16#1FF does not fit BYTE \(0\.\.255\)/],
    ['32768', 'INT', /does not fit INT \(-32768\.\.32767\)/],
    ['9223372036854775808', 'LINT', /does not fit LINT/],
    ['1.5', 'INT', /start value 1\.5 is not a whole number \(INT\)/],
    ['REAL#1.5', 'INT', /start value REAL#1\.5 is a REAL literal; the member is INT/],
    ['T#5s', 'INT', /is a TIME literal; the member is INT/],
    ['16#FG', 'WORD', /is not a WORD literal/],
    ['2#102', 'BYTE', /has a digit that base 2 does not have/],
    ['W#16#1FFFF', 'DWORD', /does not fit W# \(16 bits\)/],
    ['L#2147483648', 'LINT', /does not fit L#/],
    ['B#(1, 256)', 'WORD', /is not a byte sequence/],
    ['B#(1, 2, 3)', 'DWORD', /is not a byte sequence/],
    ['B#(1, 2, 3, 4)', 'WORD', /does not fit WORD \(0\.\.65535\)/],
    ['C#1000', 'COUNTER', /does not fit COUNTER \(0\.\.999\)/],
    ['C#1000', 'WORD', /does not fit a counter \(C#0\.\.C#999\)/],
    ['1000', 'COUNTER', /does not fit COUNTER \(0\.\.999\)/],
    ['P#DBX0.0', 'WORD', /unknown prefix P#/],
    ['yes', 'BOOL', /is not a BOOL literal \(expected e\.g\. TRUE, FALSE, 1 or 0\)/],
    ['2', 'BOOL', /is not a BOOL literal/],
    ['abc', 'REAL', /is not a REAL literal/],
    ['1e39', 'REAL', /does not fit REAL: 1e\+39 overflows REAL/],
    ["'ab'", 'CHAR', /is 2 characters; CHAR holds one/],
    ["'Ω'", 'CHAR', /does not fit CHAR: .*latin-1/],
    ["'abcd'", 'STRING', /does not fit STRING\[3\]: 4 characters/, 3],
    ["'Ω'", 'STRING', /does not fit STRING\[10\].*latin-1/, 10],
    ["'a$Qb'", 'STRING', /has the unknown escape \$Q/, 10],
    ["'a'b'", 'STRING', /has a lone '/, 10],
    ['abc', 'STRING', /is not a STRING\[10\] literal/, 10],
    ['5', 'TIME', /is not a TIME literal \(expected e\.g\. T#1h2m3s4ms\)/],
    ['T#5', 'TIME', /is not a TIME literal/],
    ['T#1s1h', 'TIME', /units out of order/],
    ['T#1s1s', 'TIME', /units out of order or twice/],
    ['T#1us', 'TIME', /is not a whole number of milliseconds \(TIME\)/],
    ['T#25d', 'TIME', /does not fit TIME \(-2147483648\.\.2147483647\)/],
    ['LT#1.5ns', 'LTIME', /finer than a nanosecond/],
    ['T#1s', 'LTIME', /is a TIME literal; the member is LTIME/],
    ['S5T#2h47m', 'S5TIME', /does not fit S5TIME/],
    ['S5T#1s5ms', 'S5TIME', /does not fit S5TIME: .*exactly/],
    ['T#1s', 'S5TIME', /is a TIME literal; the member is S5TIME/],
    ['D#2023-02-29', 'DATE', /is not a date of the calendar/],
    ['D#1989-12-31', 'DATE', /does not fit DATE \(1990-01-01\.\.2168-12-31\)/],
    ['D#2024-1-1-0:0:0', 'DATE', /is not a DATE literal/],
    ['TOD#24:00:00', 'TIME_OF_DAY', /is not a time of day/],
    ['TOD#12:00', 'TIME_OF_DAY', /is not a TIME_OF_DAY literal/],
    ['DT#2024-13-01-00:00:00', 'DATE_AND_TIME', /is not a date of the calendar/],
    ['DT#2090-01-01-00:00:00', 'DATE_AND_TIME', /does not fit DATE_AND_TIME/],
    ['DT#2024-01-01-25:00:00', 'DATE_AND_TIME', /has no valid time of day/],
    ['DT#2024-01-01-12:00:00', 'DTL', /is a DATE_AND_TIME literal; the member is DTL/],
    ['DTL#1969-12-31-23:59:59', 'DTL', /does not fit DTL/],
  ];
  for (const [text, type, message, stringLength] of refused) {
    it(`refuses ${text} for ${type}`, () => {
      const err = refusal(text, type, stringLength ?? 0);
      expect(err.code).to.equal('INVALID_SOURCE');
      expect(err.message).to.match(message);
      expect([err.file, err.line, err.column]).to.deep.equal(['Tank.db', 7, 12]);
    });
  }

  it('evaluates the start values of parsed sources at the literal position', () => {
    const [b] = parseBlockSource({
      name: 'Tank.db',
      content: 'DATA_BLOCK DB 1\nSTRUCT\n  Level : REAL := -1.5;\n  Small : SINT := 300;\nEND_STRUCT;\nEND_DATA_BLOCK',
    }) as DataBlockDecl[];
    const members = (b!.body as Extract<DataBlockDecl['body'], { kind: 'struct' }>).members;
    const level = members[0]!.initial!;
    expect(level.kind === 'literal' && literalValue(level.literal, 'REAL', 0)).to.equal(-1.5);
    const small = members[1]!.initial!;
    expect(small.kind).to.equal('literal');
    const literal = (small as Extract<typeof small, { kind: 'literal' }>).literal;
    expect(() => literalValue(literal, 'SINT', 0)).to.throw(
      SourceError,
      /^Tank\.db:4:19: start value 300 does not fit SINT \(-128\.\.127\)$/,
    );
  });
});
