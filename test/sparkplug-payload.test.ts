import { expect } from 'chai';
import { PlcError } from '../lib/errors';
import { packArray, unpackArray } from '../lib/sparkplug/arrays';
import { DataType, dataTypeName } from '../lib/sparkplug/datatypes';
import type { SparkplugMetric } from '../lib/sparkplug/model';
import { decodePayload, encodePayload } from '../lib/sparkplug/payload';
import { datatypeOfAddress, datatypeOfPlcType } from '../lib/sparkplug/types';

/**
 * The array examples of the Sparkplug 3.0 specification, section 6.4.17 "Array Types" (Decimal to
 * Metric bytes_value). Four of its examples contradict the section's own rule ("little-endian packed"):
 * Int8Array [-23, 123] is given as EF 7B (-23 is E9), FloatArray and DoubleArray are printed big-endian,
 * DateTimeArray drops the two high zero bytes of each 8-byte value. Those four are written here as the
 * rule gives them (marked "rule"), the others byte for byte as printed ("spec").
 */
const ARRAY_FIXTURES: [string, number, unknown[], string][] = [
  ['spec', DataType.Int32Array, [123456789, 987654321], '15cd5b07b168de3a'],
  ['rule', DataType.Int8Array, [-23, 123], 'e97b'],
  ['spec', DataType.Int16Array, [-30000, 30000], 'd08a3075'],
  ['spec', DataType.Int32Array, [-1, 315338746], 'fffffffffaafcb12'],
  ['spec', DataType.Int64Array, [-4270929666821191986n, -3601064768563266876n], 'ce0672ac189cbac4c4ba9c18ac7206ce'],
  ['spec', DataType.UInt8Array, [23, 250], '17fa'],
  ['spec', DataType.UInt16Array, [30, 52360], '1e0088cc'],
  ['spec', DataType.UInt32Array, [52, 3293969225], '3400000049fb55c4'],
  ['spec', DataType.UInt64Array, [52n, 16444743074749521625n], '3400000000000000d99e02d1b27637e4'],
  ['rule', DataType.FloatArray, [1.5, -2.25], '0000c03f000010c0'],
  ['rule', DataType.DoubleArray, [12.354213, 1022.9123213], 'd7a205685bb528408e171c6f4cf78f40'],
  ['spec', DataType.BooleanArray, [false, false, true, true, false, true, false, false, true, true, false, true], '0c00000034d0'],
  ['spec', DataType.StringArray, ['ABC', 'hello'], '4142430068656c6c6f00'],
  ['rule', DataType.DateTimeArray, [new Date(1256102875335), new Date(1656107875000)], 'c7d0907524010000b8bab89781010000'],
];

