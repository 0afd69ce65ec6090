/**
 * The objects an Explore answers, encoded as a CPU sends them: the data
 * block list (thePLCProgram), the CPU's operating state (theCPUexecUnit)
 * and the type-info container whose type objects carry each member's LID,
 * software type, offsets and name. Layouts: s7commplus (MIT) typeinfo.py
 * (PVartypeList, POffsetInfoType in its "new" numbering 8..14, VarnameList),
 * client.py `_parse_explore_datablocks`, server.py `_cpu_exec_unit_object`.
 */
import type { ArrayNode } from '../../symbols/layout-nodes';
import { DataType, dbAccessArea, ElementId, Ids, SoftDataType } from '../constants';
import { encodeSVlq32, encodeUVlq32, encodeUVlq64 } from '../codec/vlq';
import type { PlusMember, PlusModel, PlusType } from './model';

/** The attribute of a type object holding its byte size (typeinfo.py TI_TCOM_SIZE). */
const TI_TCOM_SIZE = 1502;
/** POffsetInfoType selectors (typeinfo.py parse_offset_info). */
const OI = Object.freeze({ std: 8, string: 9, array: 10, arrayMdim: 11, struct: 12, structArray: 13, structMdim: 14 });
/** bitoffsetinfo flag: the member has a standard (classic) address. */
const CLASSIC = 0x08;
/** Bytes of each vartype block before a new one starts, as PLCs split long lists. */
const BLOCK_BYTES = 0x7000;

function u32le(v: number): Buffer {
  const b = Buffer.alloc(4);
  b.writeUInt32LE(v >>> 0);
  return b;
}
function i32le(v: number): Buffer {
  const b = Buffer.alloc(4);
  b.writeInt32LE(v | 0);
  return b;
}
function u16le(v: number): Buffer {
  const b = Buffer.alloc(2);
  b.writeUInt16LE(v & 0xffff);
  return b;
}

/** An attribute: tag, id, then the PValue (flags 0, type, value). */
function attribute(id: number, type: number, value: Buffer): Buffer {
  return Buffer.concat([Buffer.from([ElementId.Attribute]), encodeUVlq32(id), Buffer.from([0x00, type]), value]);
}

/** The head of an object: tag, relation id (4 bytes), class id, class flags 0, attribute id 0. */
function objectHead(rid: number, classId: number): Buffer {
  const r = Buffer.alloc(5);
  r[0] = ElementId.StartOfObject;
  r.writeUInt32BE(rid >>> 0, 1);
  return Buffer.concat([r, encodeUVlq32(classId), encodeUVlq32(0), encodeUVlq32(0)]);
}

const END = Buffer.from([ElementId.TerminatingObject]);

/** A name as a WString PValue's value (length, UTF-8 bytes, as the S7-1500 sends ASCII one byte a character). */
function wstring(text: string): Buffer {
  const bytes = Buffer.from(text, 'utf8');
  return Buffer.concat([encodeUVlq32(bytes.length), bytes]);
}

/**
 * thePLCProgram explored: one DataBlock object per DB (name, number), the program's and then `unnamed`, the
 * memory's data blocks no source declares (a layout's), each named as STEP 7 names a DB without symbol (`DB10`).
 */
export function blockList(model: PlusModel, unnamed: readonly number[] = []): Buffer {
  const parts: Buffer[] = [];
  const blocks = [...model.dbs, ...unnamed.map((number) => ({ rid: dbAccessArea(number), name: `DB${number}`, number }))];
  for (const db of blocks) {
    parts.push(objectHead(db.rid, Ids.DBClassRID));
    parts.push(attribute(Ids.ObjectVariableTypeName, DataType.WString, wstring(db.name)));
    parts.push(attribute(Ids.BlockBlockNumber, DataType.UDInt, encodeUVlq32(db.number)));
    parts.push(END);
  }
  return Buffer.concat(parts);
}

/** theCPUexecUnit explored: its operating state code in the struct attribute. */
export function cpuExecUnit(stateCode: number): Buffer {
  const id = Buffer.alloc(4);
  id.writeUInt32BE(Ids.CpuExecUnitOperatingStateStructId);
  return Buffer.concat([
    objectHead(Ids.NativeTheCpuExecUnitRID, Ids.ClassCpuExecUnit),
    Buffer.from([ElementId.Attribute]),
    encodeUVlq32(Ids.CpuExecUnitOperatingStateStruct),
    Buffer.from([0x00, DataType.Struct]),
    id,
    encodeUVlq32(Ids.CpuExecUnitOperatingState),
    Buffer.from([0x00, DataType.DInt]),
    encodeSVlq32(stateCode),
    Buffer.from([0x00]),
    END,
  ]);
}

/** A type object's modification time (attribute 529) as a ULInt (PLCSIM's answer: `a3 84 11 00 05` and a 64-bit VLQ). */
function modificationTime(model: PlusModel, rid: number): Buffer {
  const time = model.times.get(rid);
  return time === undefined ? Buffer.alloc(0) : attribute(Ids.VariableTypeStructModificationTime, DataType.ULInt, encodeUVlq64(time));
}

/**
 * The type-info container: one object per type, each with its modification time and its vartype and varname lists,
 * the I, Q and M areas' type objects (the tag table) among them. Asked for attributes (`attributes` not empty), each
 * type object carries only those it has (the modification time), as thePLCProgram's blocks carry only the asked ones.
 */
