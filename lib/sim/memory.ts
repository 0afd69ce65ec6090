/**
 * The memory model the S7 and FETCH/WRITE simulators share: the areas of an
 * S7 CPU as plain Buffers, with hooks to observe reads and writes.
 */
import { EventEmitter } from 'node:events';
import type { AreaName } from '../types';

export interface MemoryLayout {
  /** Bytes of the process input image (I/E). */
  inputs?: number;
  /** Bytes of the process output image (Q/A). */
  outputs?: number;
  /** Bytes of flags (M). */
  flags?: number;
  /** Bytes of peripheral inputs/outputs (PE/PA). */
  peripheral?: number;
  /** Number of counters and timers (2 bytes each). */
  counters?: number;
  timers?: number;
  /** Data blocks: number → size in bytes. Default: DB1–DB100 of 1024 bytes. */
  dataBlocks?: Record<number, number>;
}

export interface MemoryAccess {
  area: AreaName;
  dbNumber: number;
  /** Byte offset (for C/T: counter/timer number × 2). */
  offset: number;
  length: number;
  /** The bytes written (writes only). */
  data?: Buffer;
}

export const DEFAULT_LAYOUT: Required<MemoryLayout> = Object.freeze({
  inputs: 1024,
  outputs: 1024,
  flags: 1024,
  peripheral: 1024,
  counters: 256,
  timers: 256,
  dataBlocks: defaultDataBlocks(),
});

function defaultDataBlocks(): Record<number, number> {
  const blocks: Record<number, number> = {};
  for (let db = 1; db <= 100; db++) blocks[db] = 1024;
  return blocks;
}

/** Why an access was refused; the servers map these to their protocol's return codes. */
export type MemoryFault = 'NO_SUCH_AREA' | 'OUT_OF_RANGE';

/**
 * PLC memory. Events: `read` (MemoryAccess), `write` (MemoryAccess).
 * Offsets and lengths of C and T are in bytes (2 per counter/timer).
 */
export class PlcMemory extends EventEmitter {
  private readonly areas = new Map<string, Buffer>();
  /** Data blocks by number (a server looks one up per item: no key string to build). */
  private readonly dataBlocks = new Map<number, Buffer>();

  constructor(layout: MemoryLayout = {}) {
    super();
    const l = { ...DEFAULT_LAYOUT, ...layout };
    this.areas.set('I', Buffer.alloc(l.inputs));
    this.areas.set('Q', Buffer.alloc(l.outputs));
    this.areas.set('M', Buffer.alloc(l.flags));
    // PE and PA are one address space on a real CPU's I/O bus; keep them apart so reads of PE
    // show inputs and writes to PA show outputs, as a simulator user expects.
    this.areas.set('PE', Buffer.alloc(l.peripheral));
    this.areas.set('PA', Buffer.alloc(l.peripheral));
    this.areas.set('C', Buffer.alloc(l.counters * 2));
    this.areas.set('T', Buffer.alloc(l.timers * 2));
    for (const [db, size] of Object.entries(l.dataBlocks)) this.dataBlocks.set(Number(db), Buffer.alloc(size));
  }

  /** The live buffer of an area (not a copy), or undefined when it does not exist. */
  area(area: AreaName, dbNumber = 0): Buffer | undefined {
    return area === 'DB' ? this.dataBlocks.get(dbNumber) : this.areas.get(area);
  }

  /** Adds (or replaces) a data block filled with zeros. */
  createDataBlock(dbNumber: number, size: number): void {
    this.dataBlocks.set(dbNumber, Buffer.alloc(size));
  }

  deleteDataBlock(dbNumber: number): void {
    this.dataBlocks.delete(dbNumber);
  }

  /** The numbers of the data blocks that exist, ascending (the simulator's block list). */
  dataBlockNumbers(): number[] {
    return [...this.dataBlocks.keys()].sort((a, b) => a - b);
  }

  /** Checks an access; returns the fault or undefined when it is allowed. */
  check(area: AreaName, dbNumber: number, offset: number, length: number): MemoryFault | undefined {
    const buf = this.area(area, dbNumber);
    if (!buf) return 'NO_SUCH_AREA';
    if (offset < 0 || length < 0 || offset + length > buf.length) return 'OUT_OF_RANGE';
    return undefined;
  }

  /** Copies bytes out; throws RangeError on a fault (servers call check() first). */
  read(area: AreaName, dbNumber: number, offset: number, length: number): Buffer {
    const buf = this.mustGet(area, dbNumber, offset, length);
    const data = Buffer.from(buf.subarray(offset, offset + length));
    this.emit('read', { area, dbNumber, offset, length } satisfies MemoryAccess);
    return data;
  }

  /** Copies bytes in; throws RangeError on a fault (servers call check() first). */
  write(area: AreaName, dbNumber: number, offset: number, data: Buffer): void {
    const buf = this.mustGet(area, dbNumber, offset, data.length);
    data.copy(buf, offset);
    this.emit('write', { area, dbNumber, offset, length: data.length, data: Buffer.from(data) } satisfies MemoryAccess);
  }

  /** Sets or clears one bit. */
  writeBit(area: AreaName, dbNumber: number, offset: number, bit: number, value: boolean): void {
    const buf = this.mustGet(area, dbNumber, offset, 1);
    const byte = value ? buf[offset]! | (1 << bit) : buf[offset]! & ~(1 << bit);
    this.write(area, dbNumber, offset, Buffer.of(byte));
  }

  private mustGet(area: AreaName, dbNumber: number, offset: number, length: number): Buffer {
    const fault = this.check(area, dbNumber, offset, length);
    if (fault) throw new RangeError(`${fault}: ${area}${area === 'DB' ? dbNumber : ''} ${offset}+${length}`);
    return this.area(area, dbNumber)!;
  }
}
