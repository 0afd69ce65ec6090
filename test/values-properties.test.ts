import { expect } from 'chai';
import fc from 'fast-check';
import { PlcError, ProtocolError, ValueError } from '../lib/errors';
import type { DataTypeName } from '../lib/types';
import { decodeTag, encodeInto, encodeTag, tagByteLength, tagDecoder, validateValue, writeSpan, type TagShape } from '../lib/values';

const RUNS = 200;

function shape(type: DataTypeName, options: Partial<TagShape> = {}): TagShape {
  return {
    address: `DB1.DBB0:${type}`,
    type,
    count: 1,
    isArray: false,
    stringLength: type === 'STRING' || type === 'WSTRING' ? 20 : 0,
    bitOffset: 0,
    ...options,
  };
}

const latin1Char = fc.integer({ min: 0, max: 0xff }).map((c) => String.fromCharCode(c));
const utf16Unit = fc.integer({ min: 0, max: 0xffff }).map((c) => String.fromCharCode(c));
const int64 = fc.bigInt({ min: -(2n ** 63n), max: 2n ** 63n - 1n });
const uint64 = fc.bigInt({ min: 0n, max: 2n ** 64n - 1n });
const s5time = fc.tuple(fc.integer({ min: 0, max: 999 }), fc.constantFrom(10, 100, 1000, 10000)).map(([u, b]) => u * b);
const dateIn = (min: string, max: string) => fc.date({ min: new Date(min), max: new Date(max), noInvalidDate: true });

/** Every type's valid domain, as the JS values a read returns. */
const DOMAINS: Record<DataTypeName, fc.Arbitrary<unknown>> = {
  BOOL: fc.boolean(),
  BYTE: fc.integer({ min: 0, max: 0xff }),
  USINT: fc.integer({ min: 0, max: 0xff }),
  SINT: fc.integer({ min: -128, max: 127 }),
  WORD: fc.integer({ min: 0, max: 0xffff }),
  UINT: fc.integer({ min: 0, max: 0xffff }),
  INT: fc.integer({ min: -32768, max: 32767 }),
  DWORD: fc.integer({ min: 0, max: 2 ** 32 - 1 }),
  UDINT: fc.integer({ min: 0, max: 2 ** 32 - 1 }),
  DINT: fc.integer({ min: -(2 ** 31), max: 2 ** 31 - 1 }),
  LWORD: uint64,
  ULINT: uint64,
  LINT: int64,
  REAL: fc.float().filter((f) => !Object.is(f, -0)),
  LREAL: fc.double().filter((f) => !Object.is(f, -0)),
  CHAR: latin1Char,
  WCHAR: utf16Unit,
  STRING: fc.string({ unit: latin1Char, maxLength: 20 }),
  WSTRING: fc.oneof(
    fc.string({ unit: utf16Unit, maxLength: 20 }),
    fc.string({ unit: 'binary', maxLength: 10 }).filter((s) => s.length <= 20),
  ),
  S5TIME: s5time,
  TIMER: s5time,
  COUNTER: fc.integer({ min: 0, max: 999 }),
  TIME: fc.integer({ min: -(2 ** 31), max: 2 ** 31 - 1 }),
  LTIME: int64,
  TIME_OF_DAY: fc.integer({ min: 0, max: 86_399_999 }),
  DATE: fc.integer({ min: 0, max: 65378 }).map((d) => new Date(Date.UTC(1990, 0, 1) + d * 86_400_000)),
  DATE_AND_TIME: dateIn('1990-01-01T00:00:00.000Z', '2089-12-31T23:59:59.999Z'),
  DTL: dateIn('1970-01-01T00:00:00.000Z', '2262-04-11T23:47:16.854Z'),
};
const TYPES = Object.keys(DOMAINS) as DataTypeName[];

/** The JS type a decoded element must have (lib/types.ts PlcValue). */
function jsTypeOf(type: DataTypeName): string {
  if (type === 'BOOL') return 'boolean';
  if (['LWORD', 'LINT', 'ULINT', 'LTIME'].includes(type)) return 'bigint';
  if (['CHAR', 'WCHAR', 'STRING', 'WSTRING'].includes(type)) return 'string';
  if (['DATE', 'DATE_AND_TIME', 'DTL'].includes(type)) return 'Date';
  return 'number';
}

function kindOf(v: unknown): string {
  return v instanceof Date ? 'Date' : typeof v;
}