export function typeInfoContainer(model: PlusModel, attributes: readonly number[] = []): Buffer {
  const head = objectHead(Ids.ObjectOmsTypeInfoContainer, Ids.ClassOmsTypeInfoContainer);
  const all = [...model.types, ...model.areas.map((a) => a.type)];
  if (attributes.length > 0) return Buffer.concat([head, ...all.map((t) => typeObjectAttributes(model, t.rid, attributes)), END]);
  const standardTypes = new Set<PlusType>();
  const markStd = (t: PlusType) => {
    if (standardTypes.has(t)) return;
    standardTypes.add(t);
    for (const m of t.members) if (m.type) markStd(m.type);
  };
  for (const db of model.dbs) if (!db.optimized) markStd(db.type);
  // The I, Q and M areas have fixed addresses: their tags carry a classic offset.
  for (const area of model.areas) standardTypes.add(area.type);
  const objects = all.map((t) => typeObject(model, t, standardTypes.has(t)));
  return Buffer.concat([head, ...objects, END]);
}

/** A type object with the asked attributes only (an Explore of it, or of the container, for attribute 529). */
export function typeObjectAttributes(model: PlusModel, rid: number, attributes: readonly number[]): Buffer {
  const time = attributes.includes(Ids.VariableTypeStructModificationTime) ? modificationTime(model, rid) : Buffer.alloc(0);
  return Buffer.concat([objectHead(rid, Ids.ClassTypeInfo), time, END]);
}

/** True when `rid` is one of the model's type objects. */
export function isTypeObject(model: PlusModel, rid: number): boolean {
  return model.times.has(rid);
}

function typeObject(model: PlusModel, type: PlusType, classic: boolean): Buffer {
  const elements = type.members.map((m) => vartype(m, classic));
  const blocks: Buffer[] = [];
  let current: Buffer[] = [u32le(0)];
  let size = 4;
  const flush = () => {
    const len = Buffer.alloc(2);
    len.writeUInt16BE(size);
    blocks.push(len, ...current);
    current = [];
    size = 0;
  };
  for (const e of elements) {
    if (size + e.length > BLOCK_BYTES && current.length > 0) flush();
    current.push(e);
    size += e.length;
  }
  if (elements.length > 0) flush();
  blocks.push(Buffer.alloc(2));
  const names: Buffer[] = [];
  for (const m of type.members) {
    const n = Buffer.from(m.name, 'utf8');
    names.push(Buffer.from([n.length]), n, Buffer.from([0]));
  }
  const nameBytes = Buffer.concat(names);
  const nameLen = Buffer.alloc(2);
  nameLen.writeUInt16BE(nameBytes.length);
  return Buffer.concat([
    objectHead(type.rid, 0),
    attribute(TI_TCOM_SIZE, DataType.UDInt, encodeUVlq32(type.size)),
    modificationTime(model, type.rid),
    Buffer.from([ElementId.VartypeList]),
    ...blocks,
    Buffer.from([ElementId.VarnameList]),
    ...(type.members.length > 0 ? [nameLen, nameBytes] : []),
    Buffer.alloc(2),
    END,
  ]);
}

/** One VartypeListElement: LID, symbol CRC 0, software type, flags, then its offset info. */
function vartype(m: PlusMember, classic: boolean): Buffer {
  const node = m.node;
  const bit = m.bit ?? 0;
  let oi: number;
  let info: Buffer;
  const offsets = Buffer.concat([u32le(m.byte), u32le(m.byte)]);
  if (node.kind === 'elementary') {
    if (node.dataType === 'STRING' || node.dataType === 'WSTRING') {
      oi = OI.string;
      info = Buffer.concat([u16le(node.stringLength), u16le(0), offsets]);
    } else {
      oi = OI.std;
      info = Buffer.concat([u16le(m.byte), u16le(m.byte)]);
    }
  } else if (node.kind === 'struct') {
    oi = OI.struct;
    info = Buffer.concat([u16le(0), u16le(0), offsets, u32le(m.type!.rid), Buffer.alloc(16)]);
  } else {
    ({ oi, info } = arrayInfo(m, node, offsets));
  }
  const head = Buffer.alloc(12);
  head.writeUInt32LE(m.lid, 0);
  head.writeUInt32LE(0, 4);
  head[8] = m.soft;
  head.writeUInt16BE((oi << 12) | (m.soft === SoftDataType.Bool ? bit & 7 : 0), 9);
  head[11] = (classic ? CLASSIC | ((bit & 7) << 4) : 0) | (bit & 7);
  return Buffer.concat([head, info]);
}

function arrayInfo(m: PlusMember, node: ArrayNode, offsets: Buffer): { oi: number; info: Buffer } {
  const count = node.elements.length;
  const strLen = node.elementType?.stringLength ?? 0;
  const head = Buffer.concat([u16le(strLen), u16le(0), offsets, i32le(node.dims.length === 1 ? node.dims[0]!.low : 0), u32le(count)]);
  // Multi-dimensional bounds: index 0 is the last dimension, the one that runs fastest.
  const dims = [...node.dims].reverse();
  const lows = Buffer.concat(Array.from({ length: 6 }, (_, i) => i32le(dims[i]?.low ?? 0)));
  const counts = Buffer.concat(Array.from({ length: 6 }, (_, i) => u32le(dims[i] ? dims[i].high - dims[i].low + 1 : 0)));
  const structType = m.type;
  if (!structType) {
    return node.dims.length === 1 ? { oi: OI.array, info: head } : { oi: OI.arrayMdim, info: Buffer.concat([head, lows, counts]) };
  }
  const tail = Buffer.concat([u32le(structType.size), u32le(structType.size), u32le(structType.rid), Buffer.alloc(16)]);
  return node.dims.length === 1
    ? { oi: OI.structArray, info: Buffer.concat([head, tail]) }
    : { oi: OI.structMdim, info: Buffer.concat([head, lows, counts, tail]) };
}
