/**
 * GetMultiVariables and SetMultiVariables.
 *
 *     Get request   <LinkId:4> <items:UVLQ> <fields:UVLQ> <address>… <ObjectQualifier> [IntegrityId] <fill:4>
 *     Get response  <ReturnValue:UVLQ64> (<item:UVLQ> <PValue>)… 0 (<item:UVLQ> <error:UVLQ64>)… 0
 *     Set request   <InObjectId:4> <items:UVLQ> <fields:UVLQ> <address>… (<item:UVLQ> <PValue>)… 0
 *                   <ObjectQualifier> [IntegrityId] <fill:4>
 *     Set response  <ReturnValue:UVLQ64> (<item:UVLQ> <error:UVLQ64>)… 0
 *
 * An item address is <SymbolCrc> <AccessArea> <LID count> <AccessSubArea> <LID>…
 * (all UVLQ; the count includes the sub-area; `fields` counts them all). With
 * InObjectId ≠ 0 a Set writes attributes of that object instead, each address
 * one UVLQ attribute id: the session setup writes ServerSessionVersion (306)
 * of the session back as the CreateObject answer gave it. Items are numbered
 * from 1. A standard DB read as bytes has the address (0, 0x8A0E0000 + db, 4,
 * 2550, 3, offset, length): LID 3 is the classic-blob marker.
 * Source: s7commplus (MIT), client.py _build_read_payload,
 * _parse_read_response, _build_write_payload; codec.py encode_item_address;
 * connection.py _build_session_setup_frame; server.py _resolve_classic_blob.
 */
import { ProtocolError } from '../../errors';
import { DataType, FunctionCode, Ids, TransportFlags, dbAccessArea } from '../constants';
import { Reader, Writer } from './bytes';
import {
  NO_QUALIFIER,
  readFill,
  readIntegrity,
  readObjectQualifier,
  readRequestHeader,
  readResponseHeader,
  readResponseTail,
  writeObjectQualifier,
  writeRequestHeader,
  writeResponseHeader,
  writeResponseTail,
  type DecodeOptions,
  type ObjectQualifier,
  type Request,
  type Response,
} from './header';
import { readPValue, writePValue, type PValue } from './pvalue';
import { uvlq32Length } from './vlq';

export interface ItemAddress {
  symbolCrc: number;
  accessArea: number;
  accessSubArea: number;
  lids: number[];
}

/** The most LIDs accepted in one address (a symbol path); more is refused as hostile. */
const MAX_LIDS = 64;

function writeAddress(w: Writer, a: ItemAddress): void {
  w.uvlq32(a.symbolCrc)
    .uvlq32(a.accessArea)
    .uvlq32(a.lids.length + 1)
    .uvlq32(a.accessSubArea);
  for (const lid of a.lids) w.uvlq32(lid);
}

function readAddress(r: Reader): ItemAddress {
  const symbolCrc = r.uvlq32();
  const accessArea = r.uvlq32();
  const count = r.uvlq32();
  if (count < 1 || count > MAX_LIDS + 1) throw new ProtocolError(`S7CommPlus: an item address with ${count} LIDs at offset ${r.offset}`);
  const accessSubArea = r.uvlq32();
  const lids: number[] = [];
  for (let i = 1; i < count; i++) lids.push(r.uvlq32());
  return { symbolCrc, accessArea, accessSubArea, lids };
}

const fieldsOf = (addresses: ItemAddress[]): number => addresses.reduce((n, a) => n + 4 + a.lids.length, 0);

/** `length` bytes at `offset` of standard DB `db`. */
export function classicBlobAddress(db: number, offset: number, length: number): ItemAddress {
  return { symbolCrc: 0, accessArea: dbAccessArea(db), accessSubArea: Ids.DBValueActual, lids: [Ids.LidClassicBlob, offset, length] };
}

/** The DB range a classic-blob address names, or undefined for any other address (as s7commplus's server.py reads it). */
export function resolveClassicBlob(a: ItemAddress): { db: number; offset: number; length: number } | undefined {
  if (a.lids.length !== 3 || a.lids[0] !== Ids.LidClassicBlob || (a.accessArea & 0xffff0000) >>> 0 !== Ids.DBAccessAreaBase)
    return undefined;
  return { db: a.accessArea & 0xffff, offset: a.lids[1]!, length: a.lids[2]! };
}

