/**
 * Explore: read an object and (recursively) its children.
 *
 *     request   <ExploreId:4> <ExploreRequestId:UVLQ> <ChildsRecursive:1> <flag:1> <Parents:1>
 *               <filter count:1> <attribute count:UVLQ> <AttributeId:UVLQ>… [IntegrityId] <fill:5>
 *     response  <ReturnValue:UVLQ64> <objects> <fill:4>
 *
 * `flag` is 1 in TIA's device-tree explore and 0 in its event-tree and pair
 * explores; filter objects (a count above 0) have no public layout and are
 * refused. An empty attribute list asks for every attribute. A PLC may send
 * a few bytes between the return value and the first object; they are kept as
 * `preamble`. Source: golden frames (three TIA explores); s7commplus (MIT),
 * client.py _build_explore_request, server.py _handle_explore, typeinfo.py
 * extract_type_info_objects.
 *
 * The CPU state the s7commplus client reads (client.py get_cpu_state) is an
 * Explore of theCPUexecUnit (RID 52): Struct attribute 0x8BD (struct 0xD99),
 * DInt member 0xD9E, 8 in RUN and 4 in STOP; without it, UInt attributes
 * 0x1F80/0x1F81 at 1/7 mean RUN and 0/0 STOP.
 */
import { ProtocolError } from '../../errors';
import { DataType, ElementId, FunctionCode, Ids, OperatingState, TransportFlags } from '../constants';
import { Reader, Writer } from './bytes';
import {
  readIntegrity,
  readRequestHeader,
  readResponseHeader,
  readResponseTail,
  writeRequestHeader,
  writeResponseHeader,
  writeResponseTail,
  type DecodeOptions,
  type Request,
  type Response,
} from './header';
import { attributeOf, newObject, readObjects, walkObjects, writeObject, type PObject } from './object';
import { scalar, type PValue } from './pvalue';

export interface ExploreRequest {
  exploreId: number;
  requestId: number;
  childsRecursive: number;
  flag: number;
  parents: number;
  attributes: number[];
}

export function encodeExploreRequest(req: Request<ExploreRequest>): Buffer {
  const b = req.body;
  const w = new Writer();
  writeRequestHeader(w, { ...req.header, functionCode: FunctionCode.Explore });
  w.u32(b.exploreId).uvlq32(b.requestId).u8(b.childsRecursive).u8(b.flag).u8(b.parents).u8(0).uvlq32(b.attributes.length);
  for (const id of b.attributes) w.uvlq32(id);
  if (req.integrityId !== undefined) w.uvlq32(req.integrityId);
  return w.bytes(Buffer.alloc(5)).toBuffer();
}

export function decodeExploreRequest(data: Buffer, opts: DecodeOptions): Request<ExploreRequest> {
  const r = new Reader(data);
  const header = readRequestHeader(r, FunctionCode.Explore);
  const exploreId = r.u32('ExploreId');
  const requestId = r.uvlq32();
  const childsRecursive = r.u8('ChildsRecursive');
  const flag = r.u8('explore flag');
  const parents = r.u8('ExploreParents');
  const filters = r.u8('filter count');
  if (filters !== 0) throw new ProtocolError(`S7CommPlus: Explore with ${filters} filter objects is not supported`);
  const count = r.uvlq32();
  if (count > r.remaining) throw new ProtocolError(`S7CommPlus: Explore names ${count} attributes in ${r.remaining} bytes`);
  const attributes: number[] = [];
  for (let i = 0; i < count; i++) attributes.push(r.uvlq32());
  const integrityId = readIntegrity(r, opts);
  r.bytes(5, 'closing fill');
  r.done('Explore request');
  return {
    header,
    body: { exploreId, requestId, childsRecursive, flag, parents, attributes },
    ...(integrityId === undefined ? {} : { integrityId }),
  };
}

/** An Explore as s7commplus's client sends it (children recursive, flag 1, no parents). */
export function exploreRequest(sequence: number, sessionId: number, exploreId: number, attributes: number[] = []): Request<ExploreRequest> {
  return {
    header: { functionCode: FunctionCode.Explore, sequence, sessionId, transportFlags: TransportFlags.Normal },
    body: exploreBody(exploreId, attributes),
  };
}

/** The body of an Explore of `exploreId` (see exploreRequest). */
export function exploreBody(exploreId: number, attributes: number[] = []): ExploreRequest {
  return { exploreId, requestId: 0, childsRecursive: 1, flag: 1, parents: 0, attributes };
}