describe('values: properties', () => {
  for (const type of TYPES) {
    it(`${type}: decode(encode(v)) is v over the valid domain, scalars and arrays`, () => {
      const scalar = shape(type);
      fc.assert(
        fc.property(DOMAINS[type], fc.integer({ min: 0, max: 7 }), (v, bitOffset) => {
          const tag = type === 'BOOL' ? { ...scalar, bitOffset } : scalar;
          validateValue(tag, v);
          const bytes = encodeTag(tag, v);
          expect(bytes.length).to.equal(tagByteLength(tag));
          expect(decodeTag(tag, bytes)).to.deep.equal(v);
        }),
        { numRuns: RUNS },
      );
      fc.assert(
        fc.property(
          fc.integer({ min: 1, max: 5 }).chain((n) => fc.array(DOMAINS[type], { minLength: n, maxLength: n })),
          (vs) => {
            const tag = shape(type, { count: vs.length, isArray: true });
            expect(decodeTag(tag, encodeTag(tag, vs))).to.deep.equal(vs);
          },
        ),
        { numRuns: RUNS / 4 },
      );
    });
  }

  it('decoding arbitrary bytes never throws anything but a PlcError, and enough bytes always decode to the documented JS type', () => {
    const tags = fc.oneof(
      fc.constantFrom(...TYPES).map((t) => shape(t)),
      fc
        .record({
          type: fc.constantFrom(...TYPES),
          count: fc.integer({ min: 1, max: 4 }),
          stringLength: fc.integer({ min: 0, max: 254 }),
          bitOffset: fc.integer({ min: 0, max: 7 }),
        })
        .map(({ type, count, stringLength, bitOffset }) =>
          shape(type, {
            count,
            isArray: true,
            stringLength: type === 'STRING' || type === 'WSTRING' ? stringLength : 0,
            bitOffset: type === 'BOOL' ? bitOffset : 0,
          }),
        ),
    );
    fc.assert(
      fc.property(tags, fc.uint8Array({ maxLength: 600 }), fc.integer({ min: 0, max: 4 }), (tag, bytes, offset) => {
        const data = Buffer.from(bytes);
        let value: unknown;
        try {
          value = decodeTag(tag, data, offset);
        } catch (err) {
          expect(err).to.be.instanceOf(PlcError).and.instanceOf(ProtocolError);
          expect(data.length - offset).to.be.lessThan(tagByteLength(tag));
          return;
        }
        expect(data.length - offset).to.be.at.least(tagByteLength(tag));
        // The poll path's shared, per-shape decoder gives the same value.
        expect(tagDecoder(tag)(data, offset)).to.deep.equal(value);
        const elements = tag.isArray ? (value as unknown[]) : [value];
        expect(elements).to.have.length(tag.count);
        for (const e of elements) expect(kindOf(e)).to.equal(jsTypeOf(tag.type));
      }),
      { numRuns: 3000 },
    );
  });

  it('any JS value either encodes or is a ValueError; what encodes decodes to what re-encodes to the same bytes', () => {
    fc.assert(
      fc.property(
        fc.constantFrom(...TYPES),
        fc.oneof(fc.anything(), fc.double(), fc.bigInt(), fc.date(), fc.string({ maxLength: 3 })),
        (type, v) => {
          const tag = shape(type);
          let bytes: Buffer;
          try {
            bytes = encodeTag(tag, v);
          } catch (err) {
            expect(err).to.be.instanceOf(ValueError);
            expect((err as ValueError).tag).to.equal(tag.address);
            return;
          }
          expect(encodeTag(tag, decodeTag(tag, bytes))).to.deep.equal(bytes);
        },
      ),
      { numRuns: 3000 },
    );
  });

  it('a BOOL array never changes a bit outside its own bits', () => {
    fc.assert(
      fc.property(
        fc.integer({ min: 0, max: 7 }),
        fc.integer({ min: 1, max: 30 }).chain((n) => fc.array(fc.boolean(), { minLength: n, maxLength: n })),
        fc.uint8Array({ minLength: 8, maxLength: 8 }),
        fc.integer({ min: 0, max: 3 }),
        (bitOffset, bits, before, offset) => {
          const tag = shape('BOOL', { bitOffset, count: bits.length, isArray: true });
          const target = Buffer.from(before);
          encodeInto(tag, bits, target, offset);
          for (let n = 0; n < 64; n++) {
            const tagBit = n - 8 * offset - bitOffset;
            const now = (target[n >> 3]! >> (n & 7)) & 1;
            const was = (before[n >> 3]! >> (n & 7)) & 1;
            if (tagBit >= 0 && tagBit < bits.length) expect(now).to.equal(bits[tagBit] ? 1 : 0);
            else expect(now, `bit ${n}`).to.equal(was);
          }
        },
      ),
      { numRuns: 500 },
    );
  });

  it('a STRING write by writeSpan equals encodeInto and keeps the PLC max-length byte', () => {
    fc.assert(
      fc.property(
        fc.integer({ min: 0, max: 30 }),
        fc.uint8Array({ minLength: 34, maxLength: 34 }),
        fc.string({ unit: latin1Char, maxLength: 30 }),
        (n, before, s) => {
          fc.pre(s.length <= n);
          const tag = shape('STRING', { stringLength: n });
          const viaInto = Buffer.from(before);
          encodeInto(tag, s, viaInto);
          const viaSpan = Buffer.from(before);
          const { start, data } = writeSpan(tag, s);
          data.copy(viaSpan, start);
          expect(viaInto[0]).to.equal(before[0]);
          expect(viaSpan.subarray(0, 2 + s.length)).to.deep.equal(viaInto.subarray(0, 2 + s.length));
          expect(decodeTag(tag, viaInto)).to.equal(s.slice(0, Math.min(s.length, before[0]! || n)));
        },
      ),
      { numRuns: 500 },
    );
  });
});
