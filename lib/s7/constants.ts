/**
 * S7comm protocol constants. Sources: the publicly documented S7comm
 * dissector field tables; the bytes and tables are in docs/protocols.md,
 * "S7comm over ISO-on-TCP". TPKT and COTP's own sizes and codes (RFC 1006,
 * ISO 8073 = RFC 905) are in lib/iso/constants.ts.
 */
import { PlcError, type PlcErrorCode } from '../errors';
import type { AreaName } from '../types';
import { hex4 } from '../values/text';

export const S7_PORT = 102;
export const S7_PROTOCOL_ID = 0x32;
export const S7_JOB_HEADER = 10;
export const S7_ACK_HEADER = 12;
/** Function code and item count: the parameters of a Read/Write Var job, and of its answer, before the items. */
export const VAR_PARAMETER_HEAD = 2;
/** S7 bytes of a Read/Write Var job before its request items (12). */
export const VAR_REQUEST_BASE = S7_JOB_HEADER + VAR_PARAMETER_HEAD;
/** S7 bytes of a Read/Write Var answer before its data items (14). */
export const VAR_RESPONSE_BASE = S7_ACK_HEADER + VAR_PARAMETER_HEAD;
/** A request item (the variable specification), in Read Var and Write Var jobs alike. */
export const READ_ITEM = 12;
/** Return code, transport size and length in front of each data item of a Read Var answer. */
export const READ_RESPONSE_ITEM_HEADER = 4;
/** Return code, transport size and length in front of each data item of a Write Var job. */
export const WRITE_DATA_HEADER = 4;
/** The PDU sizes the client and the planner work with: at least 64, at most what the setup's 2-byte field holds. */
export const MIN_PDU_SIZE = 64;
export const MAX_PDU_SIZE = 0xffff;

// ---------------------------------------------------------------- the handshake

/** Parallel jobs (AmQ) a client asks for in setup communication; the PLC answers with what it grants. */
export const REQUESTED_AMQ = 8;
/** TPDU size code a client asks for in its COTP connection request (ISO-on-TCP's, shared with S7CommPlus). */
export { TPDU_SIZE_CODE } from '../iso/constants';
export const enum Rosctr {
  Job = 1,
  Ack = 2,
  AckData = 3,
  UserData = 7,
}

export const enum S7Function {
  Setup = 0xf0,
  ReadVar = 0x04,
  WriteVar = 0x05,
}

/** Area codes of a request item. */
export const enum S7Area {
  PE_PA = 0x80,
  I = 0x81,
  Q = 0x82,
  M = 0x83,
  DB = 0x84,
  /** S7 counters (S5 style, 2 bytes each). */
  C = 0x1c,
  /** S7 timers (S5 style, 2 bytes each). */
  T = 0x1d,
  /** IEC counters (S7-200 family). */
  IEC_C = 0x1e,
  /** IEC timers (S7-200 family). */
  IEC_T = 0x1f,
}

export const AREA_CODES: Readonly<Record<AreaName, S7Area>> = Object.freeze({
  I: S7Area.I,
  Q: S7Area.Q,
  M: S7Area.M,
  DB: S7Area.DB,
  PE: S7Area.PE_PA,
  PA: S7Area.PE_PA,
  C: S7Area.C,
  T: S7Area.T,
});

/**
 * Transport size of a request item (how `count` is counted): the data type
 * code of the ANY pointer (Siemens, STEP 7 help "Format of the Parameter Type
 * ANY": 01 BOOL … 08 REAL, 09 DATE, 0A TIME_OF_DAY, 0B TIME, 0C S5TIME,
 * 0E DATE_AND_TIME, 13 STRING, 1C COUNTER, 1D TIMER).
 */
export const enum TransportSize {
  BIT = 0x01,
  BYTE = 0x02,
  CHAR = 0x03,
  WORD = 0x04,
  INT = 0x05,
  DWORD = 0x06,
  DINT = 0x07,
  REAL = 0x08,
  DATE = 0x09,
  TIME_OF_DAY = 0x0a,
  TIME = 0x0b,
  S5TIME = 0x0c,
  DATE_AND_TIME = 0x0e,
  /** STRING in the ANY table; Apache PLC4X asks for WCHAR with it (count 1 = one 2-byte WCHAR). */
  STRING = 0x13,
  COUNTER = 0x1c,
  TIMER = 0x1d,
}

