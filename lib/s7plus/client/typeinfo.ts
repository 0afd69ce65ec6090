/**
 * The type objects of an Explore of the type-info container, decoded: each
 * member's LID, software type, offsets (standard blocks), string length,
 * array bounds, the RID of its struct's type object, and its name; and each
 * type object's modification time (attribute 529). Pure: bytes in, members
 * out; a cut-short list is a PROTOCOL_ERROR.
 *
 * Layouts: s7commplus (MIT), typeinfo.py (parse_vartype_list,
 * parse_offset_info in its numbering 8..14, the classic flag 0x08 and the
 * bit offsets of bitoffsetinfo, parse_varname_list), client.py
 * (_type_info_times).
 */
import { PlcError } from '../../errors';
import type { DataTypeName } from '../../types';
import { attributeOf, walkObjects, type PObject } from '../codec/object';
import { ElementId, Ids, SoftDataType } from '../constants';

export const TYPE_OF: Readonly<Record<number, DataTypeName>> = Object.freeze({
  [SoftDataType.Bool]: 'BOOL',
  [SoftDataType.Byte]: 'BYTE',
  [SoftDataType.Char]: 'CHAR',
  [SoftDataType.Word]: 'WORD',
  [SoftDataType.Int]: 'INT',
  [SoftDataType.DWord]: 'DWORD',
  [SoftDataType.DInt]: 'DINT',
  [SoftDataType.Real]: 'REAL',
  [SoftDataType.Date]: 'DATE',
  [SoftDataType.TimeOfDay]: 'TIME_OF_DAY',
  [SoftDataType.Time]: 'TIME',
  [SoftDataType.S5Time]: 'S5TIME',
  [SoftDataType.DateAndTime]: 'DATE_AND_TIME',
  [SoftDataType.String]: 'STRING',
  [SoftDataType.LReal]: 'LREAL',
  [SoftDataType.ULInt]: 'ULINT',
  [SoftDataType.LInt]: 'LINT',
  [SoftDataType.LWord]: 'LWORD',
  [SoftDataType.USInt]: 'USINT',
  [SoftDataType.UInt]: 'UINT',
  [SoftDataType.UDInt]: 'UDINT',
  [SoftDataType.SInt]: 'SINT',
  [SoftDataType.WChar]: 'WCHAR',
  [SoftDataType.WString]: 'WSTRING',
  [SoftDataType.LTime]: 'LTIME',
  [SoftDataType.DTL]: 'DTL',
});

/** One member of a type object, as its vartype element and name give it. */
export interface Member {
  name: string;
  lid: number;
  soft: number;
  /** Offset in a standard block (classic), from the start of its struct; undefined in an optimized one. */
  byte?: number;
  bit?: number;
  stringLength: number;
  /** Arrays: bounds per dimension, outermost first. */
  dims?: { low: number; high: number }[];
  /** Structs and arrays of structs: the RID of the struct's type object. */
  structRid?: number;
}

export interface TypeObject {
  members: Member[];
}

