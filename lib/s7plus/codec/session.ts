/**
 * The session's messages: InitSSL, CreateObject, DeleteObject.
 *
 *     InitSSL request        <fill:4>                                      (transport flags 0x30, session id 0)
 *     InitSSL response       <ReturnValue:UVLQ64> <fill:4>
 *     CreateObject request   <RequestId:4> <RequestValue:PValue> <fill:4> [IntegrityId] <object> <fill:4>
 *     CreateObject response  <ReturnValue:UVLQ64> <count:1> <ObjectId:UVLQ>… <object> <fill:4>
 *     DeleteObject request   <ObjectId:4> [IntegrityId] <fill:4>
 *     DeleteObject response  <ReturnValue:UVLQ64> <fill:4>
 *
 * The session's own CreateObject goes to RequestId 285
 * (ObjectServerSessionContainer) with session id 288 in the header and
 * transport flags 0x36; its answer's first ObjectId is the session id, the
 * second its subscription container, and its object carries
 * ServerSessionVersion (306), echoed in the session setup (variables.ts).
 * Source: s7commplus (MIT), connection.py _init_ssl, _create_session,
 * _delete_session, server.py _handle_create_object; golden frames (the
 * subscription create, with its IntegrityId before the object).
 */
import { ProtocolError } from '../../errors';
import { DataType, FunctionCode, Ids, TransportFlags } from '../constants';
import { Reader, Writer } from './bytes';
import {
  readFill,
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
import { newObject, readObject, writeObject, type PObject } from './object';
import { readPValue, scalar, writePValue, type PValue } from './pvalue';

const NO_INTEGRITY: DecodeOptions = { integrity: false };

export function encodeInitSslRequest(sequence: number): Buffer {
  const w = new Writer();
  writeRequestHeader(w, { functionCode: FunctionCode.InitSsl, sequence, sessionId: 0, transportFlags: TransportFlags.InitSsl });
  return w.u32(0).toBuffer();
}

export function decodeInitSslRequest(data: Buffer): Request<Record<string, never>> {
  const r = new Reader(data);
  const header = readRequestHeader(r, FunctionCode.InitSsl);
  return { header, body: {} };
}

export interface ReturnOnly {
  returnValue: bigint;
}

function encodeReturnOnly(fn: number, res: Response<ReturnOnly>): Buffer {
  const w = new Writer();
  writeResponseHeader(w, { ...res.header, functionCode: fn });
  w.uvlq64(res.body.returnValue);
  return writeResponseTail(w, 4, res.integrityId);
}

function decodeReturnOnly(fn: number, data: Buffer, opts: DecodeOptions): Response<ReturnOnly> {
  const r = new Reader(data);
  const header = readResponseHeader(r, fn);
  const returnValue = r.uvlq64();
  if (r.remaining >= 4) readFill(r, 4);
  const integrityId = readResponseTail(r, opts);
  return { header, body: { returnValue }, ...(integrityId === undefined ? {} : { integrityId }) };
}

export const encodeInitSslResponse = (res: Response<ReturnOnly>): Buffer => encodeReturnOnly(FunctionCode.InitSsl, res);
export const decodeInitSslResponse = (data: Buffer): Response<ReturnOnly> => decodeReturnOnly(FunctionCode.InitSsl, data, NO_INTEGRITY);

export interface CreateObjectRequest {
  requestId: number;
  requestValue: PValue;
  object: PObject;
}

export function encodeCreateObjectRequest(req: Request<CreateObjectRequest>): Buffer {
  const w = new Writer();
  writeRequestHeader(w, { ...req.header, functionCode: FunctionCode.CreateObject });
  w.u32(req.body.requestId);
  writePValue(w, req.body.requestValue);
  w.u32(0);
  if (req.integrityId !== undefined) w.uvlq32(req.integrityId);
  writeObject(w, req.body.object);
  return w.u32(0).toBuffer();
}

export function decodeCreateObjectRequest(data: Buffer, opts: DecodeOptions): Request<CreateObjectRequest> {
  const r = new Reader(data);
  const header = readRequestHeader(r, FunctionCode.CreateObject);
  const requestId = r.u32('RequestId');
  const requestValue = readPValue(r);
  readFill(r, 4);
  // The session's own CreateObject comes before the integrity ids start.
  const integrityId = header.sessionId === Ids.ObjectNullServerSession ? undefined : readIntegrity(r, opts);
  const object = readObject(r);
  readFill(r, 4);
  r.done('CreateObject request');
  return { header, body: { requestId, requestValue, object }, ...(integrityId === undefined ? {} : { integrityId }) };
}

export interface CreateObjectResponse {
  returnValue: bigint;
  objectIds: number[];
  /** Absent when the PLC refused (a non-zero return value and nothing after it). */
  object?: PObject;
}

export function encodeCreateObjectResponse(res: Response<CreateObjectResponse>): Buffer {
  const w = new Writer();
  writeResponseHeader(w, { ...res.header, functionCode: FunctionCode.CreateObject });
  w.uvlq64(res.body.returnValue).u8(res.body.objectIds.length);
  for (const id of res.body.objectIds) w.uvlq32(id);
  if (res.body.object) writeObject(w, res.body.object);
  return writeResponseTail(w, 4, res.integrityId);
}

export function decodeCreateObjectResponse(data: Buffer, opts: DecodeOptions = NO_INTEGRITY): Response<CreateObjectResponse> {
  const r = new Reader(data);
  const header = readResponseHeader(r, FunctionCode.CreateObject);
  const returnValue = r.uvlq64();
  if (r.remaining === 0 && returnValue !== 0n) return { header, body: { returnValue, objectIds: [] } };
  const count = r.u8('ObjectId count');
  const objectIds: number[] = [];
  for (let i = 0; i < count; i++) objectIds.push(r.uvlq32());
  const body: CreateObjectResponse = { returnValue, objectIds };
  if (r.peek() === 0xa1) body.object = readObject(r);
  if (r.remaining >= 4) readFill(r, 4);
  const integrityId = readResponseTail(r, opts);
  return { header, body, ...(integrityId === undefined ? {} : { integrityId }) };
}

/** How our client introduces itself in the session's CreateObject (ServerSession attributes 233, 289, 296-301). */
export interface ClientIdentity {
  /** Class name / client name (233, 296, 298). */
  name: string;
  /** ServerSession.ClientRID (300). s7commplus sends 0x80C3C901. */
  clientRid?: number;
}

const wstring = (s: string): PValue => scalar(DataType.WString, s);

/**
 * The session's CreateObject: a NullServerSession object (RelationId 211,
 * ClassId 287) with the client's attributes and a nested SubscriptionContainer
 * (ClassId 255), as s7commplus (MIT), connection.py _create_session builds it
 * (some S7-1200 firmware answers without ServerSessionVersion to fewer attributes).
 */
export function sessionCreateRequest(sequence: number, who: ClientIdentity): Request<CreateObjectRequest> {
  return {
    header: {
      functionCode: FunctionCode.CreateObject,
      sequence,
      sessionId: Ids.ObjectNullServerSession,
      transportFlags: TransportFlags.SessionCreate,
    },
    body: sessionCreateBody(who),
  };
}

/** The body of the session's CreateObject (see sessionCreateRequest). */
export function sessionCreateBody(who: ClientIdentity): CreateObjectRequest {
  const subscriptions = newObject({ relationId: Ids.GetNewRIDOnServer, classId: Ids.ClassSubscriptions }, [
    [Ids.ObjectVariableTypeName, wstring('SubscriptionContainer')],
  ]);
  const session = newObject(
    { relationId: Ids.GetNewRIDOnServer, classId: Ids.ClassServerSession },
    [
      [Ids.ObjectVariableTypeName, wstring(who.name)],
      [Ids.ServerSessionClientId, wstring(`1:::6.0::${who.name}`)],
      [Ids.ServerSessionUser, wstring(who.name)],
      [Ids.ServerSessionApplication, wstring('')],
      [Ids.ServerSessionHost, wstring(who.name)],
      [Ids.ServerSessionRole, scalar(DataType.UDInt, 1)],
      [Ids.ServerSessionClientRID, scalar(DataType.RID, who.clientRid ?? 0x80c3c901)],
      [Ids.ServerSessionComment, wstring('')],
    ],
    [subscriptions],
  );
  return { requestId: Ids.ObjectServerSessionContainer, requestValue: scalar(DataType.UDInt, 0), object: session };
}

/** What a client needs from the answer to the session's CreateObject. */
export interface SessionInfo {
  sessionId: number;
  /** 0 when the PLC names none. */
  subscriptionContainerId: number;
  /** The ServerSessionVersion attribute (306) as it came, to echo in the session setup. */
  serverSessionVersion?: PValue;
}

/** The session from a CreateObject answer; ProtocolError when the PLC refused or named no session. */
export function sessionInfo(res: CreateObjectResponse): SessionInfo {
  if (res.returnValue !== 0n)
    throw new ProtocolError(`S7CommPlus: the PLC refused the session (CreateObject returned 0x${res.returnValue.toString(16)})`, {
      plcCode: Number(res.returnValue & 0xffffn),
    });
  const [sessionId, subscriptionContainerId = 0] = res.objectIds;
  if (sessionId === undefined) throw new ProtocolError('S7CommPlus: the CreateObject answer names no session');
  // The last one: s7commplus's server sends 306 twice (USInt, then UDInt) and its client echoes the last.
  const version = res.object?.members.reduce<PValue | undefined>(
    (v, m) => (m.kind === 'attribute' && m.id === Ids.ServerSessionVersion ? m.value : v),
    undefined,
  );
  return { sessionId, subscriptionContainerId, ...(version ? { serverSessionVersion: version } : {}) };
}

export interface DeleteObjectRequest {
  objectId: number;
}

export function encodeDeleteObjectRequest(req: Request<DeleteObjectRequest>): Buffer {
  const w = new Writer();
  writeRequestHeader(w, { ...req.header, functionCode: FunctionCode.DeleteObject });
  w.u32(req.body.objectId);
  if (req.integrityId !== undefined) w.uvlq32(req.integrityId);
  return w.u32(0).toBuffer();
}

/** Also takes s7commplus's session close, whose body is only 4 zero bytes. */
export function decodeDeleteObjectRequest(data: Buffer, opts: DecodeOptions): Request<DeleteObjectRequest> {
  const r = new Reader(data);
  const header = readRequestHeader(r, FunctionCode.DeleteObject);
  const objectId = r.u32('ObjectId');
  if (r.remaining === 0) return { header, body: { objectId } };
  const integrityId = readIntegrity(r, opts);
  readFill(r, 4);
  r.done('DeleteObject request');
  return { header, body: { objectId }, ...(integrityId === undefined ? {} : { integrityId }) };
}

export const encodeDeleteObjectResponse = (res: Response<ReturnOnly>): Buffer => encodeReturnOnly(FunctionCode.DeleteObject, res);
export const decodeDeleteObjectResponse = (data: Buffer, opts: DecodeOptions): Response<ReturnOnly> =>
  decodeReturnOnly(FunctionCode.DeleteObject, data, opts);
