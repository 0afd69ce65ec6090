/**
 * A browsed name's entry as S7CommPlus items and values: its elementary
 * members (leaves), the item address of each (the block's access area with
 * DBValueActual, or an I/Q/M tag's area object with
 * ControllerAreaValueActual, and the LIDs), a leaf's value from the PValue
 * the PLC answers, a struct or array put back together as an object or
 * array, and the leaves and PValues of a write. Pure. Layouts: s7commplus
 * (MIT), client.py (read_tags / write_tags), codec.py (the wire types).
 */
import { PlcError } from '../../errors';
import type { SymbolEntry, SymbolTable } from '../../symbols/model';
import { assembleStruct, entryTree, expandStruct } from '../../symbols/struct-tree';
import type { PlcValue } from '../../types';
import { decodeTag, encodeTag, type TagShape } from '../../values';
import type { PValue } from '../codec/pvalue';
import { blobValue, type ItemAddress } from '../codec/variables';
import { DataType, Ids } from '../constants';

/** Leaves per struct or array entry, worked out once per browsed table (a poll reads the same names again and again). */
const LEAVES = new WeakMap<SymbolEntry, readonly SymbolEntry[]>();

/** The elementary entries of an entry (itself when elementary), in order. */
export function leavesOf(table: SymbolTable, entry: SymbolEntry): readonly SymbolEntry[] {
  if (entry.kind === 'elementary') return [entry];
  let leaves = LEAVES.get(entry);
  if (!leaves) {
    leaves = (entry.children ?? []).flatMap((c) => {
      const child = table.lookup(c);
      return child ? leavesOf(table, child) : [];
    });
    LEAVES.set(entry, leaves);
  }
  return leaves;
}

/** A name's item: its block's access area with DBValueActual, or an I, Q, M tag's area object with ControllerAreaValueActual. */
export function itemOf(entry: SymbolEntry): ItemAddress {
  const subArea = entry.area === 'DB' ? Ids.DBValueActual : Ids.ControllerAreaValueActual;
  // The path's SymbolCrc: the PLC refuses the item (InvalidCRC) if a download gave its LIDs to another member.
  return { symbolCrc: entry.access!.symbolCrc ?? 0, accessArea: entry.access!.area, accessSubArea: subArea, lids: [...entry.access!.lids] };
}

export function shapeOf(entry: SymbolEntry): TagShape {
  return { address: entry.name, type: entry.dataType!, count: 1, isArray: false, stringLength: entry.stringLength, bitOffset: 0 };
}

const WIDTH: Readonly<Record<number, [number, 'u' | 's' | 'f']>> = Object.freeze({
  [DataType.USInt]: [1, 'u'],
  [DataType.Byte]: [1, 'u'],
  [DataType.SInt]: [1, 's'],
  [DataType.UInt]: [2, 'u'],
  [DataType.Word]: [2, 'u'],
  [DataType.Int]: [2, 's'],
  [DataType.UDInt]: [4, 'u'],
  [DataType.DWord]: [4, 'u'],
  [DataType.DInt]: [4, 's'],
  [DataType.Real]: [4, 'f'],
  [DataType.LReal]: [8, 'f'],
  [DataType.ULInt]: [8, 'u'],
  [DataType.LWord]: [8, 'u'],
  [DataType.LInt]: [8, 's'],
});

/** A leaf's value from the PValue the PLC answered: a BLOB as the member's standard bytes, a typed value by its wire type. */
export function valueOf(entry: SymbolEntry, v: PValue, shape: TagShape = shapeOf(entry)): PlcValue {
  const x = v.value;
  if (v.type === DataType.Bool && typeof x === 'boolean') return x;
  if ((v.type === DataType.WString || v.type === DataType.S7String) && typeof x === 'string') return x;
  let bytes: Buffer | undefined;
  if (x && typeof x === 'object' && 'data' in x && Buffer.isBuffer(x.data)) bytes = x.data;
  const width = WIDTH[v.type];
  if (!bytes && width && (typeof x === 'number' || typeof x === 'bigint')) {
    const [n, kind] = width;
    bytes = Buffer.alloc(n);
    if (kind === 'f') n === 4 ? bytes.writeFloatBE(Number(x)) : bytes.writeDoubleBE(Number(x));
    else if (n === 8) kind === 's' ? bytes.writeBigInt64BE(BigInt(x)) : bytes.writeBigUInt64BE(BigInt.asUintN(64, BigInt(x)));
    else kind === 's' ? bytes.writeIntBE(Number(x), 0, n) : bytes.writeUIntBE(Number(x), 0, n);
  }
  if (!bytes)
    throw new PlcError('PROTOCOL_ERROR', `${entry.name}: the PLC answered a value of wire type 0x${v.type.toString(16)}`, {
      tag: entry.name,
    });
  // A typed value narrower than the member (a BYTE sent as USInt for a CHAR) is its low bytes.
  const want = entry.size;
  if (bytes.length < want && !entry.dataType?.includes('STRING')) bytes = Buffer.concat([Buffer.alloc(want - bytes.length), bytes]);
  return decodeTag(shape, bytes, 0);
}

/** A struct's or array's value from its leaves' values (by name). */
export function assemble(table: SymbolTable, entry: SymbolEntry, leaf: Map<string, PlcValue>): unknown {
  return assembleStruct(entryTree(table, entry), (l) => leaf.get(l.name));
}

/**
 * The leaves of a write: each elementary member the value names with its value (a struct's from the object's
 * members, an array's by index); a struct partly given writes the members it names, as over s7://
 * (lib/symbols/struct-tree.ts walks both).
 */
export function writeLeaves(table: SymbolTable, entry: SymbolEntry, value: unknown, out: { entry: SymbolEntry; value: unknown }[]): void {
  out.push(...expandStruct(entryTree(table, entry), value, (l, v) => ({ entry: l.entry, value: v })));
}

export function pvalueOf(entry: SymbolEntry, value: unknown): PValue {
  if (entry.dataType === 'BOOL') {
    if (typeof value !== 'boolean')
      throw new PlcError('INVALID_VALUE', `${entry.name} is a BOOL: write true or false`, { tag: entry.name });
    return { flags: 0, type: DataType.Bool, value };
  }
  return blobValue(encodeTag(shapeOf(entry), value));
}
