/**
 * The SymbolCrc of an item address: a CRC of the symbol path the client
 * means, which the PLC compares with its own program. 0 asks for no check; a
 * CRC that does not match makes the PLC refuse that item alone with an error
 * whose low word is -17 (InvalidCRC), so a value is never read through a LID
 * that a download gave to another member.
 *
 * The CRC: 32 bits, polynomial 0xF4ACFB13 (x^32+x^31+x^30+x^29+x^28+x^26+x^23
 * +x^21+x^19+x^18+x^15+x^14+x^13+x^12+x^9+x^8+x^4+x+1), most significant bit
 * first, start value 0, no final XOR (HarpoS7 (MIT), HarpoS7/Integrity/
 * HarpoCrc32.cs, its table and its test vector "Tag_12" = 0x0CDF926D; the
 * polynomial also in the s7comm_plus Wireshark dissector's help of the field
 * s7comm-plus.item.addr.symbol_crc, whose error table names -17 "Invalid
 * CRC").
 *
 * A path: per level (member, struct member, …, from the block down) the CRC
 * of the member's UTF-8 name followed by its type: one byte, the software
 * data type; for an array 0x10, the element's software data type and the
 * lower bound (signed 32-bit, little-endian). The path's CRC runs over the
 * first level's CRC (4 bytes little-endian), then for each further level
 * 0x89 and that level's CRC. An element's index is not part of it: every
 * element of an array has its array's CRC. A BBOOL (software type 40) counts
 * as a BOOL. Facts (not code) from DataLogXE/node-red-contrib-s7-plus (LGPL),
 * lib/s7plus/crc/symbol-crc.js and test/symbol-crc.test.js, which give the
 * vectors of HarpoS7's author ("Test2" DInt, "TEST 3" Array[0..6] of Bool,
 * "TEST 4".T4ChildBool) and ones read from an S7-1500 (Array[1..10000] of
 * SInt and of Real); test/s7plus-symbol-crc.test.ts holds them all.
 *
 * Pure: no sockets, no state.
 */
import { SoftDataType } from '../constants';

/** The generator polynomial (HarpoS7 HarpoCrc32.cs). */
export const SYMBOL_CRC_POLYNOMIAL = 0xf4acfb13;
/** The type byte of an array level, before its element's type and lower bound. */
const ARRAY_TYPE = SoftDataType.Array;
/** The byte between two levels of a path. */
const LEVEL_SEPARATOR = 0x89;
/** The software type of a BBOOL (a BOOL of a packed struct); its CRC is a BOOL's. */
const BBOOL = 40;

const TABLE = ((): Uint32Array => {
  const t = new Uint32Array(256);
  for (let i = 0; i < 256; i++) {
    let c = i << 24;
    for (let k = 0; k < 8; k++) c = c & 0x80000000 ? (c << 1) ^ SYMBOL_CRC_POLYNOMIAL : c << 1;
    t[i] = c >>> 0;
  }
  return t;
})();

/** The CRC of `bytes`, continuing from `crc` (0 to start). */
export function crc32(bytes: Uint8Array, crc = 0): number {
  let c = crc >>> 0;
  for (const b of bytes) c = (TABLE[(b ^ (c >>> 24)) & 0xff]! ^ (c << 8)) >>> 0;
  return c;
}

function u32le(v: number): Buffer {
  const b = Buffer.alloc(4);
  b.writeUInt32LE(v >>> 0);
  return b;
}

/** One level of a symbol path: a member's name and software data type; an array's element type and lower bound. */
export interface SymbolLevel {
  /** The member's name as declared, without quotes (UTF-8 on the wire). */
  readonly name: string;
  /** The software data type (constants.ts SoftDataType): a struct's is Struct; an array's is its element's. */
  readonly soft: number;
  /** Arrays: the lower bound of the (one) dimension. */
  readonly low?: number;
}

/** The CRC of one level: its name, then its type bytes. */
export function levelCrc(level: SymbolLevel): number {
  const soft = level.soft === BBOOL ? SoftDataType.Bool : level.soft;
  if (!Number.isInteger(soft) || soft < 0 || soft > 0xff) throw new RangeError(`SymbolCrc: software type ${level.soft} of ${level.name}`);
  let type: Buffer;
  if (level.low === undefined) type = Buffer.of(soft);
  else {
    if (!Number.isInteger(level.low) || level.low < -0x80000000 || level.low > 0x7fffffff)
      throw new RangeError(`SymbolCrc: lower bound ${level.low} of ${level.name}`);
    type = Buffer.alloc(6);
    type[0] = ARRAY_TYPE;
    type[1] = soft;
    type.writeInt32LE(level.low, 2);
  }
  return crc32(type, crc32(Buffer.from(level.name, 'utf8')));
}

/** The SymbolCrc of a path (outermost level first); a path of no level is 0 (no check). */
export function symbolCrc(path: readonly SymbolLevel[]): number {
  if (path.length === 0) return 0;
  let crc = crc32(u32le(levelCrc(path[0]!)));
  for (let i = 1; i < path.length; i++) crc = crc32(u32le(levelCrc(path[i]!)), crc32(Buffer.of(LEVEL_SEPARATOR), crc));
  return crc;
}

/** True when a PLC's item error is InvalidCRC: its low word is -17 (an S7-1500 answers 0x8009890012CBFFEF). */
export function isInvalidCrc(code: bigint): boolean {
  return (code & 0xffffn) === INVALID_CRC_LOW_WORD;
}

/** -17 as the low 16 bits of an error value. */
const INVALID_CRC_LOW_WORD = 0xffefn;

/**
 * The item error an S7-1500 answers for a SymbolCrc that does not match, as a read of one showed it
 * (DataLogXE/node-red-contrib-s7-plus (LGPL), nodes/s7complus-endpoint.js: 0x8009890012cbffef "CRC mismatch").
 */
export const ITEM_ERROR_INVALID_CRC = 0x8009890012cbffefn;
