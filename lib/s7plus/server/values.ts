/**
 * Values of members as PValues: a read answers an elementary member with
 * its own wire type (fixed-width big-endian, or a VLQ for DINT and UDINT)
 * and anything else (strings, times, arrays, structs) as a BLOB of its
 * standard bytes; a write takes any of those forms back. Layouts:
 * s7commplus (MIT) codec.py (encode_pvalue_typed, decode_pvalue_to_bytes).
 */
import { ProtocolError } from '../../errors';
import type { PlcMemory } from '../../sim/memory';
import type { LayoutNode } from '../../symbols/layout-nodes';
import type { AreaName, DataTypeName } from '../../types';
import { DataType } from '../constants';
import type { Reader } from '../codec/bytes';
import { encodeSVlq32, encodeUVlq32 } from '../codec/vlq';

/** Elementary types sent with their own wire type: the type and its byte width. */
const TYPED: Readonly<Partial<Record<DataTypeName, readonly [number, number]>>> = Object.freeze({
  BYTE: [DataType.Byte, 1],
  USINT: [DataType.USInt, 1],
  SINT: [DataType.SInt, 1],
  CHAR: [DataType.USInt, 1],
  WORD: [DataType.Word, 2],
  UINT: [DataType.UInt, 2],
  INT: [DataType.Int, 2],
  DWORD: [DataType.DWord, 4],
  REAL: [DataType.Real, 4],
  UDINT: [DataType.UDInt, 4],
  DINT: [DataType.DInt, 4],
  LREAL: [DataType.LReal, 8],
  LWORD: [DataType.LWord, 8],
});

/** A BLOB PValue: flags, type, root id 0, length, bytes. */
export function blob(bytes: Buffer): Buffer {
  return Buffer.concat([Buffer.from([0x00, DataType.Blob]), encodeUVlq32(0), encodeUVlq32(bytes.length), bytes]);
}

/** The PValue of `node` in the block image `image`. */
export function readNode(node: LayoutNode, image: Buffer): Buffer {
  const raw = image.subarray(node.byte, node.byte + node.size);
  if (node.kind !== 'elementary') return blob(Buffer.from(raw));
  if (node.dataType === 'BOOL') return Buffer.from([0x00, DataType.Bool, (image[node.byte]! >> (node.bit ?? 0)) & 1]);
  const typed = TYPED[node.dataType];
  if (!typed) return blob(Buffer.from(raw));
  const [type] = typed;
  if (type === DataType.UDInt) return Buffer.concat([Buffer.from([0x00, type]), encodeUVlq32(raw.readUInt32BE(0))]);
  if (type === DataType.DInt) return Buffer.concat([Buffer.from([0x00, type]), encodeSVlq32(raw.readInt32BE(0))]);
  const out = Buffer.allocUnsafe(2 + raw.length);
  out[0] = 0x00;
  out[1] = type;
  raw.copy(out, 2);
  return out;
}

const FIXED: Readonly<Record<number, number>> = Object.freeze({
  [DataType.Bool]: 1,
  [DataType.USInt]: 1,
  [DataType.Byte]: 1,
  [DataType.SInt]: 1,
  [DataType.UInt]: 2,
  [DataType.Word]: 2,
  [DataType.Int]: 2,
  [DataType.DWord]: 4,
  [DataType.Real]: 4,
  [DataType.RID]: 4,
  [DataType.LReal]: 8,
  [DataType.LWord]: 8,
});

/** Reads one PValue of a request and gives its value as big-endian bytes (what a standard DB holds). */
export function readPValue(r: Reader): Buffer {
  const flags = r.u8('the flags of a value');
  const type = r.u8('the type of a value');
  if (flags & 0x10) {
    const count = r.uvlq32();
    const size = FIXED[type];
    if (size === undefined) throw new ProtocolError(`S7CommPlus array of wire type 0x${type.toString(16)} is not one the simulator takes`);
    return Buffer.from(r.bytes(count * size, 'an array'));
  }
  const size = FIXED[type];
  if (size !== undefined) return Buffer.from(r.bytes(size, 'a value'));
  const out = Buffer.alloc(4);
  switch (type) {
    case DataType.UDInt:
    case DataType.AID:
      out.writeUInt32BE(r.uvlq32());
      return out;
    case DataType.DInt:
      out.writeInt32BE(r.svlq32());
      return out;
    case DataType.ULInt: {
      const b = Buffer.alloc(8);
      b.writeBigUInt64BE(r.uvlq64());
      return b;
    }
    case DataType.Blob: {
      r.uvlq32();
      return Buffer.from(r.bytes(r.uvlq32(), 'a BLOB'));
    }
    case DataType.WString:
      return Buffer.from(r.bytes(r.uvlq32(), 'a WSTRING'));
    default:
      throw new ProtocolError(`S7CommPlus value of wire type 0x${type.toString(16)} is not one the simulator takes`);
  }
}

/** Writes `raw` (a value's bytes) into `node` of DB `db` (or of the area I, Q, M) in `memory` (so its observers see it); false when its length does not fit the member (nothing written). */
export function writeNode(node: LayoutNode, memory: PlcMemory, area: AreaName, db: number, raw: Buffer): boolean {
  if (node.kind === 'elementary' && node.dataType === 'BOOL') {
    if (raw.length !== 1) return false;
    memory.writeBit(area, db, node.byte, node.bit ?? 0, raw[0] !== 0);
    return true;
  }
  if (raw.length !== node.size) return false;
  memory.write(area, db, node.byte, raw);
  return true;
}