/** Reads the vartype elements (typeinfo.py parse_vartype_element / parse_offset_info). */
function vartypes(raw: Buffer): Omit<Member, 'name'>[] {
  const out: Omit<Member, 'name'>[] = [];
  let at = 0;
  let first = true;
  for (;;) {
    const len = raw.readUInt16BE(at);
    at += 2;
    if (len === 0) return out;
    const end = at + len;
    if (first) {
      at += 4;
      first = false;
    }
    while (at < end) {
      const lid = raw.readUInt32LE(at);
      const soft = raw[at + 8]!;
      const flags = raw.readUInt16BE(at + 9);
      const bitInfo = raw[at + 11]!;
      at += 12;
      const oi = (flags >> 12) & 0x0f;
      const classic = (bitInfo & 0x08) !== 0;
      const m: Omit<Member, 'name'> = { lid, soft, stringLength: 0 };
      const bit = soft === SoftDataType.Bool ? (classic ? (bitInfo & 0x70) >> 4 : flags & 7) : undefined;
      const place = (nonopt: number) => {
        if (!classic) return;
        m.byte = nonopt;
        if (bit !== undefined) m.bit = bit;
      };
      switch (oi) {
        case 8:
          place(raw.readUInt16LE(at + 2));
          at += 4;
          break;
        case 9:
          m.stringLength = raw.readUInt16LE(at);
          place(raw.readUInt32LE(at + 8));
          at += 12;
          break;
        case 10:
        case 11:
        case 13:
        case 14: {
          m.stringLength = raw.readUInt16LE(at);
          place(raw.readUInt32LE(at + 8));
          const low = raw.readInt32LE(at + 12);
          const count = raw.readUInt32LE(at + 16);
          at += 20;
          if (oi === 10 || oi === 13) m.dims = [{ low, high: low + count - 1 }];
          else {
            const dims: { low: number; high: number }[] = [];
            for (let i = 0; i < 6; i++) {
              const c = raw.readUInt32LE(at + 24 + 4 * i);
              if (c > 0) dims.push({ low: raw.readInt32LE(at + 4 * i), high: raw.readInt32LE(at + 4 * i) + c - 1 });
            }
            // Index 0 is the dimension that runs fastest: the last one written.
            m.dims = dims.reverse();
            at += 48;
          }
          if (oi === 13 || oi === 14) {
            m.structRid = raw.readUInt32LE(at + 8);
            at += 28;
          }
          break;
        }
        case 12:
          place(raw.readUInt32LE(at + 8));
          m.structRid = raw.readUInt32LE(at + 12);
          at += 32;
          break;
        default:
          throw new PlcError('PROTOCOL_ERROR', `S7CommPlus browse: offset info ${oi} of LID ${lid} is not one this client reads`);
      }
      out.push(m);
    }
  }
}

/** The names of the varname list: length byte, UTF-8 bytes, a 0 (typeinfo.py VarnameList). */
function varnames(raw: Buffer): string[] {
  const names: string[] = [];
  let at = 0;
  for (let len = raw.readUInt16BE(at); len !== 0; len = raw.readUInt16BE(at)) {
    const end = at + 2 + len;
    at += 2;
    while (at < end) {
      const n = raw[at]!;
      names.push(raw.toString('utf8', at + 1, at + 1 + n));
      at += n + 2;
    }
  }
  return names;
}

export function typeObjects(objects: PObject[]): Map<number, TypeObject> {
  const types = new Map<number, TypeObject>();
  for (const o of walkObjects(objects)) {
    const lists = o.members.filter((m) => m.kind === 'list');
    const vt = lists.find((l) => l.tag === ElementId.VartypeList);
    const vn = lists.find((l) => l.tag === ElementId.VarnameList);
    if (!vt || !vn) continue;
    try {
      const elements = vartypes(vt.raw);
      const names = varnames(vn.raw);
      types.set(o.relationId >>> 0, { members: elements.map((e, i) => ({ ...e, name: names[i] ?? `LID${e.lid}` })) });
    } catch (err) {
      if (err instanceof PlcError) throw err;
      throw new PlcError('PROTOCOL_ERROR', `S7CommPlus browse: the type object 0x${o.relationId.toString(16)} is cut short`);
    }
  }
  return types;
}

/**
 * Each type object's VariableTypeStructModificationTime (attribute 529), by RID, where the PLC reports one: what a
 * download changes (s7commplus (MIT) client.py _type_info_times; PLCSIM Advanced and a CPU 1215C report it).
 */
export type TypeTimes = ReadonlyMap<number, bigint>;

export function timesOf(objects: PObject[]): Map<number, bigint> {
  const times = new Map<number, bigint>();
  for (const o of walkObjects(objects)) {
    const v = attributeOf(o, Ids.VariableTypeStructModificationTime)?.value;
    if (typeof v === 'bigint' || typeof v === 'number') times.set(o.relationId >>> 0, BigInt(v));
  }
  return times;
}
