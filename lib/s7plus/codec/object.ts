/**
 * The object tree of S7CommPlus (CreateObject bodies, Explore answers):
 *
 *     A1 <RelationId:4> <ClassId:VLQ> <ClassFlags:VLQ> <AttributeId:VLQ>   start of object
 *     A3 <AttributeId:VLQ> <PValue>                                        attribute
 *     A4 <RelationId:VLQ> <target:4>                                       relation
 *     AB <blocks> / AC <blocks>                                            type-info lists
 *     A1 …                                                                 nested object
 *     A2                                                                   terminating object
 *
 * The type-info lists are blocks of `<length:2>` + bytes ending at a block of
 * length 0; they are kept as their raw bytes (the browse reads them). Members
 * keep their order so that an object re-encodes byte for byte. Source:
 * s7commplus (MIT), typeinfo.py parse_object / parse_vartype_list and
 * alarm.py (relations); golden frames (the subscription create).
 */
import { ProtocolError } from '../../errors';
import { ElementId } from '../constants';
import { Reader, Writer } from './bytes';
import { readPValue, writePValue, type PValue } from './pvalue';

export type PMember =
  | { kind: 'attribute'; id: number; value: PValue }
  | { kind: 'relation'; id: number; target: number }
  | { kind: 'object'; object: PObject }
  /** An AB (variable types) or AC (variable names) list: its blocks, as they came, without the tag byte. */
  | { kind: 'list'; tag: number; raw: Buffer };

export interface PObject {
  relationId: number;
  classId: number;
  classFlags: number;
  attributeId: number;
  members: PMember[];
}

const MAX_DEPTH = 64;

function readBlocks(r: Reader): Buffer {
  const start = r.offset;
  for (let len = r.u16('list block length'); len !== 0; len = r.u16('list block length')) r.bytes(len, 'list block');
  return r.buf.subarray(start, r.offset);
}

function readObjectAt(r: Reader, depth: number): PObject {
  if (depth >= MAX_DEPTH) throw new ProtocolError(`S7CommPlus: objects nested deeper than ${MAX_DEPTH} at offset ${r.offset}`);
  const at = r.offset;
  const tag = r.u8('element id');
  if (tag !== ElementId.StartOfObject)
    throw new ProtocolError(`S7CommPlus: expected an object (0xa1) at offset ${at}, found 0x${tag.toString(16).padStart(2, '0')}`);
  const obj: PObject = {
    relationId: r.u32('RelationId'),
    classId: r.uvlq32(),
    classFlags: r.uvlq32(),
    attributeId: r.uvlq32(),
    members: [],
  };
  for (;;) {
    const el = r.peek();
    if (el === undefined) throw new ProtocolError(`S7CommPlus: object starting at offset ${at} has no terminator (0xa2)`);
    switch (el) {
      case ElementId.TerminatingObject:
        r.offset++;
        return obj;
      case ElementId.Attribute:
        r.offset++;
        obj.members.push({ kind: 'attribute', id: r.uvlq32(), value: readPValue(r) });
        break;
      case ElementId.Relation:
        r.offset++;
        obj.members.push({ kind: 'relation', id: r.uvlq32(), target: r.u32('relation target') });
        break;
      case ElementId.StartOfObject:
        obj.members.push({ kind: 'object', object: readObjectAt(r, depth + 1) });
        break;
      case ElementId.VartypeList:
      case ElementId.VarnameList:
        r.offset++;
        obj.members.push({ kind: 'list', tag: el, raw: readBlocks(r) });
        break;
      default:
        throw new ProtocolError(
          `S7CommPlus: element 0x${el.toString(16).padStart(2, '0')} at offset ${r.offset} is not supported in an object`,
        );
    }
  }
}

/** Reads one object (0xA1 … 0xA2) at the reader's offset. */
export function readObject(r: Reader): PObject {
  return readObjectAt(r, 0);
}

/** Reads the objects that follow one another at the reader's offset (none if the next byte is not 0xA1). */
export function readObjects(r: Reader): PObject[] {
  const out: PObject[] = [];
  while (r.peek() === ElementId.StartOfObject) out.push(readObject(r));
  return out;
}

export function writeObject(w: Writer, obj: PObject): void {
  w.u8(ElementId.StartOfObject).u32(obj.relationId).uvlq32(obj.classId).uvlq32(obj.classFlags).uvlq32(obj.attributeId);
  for (const m of obj.members) {
    switch (m.kind) {
      case 'attribute':
        w.u8(ElementId.Attribute).uvlq32(m.id);
        writePValue(w, m.value);
        break;
      case 'relation':
        w.u8(ElementId.Relation).uvlq32(m.id).u32(m.target);
        break;
      case 'object':
        writeObject(w, m.object);
        break;
      case 'list':
        w.u8(m.tag).bytes(m.raw);
        break;
    }
  }
  w.u8(ElementId.TerminatingObject);
}

export function encodeObject(obj: PObject): Buffer {
  const w = new Writer();
  writeObject(w, obj);
  return w.toBuffer();
}

export function decodeObject(buf: Buffer, offset = 0): { value: PObject; length: number } {
  const r = new Reader(buf, offset);
  const value = readObject(r);
  return { value, length: r.offset - offset };
}

/** An object with the given head and attributes (in that order), as the encoders build them. */
export function newObject(
  head: { relationId: number; classId: number; classFlags?: number; attributeId?: number },
  attributes: [id: number, value: PValue][] = [],
  children: PObject[] = [],
): PObject {
  return {
    relationId: head.relationId,
    classId: head.classId,
    classFlags: head.classFlags ?? 0,
    attributeId: head.attributeId ?? 0,
    members: [
      ...attributes.map(([id, value]): PMember => ({ kind: 'attribute', id, value })),
      ...children.map((object): PMember => ({ kind: 'object', object })),
    ],
  };
}

/** The value of an object's attribute `id` (the first, if it repeats). */
export function attributeOf(obj: PObject, id: number): PValue | undefined {
  for (const m of obj.members) if (m.kind === 'attribute' && m.id === id) return m.value;
  return undefined;
}

/** The objects nested directly in `obj`. */
export function childrenOf(obj: PObject): PObject[] {
  return obj.members.flatMap((m) => (m.kind === 'object' ? [m.object] : []));
}

/** Every object of the trees, depth first, the roots included. */
export function walkObjects(roots: PObject[]): PObject[] {
  const out: PObject[] = [];
  const visit = (o: PObject): void => {
    out.push(o);
    for (const c of childrenOf(o)) visit(c);
  };
  roots.forEach(visit);
  return out;
}
