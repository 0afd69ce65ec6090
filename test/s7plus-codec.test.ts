/**
 * The S7CommPlus codec: VLQ, frames, PValues. Fixtures and where they come from:
 * - "s7commplus": bytes the s7commplus package 0.3.0 (PyPI, MIT) produces with
 *   its vlq.py encoders, run once to write them down here;
 * - "golden": bytes cut from the TIA Portal ↔ PLCSIM frames of
 *   gijzelaerr/s7commplus tests/fixtures/golden_tia_online_session_20260915.py (MIT),
 *   also in test/fixtures/s7plus/golden-tia.json.
 */
import { expect } from 'chai';
import fc from 'fast-check';
import { PlcError, ProtocolError } from '../lib/errors';
import fs from 'node:fs';
import path from 'node:path';
import {
  DataType,
  ElementId,
  FunctionCode,
  Ids,
  Opcode,
  ProtocolVersion,
  PValueFlag,
  READ_FUNCTIONS,
  ServiceResult,
  SoftDataType,
} from '../lib/s7plus/constants';
import { encodeFrames, S7pFrameReader } from '../lib/s7plus/codec/frame';
import {
  decodePValue,
  encodePValue,
  skipPValue,
  type BlobValue,
  type PValue,
  type SparseEntry,
  type StructMember,
  type StructValue,
} from '../lib/s7plus/codec/pvalue';
import { Writer } from '../lib/s7plus/codec/bytes';
import {
  decodeSVlq32,
  decodeSVlq64,
  decodeUVlq32,
  decodeUVlq64,
  encodeSVlq32,
  encodeSVlq64,
  encodeUVlq32,
  encodeUVlq64,
  uvlq32Length,
} from '../lib/s7plus/codec/vlq';

const hex = (s: string) => Buffer.from(s.replace(/\s+/g, ''), 'hex');

function throwsProtocol(f: () => unknown, pattern?: RegExp): void {
  try {
    f();
  } catch (err) {
    expect(err).to.be.instanceOf(ProtocolError);
    if (pattern) expect((err as Error).message).to.match(pattern);
    return;
  }
  expect.fail('no ProtocolError');
}