export interface GetMultiVariablesRequest {
  linkId: number;
  addresses: ItemAddress[];
  qualifier: ObjectQualifier;
}

export function encodeGetMultiVariablesRequest(req: Request<GetMultiVariablesRequest>): Buffer {
  const w = new Writer();
  writeRequestHeader(w, { ...req.header, functionCode: FunctionCode.GetMultiVariables });
  const { addresses } = req.body;
  w.u32(req.body.linkId).uvlq32(addresses.length).uvlq32(fieldsOf(addresses));
  for (const a of addresses) writeAddress(w, a);
  writeObjectQualifier(w, req.body.qualifier);
  if (req.integrityId !== undefined) w.uvlq32(req.integrityId);
  return w.u32(0).toBuffer();
}

function readAddresses(r: Reader): ItemAddress[] {
  const count = r.uvlq32();
  const fields = r.uvlq32();
  if (count * 4 > r.remaining) throw new ProtocolError(`S7CommPlus: ${count} item addresses in ${r.remaining} bytes`);
  const addresses: ItemAddress[] = [];
  for (let i = 0; i < count; i++) addresses.push(readAddress(r));
  if (fieldsOf(addresses) !== fields)
    throw new ProtocolError(`S7CommPlus: the request counts ${fields} address fields, its addresses have ${fieldsOf(addresses)}`);
  return addresses;
}

export function decodeGetMultiVariablesRequest(data: Buffer, opts: DecodeOptions): Request<GetMultiVariablesRequest> {
  const r = new Reader(data);
  const header = readRequestHeader(r, FunctionCode.GetMultiVariables);
  const linkId = r.u32('LinkId');
  const addresses = readAddresses(r);
  const qualifier = readObjectQualifier(r, opts.v1);
  const integrityId = readIntegrity(r, opts);
  readFill(r, 4);
  r.done('GetMultiVariables request');
  return { header, body: { linkId, addresses, qualifier }, ...(integrityId === undefined ? {} : { integrityId }) };
}

/** The body of a read of these addresses as s7commplus's client sends it. */
export function readBody(addresses: ItemAddress[]): GetMultiVariablesRequest {
  return { linkId: 0, addresses, qualifier: NO_QUALIFIER };
}

/** A read of these addresses as s7commplus's client sends it. */
export function readRequest(sequence: number, sessionId: number, addresses: ItemAddress[]): Request<GetMultiVariablesRequest> {
  return {
    header: { functionCode: FunctionCode.GetMultiVariables, sequence, sessionId, transportFlags: TransportFlags.Normal },
    body: readBody(addresses),
  };
}

/** Per item (numbered from 1): its value, or the PLC's error for it. */
export interface ItemResults {
  returnValue: bigint;
  values: Map<number, PValue>;
  errors: Map<number, bigint>;
}

function writeErrors(w: Writer, errors: Map<number, bigint>): void {
  for (const [item, code] of errors) w.uvlq32(item).uvlq64(code);
  w.uvlq32(0);
}

function readErrors(r: Reader, into: Map<number, bigint>, seen: (n: number) => boolean): void {
  for (let item = r.uvlq32(); item !== 0; item = r.uvlq32()) {
    if (seen(item)) throw new ProtocolError(`S7CommPlus: item ${item} answered twice`);
    into.set(item, r.uvlq64());
  }
}

export function encodeGetMultiVariablesResponse(res: Response<ItemResults>): Buffer {
  const w = new Writer();
  writeResponseHeader(w, { ...res.header, functionCode: FunctionCode.GetMultiVariables });
  w.uvlq64(res.body.returnValue);
  for (const [item, value] of res.body.values) {
    w.uvlq32(item);
    writePValue(w, value);
  }
  w.uvlq32(0);
  writeErrors(w, res.body.errors);
  return writeResponseTail(w, 0, res.integrityId);
}