/** Transport size of a data item (how its length is counted). */
export const enum DataTransportSize {
  NULL = 0x00,
  /** length in bits (one bit) */
  BIT = 0x03,
  /** length in bits */
  BYTE = 0x04,
  /** length in bits */
  INTEGER = 0x05,
  /** length in bytes */
  REAL = 0x07,
  /** length in bytes */
  OCTET_STRING = 0x09,
}

/** Most items one Read/Write Var job can carry (the item count is one byte). */
export const MAX_ITEMS = 255;

/**
 * Items per Read/Write Var job the client sends unless the URL says more
 * (`maxItems=N`): 20. snap7's server serves at most 20 (`MaxVars` in its
 * s7_types.h): it answers the first 20 items of a longer read as if that
 * were all, and a longer write overruns its fixed table of 20. So do the
 * devices and simulators built on snap7, and VIPA CPUs (frangoteam/FUXA#694:
 * more than 20 tags fail on a VIPA CPU, work on an S7-1200 and S7-1500).
 * Siemens CPUs limit a job by the PDU size only (12 + 12·items ≤ PDU: 19 at
 * PDU 240, 39 at 480, 79 at 960; S7NetPlus/s7netplus#157, #380: 36 items
 * written to an S7-1500 in one job).
 */
export const DEFAULT_MAX_ITEMS = 20;

/** Return codes of a read/write item. */
export const enum ReturnCode {
  Reserved = 0x00,
  HardwareFault = 0x01,
  AccessDenied = 0x03,
  AddressOutOfRange = 0x05,
  DataTypeNotSupported = 0x06,
  DataTypeInconsistent = 0x07,
  ObjectDoesNotExist = 0x0a,
  Success = 0xff,
}

const RETURN_CODES: Readonly<Record<number, [PlcErrorCode, string]>> = Object.freeze({
  0x00: ['PLC_ERROR', 'reserved return code 0x00'],
  0x01: ['PLC_ERROR', 'hardware fault'],
  0x03: ['ACCESS_DENIED', 'access denied (object access not allowed)'],
  0x05: ['ADDRESS_OUT_OF_RANGE', 'address out of range (beyond the end of the area or data block)'],
  0x06: ['TYPE_NOT_SUPPORTED', 'data type not supported'],
  0x07: ['TYPE_NOT_SUPPORTED', 'data type inconsistent (size mismatch)'],
  0x0a: ['OBJECT_DOES_NOT_EXIST', 'object does not exist (missing DB?)'],
});

/** The words and error code of an item return code. */
export function describeReturnCode(code: number): { code: PlcErrorCode; text: string } {
  const known = RETURN_CODES[code];
  if (known) return { code: known[0], text: known[1] };
  return { code: 'PLC_ERROR', text: `unknown return code 0x${code.toString(16).padStart(2, '0')}` };
}

/** An item return code as a typed PlcError: `${context}: the PLC answered 0x0A: object does not exist (missing DB?)`. */
export function returnCodeError(returnCode: number, context?: string, tag?: string): PlcError {
  const { code, text } = describeReturnCode(returnCode);
  const hex = `0x${returnCode.toString(16).padStart(2, '0').toUpperCase()}`;
  return new PlcError(
    code,
    `${context === undefined ? '' : `${context}: `}the PLC answered ${hex}: ${text}`,
    tag === undefined ? { plcCode: returnCode } : { plcCode: returnCode, tag },
  );
}

/**
 * Error class of an ack or ack-data header (its byte 10), with the names of
 * the S7comm dissector's error-class table (wireshark/wireshark,
 * epan/dissectors/packet-s7comm.c, `errcls_names`).
 */
export const enum HeaderErrorClass {
  NoError = 0x00,
  ApplicationRelationship = 0x81,
  ObjectDefinition = 0x82,
  NoResources = 0x83,
  ServiceProcessing = 0x84,
  Supplies = 0x85,
  Access = 0x87,
}