describe('S7CommPlus codec', () => {
  describe('VLQ (s7commplus vlq.py vectors)', () => {
    const u32: [number, string][] = [
      [0, '00'],
      [127, '7f'],
      [128, '8100'],
      [415, '831f'], // golden: the symbolic write's address 83 1f
      [900, '8704'], // golden: the subscription's cycle attribute 87 04
      [16383, 'ff7f'],
      [16384, '818000'],
      [0x80010000, '8880848000'], // golden: first reference-list entry of the subscription create
      [0xffffffff, '8fffffff7f'],
    ];
    const s32: [number, string][] = [
      [0, '00'],
      [-1, '7f'],
      [63, '3f'],
      [64, '8040'],
      [-64, 'ff40'],
      [-65, 'ff3f'],
      [8191, 'bf7f'],
      [-8192, 'ffc000'],
      [0x7fffffff, '87ffffff7f'],
      [-0x80000000, 'f880808000'],
    ];
    const u64: [bigint, string][] = [
      [0n, '00'],
      [128n, '8100'],
      [(1n << 56n) - 1n, 'ffffffffffffff7f'],
      [1n << 56n, '80c080808080808000'],
      [(1n << 57n) + 5n, '818080808080808005'],
      [(1n << 64n) - 1n, 'ffffffffffffffffff'],
    ];
    const s64: [bigint, string][] = [
      [0n, '00'],
      [-1n, '7f'],
      [-65n, 'ff3f'],
      [(1n << 55n) - 1n, 'bfffffffffffff7f'],
      [1n << 55n, '80a080808080808000'],
      [-(1n << 55n), 'ffe080808080808000'],
      [-(1n << 55n) - 1n, 'ffdfffffffffffffff'],
      [(1n << 63n) - 1n, 'bfffffffffffffffff'],
      [-(1n << 63n), 'c08080808080808000'],
    ];

    it('encodes and decodes unsigned 32-bit values as s7commplus does', () => {
      for (const [v, h] of u32) {
        expect(encodeUVlq32(v).toString('hex'), `${v}`).to.equal(h);
        expect(decodeUVlq32(hex(h + 'ff'), 0)).to.deep.equal({ value: v, length: h.length / 2 });
      }
    });

    it('encodes and decodes signed 32-bit values (sign in bit 6 of the first byte)', () => {
      for (const [v, h] of s32) {
        expect(encodeSVlq32(v).toString('hex'), `${v}`).to.equal(h);
        expect(decodeSVlq32(hex('aa' + h), 1)).to.deep.equal({ value: v, length: h.length / 2 });
      }
    });

    it('encodes and decodes 64-bit values as bigint, the ninth byte taking 8 bits', () => {
      for (const [v, h] of u64) {
        expect(encodeUVlq64(v).toString('hex'), `${v}`).to.equal(h);
        expect(decodeUVlq64(hex(h), 0)).to.deep.equal({ value: v, length: h.length / 2 });
      }
      for (const [v, h] of s64) {
        expect(encodeSVlq64(v).toString('hex'), `${v}`).to.equal(h);
        expect(decodeSVlq64(hex(h), 0)).to.deep.equal({ value: v, length: h.length / 2 });
      }
    });

    it('decodes the return value of an Explore of a missing object (s7commplus server.py 0x8020AB001992FFF4)', () => {
      const v = 0x8020ab001992fff4n;
      expect(decodeUVlq64(encodeUVlq64(v), 0).value).to.equal(v);
    });

    it('throws ProtocolError on truncated, overlong and too wide input', () => {
      throwsProtocol(() => decodeUVlq32(hex('8181'), 0), /truncated VLQ at offset 0/);
      throwsProtocol(() => decodeUVlq32(Buffer.alloc(0), 0), /truncated/);
      throwsProtocol(() => decodeUVlq32(hex('8080808080'), 0), /longer than 5 bytes/);
      throwsProtocol(() => decodeUVlq32(hex('9080808000'), 0), /exceeds 32 bits/);
      throwsProtocol(() => decodeSVlq32(hex('b880808000'), 0), /exceeds 32 bits/);
      throwsProtocol(() => decodeUVlq64(hex('8080808080808080'), 0), /truncated/);
      throwsProtocol(() => decodeSVlq64(hex('ff'), 0), /truncated/);
    });

    it('round-trips every value of each width (property)', () => {
      fc.assert(
        fc.property(fc.integer({ min: 0, max: 0xffffffff }), fc.integer({ min: -0x80000000, max: 0x7fffffff }), (u, s) => {
          expect(decodeUVlq32(encodeUVlq32(u), 0).value).to.equal(u);
          expect(decodeSVlq32(encodeSVlq32(s), 0).value).to.equal(s);
        }),
      );
      fc.assert(
        fc.property(fc.bigInt({ min: 0n, max: (1n << 64n) - 1n }), fc.bigInt({ min: -(1n << 63n), max: (1n << 63n) - 1n }), (u, s) => {
          expect(decodeUVlq64(encodeUVlq64(u), 0).value).to.equal(u);
          expect(decodeSVlq64(encodeSVlq64(s), 0).value).to.equal(s);
        }),
      );
    });

    it("the Writer's UVLQ32 (written in place) is encodeUVlq32's bytes, at every length boundary, after other bytes and past its first buffer", () => {
      const w = new Writer();
      const expected: Buffer[] = [];
      for (const [v] of u32) {
        w.u8(0xee).uvlq32(v);
        expected.push(Buffer.from([0xee]), encodeUVlq32(v));
      }
      for (const v of [0x7f, 0x80, 0x3fff, 0x4000, 0x1fffff, 0x200000, 0xfffffff, 0x10000000, 0xffffffff]) {
        expect(uvlq32Length(v), `${v}`).to.equal(encodeUVlq32(v).length);
        w.uvlq32(v);
        expected.push(encodeUVlq32(v));
      }
      expect(w.toBuffer().toString('hex')).to.equal(Buffer.concat(expected).toString('hex'));
      expect(() => new Writer().uvlq32(2 ** 32)).to.throw(RangeError);
      expect(() => new Writer().uvlq32(1.5)).to.throw(RangeError);
    });

    it('refuses to encode a value outside the width (a caller bug, RangeError)', () => {
      expect(() => encodeUVlq32(-1)).to.throw(RangeError);
      expect(() => encodeUVlq32(2 ** 32)).to.throw(RangeError);
      expect(() => encodeSVlq32(2 ** 31)).to.throw(RangeError);
      expect(() => encodeUVlq64(1n << 64n)).to.throw(RangeError);
      expect(() => encodeSVlq64(1n << 63n)).to.throw(RangeError);
    });
  });

  describe('frames', () => {
    // golden: the device-tree Explore request's data (its frame without 72 02 00 1e), then our trailer.
    const explore = hex('3100 0004bb 0000 0009 7000103d 34 00000022 00 01 01 00 00 00 04 0000000000');

    it('frames a message as header, data, trailer (golden: 72 02 00 1e)', () => {
      const frame = encodeFrames(2, explore);
      expect(frame.subarray(0, 4).toString('hex')).to.equal('7202001e');
      expect(frame.subarray(-4).toString('hex')).to.equal('72020000');
      expect(frame.length).to.equal(4 + 30 + 4);
    });

    it('joins a message cut into PDUs, fed one byte at a time, and a SystemEvent between them', () => {
      const data = Buffer.alloc(300, 7);
      data[0] = 0x32;
      const frames = encodeFrames(2, data, 128); // 128 + 128 + 44, trailer after the last
      expect(frames.length).to.equal(300 + 3 * 4 + 4);
      const event = hex('72fe0004 01020304');
      const stream = Buffer.concat([frames.subarray(0, 132), event, frames.subarray(132)]);
      const reader = new S7pFrameReader();
      const got = [];
      for (const b of stream) got.push(...reader.push(Buffer.of(b)));
      expect(got.map((m) => m.version)).to.deep.equal([0xfe, 2]);
      expect(got[0]!.data.toString('hex')).to.equal('01020304');
      expect(got[1]!.data.equals(data)).to.equal(true);
      expect(reader.buffered).to.equal(0);
    });

    it('returns two messages that arrive in one chunk, and keeps a partial third', () => {
      const reader = new S7pFrameReader();
      const a = encodeFrames(1, hex('31aa'));
      const b = encodeFrames(1, hex('32bb'));
      const got = reader.push(Buffer.concat([a, b, a.subarray(0, 5)]));
      expect(got.map((m) => m.data.toString('hex'))).to.deep.equal(['31aa', '32bb']);
      expect(reader.buffered).to.equal(5);
      expect(reader.push(a.subarray(5)).map((m) => m.data.toString('hex'))).to.deep.equal(['31aa']);
    });

    it('throws ProtocolError on a frame not starting with 0x72, a bare trailer, a version change, and too long a message', () => {
      throwsProtocol(() => new S7pFrameReader().push(hex('0300001611')), /not 0x72/);
      throwsProtocol(() => new S7pFrameReader().push(hex('72020000')), /without a frame/);
      throwsProtocol(() => new S7pFrameReader().push(hex('720200013172030001ff')), /version changed from 2 to 3/);
      throwsProtocol(() => new S7pFrameReader({ maxMessage: 100 }).push(encodeFrames(2, Buffer.alloc(101, 1), 60)), /longer than 100/);
      throwsProtocol(() => new S7pFrameReader({ maxPdus: 2 }).push(encodeFrames(2, Buffer.alloc(30, 1), 10)), /more than 2 PDUs/);
    });

    it('fails a message as soon as its announced length passes the limit, before the bytes arrive', () => {
      const reader = new S7pFrameReader({ maxMessage: 1000 });
      throwsProtocol(() => reader.push(hex('7202ffff31')), /longer than 1000/);
    });
  });

  describe('PValues', () => {
    const cases: [string, string, PValue][] = [
      [
        'golden: notification struct 0xE79 with four DInt members',
        '0017 00000e79 9c74 0008 03 9c70 0008 01 9c71 0008 02 9c72 0008 00 00',
        {
          flags: 0,
          type: DataType.Struct,
          value: {
            id: 0xe79,
            members: [
              { key: 0xe74, value: { flags: 0, type: DataType.DInt, value: 3 } },
              { key: 0xe70, value: { flags: 0, type: DataType.DInt, value: 1 } },
              { key: 0xe71, value: { flags: 0, type: DataType.DInt, value: 2 } },
              { key: 0xe72, value: { flags: 0, type: DataType.DInt, value: 0 } },
            ],
          },
        },
      ],
      [
        'golden: subscription name WString',
        '0015 17 ' + Buffer.from('Subscription_2147467350').toString('hex'),
        {
          flags: 0,
          type: DataType.WString,
          value: 'Subscription_2147467350',
        },
      ],
      [
        'golden: subscription reference list, an address array of UDInt',
        '2004 03 8880848000 00 00',
        {
          flags: PValueFlag.AddressArray,
          type: DataType.UDInt,
          value: [0x80010000, 0, 0],
        },
      ],
      ['golden: credit limit Int -1', '0007 ffff', { flags: 0, type: DataType.Int, value: -1 }],
      ['golden: ticks UInt 65535', '0003 ffff', { flags: 0, type: DataType.UInt, value: 0xffff }],
      ['golden: subsystem error LInt 0', '0009 00', { flags: 0, type: DataType.LInt, value: 0n }],
      ['golden: active Bool', '0001 01', { flags: 0, type: DataType.Bool, value: true }],
      [
        'golden: the written Blob "test"',
        '0014 00 04 74657374',
        { flags: 0, type: DataType.Blob, value: { rootId: 0, data: Buffer.from('test') } },
      ],
      ['golden: the ObjectQualifier ParentRID, a RID', '0012 00000000', { flags: 0, type: DataType.RID, value: 0 }],
      ['golden: the ObjectQualifier CompositionAID, an AID', '0013 00', { flags: 0, type: DataType.AID, value: 0 }],
      ['s7commplus server.py: the CreateObject session attribute, UDInt', '0004 8171', { flags: 0, type: DataType.UDInt, value: 0xf1 }],
      [
        's7commplus connection.py: the 20-byte challenge, an array of USInt',
        '1002 03 0a0b0c',
        { flags: PValueFlag.Array, type: DataType.USInt, value: [10, 11, 12] },
      ],
      ['SInt, Byte, Word, DWord', '0006 80', { flags: 0, type: DataType.SInt, value: -128 }],
      ['Word', '000b beef', { flags: 0, type: DataType.Word, value: 0xbeef }],
      ['DWord is fixed 4 bytes, not VLQ (s7commplus codec.py)', '000c 12345678', { flags: 0, type: DataType.DWord, value: 0x12345678 }],
      ['LWord is fixed 8 bytes', '000d 0102030405060708', { flags: 0, type: DataType.LWord, value: 0x0102030405060708n }],
      ['Real 1.5', '000e 3fc00000', { flags: 0, type: DataType.Real, value: 1.5 }],
      ['LReal -2.25', '000f c002000000000000', { flags: 0, type: DataType.LReal, value: -2.25 }],
      ['ULInt VLQ', '0005 8100', { flags: 0, type: DataType.ULInt, value: 128n }],
      [
        'Timestamp (golden: the notification time 0x00065B8BA19931A9 µs)',
        '0010 00065b8ba19931a9',
        { flags: 0, type: DataType.Timestamp, value: 0x00065b8ba19931a9n },
      ],
      ['Timespan, signed VLQ', '0011 7f', { flags: 0, type: DataType.Timespan, value: -1n }],
      ['S7String (Latin-1)', '0019 03 c46263', { flags: 0, type: DataType.S7String, value: 'Äbc' }],
      ['Null', '0000', { flags: 0, type: DataType.Null, value: null }],
      ['an array of DInt (each a signed VLQ)', '1008 03 7f 8040 00', { flags: PValueFlag.Array, type: DataType.DInt, value: [-1, 64, 0] }],
      ['an array of LReal', '100f 01 3ff0000000000000', { flags: PValueFlag.Array, type: DataType.LReal, value: [1] }],
      [
        'a sparse array of UDInt: (key, value) pairs ending at key 0',
        '4004 01 05 8100 07 00',
        {
          flags: PValueFlag.SparseArray,
          type: DataType.UDInt,
          value: [
            { key: 1, value: 5 },
            { key: 128, value: 7 },
          ],
        },
      ],
      [
        'a packed struct (id 0x90000001): timestamp, flags, count, bytes',
        '0017 90000001 0000000000000009 00 02 abcd',
        {
          flags: 0,
          type: DataType.Struct,
          value: { id: 0x90000001, packed: { interfaceTimestamp: 9n, transportFlags: 0, data: hex('abcd') } },
        },
      ],
      [
        'a packed struct with the second count (flag 0x400)',
        '0017 02000010 0000000000000000 8800 05 02 abcd',
        {
          flags: 0,
          type: DataType.Struct,
          value: { id: 0x02000010, packed: { interfaceTimestamp: 0n, transportFlags: 0x400, firstCount: 5, data: hex('abcd') } },
        },
      ],
    ];

    for (const [name, h, value] of cases) {
      it(`decodes and re-encodes: ${name}`, () => {
        const bytes = hex(h);
        const got = decodePValue(Buffer.concat([bytes, hex('a2')]), 0);
        expect(got.length).to.equal(bytes.length);
        expect(got.value).to.deep.equal(value);
        expect(encodePValue(value).toString('hex')).to.equal(bytes.toString('hex'));
        expect(skipPValue(Buffer.concat([hex('ee'), bytes]), 1)).to.equal(1 + bytes.length);
      });
    }

    it('encodes a struct built from its parts: a blob member, a sparse-array member', () => {
      const blob: BlobValue = { rootId: 1, data: hex('ff00') };
      const sparse: SparseEntry[] = [{ key: 3, value: true }];
      const members: StructMember[] = [
        { key: 10, value: { flags: 0, type: DataType.Blob, value: blob } },
        { key: 11, value: { flags: PValueFlag.SparseArray, type: DataType.Bool, value: sparse } },
      ];
      const struct: StructValue = { id: 0x1234, members };
      const bytes = encodePValue({ flags: 0, type: DataType.Struct, value: struct });
      expect(bytes.toString('hex')).to.equal(
        '0017' + '00001234' + '0a' + '0014' + '01' + '02' + 'ff00' + '0b' + '4001' + '03' + '01' + '00' + '00',
      );
      expect(decodePValue(bytes, 0).value.value).to.deep.equal(struct);
    });

    it('keeps flag bits it does not know', () => {
      const p = decodePValue(hex('0104 05'), 0).value;
      expect(p).to.deep.equal({ flags: 1, type: DataType.UDInt, value: 5 });
      expect(encodePValue(p).toString('hex')).to.equal('010405');
    });

    it('throws ProtocolError on truncated values, unknown types, impossible counts and nesting too deep', () => {
      throwsProtocol(() => decodePValue(hex('000e 3fc0'), 0), /truncated Real at offset 2/);
      throwsProtocol(() => decodePValue(hex('0014 00 05 7465'), 0), /truncated Blob/);
      throwsProtocol(() => decodePValue(hex('0016 00'), 0), /datatype Variant .* not supported/);
      throwsProtocol(() => decodePValue(hex('0018'), 0), /datatype 0x18/);
      throwsProtocol(() => decodePValue(hex('1002 8fffffff7f 00'), 0), /array of 4294967295 USInt/);
      throwsProtocol(() => decodePValue(hex('3002 01 00'), 0), /combine array kinds/);
      throwsProtocol(() => decodePValue(hex('0017 00000001 01 0017 00000001 01'), 0), /truncated/);
      const deep = hex('0017 00000001 01'.repeat(40));
      throwsProtocol(() => decodePValue(deep, 0), /nested deeper than 32/);
      throwsProtocol(() => decodePValue(hex('00'), 0), /truncated PValue datatype/);
    });

    it('refuses to encode a value of the wrong kind (TypeError: a bug of the caller, not of the peer)', () => {
      expect(() => encodePValue({ flags: 0, type: DataType.USInt, value: 256 })).to.throw(TypeError);
      expect(() => encodePValue({ flags: 0, type: DataType.LInt, value: 1 })).to.throw(TypeError);
      expect(() => encodePValue({ flags: 0x10, type: DataType.USInt, value: 1 })).to.throw(TypeError);
      expect(() => encodePValue({ flags: 0, type: DataType.Variant, value: null })).to.throw(TypeError);
    });

    it('round-trips random scalars of every fixed and VLQ type (property)', () => {
      const arb = fc.oneof(
        fc.integer({ min: 0, max: 255 }).map((v) => ({ flags: 0, type: DataType.USInt, value: v }) as PValue),
        fc.integer({ min: -32768, max: 32767 }).map((v) => ({ flags: 0, type: DataType.Int, value: v }) as PValue),
        fc.integer({ min: -0x80000000, max: 0x7fffffff }).map((v) => ({ flags: 0, type: DataType.DInt, value: v }) as PValue),
        fc.integer({ min: 0, max: 0xffffffff }).map((v) => ({ flags: 0, type: DataType.UDInt, value: v }) as PValue),
        fc.bigInt({ min: -(1n << 63n), max: (1n << 63n) - 1n }).map((v) => ({ flags: 0, type: DataType.LInt, value: v }) as PValue),
        fc.string().map((v) => ({ flags: 0, type: DataType.WString, value: v }) as PValue),
        fc.array(fc.double({ noNaN: true }), { maxLength: 5 }).map((v) => ({ flags: 0x10, type: DataType.LReal, value: v }) as PValue),
      );
      fc.assert(
        fc.property(arb, (p) => {
          const bytes = encodePValue(p);
          const back = decodePValue(bytes, 0);
          expect(back.length).to.equal(bytes.length);
          expect(back.value).to.deep.equal(p);
        }),
      );
    });

    it('never throws anything but a PlcError on random bytes', () => {
      fc.assert(
        fc.property(fc.uint8Array({ maxLength: 64 }), (a) => {
          try {
            decodePValue(Buffer.from(a), 0);
          } catch (err) {
            expect(err).to.be.instanceOf(PlcError);
          }
        }),
        { numRuns: 5000 },
      );
    });
  });
});

