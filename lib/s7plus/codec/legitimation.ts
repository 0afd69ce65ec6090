/**
 * Legitimation (the PLC's password) as bytes: the reads of the protection
 * level and the challenge (GetVarSubStreamed, substreamed.ts), the SetVariable
 * that carries the answer, the new form's credentials and the device string
 * of ServerSessionVersion that tells which form a firmware takes.
 *
 *     SetVariable request   <InObjectId:4> <count:UVLQ = 1> <address:UVLQ> <value:PValue> <ObjectQualifier> 00 [IntegrityId] <fill:4>
 *     SetVariable response  <ReturnValue:UVLQ64> [<fill:4>] [IntegrityId]
 *     credentials           00 17 <40400:4> 40401 <type:UDInt> 40402 <user:Blob> 40403 <password:Blob> 00
 *
 * Source: s7commplus (MIT), connection.py _build_set_variable_payload,
 * _check_set_variable_response, _parse_protection_level_response,
 * _parse_get_var_substreamed_response, _send_legitimation_new/_legacy, and
 * legitimation.py _build_legitimation_payload, extract_session_version_string,
 * decide_legitimation_mode.
 * Pure: the crypto (SHA-1, AES) is the client's (client/legitimation.ts).
 */
import { ProtocolError } from '../../errors';
import { DataType, FunctionCode, Ids, PValueFlag, TransportFlags } from '../constants';
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
import { readPValue, scalar, writePValue, type PValue } from './pvalue';
import type { SubStreamedRequest } from './substreamed';

export interface SetVariableRequest {
  inObjectId: number;
  address: number;
  value: PValue;
  qualifier: ObjectQualifier;
}

export function encodeSetVariableRequest(req: Request<SetVariableRequest>): Buffer {
  const b = req.body;
  const w = new Writer();
  writeRequestHeader(w, req.header);
  w.u32(b.inObjectId).uvlq32(1).uvlq32(b.address);
  writePValue(w, b.value);
  writeObjectQualifier(w, b.qualifier);
  // The byte after the ObjectQualifier of a plain SetVariable (connection.py: "real PLCs accept it").
  w.u8(0);
  if (req.integrityId !== undefined) w.uvlq32(req.integrityId);
  return w.u32(0).toBuffer();
}

export function decodeSetVariableRequest(data: Buffer, opts: DecodeOptions): Request<SetVariableRequest> {
  const r = new Reader(data);
  const header = readRequestHeader(r, FunctionCode.SetVariable);
  const inObjectId = r.u32('InObjectId');
  const count = r.uvlq32();
  if (count !== 1) throw new ProtocolError(`S7CommPlus: a SetVariable of ${count} attributes (one is what a legitimation writes)`);
  const body: SetVariableRequest = { inObjectId, address: r.uvlq32(), value: readPValue(r), qualifier: readObjectQualifier(r, opts.v1) };
  r.u8('the byte after the ObjectQualifier');
  const integrityId = readIntegrity(r, opts);
  readFill(r, 4);
  r.done('SetVariable request');
  return { header, body, ...(integrityId === undefined ? {} : { integrityId }) };
}

export interface SetVariableResponse {
  returnValue: bigint;
}

export function encodeSetVariableResponse(res: Response<SetVariableResponse>): Buffer {
  const w = new Writer();
  writeResponseHeader(w, { ...res.header, functionCode: FunctionCode.SetVariable });
  w.uvlq64(res.body.returnValue);
  return writeResponseTail(w, 4, res.integrityId);
}

export function decodeSetVariableResponse(data: Buffer, opts: DecodeOptions): Response<SetVariableResponse> {
  const r = new Reader(data);
  const header = readResponseHeader(r, FunctionCode.SetVariable);
  const returnValue = r.uvlq64();
  if (r.remaining >= 4) readFill(r, 4);
  const integrityId = readResponseTail(r, opts);
  return { header, body: { returnValue }, ...(integrityId === undefined ? {} : { integrityId }) };
}