export interface ExploreResponse {
  returnValue: bigint;
  preamble?: Buffer;
  objects: PObject[];
}

/** The most bytes taken for a preamble before the first object. */
const MAX_PREAMBLE = 16;

export function encodeExploreResponse(res: Response<ExploreResponse>): Buffer {
  const w = new Writer();
  writeResponseHeader(w, { ...res.header, functionCode: FunctionCode.Explore });
  w.uvlq64(res.body.returnValue);
  if (res.body.preamble) w.bytes(res.body.preamble);
  for (const o of res.body.objects) writeObject(w, o);
  return writeResponseTail(w, 4, res.integrityId);
}

export function decodeExploreResponse(data: Buffer, opts: DecodeOptions): Response<ExploreResponse> {
  const r = new Reader(data);
  const header = readResponseHeader(r, FunctionCode.Explore);
  const returnValue = r.uvlq64();
  if (returnValue !== 0n) return { header, body: { returnValue, objects: [] } };
  const start = r.offset;
  const limit = Math.min(r.end, start + MAX_PREAMBLE);
  let at = start;
  while (at < limit && data[at] !== ElementId.StartOfObject) at++;
  const body: ExploreResponse = { returnValue, objects: [] };
  if (at < limit) {
    if (at > start) body.preamble = r.bytes(at - start, 'preamble');
    body.objects = readObjects(r);
  }
  if (r.remaining >= 4) r.bytes(4, 'closing fill');
  const integrityId = readResponseTail(r, opts);
  return { header, body, ...(integrityId === undefined ? {} : { integrityId }) };
}

export type CpuState = 'RUN' | 'STOP' | 'UNKNOWN';

function operatingStateCode(v: PValue | undefined): number | undefined {
  if (!v || v.type !== DataType.Struct || v.flags !== 0) return undefined;
  const s = v.value as { id: number; members?: { key: number; value: PValue }[] };
  if (s.id !== Ids.CpuExecUnitOperatingStateStructId || !s.members) return undefined;
  const m = s.members.find((x) => x.key === Ids.CpuExecUnitOperatingState);
  return m && m.value.type === DataType.DInt && typeof m.value.value === 'number' ? m.value.value : undefined;
}

const CPU_EXECUTING = 0x1f80;
const CPU_OPERATING_MODE = 0x1f81;

/** The CPU state in the objects of an Explore of theCPUexecUnit, as s7commplus (MIT), client.py _parse_cpu_state reads it. */
export function cpuStateOf(objects: PObject[]): CpuState {
  const all = walkObjects(objects);
  const codes = new Set(
    all.map((o) => operatingStateCode(attributeOf(o, Ids.CpuExecUnitOperatingStateStruct))).filter((c) => c !== undefined),
  );
  if (codes.size === 1) {
    const [code] = codes;
    return code === OperatingState.Run ? 'RUN' : code === OperatingState.Stop ? 'STOP' : 'UNKNOWN';
  }
  if (codes.size > 1) return 'UNKNOWN';
  const uint = (id: number) =>
    new Set(
      all.flatMap((o) => {
        const v = attributeOf(o, id);
        return v && v.flags === 0 && v.type === DataType.UInt ? [v.value as number] : [];
      }),
    );
  const exec = [...uint(CPU_EXECUTING)].join();
  const mode = [...uint(CPU_OPERATING_MODE)].join();
  if (exec === '1' && mode === '7') return 'RUN';
  if (exec === '0' && mode === '0') return 'STOP';
  return 'UNKNOWN';
}

/** theCPUexecUnit as the simulator reports it: the operating-state struct only (s7commplus (MIT), server.py _cpu_exec_unit_object). */
export function cpuExecUnitObject(state: CpuState): PObject {
  const code = state === 'RUN' ? OperatingState.Run : state === 'STOP' ? OperatingState.Stop : 0;
  return newObject({ relationId: Ids.NativeTheCpuExecUnitRID, classId: Ids.ClassCpuExecUnit }, [
    [
      Ids.CpuExecUnitOperatingStateStruct,
      scalar(DataType.Struct, {
        id: Ids.CpuExecUnitOperatingStateStructId,
        members: [{ key: Ids.CpuExecUnitOperatingState, value: scalar(DataType.DInt, code) }],
      }),
    ],
  ]);
}
