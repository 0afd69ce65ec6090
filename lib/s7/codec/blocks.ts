/**
 * Block functions (userdata group 3) and the block's load-memory form that
 * upload returns. Decoders for the client, encoders for the simulator.
 *
 * List all blocks: 7 entries of 4 bytes: '0', block type letter, count (2).
 * List blocks of a type: entries of 4 bytes: number (2), flags (1), language (1).
 * Block info request: '0', type letter, number as 5 ASCII digits, 'A'.
 * Block info answer (78 bytes, offsets into the data):
 *    0 '0' + type letter   2 info length   4 reserved   6 "pp"   8 reserved
 *    9 flags   10 language   11 sub-block type   12 number (2)   14 load memory length (4)
 *   18 security (4)   22 code time stamp (6)   28 interface time stamp (6)
 *   34 SBB length   36 ADD length   38 local data length   40 MC7 code length (for a DB: its data length)
 *   42 author (8)   50 family (8)   58 name (8)   66 version (major << 4 | minor)
 *   67 reserved   68 checksum (2)   70 reserved (8)
 * A time stamp is milliseconds since midnight (4) and days since 1984-01-01 (2).
 */
import { ProtocolError } from '../../errors';
import { BLOCK_LANGUAGES, BLOCK_TYPES, SUBBLOCK_TYPES, blockTypeName, type BlockType } from '../constants';

/** Block counts per type (`listBlocks()`). */
export type BlockCounts = Record<BlockType, number>;

export interface BlockListEntry {
  number: number;
  flags: number;
  /** Language code (BLOCK_LANGUAGES). */
  language: number;
}

export interface BlockInfo {
  type: BlockType;
  number: number;
  /** Programming language ("DB", "STL", "LAD" …) and its code. */
  language: string;
  languageCode: number;
  flags: number;
  /** Bytes the block takes in load memory. */
  loadSize: number;
  /** MC7 code length; for a DB the length of its data (what `readDb` reads). */
  mc7Size: number;
  /** Length of the data of a DB (the MC7 size); undefined for other blocks. */
  dataLength: number | undefined;
  localDataSize: number;
  sbbLength: number;
  addLength: number;
  author: string;
  family: string;
  name: string;
  /** Block version "major.minor". */
  version: string;
  checksum: number;
  /** Know-how protection (security field ≠ 0). */
  protected: boolean;
  codeTime: Date;
  interfaceTime: Date;
}

const EPOCH_1984 = Date.UTC(1984, 0, 1);
const DAY_MS = 86_400_000;
const BLOCK_INFO_LENGTH = 78;
const BLOCK_HEADER = 36;
const BLOCK_FOOTER = 56;

/** The order a CPU lists the block types in. */
const LIST_ORDER: readonly BlockType[] = ['OB', 'FB', 'FC', 'DB', 'SDB', 'SFC', 'SFB'];

function timestamp(b: Buffer, o: number): Date {
  return new Date(EPOCH_1984 + b.readUInt16BE(o + 4) * DAY_MS + (b.readUInt32BE(o) & 0x0fffffff));
}

function putTimestamp(b: Buffer, o: number, d: Date): void {
  const ms = Math.max(0, d.getTime() - EPOCH_1984);
  b.writeUInt32BE(ms % DAY_MS, o);
  b.writeUInt16BE(Math.min(0xffff, Math.floor(ms / DAY_MS)), o + 4);
}

function text8(b: Buffer, o: number): string {
  const f = b.subarray(o, o + 8);
  const nul = f.indexOf(0);
  return (nul < 0 ? f : f.subarray(0, nul)).toString('latin1').trimEnd();
}

function put8(b: Buffer, o: number, s: string): void {
  b.fill(0, o, o + 8);
  b.write(s.slice(0, 8), o, 'latin1');
}

function typeOf(code: number, what: string): BlockType {
  const t = blockTypeName(code);
  if (!t) throw new ProtocolError(`${what}: unknown block type 0x${code.toString(16)}`);
  return t;
}

// ---------------------------------------------------------------- list all

export function decodeBlockCounts(data: Buffer): BlockCounts {
  if (data.length % 4 !== 0) throw new ProtocolError(`block list of ${data.length} bytes is not made of 4-byte entries`);
  const counts = Object.fromEntries(LIST_ORDER.map((t) => [t, 0])) as BlockCounts;
  for (let o = 0; o < data.length; o += 4) {
    const t = blockTypeName(data[o + 1]!);
    // A type this library does not name (a newer CPU's) is skipped, not an error.
    if (t) counts[t] = data.readUInt16BE(o + 2);
  }
  return counts;
}