/**
 * The header errors (class << 8 | code) a simulated CPU refuses a whole job
 * with; the words are HEADER_ERRORS' and SERVICE_ERRORS'. 0x8104: class 0x81,
 * code 4, "function not supported" (S7NetPlus/s7netplus#403 shows an
 * S7-1200/1500 without PUT/GET answering `32 02 … 81 04`); 0x8500: class 0x85,
 * code 0, the PDU does not fit the negotiated size; 0xD241: the protection
 * level forbids the job (the error field of the CPU services, sent as the
 * header error of an ack).
 */
export const enum HeaderError {
  FunctionNotSupported = (HeaderErrorClass.ApplicationRelationship << 8) | 0x04,
  PduTooLarge = (HeaderErrorClass.Supplies << 8) | 0x00,
  ProtectionLevel = 0xd241,
}

/** Header error class (ack and ack-data PDUs). */
const ERROR_CLASSES: Readonly<Record<number, string>> = Object.freeze({
  0x00: 'no error',
  0x81: 'application relationship error',
  0x82: 'object definition error',
  0x83: 'no resources available',
  0x84: 'error on service processing',
  0x85: 'error on supplies',
  0x87: 'access error',
});

/** Well-known header errors (class << 8 | code). */
const HEADER_ERRORS: Readonly<Record<number, [PlcErrorCode, string]>> = Object.freeze({
  0x8104: [
    'ACCESS_DENIED',
    'function not supported or access denied: PUT/GET access is not enabled on this S7-1200/1500 (or the block is optimized)',
  ],
  0x8304: ['ACCESS_DENIED', 'no resources / access denied: PUT/GET access is not enabled on this S7-1200/1500'],
  0x8404: ['PROTOCOL_ERROR', 'fatal error in the protocol'],
  0x8500: ['PDU_TOO_LARGE', 'PDU too large for the negotiated size'],
  0x8702: ['PLC_ERROR', 'the PLC is not in a state to serve the request'],
  0xd209: ['OBJECT_DOES_NOT_EXIST', 'block not found'],
  0xd241: ['ACCESS_DENIED', 'the protection level forbids it (enter the password)'],
  0xd401: ['PLC_ERROR', 'invalid parameter'],
});

/** A header error (class, code) as a typed PlcError with words. */
export function headerError(errorClass: number, errorCode: number, context: string): PlcError {
  const key = (errorClass << 8) | errorCode;
  const hex = `0x${hex4(key)}`;
  const known = HEADER_ERRORS[key];
  if (known) return new PlcError(known[0], `${context}: the PLC answered ${hex}: ${known[1]}`, { plcCode: key });
  const cls = ERROR_CLASSES[errorClass] ?? 'unknown error class';
  return new PlcError('PLC_ERROR', `${context}: the PLC answered ${hex} (${cls})`, { plcCode: key });
}

export { remoteTsapFor } from './tsap';

// ---------------------------------------------------------------- userdata (ROSCTR 7) and CPU services

/** Parameter head of every userdata PDU. */
export const USERDATA_HEAD = 0x000112;
/** Method byte: a request, or a response (also sent by a client to ask for the next part of a multi-part answer). */
export const enum UserdataMethod {
  Request = 0x11,
  Response = 0x12,
}
/** High nibble of the type/group byte. */
export const enum UserdataType {
  Push = 0x0,
  Request = 0x4,
  Response = 0x8,
}
/** Low nibble of the type/group byte: the function group. */
export const enum UserdataGroup {
  Programmer = 0x1,
  Cyclic = 0x2,
  Block = 0x3,
  /** CPU functions: read SZL. */
  Cpu = 0x4,
  Security = 0x5,
  Time = 0x7,
}
export const enum BlockSubfunction {
  ListAll = 0x01,
  ListType = 0x02,
  BlockInfo = 0x03,
}
export const enum CpuSubfunction {
  ReadSzl = 0x01,
}
export const enum SecuritySubfunction {
  SetPassword = 0x01,
  ClearPassword = 0x02,
}
export const enum TimeSubfunction {
  ReadClock = 0x01,
  SetClock = 0x02,
}
/** "Last data unit" byte of a 12-byte userdata parameter part. */
export const LAST_DATA_UNIT = 0x00;
export const MORE_DATA_UNITS = 0x01;

