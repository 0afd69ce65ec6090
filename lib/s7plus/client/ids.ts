/**
 * The numbers the client's session layer puts on the wire: frame header,
 * opcodes, function codes, transport flags, the objects of the session
 * handshake. Facts from s7commplus (MIT), protocol.py (Opcode,
 * FunctionCode, ProtocolVersion, ObjectId, READ_FUNCTION_CODES,
 * FLAGS_34_FUNCTION_CODES) and connection.py (_init_ssl, _create_session,
 * _setup_session, _delete_session). The codec's constants table
 * (lib/s7plus/constants.ts) takes them over once it exists.
 */

/** First byte of every S7CommPlus frame header: 0x72, version, data length (u16). */
export const PROTOCOL_ID = 0x72;

/** The frame header's version byte. */
export const Version = Object.freeze({ V1: 0x01, V2: 0x02, V3: 0x03, SYSTEM_EVENT: 0xfe });

export const Opcode = Object.freeze({ REQUEST: 0x31, RESPONSE: 0x32, NOTIFICATION: 0x33, RESPONSE2: 0x02 });

export const Fn = Object.freeze({
  ERROR: 0x04b1,
  EXPLORE: 0x04bb,
  CREATE_OBJECT: 0x04ca,
  DELETE_OBJECT: 0x04d4,
  SET_VARIABLE: 0x04f2,
  GET_VARIABLE: 0x04fc,
  GET_LINK: 0x0524,
  SET_MULTI_VARIABLES: 0x0542,
  GET_MULTI_VARIABLES: 0x054c,
  GET_VAR_SUBSTREAMED: 0x0586,
  GET_VARIABLES_ADDRESS: 0x0590,
  INIT_SSL: 0x05b3,
});

/**
 * The requests that advance the read IntegrityId; every other request of an
 * established session advances the write one (connection.py, _send_request).
 */
export const READ_FUNCTIONS: ReadonlySet<number> = new Set([
  Fn.GET_MULTI_VARIABLES,
  Fn.EXPLORE,
  Fn.GET_VAR_SUBSTREAMED,
  Fn.GET_LINK,
  Fn.GET_VARIABLE,
  Fn.GET_VARIABLES_ADDRESS,
]);

/** Transport flags of a request: InitSSL 0x30, the session CreateObject 0x36, the data requests 0x34. */
export const Flags = Object.freeze({ INIT_SSL: 0x30, CREATE_OBJECT: 0x36, DATA: 0x34 });

/** Object ids of the session handshake (protocol.py, ObjectId). */
export const ObjectId = Object.freeze({
  GET_NEW_RID_ON_SERVER: 211,
  CLASS_SUBSCRIPTIONS: 255,
  OBJECT_SERVER_SESSION_CONTAINER: 285,
  CLASS_SERVER_SESSION: 287,
  OBJECT_NULL_SERVER_SESSION: 288,
  SERVER_SESSION_CLIENT_RID: 300,
  SERVER_SESSION_VERSION: 306,
  OBJECT_VARIABLE_TYPE_NAME: 233,
});

/** Tags of the object serialization (protocol.py, ElementID). */
export const Element = Object.freeze({ START_OF_OBJECT: 0xa1, TERMINATING_OBJECT: 0xa2, ATTRIBUTE: 0xa3 });

/** The S7CommPlus TSAPs: the calling one, and the called one per role as ASCII (protocol.py, S7COMMPLUS_LOCAL_TSAP, ConnectionType). */
export const LOCAL_TSAP = 0x0600;
export const REMOTE_TSAP = Object.freeze({ hmi: 'SIMATIC-ROOT-HMI', es: 'SIMATIC-ROOT-ES', pg: 'SIMATIC-ROOT-PG' });

/** Bytes of a request header (opcode, reserved, function, reserved, sequence, session id, flags) and of a response header (no session id). */
export const REQUEST_HEADER = 14;
export const RESPONSE_HEADER = 10;