export function encodeBlockCounts(counts: Partial<BlockCounts>): Buffer {
  const out = Buffer.alloc(LIST_ORDER.length * 4);
  LIST_ORDER.forEach((t, i) => {
    out[i * 4] = 0x30;
    out[i * 4 + 1] = BLOCK_TYPES[t];
    out.writeUInt16BE(counts[t] ?? 0, i * 4 + 2);
  });
  return out;
}

// ---------------------------------------------------------------- list of a type

export function encodeListTypeRequest(typeCode: number): Buffer {
  return Buffer.of(0x30, typeCode);
}

export function decodeBlockListEntries(data: Buffer): BlockListEntry[] {
  if (data.length % 4 !== 0) throw new ProtocolError(`list of blocks of ${data.length} bytes is not made of 4-byte entries`);
  const out: BlockListEntry[] = [];
  for (let o = 0; o < data.length; o += 4) out.push({ number: data.readUInt16BE(o), flags: data[o + 2]!, language: data[o + 3]! });
  return out;
}

export function encodeBlockListEntries(entries: readonly BlockListEntry[]): Buffer {
  const out = Buffer.alloc(entries.length * 4);
  entries.forEach((e, i) => {
    out.writeUInt16BE(e.number, i * 4);
    out[i * 4 + 2] = e.flags;
    out[i * 4 + 3] = e.language;
  });
  return out;
}

// ---------------------------------------------------------------- block info

/** '0', type letter, 5 digits, 'A'. */
export function encodeBlockInfoRequest(typeCode: number, number: number): Buffer {
  return Buffer.from(`0${String.fromCharCode(typeCode)}${String(number).padStart(5, '0')}A`, 'latin1');
}

export function decodeBlockInfoRequest(data: Buffer): { typeCode: number; number: number } {
  const m = data.length === 8 ? /^0(.)([0-9]{5})(.)$/.exec(data.toString('latin1')) : null;
  if (!m) throw new ProtocolError('block info request: not "0", a type, 5 digits and a file system letter');
  return { typeCode: m[1]!.charCodeAt(0), number: Number(m[2]) };
}

export function decodeBlockInfo(data: Buffer): BlockInfo {
  if (data.length < BLOCK_INFO_LENGTH) throw new ProtocolError(`block info of ${data.length} bytes, expected ${BLOCK_INFO_LENGTH}`);
  // The type is in the sub-block type byte (0x0A DB …); the leading '0' + letter is not sent by every peer.
  const sub = data[11]!;
  const entry = (Object.entries(SUBBLOCK_TYPES) as [BlockType, number][]).find(([, v]) => v === sub);
  const type = entry ? entry[0] : typeOf(data[1]!, 'block info');
  const languageCode = data[10]!;
  const mc7Size = data.readUInt16BE(40);
  const v = data[66]!;
  return {
    type,
    number: data.readUInt16BE(12),
    language: BLOCK_LANGUAGES[languageCode] ?? `0x${languageCode.toString(16).padStart(2, '0')}`,
    languageCode,
    flags: data[9]!,
    loadSize: data.readUInt32BE(14),
    mc7Size,
    dataLength: type === 'DB' ? mc7Size : undefined,
    localDataSize: data.readUInt16BE(38),
    sbbLength: data.readUInt16BE(34),
    addLength: data.readUInt16BE(36),
    author: text8(data, 42),
    family: text8(data, 50),
    name: text8(data, 58),
    version: `${v >> 4}.${v & 0x0f}`,
    checksum: data.readUInt16BE(68),
    protected: data.readUInt32BE(18) !== 0,
    codeTime: timestamp(data, 22),
    interfaceTime: timestamp(data, 28),
  };
}

/** What the simulator knows of a block; the rest of BlockInfo follows from it. */
export interface BlockSpec {
  type: BlockType;
  number: number;
  languageCode: number;
  mc7Size: number;
  localDataSize?: number;
  author: string;
  family: string;
  name: string;
  /** major << 4 | minor */
  version: number;
  checksum: number;
  codeTime: Date;
  interfaceTime: Date;
}

/** SBB bytes in a block's footer, as counted in its block info. */
const SBB_LENGTH = 20;

