/**
 * The blocks of a simulated CPU: a DB per data block of its memory and a few
 * fixed OBs, FCs, SFCs … so lists look real; their block info, load-memory
 * image for upload, and the userdata block functions (list all, list of a
 * type, block info).
 */
import type { PlcMemory } from '../../sim/memory';
import { encodeUserdataResponse, type UserdataPdu } from '../codec/userdata';
import { encodeBlockCounts, encodeBlockInfo, encodeBlockListEntries, decodeBlockInfoRequest, type BlockSpec } from '../codec/blocks';
import { BLOCK_TYPES, BlockSubfunction, blockTypeName, type BlockType } from '../constants';
import { SERVICE_CODE as E } from './service-codes';

const FIXED_BLOCKS: Readonly<Partial<Record<BlockType, readonly number[]>>> = Object.freeze({
  OB: [1, 35, 80, 82, 86, 100, 121, 122],
  FB: [1],
  FC: [1, 2],
  SDB: [0, 1, 2, 7],
  SFC: [0, 1, 14, 15, 20, 46, 51, 52],
  SFB: [0, 1, 2, 3, 4, 5],
});
/** MC7 of a block that does nothing: BE (block end). */
const EMPTY_CODE = Buffer.of(0x65, 0x00);

/** A block as the simulator serves it: its info and its code (a DB's code is its data). */
export interface SimulatedBlock {
  spec: BlockSpec;
  code: Buffer;
}

/** Every block of the simulated CPU: a DB per data block of the memory, and the fixed OBs, FCs … */
export function blockNumbers(memory: PlcMemory, type: BlockType): number[] {
  if (type === 'DB') return memory.dataBlockNumbers();
  return [...(FIXED_BLOCKS[type] ?? [])];
}

/** The block `type` `number` (created at `created`), or undefined when the CPU has no such block. */
export function blockSpec(memory: PlcMemory, created: Date, type: BlockType, number: number): SimulatedBlock | undefined {
  let code: Buffer;
  if (type === 'DB') {
    const db = memory.area('DB', number);
    if (!db) return undefined;
    code = db;
  } else {
    if (!blockNumbers(memory, type).includes(number)) return undefined;
    code = EMPTY_CODE;
  }
  let checksum = 0;
  for (let k = 0; k < code.length; k++) checksum = (checksum + code[k]! * ((k % 7) + 1)) & 0xffff;
  return {
    code,
    spec: {
      type,
      number,
      languageCode: type === 'DB' ? 0x05 : type === 'SDB' ? 0x07 : 0x01,
      mc7Size: code.length,
      author: 'PLCWIRE',
      family: 'SIM',
      name: `${type}${number}`,
      version: 0x10,
      checksum,
      codeTime: created,
      interfaceTime: created,
    },
  };
}

/**
 * Answers a block function (userdata group 3). `inParts` sends an answer that
 * may need several PDUs (a block list) part by part.
 */
export function serveBlockFunction(u: UserdataPdu, memory: PlcMemory, created: Date, inParts: (bytes: Buffer) => Buffer): Buffer {
  const { group, subfunction } = u.params;
  const error = (errorCode: number) => encodeUserdataResponse(u.pduRef, group, subfunction, { errorCode });
  if (subfunction === BlockSubfunction.ListAll) {
    const counts = Object.fromEntries((Object.keys(BLOCK_TYPES) as BlockType[]).map((t) => [t, blockNumbers(memory, t).length]));
    return encodeUserdataResponse(u.pduRef, group, subfunction, { data: encodeBlockCounts(counts) });
  }
  if (subfunction === BlockSubfunction.ListType) {
    if (u.data.length !== 2 || u.data[0] !== 0x30) return error(E.SYNTAX);
    const type = blockTypeName(u.data[1]!);
    if (!type) return error(E.SYNTAX);
    const numbers = blockNumbers(memory, type);
    if (numbers.length === 0) return error(E.NO_BLOCKS);
    const language = type === 'DB' ? 0x05 : type === 'SDB' ? 0x07 : 0x01;
    return inParts(encodeBlockListEntries(numbers.map((number) => ({ number, flags: 0x22, language }))));
  }
  if (subfunction === BlockSubfunction.BlockInfo) {
    const { typeCode, number } = decodeBlockInfoRequest(u.data);
    const type = blockTypeName(typeCode);
    const block = type ? blockSpec(memory, created, type, number) : undefined;
    if (!block) return error(E.BLOCK_NOT_FOUND);
    return encodeUserdataResponse(u.pduRef, group, subfunction, { data: encodeBlockInfo(block.spec) });
  }
  return error(E.NOT_IMPLEMENTED);
}
