/**
 * PValues: the typed values of S7CommPlus. On the wire a flags byte, the
 * datatype byte (DataType in ../constants), then the value:
 *
 * - fixed big-endian: Bool, USInt, SInt, Byte (1), UInt, Int, Word (2),
 *   DWord, Real, RID (4), LWord, LReal, Timestamp (8);
 * - VLQ: UDInt, AID (unsigned 32), DInt (signed 32), ULInt (unsigned 64),
 *   LInt, Timespan (signed 64);
 * - WString, S7String: a UVLQ byte count, then the text (UTF-8 / Latin-1);
 * - Blob: a UVLQ root id, a UVLQ byte count, the bytes; a root id above 1
 *   (a typed blob: an alarm's associated value names its Softdatatype there)
 *   has 8 bytes and a blob type (2 or 3) between the root id and the count
 *   (s7commplus (MIT), alarm.py _decode_blob);
 * - Struct: a UInt32 struct id, then (UVLQ key, PValue) members ending at key
 *   0; or, for the packed struct ids, a UInt64 interface timestamp, UVLQ
 *   transport flags, a UVLQ count (a second one when flags has 0x400) and
 *   that many bytes.
 *
 * Flag 0x10 (array) and 0x20 (address array): a UVLQ count, then the
 * elements; flag 0x40 (sparse array): (UVLQ key, element) pairs ending at key
 * 0. Other flag bits are kept as they came.
 * Source: s7commplus (MIT), codec.py (encode_typed_value,
 * decode_pvalue_to_bytes: which types are VLQ and which fixed) and
 * subscription.py; golden frames (address arrays, structs in notifications).
 * Timestamp is kept as the raw UInt64 (microseconds since 1970 in the golden
 * notifications); Variant (0x16) has no public layout and is refused.
 */
import { ProtocolError } from '../../errors';
import { DataType, PACKED_STRUCT_COUNT2, PACKED_STRUCT_RANGES, PValueFlag } from '../constants';
import { Reader, Writer } from './bytes';

export interface BlobValue {
  rootId: number;
  data: Buffer;
  /** A typed blob's (root id above 1) 8 bytes before its blob type; zeros when absent. */
  typeHead?: Buffer;
  /** A typed blob's blob type, 2 or 3; 2 when absent. */
  blobType?: number;
}

/** A typed blob's head: its 8 bytes and its blob type (alarm.py _decode_blob). */
const TYPED_BLOB_HEAD = 8;

export interface StructMember {
  key: number;
  value: PValue;
}

/** A struct: members by key, or (packed ids) its members' bytes as one blob. */
export type StructValue =
  | { id: number; members: StructMember[] }
  | {
      id: number;
      /** firstCount: with transport flag 0x400 two counts travel; the second is data's length, the first is kept as it came. */
      packed: { interfaceTimestamp: bigint; transportFlags: number; firstCount?: number; data: Buffer };
    };

export type Scalar = null | boolean | number | bigint | string | BlobValue | StructValue;

export interface SparseEntry {
  key: number;
  value: Scalar;
}

/**
 * A decoded PValue. `value` is one Scalar, an array of them (flag 0x10 or
 * 0x20), or SparseEntry[] (flag 0x40). Number for the ≤32-bit types, bigint
 * for the 64-bit ones, boolean for Bool, string for the strings.
 */
export interface PValue {
  flags: number;
  type: number;
  value: Scalar | Scalar[] | SparseEntry[];
}

const CONTAINER = PValueFlag.Array | PValueFlag.AddressArray | PValueFlag.SparseArray;
/** Deeper nesting (structs in structs) is refused: no real type nests this far, and the stack stays bounded. */
const MAX_DEPTH = 32;
/** An element count that cannot fit the bytes left is refused before anything is allocated. */
const MIN_ELEMENT_BYTES = 1;

function isPacked(structId: number): boolean {
  return PACKED_STRUCT_RANGES.some(([lo, hi]) => structId > lo && structId < hi);
}

function typeName(type: number): string {
  const name = Object.entries(DataType).find(([, v]) => v === type)?.[0];
  return name ?? `0x${type.toString(16).padStart(2, '0')}`;
}