export function loadSizeOf(spec: BlockSpec): number {
  return spec.mc7Size + BLOCK_HEADER + BLOCK_FOOTER;
}

export function encodeBlockInfo(spec: BlockSpec): Buffer {
  const b = Buffer.alloc(BLOCK_INFO_LENGTH);
  b[0] = 0x30;
  b[1] = BLOCK_TYPES[spec.type];
  b.writeUInt16BE(BLOCK_INFO_LENGTH - 4, 2);
  b.writeUInt16BE(0x2200, 4);
  b.write('pp', 6, 'latin1');
  b[8] = 0x01;
  b[9] = 0x01;
  b[10] = spec.languageCode;
  b[11] = SUBBLOCK_TYPES[spec.type];
  b.writeUInt16BE(spec.number, 12);
  b.writeUInt32BE(loadSizeOf(spec), 14);
  putTimestamp(b, 22, spec.codeTime);
  putTimestamp(b, 28, spec.interfaceTime);
  b.writeUInt16BE(SBB_LENGTH, 34);
  b.writeUInt16BE(spec.localDataSize ?? 0, 38);
  b.writeUInt16BE(spec.mc7Size, 40);
  put8(b, 42, spec.author);
  put8(b, 50, spec.family);
  put8(b, 58, spec.name);
  b[66] = spec.version;
  b.writeUInt16BE(spec.checksum, 68);
  return b;
}

// ---------------------------------------------------------------- load-memory form (upload)

/**
 * A block as upload returns it: a 36-byte header ("pp", flags, language,
 * sub-block type, number, load length, security, time stamps, SBB/ADD/local
 * data/MC7 lengths), the MC7 code (a DB's data), and a 56-byte footer
 * (SBB, author, family, name, version, checksum).
 */
export function encodeLoadBlock(spec: BlockSpec, code: Buffer): Buffer {
  const out = Buffer.alloc(BLOCK_HEADER + code.length + BLOCK_FOOTER);
  out.write('pp', 0, 'latin1');
  out[2] = 0x01;
  out[3] = 0x01;
  out[4] = spec.languageCode;
  out[5] = SUBBLOCK_TYPES[spec.type];
  out.writeUInt16BE(spec.number, 6);
  out.writeUInt32BE(out.length, 8);
  putTimestamp(out, 16, spec.codeTime);
  putTimestamp(out, 22, spec.interfaceTime);
  out.writeUInt16BE(SBB_LENGTH, 28);
  out.writeUInt16BE(spec.localDataSize ?? 0, 32);
  out.writeUInt16BE(code.length, 34);
  code.copy(out, BLOCK_HEADER);
  const f = BLOCK_HEADER + code.length;
  put8(out, f + SBB_LENGTH, spec.author);
  put8(out, f + SBB_LENGTH + 8, spec.family);
  put8(out, f + SBB_LENGTH + 16, spec.name);
  out[f + SBB_LENGTH + 24] = spec.version;
  out.writeUInt16BE(spec.checksum, f + SBB_LENGTH + 26);
  return out;
}

/** An uploaded block: its header fields and its MC7 code (a DB's data). Throws ProtocolError when the lengths do not add up. */
export interface UploadedBlock {
  type: BlockType;
  number: number;
  /** The whole block in load-memory form, as the CPU sent it. */
  bytes: Buffer;
  /** The MC7 code; for a DB, its data. */
  code: Buffer;
}

export function decodeLoadBlock(bytes: Buffer): UploadedBlock {
  if (bytes.length < BLOCK_HEADER) throw new ProtocolError(`uploaded block of ${bytes.length} bytes is shorter than its header`);
  if (bytes[0] !== 0x70 || bytes[1] !== 0x70) throw new ProtocolError('uploaded block does not start with "pp"');
  const sub = bytes[5]!;
  const entry = (Object.entries(SUBBLOCK_TYPES) as [BlockType, number][]).find(([, v]) => v === sub);
  if (!entry) throw new ProtocolError(`uploaded block: unknown sub-block type 0x${sub.toString(16)}`);
  const mc7 = bytes.readUInt16BE(34);
  if (BLOCK_HEADER + mc7 > bytes.length)
    throw new ProtocolError(`uploaded block announces ${mc7} bytes of code, ${bytes.length - BLOCK_HEADER} arrived`);
  return { type: entry[0], number: bytes.readUInt16BE(6), bytes, code: bytes.subarray(BLOCK_HEADER, BLOCK_HEADER + mc7) };
}
