/**
 * The ids the simulator answers with, each from a public source: s7commplus
 * (MIT) protocol.py, typeinfo.py, server.py and tag_browser.py, which take
 * them from thomas-v2/S7CommPlusDriver Core/Ids.cs (facts only) and
 * captures of S7-1200/1500 CPUs and PLCSIM Advanced.
 */

/** The frame's first byte and the trailer after each frame (protocol.py PROTOCOL_ID). */
export const PROTOCOL_ID = 0x72;
/** Frame versions: V1 before the session, V2 for data on a TLS session (connection.py). */
export const V1 = 0x01;
export const V2 = 0x02;

/** Opcodes (protocol.py Opcode). */
export const OP_REQUEST = 0x31;
export const OP_RESPONSE = 0x32;
export const OP_NOTIFICATION = 0x33;

/** Function codes (protocol.py FunctionCode). */
export const FN = Object.freeze({
  error: 0x04b1,
  explore: 0x04bb,
  createObject: 0x04ca,
  deleteObject: 0x04d4,
  setVariable: 0x04f2,
  setMultiVariables: 0x0542,
  getMultiVariables: 0x054c,
  setVarSubStreamed: 0x057c,
  getVarSubStreamed: 0x0586,
  initSsl: 0x05b3,
});

/** Requests counted by the read integrity id; every other one after the session's setup by the write id (protocol.py READ_FUNCTION_CODES). */
export const READ_FUNCTIONS: ReadonlySet<number> = new Set([FN.getMultiVariables, FN.explore, FN.getVarSubStreamed, 0x0524, 0x04fc]);

/** PValue data types on the wire (protocol.py DataType). */
export const DT = Object.freeze({
  bool: 0x01,
  usint: 0x02,
  uint: 0x03,
  udint: 0x04,
  ulint: 0x05,
  sint: 0x06,
  int: 0x07,
  dint: 0x08,
  lint: 0x09,
  byte: 0x0a,
  word: 0x0b,
  dword: 0x0c,
  lword: 0x0d,
  real: 0x0e,
  lreal: 0x0f,
  rid: 0x12,
  aid: 0x13,
  blob: 0x14,
  wstring: 0x15,
  struct: 0x17,
});

/** Object stream tags (protocol.py ElementID, typeinfo.py). */
export const EL = Object.freeze({ startOfObject: 0xa1, terminatingObject: 0xa2, attribute: 0xa3, vartypeList: 0xab, varnameList: 0xac });

/** Object and attribute ids (protocol.py Ids / ObjectId / LegitimationId). */
export const ID = Object.freeze({
  /** A DB's access area is this plus its number; the client recovers the number from the low 16 bits. */
  dbAccessAreaBase: 0x8a0e0000,
  /** The ClassId of a DataBlock object in an Explore answer. */
  dbClass: 2574,
  /** DB values (sub-area of a DB address) and I/Q/M values (sub-area of a controller area address). */
  dbValueActual: 2550,
  controllerAreaValueActual: 3736,
  /** The first LID of a by-address item: then byte offset and length. */
  lidClassicBlob: 3,
  thePlcProgram: 3,
  theCpuExecUnit: 52,
  theIArea: 80,
  theQArea: 81,
  theMArea: 82,
  typeInfoContainer: 537,
  /** typeinfo.py CLASS_OMS_TYPE_INFO_CONTAINER: the class of the object holding the type objects. */
  typeInfoContainerClass: 534,
  objectVariableTypeName: 233,
  blockNumber: 2521,
  /** typeinfo.py TI_TCOM_SIZE: the byte size of a struct type. */
  tcomSize: 1502,
  typeModificationTime: 529,
  serverSessionVersion: 306,
  sessionSetupLegitimation: 1830,
  serverSessionContainer: 285,
  nullServerSession: 288,
  /** The CPU state: a Struct attribute 0x8BD (struct id 0xD99) whose DINT member 0xD9E is 8 in RUN, 4 in STOP (PLCSIM Advanced captures in server.py). */
  operatingStateStruct: 0x8bd,
  operatingStateStructId: 0xd99,
  operatingState: 0xd9e,
  cpuExecUnitClass: 0x883,
});

/** Operating state codes (protocol.py OPERATING_STATE_*_OBSERVED). */
export const STATE_RUN = 8;
export const STATE_STOP = 4;

/**
 * A real S7-1500's ReturnValue for an Explore of an object that does not
 * exist: error flag (bit 63), code -12 in the low 16 bits (server.py,
 * _EXPLORE_NO_SUCH_OBJECT). Written as the 64-bit VLQ needs its ninth byte.
 */
export const EXPLORE_NO_SUCH_OBJECT = 0x8020ab001992fff4n;

/** The item error the simulator answers for an address it cannot serve (server.py _ITEM_ERROR). */
export const ITEM_ERROR = 0x8104;

/** The type ids of the PLC's software data types (typeinfo.py Softdatatype). */
export const SOFT = Object.freeze({
  bool: 1,
  byte: 2,
  char: 3,
  word: 4,
  int: 5,
  dword: 6,
  dint: 7,
  real: 8,
  date: 9,
  timeOfDay: 10,
  time: 11,
  s5time: 12,
  dateAndTime: 14,
  struct: 17,
  string: 19,
  lreal: 48,
  ulint: 49,
  lint: 50,
  lword: 51,
  usint: 52,
  uint: 53,
  udint: 54,
  sint: 55,
  wchar: 61,
  wstring: 62,
  ltime: 64,
  ltod: 65,
  ldt: 66,
  dtl: 67,
});