describe('S7CommPlus constants against s7commplus protocol.py (test/fixtures/s7plus/s7commplus-tables.json)', () => {
  const tables = (
    JSON.parse(fs.readFileSync(path.join(__dirname, '..', '..', 'test', 'fixtures', 's7plus', 's7commplus-tables.json'), 'utf8')) as {
      tables: Record<string, Record<string, number> | number[]>;
    }
  ).tables;
  const norm = (name: string) => name.replace(/_/g, '').toLowerCase();
  const byName = (ours: Record<string, number>) => new Map(Object.entries(ours).map(([k, v]) => [norm(k), v]));

  for (const [theirs, ours] of [
    ['Opcode', Opcode],
    ['FunctionCode', FunctionCode],
    ['DataType', DataType],
    ['SoftDataType', SoftDataType],
    ['ProtocolVersion', ProtocolVersion],
  ] as const) {
    it(`${theirs}: every name of theirs is ours, with the same value`, () => {
      const mine = byName(ours);
      for (const [name, value] of Object.entries(tables[theirs] as Record<string, number>))
        expect(mine.get(norm(name)), name).to.equal(value);
      expect(mine.size).to.equal(Object.keys(tables[theirs]!).length);
    });
  }

  it('ElementID: the same ids', () => {
    expect(Object.values(ElementId).sort()).to.deep.equal(Object.values(tables.ElementID as Record<string, number>).sort());
  });

  it('Ids: every id we share by name has their value (at least 60 of them)', () => {
    const theirs = new Map(
      ['ObjectId', 'Ids', 'LegitimationId'].flatMap((t) =>
        Object.entries(tables[t] as Record<string, number>).map(([k, v]) => [norm(k), v] as const),
      ),
    );
    let shared = 0;
    for (const [name, value] of Object.entries(Ids)) {
      const v = theirs.get(norm(name));
      if (v === undefined) continue;
      shared++;
      expect(value, name).to.equal(v);
    }
    expect(shared).to.be.at.least(60);
  });

  it('ServiceResult: each code of ours is one of theirs (but -12, from their server.py)', () => {
    const theirs = new Set(Object.values(tables.ServiceResult as Record<string, number>));
    for (const [name, v] of Object.entries(ServiceResult)) if (name !== 'NoSuchObject') expect(theirs.has(v), name).to.equal(true);
  });

  it('READ_FUNCTIONS: the functions that count on the read integrity id', () => {
    expect([...READ_FUNCTIONS].sort()).to.deep.equal([...(tables.READ_FUNCTION_CODES as number[])].sort());
    // The golden frames: explores count 4, 33, 34 on the read counter; the subscription create 0x12 and the write 6 on the write one.
    expect(READ_FUNCTIONS.has(FunctionCode.Explore)).to.equal(true);
    expect(READ_FUNCTIONS.has(FunctionCode.CreateObject) || READ_FUNCTIONS.has(FunctionCode.SetVarSubStreamed)).to.equal(false);
  });
});
