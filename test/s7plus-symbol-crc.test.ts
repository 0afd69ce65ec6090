/**
 * The SymbolCrc of an item address (lib/s7plus/codec/symbol-crc.ts) against the public vectors:
 * - HarpoS7 (MIT), HarpoS7.Tests/Integrity/HarpoCrc32Tests.cs: "Tag_12" → 0x0CDF926D, and entry 1 of
 *   HarpoS7/Integrity/HarpoCrc32.cs's table (4104977171);
 * - the vectors of HarpoS7's author and of an S7-1500 as DataLogXE/node-red-contrib-s7-plus (LGPL)
 *   test/symbol-crc.test.js and test/crc-integration.test.js give them (numbers only).
 */
import { expect } from 'chai';
import fc from 'fast-check';
import { SoftDataType } from '../lib/s7plus/constants';
import { crc32, isInvalidCrc, ITEM_ERROR_INVALID_CRC, levelCrc, symbolCrc, SYMBOL_CRC_POLYNOMIAL } from '../lib/s7plus/codec/symbol-crc';

const hex = (n: number) => `0x${n.toString(16).toUpperCase().padStart(8, '0')}`;

describe('S7CommPlus SymbolCrc', () => {
  it('is the CRC-32 of polynomial 0xF4ACFB13, start 0, no final XOR (HarpoS7)', () => {
    expect(SYMBOL_CRC_POLYNOMIAL).to.equal(0xf4acfb13);
    expect(crc32(Buffer.of(1))).to.equal(4104977171);
    expect(hex(crc32(Buffer.from('Tag_12')))).to.equal('0x0CDF926D');
    expect(crc32(Buffer.alloc(0))).to.equal(0);
  });

  it('continues from a CRC as over the bytes joined', () => {
    fc.assert(
      fc.property(fc.uint8Array(), fc.uint8Array(), (a, b) => {
        expect(crc32(b, crc32(a))).to.equal(crc32(Buffer.concat([a, b])));
      }),
    );
  });

  it('gives a member its name and type: "Test2" DInt (HarpoS7 author)', () => {
    expect(hex(levelCrc({ name: 'Test2', soft: SoftDataType.DInt }))).to.equal('0x9E858004');
    expect(hex(symbolCrc([{ name: 'Test2', soft: SoftDataType.DInt }]))).to.equal('0x4CA70840');
  });

  it('gives an array its element type and lower bound: "TEST 3" Array[0..6] of Bool (HarpoS7 author)', () => {
    expect(hex(symbolCrc([{ name: 'TEST 3', soft: SoftDataType.Bool, low: 0 }]))).to.equal('0x0CC865FB');
  });

  it('as an S7-1500 checks arrays from 1: Array[1..10000] of SInt and of Real', () => {
    expect(hex(symbolCrc([{ name: 'sintItems', soft: SoftDataType.SInt, low: 1 }]))).to.equal('0x6E16F413');
    expect(hex(symbolCrc([{ name: 'realItems', soft: SoftDataType.Real, low: 1 }]))).to.equal('0x007CD376');
    // The lower bound is part of it: the same array from 0 has another CRC.
    expect(symbolCrc([{ name: 'realItems', soft: SoftDataType.Real, low: 0 }])).to.not.equal(0x007cd376);
  });

  it('chains the levels of a struct member: "TEST 4".T4ChildBool (HarpoS7 author)', () => {
    const path = [
      { name: 'TEST 4', soft: SoftDataType.Struct },
      { name: 'T4ChildBool', soft: SoftDataType.Bool },
    ];
    expect(hex(symbolCrc(path))).to.equal('0x1AC12998');
  });

  it('gives the other published members theirs: flag Bool, readings Array of Real', () => {
    expect(hex(symbolCrc([{ name: 'flag', soft: SoftDataType.Bool }]))).to.equal('0xFC8BA389');
    expect(hex(symbolCrc([{ name: 'readings', soft: SoftDataType.Real, low: 0 }]))).to.equal('0x6580D02C');
  });

  it('hashes a name as UTF-8 and a BBOOL as a BOOL', () => {
    const utf8 = crc32(Buffer.of(SoftDataType.Real), crc32(Buffer.from('wärt', 'utf8')));
    expect(levelCrc({ name: 'wärt', soft: SoftDataType.Real })).to.equal(utf8);
    expect(levelCrc({ name: 'wärt', soft: SoftDataType.Real })).to.not.equal(crc32(Buffer.of(8), crc32(Buffer.from('wärt', 'latin1'))));
    expect(levelCrc({ name: 'b', soft: 40 })).to.equal(levelCrc({ name: 'b', soft: SoftDataType.Bool }));
  });

  it('is 0 (no check) for no path, and refuses a type or bound that is no byte or Int32', () => {
    expect(symbolCrc([])).to.equal(0);
    expect(() => levelCrc({ name: 'x', soft: 256 })).to.throw(RangeError, /software type 256 of x/);
    expect(() => levelCrc({ name: 'x', soft: 8, low: 2 ** 31 })).to.throw(RangeError, /lower bound/);
  });

  it('tells InvalidCRC by the low word -17 of an item error', () => {
    expect(isInvalidCrc(ITEM_ERROR_INVALID_CRC)).to.equal(true);
    expect(isInvalidCrc(0xffefn)).to.equal(true);
    expect(isInvalidCrc(0x8104n)).to.equal(false);
    expect(isInvalidCrc(0n)).to.equal(false);
  });
});