describe('Sparkplug B payload codec', () => {
  describe('array datatypes (Sparkplug 3.0, 6.4.17)', () => {
    for (const [source, type, values, hex] of ARRAY_FIXTURES) {
      it(`${source}: ${dataTypeName(type)} ${hex}`, () => {
        expect(packArray(type, values, 'a').toString('hex')).to.equal(hex);
        expect(unpackArray(type, Buffer.from(hex, 'hex'), 'a')).to.deep.equal(values);
      });
    }

    it('a bytes_value that is not a whole number of elements is a PROTOCOL_ERROR naming the metric', () => {
      expect(() => unpackArray(DataType.Int32Array, Buffer.from('010203', 'hex'), 'Temps'))
        .to.throw(PlcError, /Temps.*3 bytes/)
        .with.property('code', 'PROTOCOL_ERROR');
      expect(() => unpackArray(DataType.BooleanArray, Buffer.from('0900000000', 'hex'), 'Bits'))
        .to.throw(PlcError)
        .with.property('code', 'PROTOCOL_ERROR');
      expect(() => unpackArray(DataType.StringArray, Buffer.from('4142', 'hex'), 'Names')).to.throw(PlcError, /NUL/);
    });

    it('an element out of its type range is an INVALID_VALUE naming the element', () => {
      expect(() => packArray(DataType.Int8Array, [1, 200], 'Bytes'))
        .to.throw(PlcError, /Bytes\[1\].*200/)
        .with.property('code', 'INVALID_VALUE');
    });
  });

  describe('payloads', () => {
    it('NDEATH of bdSeq 0: the bytes as the schema gives them (timestamp 1, metric bdSeq Int64 0); seq absent', () => {
      const bytes = encodePayload({ timestamp: 1, metrics: [{ name: 'bdSeq', datatype: DataType.Int64, value: 0n }] });
      // 08 01: timestamp=1; 12 0b: metric, 11 bytes: 0a 05 "bdSeq", 20 04 datatype=Int64, 58 00 long_value=0
      expect(bytes.toString('hex')).to.equal('0801120b0a0562645365712004' + '5800');
      const back = decodePayload(bytes);
      expect(back).to.deep.equal({ timestamp: 1, metrics: [{ name: 'bdSeq', datatype: DataType.Int64, value: 0n }] });
      expect(back.seq).to.equal(undefined);
    });

    it('seq 0 and alias 0 are sent (proto2 presence), so an NBIRTH has its seq', () => {
      const bytes = encodePayload({ seq: 0, metrics: [{ name: 'x', alias: 0, datatype: DataType.Boolean, value: false }] });
      expect(bytes.toString('hex')).to.equal('12090a01781000200b70001800');
      expect(decodePayload(bytes)).to.deep.equal({ seq: 0, metrics: [{ name: 'x', alias: 0, datatype: DataType.Boolean, value: false }] });
    });

    const ROUND_TRIPS: [string, SparkplugMetric][] = [
      ['Int8 -128', { name: 'a', datatype: DataType.Int8, value: -128 }],
      ['Int16 -32768', { name: 'a', datatype: DataType.Int16, value: -32768 }],
      ['Int32 -2147483648', { name: 'a', datatype: DataType.Int32, value: -2147483648 }],
      ['Int64 -(2^63)', { name: 'a', datatype: DataType.Int64, value: -(2n ** 63n) }],
      ['Int64 2^53+1', { name: 'a', datatype: DataType.Int64, value: 2n ** 53n + 1n }],
      ['UInt8 255', { name: 'a', datatype: DataType.UInt8, value: 255 }],
      ['UInt32 4294967295', { name: 'a', datatype: DataType.UInt32, value: 4294967295 }],
      ['UInt64 2^64-1', { name: 'a', datatype: DataType.UInt64, value: 2n ** 64n - 1n }],
      ['Float 1.5', { name: 'a', datatype: DataType.Float, value: 1.5 }],
      ['Double -0.1', { name: 'a', datatype: DataType.Double, value: -0.1 }],
      ['Boolean true', { name: 'a', datatype: DataType.Boolean, value: true }],
      ['String', { name: 'a', datatype: DataType.String, value: 'Füllstand ⚙' }],
      ['Text', { name: 'a', datatype: DataType.Text, value: 'long text' }],
      ['UUID', { name: 'a', datatype: DataType.UUID, value: '123e4567-e89b-12d3-a456-426614174000' }],
      ['DateTime', { name: 'a', datatype: DataType.DateTime, value: new Date('2026-12-03T13:00:00.123Z') }],
      ['Bytes', { name: 'a', datatype: DataType.Bytes, value: Buffer.from([0, 1, 255]) }],
      ['null String', { name: 'a', datatype: DataType.String, isNull: true, value: null }],
      [
        'Quality property',
        { name: 'a', datatype: DataType.Int16, isNull: true, value: null, properties: { Quality: { type: DataType.Int32, value: 0 } } },
      ],
      [
        'historical, transient',
        { name: 'a', alias: 7, timestamp: 5, datatype: DataType.Float, isHistorical: true, isTransient: true, value: 2 },
      ],
      [
        'DataSet',
        {
          name: 'a',
          datatype: DataType.DataSet,
          value: {
            kind: 'DataSet',
            columns: ['n', 's'],
            types: [DataType.Int32, DataType.String],
            rows: [
              [-1, 'x'],
              [2, null],
            ],
          },
        },
      ],
      [
        'Template',
        {
          name: 'a',
          datatype: DataType.Template,
          value: {
            kind: 'Template',
            templateRef: 'Motor',
            metrics: [{ name: 'Speed', datatype: DataType.Float, value: 1 }],
            parameters: [{ name: 'p', type: DataType.String, value: 'v' }],
          },
        },
      ],
    ];
    for (const [what, metric] of ROUND_TRIPS) {
      it(`round-trips ${what}`, () => {
        expect(decodePayload(encodePayload({ timestamp: 1, metrics: [metric] })).metrics[0]).to.deep.equal(metric);
      });
    }

    it('a signed value is sign-extended in int_value (Int8 -1 is 0xFFFFFFFF, as Tahu writes it) and a narrow 0xFF reads back -1 too', () => {
      const wide = encodePayload({ metrics: [{ datatype: DataType.Int8, value: -1 }] });
      expect(wide.toString('hex')).to.equal('1208200150ffffffff0f');
      expect(decodePayload(Buffer.from('1205200150ff01', 'hex')).metrics[0]!.value).to.equal(-1);
    });

    it('a UInt32 in long_value, as Eclipse Tahu 1.0.21 encodes one (a DCMD it sends), is read; beyond 32 bits it is a PROTOCOL_ERROR', () => {
      // Metric { name "x", datatype 7 (UInt32), long_value 257 }: the field Tahu's Java encoder fills for a Long.
      expect(decodePayload(Buffer.from('12080a01782007588102', 'hex')).metrics[0]).to.deep.include({ name: 'x', value: 257 });
      expect(() => decodePayload(Buffer.from('120b0a017820075880808080' + '10', 'hex')))
        .to.throw(PlcError, /metric x: long_value 4294967296 .*UInt32/)
        .with.property('code', 'PROTOCOL_ERROR');
      // What we send stays in int_value, as section 6.4.16 gives it.
      expect(encodePayload({ metrics: [{ name: 'x', datatype: DataType.UInt32, value: 257 }] }).toString('hex')).to.equal(
        '12080a01782007508102',
      );
    });

    it('a value that does not fit its datatype is an INVALID_VALUE naming the metric', () => {
      expect(() => encodePayload({ metrics: [{ name: 'Speed', datatype: DataType.Int16, value: 40000 }] }))
        .to.throw(PlcError, /Speed.*40000.*Int16/)
        .with.property('code', 'INVALID_VALUE');
      expect(() => encodePayload({ metrics: [{ name: 'On', datatype: DataType.Boolean, value: 1 }] })).to.throw(PlcError, /On/);
      expect(() => encodePayload({ metrics: [{ name: 'T', datatype: DataType.DateTime, value: new Date(NaN) }] })).to.throw(PlcError, /T/);
    });

    it('bytes that are not a Payload, or a metric without its value field, are a PROTOCOL_ERROR', () => {
      expect(() => decodePayload(Buffer.from('ffffffff', 'hex')))
        .to.throw(PlcError)
        .with.property('code', 'PROTOCOL_ERROR');
      expect(() => decodePayload(Buffer.from('12050a0161200c', 'hex')))
        .to.throw(PlcError, /metric a.*string_value/)
        .with.property('code', 'PROTOCOL_ERROR');
      // An Int32Array without its bytes_value (found by npm run fuzz: it was a TypeError).
      expect(() => decodePayload(Buffer.from('12050a01782018', 'hex')))
        .to.throw(PlcError, /metric x: a Int32Array without its bytes_value/)
        .with.property('code', 'PROTOCOL_ERROR');
    });
  });

  describe('PLC types as datatypes', () => {
    it('maps the elementary types as issue #34 lists them', () => {
      const map: Record<string, number> = {
        BOOL: DataType.Boolean,
        SINT: DataType.Int8,
        INT: DataType.Int16,
        DINT: DataType.Int32,
        LINT: DataType.Int64,
        USINT: DataType.UInt8,
        BYTE: DataType.UInt8,
        UINT: DataType.UInt16,
        WORD: DataType.UInt16,
        UDINT: DataType.UInt32,
        DWORD: DataType.UInt32,
        ULINT: DataType.UInt64,
        LWORD: DataType.UInt64,
        REAL: DataType.Float,
        LREAL: DataType.Double,
        STRING: DataType.String,
        WSTRING: DataType.String,
        CHAR: DataType.String,
        DTL: DataType.DateTime,
        DATE_AND_TIME: DataType.DateTime,
      };
      for (const [plc, dt] of Object.entries(map)) expect(datatypeOfPlcType(plc as never, false), plc).to.equal(dt);
    });

    it('takes addresses: arrays to the array types, CHAR[n] to one String', () => {
      expect(datatypeOfAddress('DB1.DBW0:INT[4]')).to.equal(DataType.Int16Array);
      expect(datatypeOfAddress('DB1.DBX0.0:BOOL[16]')).to.equal(DataType.BooleanArray);
      expect(datatypeOfAddress('DB1.DBD0:REAL')).to.equal(DataType.Float);
      expect(datatypeOfAddress('M10.0')).to.equal(DataType.Boolean);
      expect(datatypeOfAddress('DB1.DBB0:CHAR[8]')).to.equal(DataType.String);
    });
  });
});