/** Job (ROSCTR 1) functions of the CPU services: PLC control and block upload. */
export const enum ControlFunction {
  StartUpload = 0x1d,
  Upload = 0x1e,
  EndUpload = 0x1f,
  PiService = 0x28,
  PlcStop = 0x29,
}

/** Block types as the block functions name them (ASCII characters). */
export const BLOCK_TYPES = Object.freeze({ OB: 0x38, DB: 0x41, SDB: 0x42, FC: 0x43, SFC: 0x44, FB: 0x45, SFB: 0x46 } as const);
export type BlockType = keyof typeof BLOCK_TYPES;
/** The code of a block type name ("DB" → 0x41); undefined for anything else. */
export function blockTypeCode(name: string): number | undefined {
  return Object.prototype.hasOwnProperty.call(BLOCK_TYPES, name) ? BLOCK_TYPES[name as BlockType] : undefined;
}
/** The name of a block type code (0x41 → "DB"); undefined for an unknown code. */
export function blockTypeName(code: number): BlockType | undefined {
  return (Object.keys(BLOCK_TYPES) as BlockType[]).find((k) => BLOCK_TYPES[k] === code);
}
/** Sub-block type byte of block info and of a block's header (OB 0x08, DB 0x0A …), by block type. */
export const SUBBLOCK_TYPES: Readonly<Record<BlockType, number>> = Object.freeze({
  OB: 0x08,
  DB: 0x0a,
  SDB: 0x0b,
  FC: 0x0c,
  SFC: 0x0d,
  FB: 0x0e,
  SFB: 0x0f,
});
/** Programming languages of a block (block info byte "language"). */
export const BLOCK_LANGUAGES: Readonly<Record<number, string>> = Object.freeze({
  0x00: 'undefined',
  0x01: 'STL',
  0x02: 'LAD',
  0x03: 'FBD',
  0x04: 'SCL',
  0x05: 'DB',
  0x06: 'GRAPH',
  0x07: 'SDB',
  0x08: 'CPU-DB',
  0x11: 'SDB (after overall reset)',
  0x12: 'SDB (routing)',
  0x29: 'encrypted',
});

/**
 * Error codes of CPU services: the 2-byte error field of a userdata
 * response's parameters, and the header error (class << 8 | code) of a
 * refused control or upload job. One table for the simulator (which picks
 * codes from it) and the client (which turns them into words).
 */
export const SERVICE_ERRORS: Readonly<Record<number, readonly [PlcErrorCode, string]>> = Object.freeze({
  0x8104: ['NOT_SUPPORTED', 'this CPU does not offer the service (function not implemented)'],
  0x8304: ['PLC_ERROR', 'no resources for another upload'],
  0x8402: ['PLC_ERROR', 'the CPU is not in a state to perform the service'],
  0x8500: ['PDU_TOO_LARGE', 'the request does not fit the negotiated PDU'],
  0xd0a1: ['ACCESS_DENIED', 'the protection level forbids it (enter the password)'],
  0xd209: ['OBJECT_DOES_NOT_EXIST', 'block not found'],
  0xd20e: ['OBJECT_DOES_NOT_EXIST', 'no (further) block of that type'],
  0xd241: ['ACCESS_DENIED', 'the protection level forbids it (enter the password)'],
  0xd401: ['SZL_NOT_AVAILABLE', 'the SZL ID is not available on this CPU'],
  0xd402: ['SZL_NOT_AVAILABLE', 'the SZL index is not available on this CPU'],
  0xd405: ['NOT_SUPPORTED', 'service not supported, or a syntax error in its parameters'],
  0xd602: ['ACCESS_DENIED', 'wrong password'],
  0xd604: ['PLC_ERROR', 'the connection is already enabled'],
  0xd605: ['PLC_ERROR', 'the CPU has no password set'],
  0xdc01: ['INVALID_VALUE', 'date and/or time invalid'],
});

/** A CPU service error as a typed PlcError: `${context}: the PLC answered 0xd401: the SZL ID is not available on this CPU`. */
export function serviceError(code: number, context: string): PlcError {
  const hex = `0x${hex4(code)}`;
  const known = SERVICE_ERRORS[code];
  if (known) return new PlcError(known[0], `${context}: the PLC answered ${hex}: ${known[1]}`, { plcCode: code });
  return headerError(code >> 8, code & 0xff, context);
}
