/**
 * lib/values/time-text.ts: times and dates as TIA Portal writes their
 * literals, for the CLI's text output (its JSON keeps the numbers and ISO
 * dates: cli.test.ts).
 */
import { expect } from 'chai';
import { timeText } from '../lib/values/time-text';

describe('TIA literals of times and dates', () => {
  it('TIME: T#5S, units joined by _, zero units left out, T#0MS, below zero T#-…', () => {
    expect(timeText('TIME', 5000)).to.equal('T#5S');
    expect(timeText('TIME', 93_784_005)).to.equal('T#1D_2H_3M_4S_5MS');
    expect(timeText('TIME', 0)).to.equal('T#0MS');
    expect(timeText('TIME', -1500)).to.equal('T#-1S_500MS');
    expect(timeText('TIME', -2_147_483_648)).to.equal('T#-24D_20H_31M_23S_648MS');
  });

  it('LTIME (bigint ns) to the nanosecond, S5TIME as S5T#', () => {
    expect(timeText('LTIME', 1_500_010_003n)).to.equal('LT#1S_500MS_10US_3NS');
    expect(timeText('LTIME', 0n)).to.equal('LT#0NS');
    expect(timeText('LTIME', -(2n ** 63n))).to.equal('LT#-106751D_23H_47M_16S_854MS_775US_808NS');
    expect(timeText('S5TIME', 127_000)).to.equal('S5T#2M_7S');
  });

  it('TIME_OF_DAY as TOD#hh:mm:ss.mmm, DATE as D#, DATE_AND_TIME and DTL with the time of day', () => {
    expect(timeText('TIME_OF_DAY', 43_200_000)).to.equal('TOD#12:00:00.000');
    expect(timeText('TIME_OF_DAY', 86_399_999)).to.equal('TOD#23:59:59.999');
    expect(timeText('DATE', new Date('2024-01-31T00:00:00Z'))).to.equal('D#2024-01-31');
    expect(timeText('DATE_AND_TIME', new Date('2024-01-31T12:00:01.250Z'))).to.equal('DT#2024-01-31-12:00:01.250');
    expect(timeText('DTL', new Date('1970-01-01T00:00:00Z'))).to.equal('DTL#1970-01-01-00:00:00.000');
  });

  it('arrays element by element; other types, and values not of the type, are left to the caller', () => {
    expect(timeText('TIME', [1000, 60_000])).to.equal('[T#1S, T#1M]');
    expect(timeText('INT', 5000)).to.equal(undefined);
    expect(timeText(undefined, 5000)).to.equal(undefined);
    expect(timeText('DATE', new Date(Number.NaN))).to.equal(undefined);
    expect(timeText('TIME', 'x')).to.equal(undefined);
  });
});
