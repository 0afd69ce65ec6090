/**
 * Bit strings, integers and floating point numbers: big-endian two's
 * complement / IEEE 754, as S7 stores them.
 */
import { bigIntegerIn, integerIn, numberFor, reject, type CodecTable } from './checks';

const INT64_MIN = -(2n ** 63n);
const INT64_MAX = 2n ** 63n - 1n;
const UINT64_MAX = 2n ** 64n - 1n;

type NumberType =
  'BYTE' | 'USINT' | 'SINT' | 'WORD' | 'UINT' | 'INT' | 'DWORD' | 'UDINT' | 'DINT' | 'LWORD' | 'ULINT' | 'LINT' | 'REAL' | 'LREAL';

export const NUMBER_CODECS: CodecTable<NumberType> = {
  BYTE: {
    encode: (t, v, b, o) => void b.writeUInt8(integerIn(t.type, v, 0, 0xff), o),
    decode: (_t, b, o) => b.readUInt8(o),
  },
  USINT: {
    encode: (t, v, b, o) => void b.writeUInt8(integerIn(t.type, v, 0, 0xff), o),
    decode: (_t, b, o) => b.readUInt8(o),
  },
  SINT: {
    encode: (t, v, b, o) => void b.writeInt8(integerIn(t.type, v, -0x80, 0x7f), o),
    decode: (_t, b, o) => b.readInt8(o),
  },
  WORD: {
    encode: (t, v, b, o) => void b.writeUInt16BE(integerIn(t.type, v, 0, 0xffff), o),
    decode: (_t, b, o) => b.readUInt16BE(o),
  },
  UINT: {
    encode: (t, v, b, o) => void b.writeUInt16BE(integerIn(t.type, v, 0, 0xffff), o),
    decode: (_t, b, o) => b.readUInt16BE(o),
  },
  INT: {
    encode: (t, v, b, o) => void b.writeInt16BE(integerIn(t.type, v, -0x8000, 0x7fff), o),
    decode: (_t, b, o) => b.readInt16BE(o),
  },
  DWORD: {
    encode: (t, v, b, o) => void b.writeUInt32BE(integerIn(t.type, v, 0, 0xffffffff), o),
    decode: (_t, b, o) => b.readUInt32BE(o),
  },
  UDINT: {
    encode: (t, v, b, o) => void b.writeUInt32BE(integerIn(t.type, v, 0, 0xffffffff), o),
    decode: (_t, b, o) => b.readUInt32BE(o),
  },
  DINT: {
    encode: (t, v, b, o) => void b.writeInt32BE(integerIn(t.type, v, -0x80000000, 0x7fffffff), o),
    decode: (_t, b, o) => b.readInt32BE(o),
  },
  LWORD: {
    encode: (t, v, b, o) => void b.writeBigUInt64BE(bigIntegerIn(t.type, v, 0n, UINT64_MAX), o),
    decode: (_t, b, o) => b.readBigUInt64BE(o),
  },
  ULINT: {
    encode: (t, v, b, o) => void b.writeBigUInt64BE(bigIntegerIn(t.type, v, 0n, UINT64_MAX), o),
    decode: (_t, b, o) => b.readBigUInt64BE(o),
  },
  LINT: {
    encode: (t, v, b, o) => void b.writeBigInt64BE(bigIntegerIn(t.type, v, INT64_MIN, INT64_MAX), o),
    decode: (_t, b, o) => b.readBigInt64BE(o),
  },
  REAL: {
    // NaN and ±Infinity are REAL values a PLC can hold (and a read can return),
    // so they are written as given; a finite number that float32 cannot hold is
    // refused instead of silently becoming Infinity. Precision is rounded to
    // the nearest float32 like the PLC does.
    encode: (t, v, b, o) => {
      const n = numberFor(t.type, v);
      if (Number.isFinite(n) && !Number.isFinite(Math.fround(n))) {
        reject(`${n} overflows REAL (float32, at most ±3.4028234663852886e38)`);
      }
      b.writeFloatBE(n, o);
    },
    decode: (_t, b, o) => b.readFloatBE(o),
  },
  LREAL: {
    encode: (t, v, b, o) => void b.writeDoubleBE(numberFor(t.type, v), o),
    decode: (_t, b, o) => b.readDoubleBE(o),
  },
};