export function decodeGetMultiVariablesResponse(data: Buffer, opts: DecodeOptions): Response<ItemResults> {
  const r = new Reader(data);
  const header = readResponseHeader(r, FunctionCode.GetMultiVariables);
  const body: ItemResults = { returnValue: r.uvlq64(), values: new Map(), errors: new Map() };
  if (body.returnValue !== 0n && r.remaining === 0) return { header, body };
  for (let item = r.uvlq32(); item !== 0; item = r.uvlq32()) {
    if (body.values.has(item)) throw new ProtocolError(`S7CommPlus: item ${item} answered twice`);
    body.values.set(item, readPValue(r));
  }
  readErrors(r, body.errors, (n) => body.values.has(n) || body.errors.has(n));
  const integrityId = readResponseTail(r, opts);
  return { header, body, ...(integrityId === undefined ? {} : { integrityId }) };
}

/** Item addresses (InObjectId 0) or attribute ids of object InObjectId. */
export type SetTargets = { kind: 'items'; addresses: ItemAddress[] } | { kind: 'attributes'; inObjectId: number; ids: number[] };

export interface SetMultiVariablesRequest {
  targets: SetTargets;
  /** One per target, in order (item numbers 1…n). */
  values: PValue[];
  qualifier: ObjectQualifier;
}

export function encodeSetMultiVariablesRequest(req: Request<SetMultiVariablesRequest>): Buffer {
  const { targets, values } = req.body;
  const w = new Writer();
  writeRequestHeader(w, { ...req.header, functionCode: FunctionCode.SetMultiVariables });
  if (targets.kind === 'items') {
    w.u32(0).uvlq32(targets.addresses.length).uvlq32(fieldsOf(targets.addresses));
    for (const a of targets.addresses) writeAddress(w, a);
  } else {
    w.u32(targets.inObjectId).uvlq32(targets.ids.length).uvlq32(targets.ids.length);
    for (const id of targets.ids) w.uvlq32(id);
  }
  values.forEach((v, i) => {
    w.uvlq32(i + 1);
    writePValue(w, v);
  });
  w.uvlq32(0);
  writeObjectQualifier(w, req.body.qualifier);
  if (req.integrityId !== undefined) w.uvlq32(req.integrityId);
  return w.u32(0).toBuffer();
}

export function decodeSetMultiVariablesRequest(data: Buffer, opts: DecodeOptions): Request<SetMultiVariablesRequest> {
  const r = new Reader(data);
  const header = readRequestHeader(r, FunctionCode.SetMultiVariables);
  const inObjectId = r.u32('InObjectId');
  let targets: SetTargets;
  if (inObjectId === 0) targets = { kind: 'items', addresses: readAddresses(r) };
  else {
    const count = r.uvlq32();
    const fields = r.uvlq32();
    if (fields !== count || count > r.remaining) throw new ProtocolError(`S7CommPlus: ${count} attribute ids in ${fields} fields`);
    const ids: number[] = [];
    for (let i = 0; i < count; i++) ids.push(r.uvlq32());
    targets = { kind: 'attributes', inObjectId, ids };
  }
  const expected = targets.kind === 'items' ? targets.addresses.length : targets.ids.length;
  const values: PValue[] = [];
  for (let item = r.uvlq32(); item !== 0; item = r.uvlq32()) {
    if (item !== values.length + 1 || item > expected)
      throw new ProtocolError(`S7CommPlus: value for item ${item} where item ${values.length + 1} of ${expected} was due`);
    values.push(readPValue(r));
  }
  if (values.length !== expected) throw new ProtocolError(`S7CommPlus: ${values.length} values for ${expected} items`);
  const qualifier = readObjectQualifier(r, opts.v1);
  const integrityId = readIntegrity(r, opts);
  readFill(r, 4);
  r.done('SetMultiVariables request');
  return { header, body: { targets, values, qualifier }, ...(integrityId === undefined ? {} : { integrityId }) };
}

/** The body of a write of values to these addresses. */
export function writeBody(addresses: ItemAddress[], values: PValue[]): SetMultiVariablesRequest {
  return { targets: { kind: 'items', addresses }, values, qualifier: NO_QUALIFIER };
}

/** A write of values to these addresses. */
export function writeRequest(
  sequence: number,
  sessionId: number,
  addresses: ItemAddress[],
  values: PValue[],
): Request<SetMultiVariablesRequest> {
  return {
    header: { functionCode: FunctionCode.SetMultiVariables, sequence, sessionId, transportFlags: TransportFlags.Normal },
    body: writeBody(addresses, values),
  };
}

