/**
 * The payloads of the session handshake, pure: InitSSL, the CreateObject of
 * a ServerSession (the client introduces itself as TIA does), the session
 * setup write that echoes the ServerSessionVersion, and the reading of the
 * CreateObject answer. Layouts from s7commplus (MIT), connection.py
 * (_init_ssl, _create_session, _build_session_setup_frame) and codec.py
 * (parse_create_object_attributes, encode_object_qualifier).
 */
import { ProtocolError } from '../../errors';
import { skipPValue } from '../codec/pvalue';
import { decodeUVlq32 as readVlqU32, decodeUVlq64, encodeUVlq32 as vlqU32 } from '../codec/vlq';
import { DataType, ElementId as Element, Ids } from '../constants';

const { UDInt: UDINT, RID, AID, WString: WSTRING } = DataType;

/** InitSSL: nothing but the trailing u32 after the request header. */
export function initSslPayload(): Buffer {
  return Buffer.alloc(4);
}

function attribute(id: number, type: number, value: Buffer): Buffer {
  return Buffer.concat([Buffer.from([Element.Attribute]), vlqU32(id), Buffer.from([0x00, type]), value]);
}

function wstring(id: number, text: string): Buffer {
  const bytes = Buffer.from(text, 'utf8');
  return attribute(id, WSTRING, Buffer.concat([vlqU32(bytes.length), bytes]));
}

function objectStart(classId: number): Buffer {
  const relation = Buffer.alloc(4);
  relation.writeUInt32BE(Ids.GetNewRIDOnServer);
  return Buffer.concat([Buffer.from([Element.StartOfObject]), relation, vlqU32(classId), vlqU32(0), vlqU32(0)]);
}

/**
 * The CreateObject of a ServerSession under the server session container,
 * with the client's names (attributes 233, 289, 296–301) and a nested
 * subscription container: connection.py says S7-1200 firmware answers a
 * fuller session only to a client that introduces itself so.
 */
export function createObjectPayload(clientName = 'plcwire'): Buffer {
  const head = Buffer.alloc(4);
  head.writeUInt32BE(Ids.ObjectServerSessionContainer);
  const rid = Buffer.alloc(4);
  rid.writeUInt32BE(0x80c3c901);
  return Buffer.concat([
    head,
    Buffer.from([0x00, UDINT]),
    vlqU32(0),
    Buffer.alloc(4),
    objectStart(Ids.ClassServerSession),
    wstring(Ids.ObjectVariableTypeName, clientName),
    wstring(Ids.ServerSessionClientId, `1:::6.0::${clientName}`),
    wstring(Ids.ServerSessionUser, clientName),
    wstring(Ids.ServerSessionApplication, ''),
    wstring(Ids.ServerSessionHost, clientName),
    attribute(Ids.ServerSessionRole, UDINT, vlqU32(1)),
    attribute(Ids.ServerSessionClientRID, RID, rid),
    wstring(Ids.ServerSessionComment, ''),
    objectStart(Ids.ClassSubscriptions),
    wstring(Ids.ObjectVariableTypeName, 'SubscriptionContainer'),
    Buffer.from([Element.TerminatingObject, Element.TerminatingObject]),
    Buffer.alloc(4),
  ]);
}

/** What the CreateObject answer gives the session. */
export interface CreatedSession {
  /** The PLC's return value (0: fine; some S7-1200 answer non-zero on a usable TLS session). */
  returnValue: bigint;
  sessionId: number;
  /** The ServerSessionVersion attribute as it came (flags, type, value), to echo back; undefined when absent. */
  serverSessionVersion: Buffer | undefined;
}

/** Reads a CreateObject answer (after the response header): return value, object ids, attribute 306. */
export function readCreateObject(payload: Buffer): CreatedSession {
  let at = 0;
  const ret = decodeUVlq64(payload, at);
  at += ret.length;
  const count = payload[at++];
  if (count === undefined || count === 0) throw new ProtocolError('S7CommPlus: the CreateObject answer names no session object');
  const first = readVlqU32(payload, at);
  at += first.length;
  for (let i = 1; i < count; i++) at += readVlqU32(payload, at).length;
  return {
    returnValue: ret.value,
    sessionId: first.value,
    serverSessionVersion: findAttribute(payload, at, Ids.ServerSessionVersion),
  };
}

/**
 * Walks an object tree (start of object, attribute, end of object) from
 * `offset` for the attribute `id`; its typed value's bytes, or undefined.
 */
function findAttribute(buf: Buffer, offset: number, id: number): Buffer | undefined {
  let at = offset;
  while (at < buf.length) {
    const tag = buf[at++]!;
    if (tag === Element.StartOfObject) {
      at += 4; // relation id
      for (let i = 0; i < 3; i++) at += readVlqU32(buf, at).length; // class id, class flags, attribute id
    } else if (tag === Element.TerminatingObject) {
      continue;
    } else if (tag === Element.Attribute) {
      const attr = readVlqU32(buf, at);
      at += attr.length;
      const end = skipPValue(buf, at);
      if (attr.value === id) return Buffer.from(buf.subarray(at, end));
      at = end;
    } else {
      return undefined; // the trailing fill, or an element the session does not need
    }
  }
  return undefined;
}

/** The object qualifier every data request ends with (codec.py, encode_object_qualifier): parent RID, composition AID, key qualifier. */
export function objectQualifier(v1: boolean): Buffer {
  const id = Buffer.alloc(4);
  id.writeUInt32BE(Ids.ObjectQualifier);
  const rid = Buffer.alloc(4);
  const key = v1
    ? Buffer.concat([Buffer.from([0x00, UDINT]), Buffer.alloc(4)])
    : Buffer.concat([Buffer.from([0x00, UDINT]), vlqU32(0), Buffer.from([0x00])]);
  return Buffer.concat([
    id,
    vlqU32(Ids.ParentRID),
    Buffer.from([0x00, RID]),
    rid,
    vlqU32(Ids.CompositionAID),
    Buffer.from([0x00, AID]),
    vlqU32(0),
    vlqU32(Ids.KeyQualifier),
    key,
  ]);
}

/**
 * The session setup write (SetMultiVariables of attribute 306 on the
 * session): the ServerSessionVersion echoed as the PLC sent it.
 */
export function sessionSetupPayload(sessionId: number, serverSessionVersion: Buffer, v1: boolean): Buffer {
  const head = Buffer.alloc(4);
  head.writeUInt32BE(sessionId >>> 0);
  return Buffer.concat([
    head,
    vlqU32(1),
    vlqU32(1),
    vlqU32(Ids.ServerSessionVersion),
    vlqU32(1),
    serverSessionVersion,
    Buffer.from([0x00]),
    objectQualifier(v1),
    Buffer.alloc(4),
  ]);
}

/** The session setup's answer: accepted when its return value is 0. */
export function setupAccepted(payload: Buffer): boolean {
  return payload.length > 0 && decodeUVlq64(payload, 0).value === 0n;
}
