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
import type { DataTypeName } from '../../types';
import { DT } from './ids';
import { i32, u32, type WireReader } from './wire';

/** Elementary types sent with their own wire type: the type and its byte width. */
const TYPED: Readonly<Partial<Record<DataTypeName, readonly [number, number]>>> = Object.freeze({
  BYTE: [DT.byte, 1],
  USINT: [DT.usint, 1],
  SINT: [DT.sint, 1],
  CHAR: [DT.usint, 1],
  WORD: [DT.word, 2],
  UINT: [DT.uint, 2],
  INT: [DT.int, 2],
  DWORD: [DT.dword, 4],
  REAL: [DT.real, 4],
  UDINT: [DT.udint, 4],
  DINT: [DT.dint, 4],
  LREAL: [DT.lreal, 8],
  LWORD: [DT.lword, 8],
});

/** A BLOB PValue: flags, type, root id 0, length, bytes. */
export function blob(bytes: Buffer): Buffer {
  return Buffer.concat([Buffer.from([0x00, DT.blob]), u32(0), u32(bytes.length), bytes]);
}

/** The PValue of `node` in the block image `image`. */
export function readNode(node: LayoutNode, image: Buffer): Buffer {
  const raw = image.subarray(node.byte, node.byte + node.size);
  if (node.kind !== 'elementary') return blob(Buffer.from(raw));
  if (node.dataType === 'BOOL') return Buffer.from([0x00, DT.bool, (image[node.byte]! >> (node.bit ?? 0)) & 1]);
  const typed = TYPED[node.dataType];
  if (!typed) return blob(Buffer.from(raw));
  const [type] = typed;
  if (type === DT.udint) return Buffer.concat([Buffer.from([0x00, type]), u32(raw.readUInt32BE(0))]);
  if (type === DT.dint) return Buffer.concat([Buffer.from([0x00, type]), i32(raw.readInt32BE(0))]);
  return Buffer.concat([Buffer.from([0x00, type]), raw]);
}

const FIXED: Readonly<Record<number, number>> = Object.freeze({
  [DT.bool]: 1,
  [DT.usint]: 1,
  [DT.byte]: 1,
  [DT.sint]: 1,
  [DT.uint]: 2,
  [DT.word]: 2,
  [DT.int]: 2,
  [DT.dword]: 4,
  [DT.real]: 4,
  [DT.rid]: 4,
  [DT.lreal]: 8,
  [DT.lword]: 8,
});

/** Reads one PValue of a request and gives its value as big-endian bytes (what a standard DB holds). */
export function readPValue(r: WireReader): Buffer {
  const flags = r.byte('the flags of a value');
  const type = r.byte('the type of a value');
  if (flags & 0x10) {
    const count = r.vlq('an array count');
    const size = FIXED[type];
    if (size === undefined) throw new ProtocolError(`S7CommPlus array of wire type 0x${type.toString(16)} is not one the simulator takes`);
    return Buffer.from(r.bytes(count * size, 'an array'));
  }
  const size = FIXED[type];
  if (size !== undefined) return Buffer.from(r.bytes(size, 'a value'));
  const out = Buffer.alloc(4);
  switch (type) {
    case DT.udint:
    case DT.aid:
      out.writeUInt32BE(r.vlq('a UDINT value'));
      return out;
    case DT.dint:
      out.writeInt32BE(r.vlqSigned('a DINT value'));
      return out;
    case DT.ulint: {
      const b = Buffer.alloc(8);
      b.writeBigUInt64BE(r.vlq64('a ULINT value'));
      return b;
    }
    case DT.blob: {
      r.vlq('a BLOB root id');
      return Buffer.from(r.bytes(r.vlq('a BLOB length'), 'a BLOB'));
    }
    case DT.wstring:
      return Buffer.from(r.bytes(r.vlq('a WSTRING length'), 'a WSTRING'));
    default:
      throw new ProtocolError(`S7CommPlus value of wire type 0x${type.toString(16)} is not one the simulator takes`);
  }
}

/** Writes `raw` (a value's bytes) into `node` of DB `db` in `memory` (so its observers see it); false when its length does not fit the member (nothing written). */
export function writeNode(node: LayoutNode, memory: PlcMemory, db: number, raw: Buffer): boolean {
  if (node.kind === 'elementary' && node.dataType === 'BOOL') {
    if (raw.length !== 1) return false;
    memory.writeBit('DB', db, node.byte, node.bit ?? 0, raw[0] !== 0);
    return true;
  }
  if (raw.length !== node.size) return false;
  memory.write('DB', db, node.byte, raw);
  return true;
}
