/**
 * GetVarSubStreamed and SetVarSubStreamed: one attribute of one object, read
 * or written (TIA's symbolic write of a watch table; the protection level and
 * legitimation reads).
 *
 *     request   <InObjectId:4> <address:PValue> <ObjectQualifier> <sequence field:2>
 *               [<value:PValue> (Set)] [IntegrityId] <fill:4>
 *     response  <ReturnValue:UVLQ64> <marker:1> [<value:PValue> (Get)] <fill:4>
 *
 * The address is an address array of UDInt (flags 0x20, `20 04 01 83 1f` in
 * the golden write). The byte after the return value is 0x0D in the golden
 * SetVarSubStreamed answer and 0x00 in GetVarSubStreamed answers; its meaning
 * is not public, it is kept as `marker`. Source: golden frames (the symbolic
 * write and its answer); s7commplus (MIT), connection.py
 * _build_get_var_substreamed_payload and _parse_get_var_substreamed_response.
 */
import { ProtocolError } from '../../errors';
import { FunctionCode } from '../constants';
import { Reader, Writer } from './bytes';
import {
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

export interface SubStreamedRequest {
  inObjectId: number;
  address: PValue;
  qualifier: ObjectQualifier;
  sequenceField: number;
  /** The value written (SetVarSubStreamed only). */
  value?: PValue;
}

export function encodeSubStreamedRequest(req: Request<SubStreamedRequest>): Buffer {
  const b = req.body;
  const w = new Writer();
  writeRequestHeader(w, req.header);
  w.u32(b.inObjectId);
  writePValue(w, b.address);
  writeObjectQualifier(w, b.qualifier);
  w.u16(b.sequenceField);
  if (b.value) writePValue(w, b.value);
  if (req.integrityId !== undefined) w.uvlq32(req.integrityId);
  return w.u32(0).toBuffer();
}

/** A GetVarSubStreamed or SetVarSubStreamed request (the header's function says which). */
export function decodeSubStreamedRequest(data: Buffer, opts: DecodeOptions): Request<SubStreamedRequest> {
  const r = new Reader(data);
  const header = readRequestHeader(r);
  const set = header.functionCode === FunctionCode.SetVarSubStreamed;
  if (!set && header.functionCode !== FunctionCode.GetVarSubStreamed)
    throw new ProtocolError(
      `S7CommPlus: expected GetVarSubStreamed or SetVarSubStreamed, found function 0x${header.functionCode.toString(16)}`,
    );
  const body: SubStreamedRequest = {
    inObjectId: r.u32('InObjectId'),
    address: readPValue(r),
    qualifier: readObjectQualifier(r, opts.v1),
    sequenceField: r.u16('sequence field'),
  };
  if (set) body.value = readPValue(r);
  const integrityId = readIntegrity(r, opts);
  readFill(r, 4);
  r.done('substreamed request');
  return { header, body, ...(integrityId === undefined ? {} : { integrityId }) };
}

export interface SubStreamedResponse {
  returnValue: bigint;
  marker: number;
  value?: PValue;
}

export function encodeSubStreamedResponse(res: Response<SubStreamedResponse>): Buffer {
  const w = new Writer();
  writeResponseHeader(w, res.header);
  w.uvlq64(res.body.returnValue).u8(res.body.marker);
  if (res.body.value) writePValue(w, res.body.value);
  return writeResponseTail(w, 4, res.integrityId);
}

/** `fn`: the function of the request answered (GetVarSubStreamed answers carry a value). */
export function decodeSubStreamedResponse(data: Buffer, fn: number, opts: DecodeOptions): Response<SubStreamedResponse> {
  const r = new Reader(data);
  const header = readResponseHeader(r, fn);
  const returnValue = r.uvlq64();
  if (returnValue !== 0n && r.remaining === 0) return { header, body: { returnValue, marker: 0 } };
  const body: SubStreamedResponse = { returnValue, marker: r.u8('marker') };
  if (fn === FunctionCode.GetVarSubStreamed && returnValue === 0n) body.value = readPValue(r);
  if (r.remaining >= 4) readFill(r, 4);
  const integrityId = readResponseTail(r, opts);
  return { header, body, ...(integrityId === undefined ? {} : { integrityId }) };
}