function readScalar(r: Reader, type: number, depth: number): Scalar {
  switch (type) {
    case DataType.Null:
      return null;
    case DataType.Bool:
      return r.u8('Bool') !== 0;
    case DataType.USInt:
    case DataType.Byte:
      return r.u8(typeName(type));
    case DataType.SInt:
      return (r.u8('SInt') << 24) >> 24;
    case DataType.UInt:
    case DataType.Word:
      return r.u16(typeName(type));
    case DataType.Int:
      return (r.u16('Int') << 16) >> 16;
    case DataType.DWord:
    case DataType.RID:
      return r.u32(typeName(type));
    case DataType.Real:
      return r.bytes(4, 'Real').readFloatBE(0);
    case DataType.LReal:
      return r.bytes(8, 'LReal').readDoubleBE(0);
    case DataType.LWord:
    case DataType.Timestamp:
      return r.u64(typeName(type));
    case DataType.UDInt:
    case DataType.AID:
      return r.uvlq32();
    case DataType.DInt:
      return r.svlq32();
    case DataType.ULInt:
      return r.uvlq64();
    case DataType.LInt:
    case DataType.Timespan:
      return r.svlq64();
    case DataType.WString:
      return r.bytes(r.uvlq32(), 'WString').toString('utf8');
    case DataType.S7String:
      return r.bytes(r.uvlq32(), 'S7String').toString('latin1');
    case DataType.Blob: {
      const rootId = r.uvlq32();
      if (rootId <= 1) return { rootId, data: r.bytes(r.uvlq32(), 'Blob') };
      const typeHead = r.bytes(TYPED_BLOB_HEAD, 'typed Blob head');
      const at = r.offset;
      const blobType = r.u8('Blob type');
      if (blobType !== 2 && blobType !== 3)
        throw new ProtocolError(`S7CommPlus: typed Blob of type ${blobType} at offset ${at} (2 or 3 are known)`);
      return { rootId, typeHead, blobType, data: r.bytes(r.uvlq32(), 'Blob') };
    }
    case DataType.Struct:
      return readStruct(r, depth);
    default:
      throw new ProtocolError(`S7CommPlus: PValue of datatype ${typeName(type)} at offset ${r.offset - 1} is not supported`);
  }
}

function readStruct(r: Reader, depth: number): StructValue {
  if (depth >= MAX_DEPTH) throw new ProtocolError(`S7CommPlus: structs nested deeper than ${MAX_DEPTH} at offset ${r.offset}`);
  const id = r.u32('struct id');
  if (isPacked(id)) {
    const interfaceTimestamp = r.u64('packed struct timestamp');
    const transportFlags = r.uvlq32();
    const count = r.uvlq32();
    if (transportFlags & PACKED_STRUCT_COUNT2) {
      const data = r.bytes(r.uvlq32(), 'packed struct');
      return { id, packed: { interfaceTimestamp, transportFlags, firstCount: count, data } };
    }
    return { id, packed: { interfaceTimestamp, transportFlags, data: r.bytes(count, 'packed struct') } };
  }
  const members: StructMember[] = [];
  for (let key = r.uvlq32(); key !== 0; key = r.uvlq32()) members.push({ key, value: readPValueAt(r, depth + 1) });
  return { id, members };
}

function readPValueAt(r: Reader, depth: number): PValue {
  const flags = r.u8('PValue flags');
  const type = r.u8('PValue datatype');
  const container = flags & CONTAINER;
  if (container === 0) return { flags, type, value: readScalar(r, type, depth) };
  if (container === PValueFlag.SparseArray) {
    const entries: SparseEntry[] = [];
    for (let key = r.uvlq32(); key !== 0; key = r.uvlq32()) entries.push({ key, value: readScalar(r, type, depth) });
    return { flags, type, value: entries };
  }
  if (container !== PValueFlag.Array && container !== PValueFlag.AddressArray)
    throw new ProtocolError(`S7CommPlus: PValue flags 0x${flags.toString(16)} at offset ${r.offset - 2} combine array kinds`);
  const count = r.uvlq32();
  if (count * MIN_ELEMENT_BYTES > r.remaining && type !== DataType.Null)
    throw new ProtocolError(
      `S7CommPlus: array of ${count} ${typeName(type)} at offset ${r.offset} is longer than the ${r.remaining} bytes left`,
    );
  if (type === DataType.Null && count > 0) throw new ProtocolError(`S7CommPlus: array of ${count} Null values at offset ${r.offset}`);
  const items: Scalar[] = new Array<Scalar>(count);
  for (let i = 0; i < count; i++) items[i] = readScalar(r, type, depth);
  return { flags, type, value: items };
}

/** Reads one PValue at the reader's offset and moves past it. */
export function readPValue(r: Reader): PValue {
  return readPValueAt(r, 0);
}

/** Decodes the PValue at `offset` of `buf`: the value and the bytes it took. */
export function decodePValue(buf: Buffer, offset = 0): { value: PValue; length: number } {
  const r = new Reader(buf, offset);
  const value = readPValue(r);
  return { value, length: r.offset - offset };
}

/** The offset just past the PValue at `offset` (it is checked on the way, as a decode would). */
export function skipPValue(buf: Buffer, offset: number): number {
  return offset + decodePValue(buf, offset).length;
}

function wrongValue(type: number, v: unknown): TypeError {
  return new TypeError(`S7CommPlus: ${typeName(type)} cannot encode ${typeof v === 'bigint' ? `${v}n` : JSON.stringify(v)}`);
}

function num(type: number, v: Scalar, lo: number, hi: number): number {
  if (typeof v !== 'number' || !Number.isInteger(v) || v < lo || v > hi) throw wrongValue(type, v);
  return v;
}

function big(type: number, v: Scalar): bigint {
  if (typeof v !== 'bigint') throw wrongValue(type, v);
  return v;
}