/**
 * The session setup: ServerSessionVersion written back to the session, with
 * no integrity id, in a frame of version 2 whatever the session's version
 * (`v1`: a session of frame version 1, whose qualifier has the V1 form).
 * s7commplus (MIT), connection.py _build_session_setup_frame.
 */
export function sessionSetupRequest(
  sequence: number,
  sessionId: number,
  serverSessionVersion: PValue,
  v1 = false,
): Request<SetMultiVariablesRequest> {
  return {
    header: { functionCode: FunctionCode.SetMultiVariables, sequence, sessionId, transportFlags: TransportFlags.Normal },
    body: sessionSetupBody(sessionId, serverSessionVersion, v1),
  };
}

/** The session setup's body (see sessionSetupRequest). */
export function sessionSetupBody(sessionId: number, serverSessionVersion: PValue, v1 = false): SetMultiVariablesRequest {
  return {
    targets: { kind: 'attributes', inObjectId: sessionId, ids: [Ids.ServerSessionVersion] },
    values: [serverSessionVersion],
    qualifier: v1 ? { ...NO_QUALIFIER, v1 } : NO_QUALIFIER,
  };
}

/** Whether a SetMultiVariables is the session setup (it writes ServerSessionVersion). */
export function isSessionSetup(body: SetMultiVariablesRequest): boolean {
  return body.targets.kind === 'attributes' && body.targets.ids.includes(Ids.ServerSessionVersion);
}

export interface SetResults {
  returnValue: bigint;
  errors: Map<number, bigint>;
}

export function encodeSetMultiVariablesResponse(res: Response<SetResults>): Buffer {
  const w = new Writer();
  writeResponseHeader(w, { ...res.header, functionCode: FunctionCode.SetMultiVariables });
  w.uvlq64(res.body.returnValue);
  writeErrors(w, res.body.errors);
  return writeResponseTail(w, 0, res.integrityId);
}

export function decodeSetMultiVariablesResponse(data: Buffer, opts: DecodeOptions): Response<SetResults> {
  const r = new Reader(data);
  const header = readResponseHeader(r, FunctionCode.SetMultiVariables);
  const body: SetResults = { returnValue: r.uvlq64(), errors: new Map() };
  if (r.remaining === 0) return { header, body };
  readErrors(r, body.errors, (n) => body.errors.has(n));
  const integrityId = readResponseTail(r, opts);
  return { header, body, ...(integrityId === undefined ? {} : { integrityId }) };
}

/** A blob PValue of raw bytes, as the classic-blob reads answer and writes send (s7commplus (MIT), codec.py encode_pvalue_blob). */
export function blobValue(data: Buffer): PValue {
  return { flags: 0, type: DataType.Blob, value: { rootId: 0, data } };
}

/** Bytes of an item address on the wire (its SymbolCrc, area, LID count, sub-area and LIDs as UVLQs). */
export function addressBytes(a: ItemAddress): number {
  let n = uvlq32Length(a.symbolCrc) + uvlq32Length(a.accessArea) + uvlq32Length(a.lids.length + 1) + uvlq32Length(a.accessSubArea);
  for (const lid of a.lids) n += uvlq32Length(lid);
  return n;
}

/**
 * The most bytes a Get/SetMultiVariables request frame has besides its addresses and values: the PDU header (4),
 * the request header (14), the LinkId or InObjectId (4), the item and field counts (UVLQs of at most 3 bytes), the
 * end of a write's values (1), the ObjectQualifier, an integrity id (at most 5), the fill (4) and the trailer (4).
 */
export const MULTI_VARIABLES_FRAME_OVERHEAD = ((): number => {
  const w = new Writer();
  writeObjectQualifier(w, NO_QUALIFIER);
  return 4 + 14 + 4 + 3 + 3 + 1 + w.toBuffer().length + 5 + 4 + 4;
})();

/** Bytes a value of a write adds: its item number (at most 3) and its PValue. */
export function writeValueBytes(v: PValue): number {
  const w = new Writer();
  writePValue(w, v);
  return 3 + w.toBuffer().length;
}