/** A refused SetVariable: bit 15 of the return value, the sign of its 16-bit code (connection.py _check_set_variable_response). */
export function setVariableRefused(returnValue: bigint): boolean {
  return (returnValue & 0x8000n) !== 0n;
}

/** GetVarSubStreamed of one attribute of the session (the protection level 1842, the challenge 303). */
export function sessionAttributeRequest(sessionId: number, address: number): SubStreamedRequest {
  return {
    inObjectId: sessionId,
    address: { flags: PValueFlag.AddressArray, type: DataType.UDInt, value: [address] },
    qualifier: NO_QUALIFIER,
    sequenceField: 1,
  };
}

/** SetVariable of one attribute of the session: the answer to the challenge. */
export function legitimateRequest(sequence: number, sessionId: number, address: number, value: PValue): Request<SetVariableRequest> {
  return {
    header: { functionCode: FunctionCode.SetVariable, sequence, sessionId, transportFlags: TransportFlags.Normal },
    body: legitimateBody(sessionId, address, value),
  };
}

/** The body of the password's SetVariable (see legitimateRequest). */
export function legitimateBody(sessionId: number, address: number, value: PValue): SetVariableRequest {
  return { inObjectId: sessionId, address, value, qualifier: NO_QUALIFIER };
}

/** The protection level of a GetVarSubStreamed answer: a scalar UDInt (connection.py _parse_protection_level_response). */
export function protectionLevelOf(value: PValue | undefined): number {
  if (!value || value.flags !== 0 || value.type !== DataType.UDInt || typeof value.value !== 'number')
    throw new ProtocolError(
      `S7CommPlus: the protection level is not a UDInt (${value ? `flags 0x${value.flags.toString(16)}, datatype 0x${value.type.toString(16)}` : 'no value'})`,
    );
  return value.value;
}

/** The challenge of a GetVarSubStreamed answer: a USInt array, or a Blob (connection.py _parse_get_var_substreamed_response). */
export function challengeOf(value: PValue | undefined): Buffer {
  if (value && value.type === DataType.USInt && value.flags & PValueFlag.Array && Array.isArray(value.value))
    return Buffer.from(value.value as number[]);
  if (value && value.type === DataType.Blob && value.flags === 0 && typeof value.value === 'object' && value.value && 'data' in value.value)
    return Buffer.from(value.value.data);
  throw new ProtocolError('S7CommPlus: the legitimation challenge is neither a USInt array nor a Blob');
}

/** The legacy form's answer (SHA-1 XOR challenge) as the PLC takes it: a USInt array (connection.py _send_legitimation_legacy). */
export function legacyAnswerValue(answer: Buffer): PValue {
  return { flags: PValueFlag.Array, type: DataType.USInt, value: [...answer] };
}

/** The new form's encrypted credentials as the PLC takes them: a Blob of root id 0 (connection.py _send_legitimation_new). */
export function credentialsBlobValue(encrypted: Buffer): PValue {
  return scalar(DataType.Blob, { rootId: 0, data: encrypted });
}

export interface Credentials {
  /** LegitimationType: 1 with the password as its SHA-1 (no user), 2 with a user and the password itself. */
  type: number;
  username: Buffer;
  password: Buffer;
}

/** The new form's credentials in plain text, before the AES encryption (legitimation.py _build_legitimation_payload). */
export function encodeCredentials(c: Credentials): Buffer {
  const blob = (data: Buffer): PValue => scalar(DataType.Blob, { rootId: 0, data });
  const w = new Writer();
  writePValue(w, {
    flags: 0,
    type: DataType.Struct,
    value: {
      id: Ids.LegitimationPayloadStruct,
      members: [
        { key: Ids.LegitimationPayloadType, value: scalar(DataType.UDInt, c.type) },
        { key: Ids.LegitimationPayloadUsername, value: blob(c.username) },
        { key: Ids.LegitimationPayloadPassword, value: blob(c.password) },
      ],
    },
  });
  return w.toBuffer();
}

