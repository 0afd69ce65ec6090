/**
 * The payloads of the session handshake, pure: InitSSL, the CreateObject of
 * a ServerSession (the client introduces itself as TIA does), the session
 * setup write that echoes the ServerSessionVersion, and the reading of the
 * CreateObject answer. Layouts from s7commplus (MIT), connection.py
 * (_init_ssl, _create_session, _build_session_setup_frame) and codec.py
 * (parse_create_object_attributes, encode_object_qualifier).
 */
import { ProtocolError } from '../../errors';
import { readVlqU32, vlqU32 } from './frame';
import { Element, ObjectId } from './ids';
import { skipValue } from './pvalue-skip';

const UDINT = 0x04;
const RID = 0x12;
const AID = 0x13;
const WSTRING = 0x15;

/** InitSSL: nothing but the trailing u32 after the request header. */
export function initSslPayload(): Buffer {
  return Buffer.alloc(4);
}

function attribute(id: number, type: number, value: Buffer): Buffer {
  return Buffer.concat([Buffer.from([Element.ATTRIBUTE]), vlqU32(id), Buffer.from([0x00, type]), value]);
}

function wstring(id: number, text: string): Buffer {
  const bytes = Buffer.from(text, 'utf8');
  return attribute(id, WSTRING, Buffer.concat([vlqU32(bytes.length), bytes]));
}

function objectStart(classId: number): Buffer {
  const relation = Buffer.alloc(4);
  relation.writeUInt32BE(ObjectId.GET_NEW_RID_ON_SERVER);
  return Buffer.concat([Buffer.from([Element.START_OF_OBJECT]), relation, vlqU32(classId), vlqU32(0), vlqU32(0)]);
}

/**
 * The CreateObject of a ServerSession under the server session container,
 * with the client's names (attributes 233, 289, 296–301) and a nested
 * subscription container: connection.py says S7-1200 firmware answers a
 * fuller session only to a client that introduces itself so.
 */
export function createObjectPayload(clientName = 'plcwire'): Buffer {
  const head = Buffer.alloc(4);
  head.writeUInt32BE(ObjectId.OBJECT_SERVER_SESSION_CONTAINER);
  const rid = Buffer.alloc(4);
  rid.writeUInt32BE(0x80c3c901);
  return Buffer.concat([
    head,
    Buffer.from([0x00, UDINT]),
    vlqU32(0),
    Buffer.alloc(4),
    objectStart(ObjectId.CLASS_SERVER_SESSION),
    wstring(ObjectId.OBJECT_VARIABLE_TYPE_NAME, clientName),
    wstring(289, `1:::6.0::${clientName}`),
    wstring(296, clientName),
    wstring(297, ''),
    wstring(298, clientName),
    attribute(299, UDINT, vlqU32(1)),
    attribute(ObjectId.SERVER_SESSION_CLIENT_RID, RID, rid),
    wstring(301, ''),
    objectStart(ObjectId.CLASS_SUBSCRIPTIONS),
    wstring(ObjectId.OBJECT_VARIABLE_TYPE_NAME, 'SubscriptionContainer'),
    Buffer.from([Element.TERMINATING_OBJECT, Element.TERMINATING_OBJECT]),
    Buffer.alloc(4),
  ]);
}

/** What the CreateObject answer gives the session. */
export interface CreatedSession {
  /** The PLC's return value (0: fine; some S7-1200 answer non-zero on a usable TLS session). */
  returnValue: number;
  sessionId: number;
  /** The ServerSessionVersion attribute as it came (flags, type, value), to echo back; undefined when absent. */
  serverSessionVersion: Buffer | undefined;
}

/** Reads a CreateObject answer (after the response header): return value, object ids, attribute 306. */
export function readCreateObject(payload: Buffer): CreatedSession {
  let at = 0;
  const ret = readVlqU64Small(payload, at);
  at += ret.length;
  const count = payload[at++];
  if (count === undefined || count === 0) throw new ProtocolError('S7CommPlus: the CreateObject answer names no session object');
  const first = readVlqU32(payload, at);
  at += first.length;
  for (let i = 1; i < count; i++) at += readVlqU32(payload, at).length;
  return {
    returnValue: ret.value,
    sessionId: first.value,
    serverSessionVersion: findAttribute(payload, at, ObjectId.SERVER_SESSION_VERSION),
  };
}

/** A return value (a 64-bit VLQ) read as a number: exact up to 2^53, which tells 0 from not 0 all the same. */
function readVlqU64Small(buf: Buffer, offset: number): { value: number; length: number } {
  let value = 0;
  for (let i = 0; i < 9; i++) {
    const b = buf[offset + i];
    if (b === undefined) throw new ProtocolError('S7CommPlus: a return value runs past the end of the answer');
    if (i === 8) return { value: value * 256 + b, length: 9 };
    value = value * 128 + (b & 0x7f);
    if ((b & 0x80) === 0) return { value, length: i + 1 };
  }
  throw new ProtocolError('S7CommPlus: a return value is malformed');
}

/**
 * Walks an object tree (start of object, attribute, end of object) from
 * `offset` for the attribute `id`; its typed value's bytes, or undefined.
 */
function findAttribute(buf: Buffer, offset: number, id: number): Buffer | undefined {
  let at = offset;
  while (at < buf.length) {
    const tag = buf[at++]!;
    if (tag === Element.START_OF_OBJECT) {
      at += 4; // relation id
      for (let i = 0; i < 3; i++) at += readVlqU32(buf, at).length; // class id, class flags, attribute id
    } else if (tag === Element.TERMINATING_OBJECT) {
      continue;
    } else if (tag === Element.ATTRIBUTE) {
      const attr = readVlqU32(buf, at);
      at += attr.length;
      const end = skipValue(buf, at);
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
  id.writeUInt32BE(1256);
  const rid = Buffer.alloc(4);
  const key = v1
    ? Buffer.concat([Buffer.from([0x00, UDINT]), Buffer.alloc(4)])
    : Buffer.concat([Buffer.from([0x00, UDINT]), vlqU32(0), Buffer.from([0x00])]);
  return Buffer.concat([
    id,
    vlqU32(1257),
    Buffer.from([0x00, RID]),
    rid,
    vlqU32(1258),
    Buffer.from([0x00, AID]),
    vlqU32(0),
    vlqU32(1259),
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
    vlqU32(ObjectId.SERVER_SESSION_VERSION),
    vlqU32(1),
    serverSessionVersion,
    Buffer.from([0x00]),
    objectQualifier(v1),
    Buffer.alloc(4),
  ]);
}

/** The session setup's answer: accepted when its return value is 0. */
export function setupAccepted(payload: Buffer): boolean {
  return payload.length > 0 && readVlqU64Small(payload, 0).value === 0;
}
