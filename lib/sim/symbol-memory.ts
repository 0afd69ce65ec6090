/**
 * The simulators' memory from compiled sources: each data block at the
 * length its sources declare (what a CPU's block info reports after the
 * download, and what the client's stale-layout check compares), holding what
 * a CPU holds right after a download: the start values, the max-length header
 * of every STRING[n] (byte n, then 0 characters) and WSTRING[n] (word n,
 * then 0), DTL and DATE_AND_TIME at their types' initial values
 * (DTL#1970-01-01-00:00:00, DT#1990-01-01-00:00:00), zeros elsewhere. So a
 * foreign client reading the simulator sees the bytes a real PLC shows.
 */
import { PlcMemory, type MemoryLayout } from './memory';
import type { PlcValue } from '../types';
import { encodeInto, type TagShape } from '../values';
import type { SymbolEntry, SymbolTable } from '../symbols/model';

/** What a CPU holds in a DTL or DATE_AND_TIME the source gives no start value (the types' documented initial values). */
const TYPE_INITIAL: Partial<Record<string, PlcValue>> = Object.freeze({
  DTL: new Date(Date.UTC(1970, 0, 1)),
  DATE_AND_TIME: new Date(Date.UTC(1990, 0, 1)),
});

/** An elementary entry as the value codecs see it: one element at its byte (and bit). */
function shapeOf(entry: SymbolEntry): TagShape {
  return {
    address: entry.name,
    type: entry.dataType!,
    count: 1,
    isArray: false,
    stringLength: entry.stringLength,
    bitOffset: entry.bit ?? 0,
  };
}

/**
 * The bytes of every data block of `table`, by number, as a CPU holds them
 * after the download. A start value that does not fit its member is a
 * ValueError naming the member (compileSymbols evaluates start values to
 * their types, so this is a table made by hand).
 */
export function dataBlockImages(table: SymbolTable): Map<number, Buffer> {
  const images = new Map<number, Buffer>();
  // An optimized block has no standard-access image: the simulators of PUT/GET and FETCH/WRITE do not hold it.
  for (const block of table.blocks) if (block.length !== null) images.set(block.db, Buffer.alloc(block.length));
  for (const entry of table.entries) {
    if (entry.kind !== 'elementary' || entry.dataType === undefined || entry.db === null || entry.byte === null) continue;
    const image = images.get(entry.db);
    if (image === undefined) continue;
    const tag = shapeOf(entry);
    if (tag.type === 'STRING') image[entry.byte] = entry.stringLength;
    else if (tag.type === 'WSTRING') image.writeUInt16BE(entry.stringLength, entry.byte);
    const initial = entry.initial ?? TYPE_INITIAL[tag.type];
    if (initial !== undefined) encodeInto(tag, initial, image, entry.byte);
  }
  return images;
}

/**
 * Simulator memory whose data blocks are those of `table` (replacing the
 * layout's: a CPU holds the blocks downloaded to it), with the layout's other
 * areas. `new S7Server({ symbols })` and `new FetchWriteServer({ symbols })` use it.
 */
export function memoryFromSymbols(table: SymbolTable, layout: MemoryLayout = {}): PlcMemory {
  const memory = new PlcMemory({ ...layout, dataBlocks: {} });
  for (const [db, image] of dataBlockImages(table)) {
    memory.createDataBlock(db, image.length);
    image.copy(memory.area('DB', db)!);
  }
  return memory;
}