function writeScalar(w: Writer, type: number, v: Scalar): void {
  switch (type) {
    case DataType.Null:
      if (v !== null) throw wrongValue(type, v);
      return;
    case DataType.Bool:
      if (typeof v !== 'boolean') throw wrongValue(type, v);
      w.u8(v ? 1 : 0);
      return;
    case DataType.USInt:
    case DataType.Byte:
      w.u8(num(type, v, 0, 0xff));
      return;
    case DataType.SInt:
      w.u8(num(type, v, -0x80, 0x7f));
      return;
    case DataType.UInt:
    case DataType.Word:
      w.u16(num(type, v, 0, 0xffff));
      return;
    case DataType.Int:
      w.u16(num(type, v, -0x8000, 0x7fff));
      return;
    case DataType.DWord:
    case DataType.RID:
      w.u32(num(type, v, 0, 0xffffffff));
      return;
    case DataType.Real:
    case DataType.LReal: {
      if (typeof v !== 'number') throw wrongValue(type, v);
      const b = Buffer.allocUnsafe(type === DataType.Real ? 4 : 8);
      if (type === DataType.Real) b.writeFloatBE(v);
      else b.writeDoubleBE(v);
      w.bytes(b);
      return;
    }
    case DataType.LWord:
    case DataType.Timestamp: {
      const b = big(type, v);
      if (b < 0n || b > 0xffffffffffffffffn) throw wrongValue(type, v);
      w.u64(b);
      return;
    }
    case DataType.UDInt:
    case DataType.AID:
      w.uvlq32(num(type, v, 0, 0xffffffff));
      return;
    case DataType.DInt:
      w.svlq32(num(type, v, -0x80000000, 0x7fffffff));
      return;
    case DataType.ULInt:
      w.uvlq64(big(type, v));
      return;
    case DataType.LInt:
    case DataType.Timespan:
      w.svlq64(big(type, v));
      return;
    case DataType.WString:
    case DataType.S7String: {
      if (typeof v !== 'string') throw wrongValue(type, v);
      const b = Buffer.from(v, type === DataType.WString ? 'utf8' : 'latin1');
      w.uvlq32(b.length).bytes(b);
      return;
    }
    case DataType.Blob:
      if (v === null || typeof v !== 'object' || !('rootId' in v)) throw wrongValue(type, v);
      w.uvlq32(v.rootId);
      if (v.rootId > 1) {
        const head = v.typeHead ?? Buffer.alloc(TYPED_BLOB_HEAD);
        if (head.length !== TYPED_BLOB_HEAD) throw new RangeError(`S7CommPlus: a typed Blob's head has ${TYPED_BLOB_HEAD} bytes`);
        w.bytes(head).u8(v.blobType ?? 2);
      }
      w.uvlq32(v.data.length).bytes(v.data);
      return;
    case DataType.Struct:
      if (v === null || typeof v !== 'object' || !('id' in v)) throw wrongValue(type, v);
      writeStruct(w, v);
      return;
    default:
      throw new TypeError(`S7CommPlus: datatype ${typeName(type)} cannot be encoded`);
  }
}

function writeStruct(w: Writer, s: StructValue): void {
  w.u32(s.id);
  if ('packed' in s) {
    const p = s.packed;
    w.u64(p.interfaceTimestamp).uvlq32(p.transportFlags);
    if (p.transportFlags & PACKED_STRUCT_COUNT2) w.uvlq32(p.firstCount ?? p.data.length);
    w.uvlq32(p.data.length).bytes(p.data);
    return;
  }
  for (const m of s.members) {
    if (m.key === 0) throw new TypeError('S7CommPlus: a struct member key of 0 would end the struct');
    w.uvlq32(m.key);
    writePValue(w, m.value);
  }
  w.uvlq32(0);
}

/** Writes one PValue. Throws TypeError (a bug of the caller) for a value that does not fit its type. */
export function writePValue(w: Writer, p: PValue): void {
  w.u8(p.flags).u8(p.type);
  const container = p.flags & CONTAINER;
  if (container === 0) {
    writeScalar(w, p.type, p.value as Scalar);
    return;
  }
  if (!Array.isArray(p.value)) throw wrongValue(p.type, p.value);
  if (container === PValueFlag.SparseArray) {
    for (const e of p.value as SparseEntry[]) {
      if (e.key === 0) throw new TypeError('S7CommPlus: a sparse-array key of 0 would end the array');
      w.uvlq32(e.key);
      writeScalar(w, p.type, e.value);
    }
    w.uvlq32(0);
    return;
  }
  w.uvlq32(p.value.length);
  for (const e of p.value as Scalar[]) writeScalar(w, p.type, e);
}

export function encodePValue(p: PValue): Buffer {
  const w = new Writer();
  writePValue(w, p);
  return w.toBuffer();
}

/** A scalar PValue with flags 0. */
export function scalar(type: number, value: Scalar): PValue {
  return { flags: 0, type, value };
}