/** Credentials decrypted (the simulator's side); ProtocolError for anything else. */
export function decodeCredentials(plain: Buffer): Credentials {
  const r = new Reader(plain);
  const v = readPValue(r);
  r.done('legitimation credentials');
  const s = v.value;
  if (
    v.flags !== 0 ||
    v.type !== DataType.Struct ||
    !s ||
    typeof s !== 'object' ||
    !('members' in s) ||
    s.id !== Ids.LegitimationPayloadStruct
  )
    throw new ProtocolError(`S7CommPlus: legitimation credentials are not Struct ${Ids.LegitimationPayloadStruct}`);
  const member = (key: number) => s.members.find((m) => m.key === key)?.value;
  const blob = (key: number): Buffer => {
    const m = member(key)?.value;
    if (m && typeof m === 'object' && 'data' in m) return Buffer.from(m.data);
    throw new ProtocolError(`S7CommPlus: legitimation credentials without Blob ${key}`);
  };
  const type = member(Ids.LegitimationPayloadType)?.value;
  if (typeof type !== 'number') throw new ProtocolError('S7CommPlus: legitimation credentials without their type');
  return { type, username: blob(Ids.LegitimationPayloadUsername), password: blob(Ids.LegitimationPayloadPassword) };
}

/**
 * The device string ("PAOM": `<id>;<order number>;<firmware>`, e.g.
 * `1;6ES7 513-1AL02-0AB0;V3.1`) of a ServerSessionVersion: member 319 of its
 * struct, a WString. Undefined when there is none (a bare UDInt version).
 */
export function paomString(version: PValue | undefined): string | undefined {
  const s = version?.value;
  if (!version || version.type !== DataType.Struct || !s || typeof s !== 'object' || !('members' in s)) return undefined;
  const m = s.members.find((x) => x.key === Ids.SessionVersionSystemPaomString);
  return m && m.value.type === DataType.WString && typeof m.value.value === 'string' ? m.value.value : undefined;
}

export type LegitimationForm = 'new' | 'legacy';

/**
 * The form of legitimation a firmware takes, from the device string of its
 * ServerSessionVersion (`1;6ES7 513-1AL02-0AB0;V3.1`); undefined when it
 * takes none we know. The series is the first digit of the last three-digit
 * model number after a 1 or 7 (PLCSIM's "SIM-01500" reads 500), the firmware
 * major*100+minor. s7commplus (MIT), legitimation.py _parse_paom_string and
 * decide_legitimation_mode (which cite thomas-v2/S7CommPlusDriver, facts only).
 */
export function legitimationForm(paom: string): LegitimationForm | undefined {
  const fields = paom.split(';');
  if (fields.length < 3 || paom.includes('\n')) return undefined;
  const firmware = /^[VS](\d{1,2})\.(\d{1,4})$/i.exec(fields[fields.length - 1]!);
  const series = seriesOf(fields[1]!);
  if (!firmware || series === undefined) return undefined;
  const fw = Number(firmware[1]) * 100 + Number(firmware[2]);
  if (series === '5') return fw < 209 ? undefined : fw < 301 ? 'legacy' : 'new';
  if (series === '2' && paom.toUpperCase().includes('50-0XB0')) return 'new'; // S7-1200 G2
  if (series === '2') return fw < 403 ? undefined : fw < 407 ? 'legacy' : 'new';
  if (series === '6') return fw < 2109 ? undefined : 'legacy'; // S7-1507S software controller
  return undefined;
}

function seriesOf(order: string): string | undefined {
  let last: string | undefined;
  for (let i = 0; i < order.length; i++) {
    if (order[i] !== '1' && order[i] !== '7') continue;
    const m = /^\s*(\d)\d\d/.exec(order.slice(i + 1, i + 1 + 64));
    if (m) last = m[1];
  }
  return last;
}
