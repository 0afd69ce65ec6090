/**
 * S7CommPlus constants: the one table of ids, opcodes and codes that the
 * codec, the client and the simulator share. Every group names its public
 * source. "s7commplus (MIT)" is the s7commplus package 0.3.0 on PyPI
 * (github.com/gijzelaerr/s7commplus); "golden frames" are the TIA Portal ↔
 * PLCSIM frames in that repository's
 * tests/fixtures/golden_tia_online_session_20260915.py (test/fixtures/s7plus/golden-tia.json).
 * Only facts (numbers, layouts) are taken; the names follow the sources' spelling.
 */

/** The first byte of every S7CommPlus frame header and trailer (S7comm's is 0x32). s7commplus (MIT), protocol.py PROTOCOL_ID. */
export const S7P_PROTOCOL_ID = 0x72;

/** The version byte of the frame header. s7commplus (MIT), protocol.py ProtocolVersion. */
export const ProtocolVersion = {
  /** No TLS; older firmware, optionally with the (unsupported) legacy session key. */
  V1: 0x01,
  /** Integrity ids; what a TLS session speaks (golden frames: every frame is `72 02`). */
  V2: 0x02,
  /** HMAC-protected frames of the legacy session-key handshake. */
  V3: 0x03,
  /** A SystemEvent frame: no opcode, no trailer. */
  SystemEvent: 0xfe,
} as const;

/** The first byte after the frame header. s7commplus (MIT), protocol.py Opcode; golden frames. */
export const Opcode = {
  Request: 0x31,
  Response: 0x32,
  Notification: 0x33,
  /** A response opcode some older firmware sends. */
  Response2: 0x02,
} as const;

/** The 16-bit function code of requests and responses. s7commplus (MIT), protocol.py FunctionCode; golden frames (0x04BB, 0x04CA, 0x057C, 0x0586). */
export const FunctionCode = {
  Error: 0x04b1,
  Explore: 0x04bb,
  CreateObject: 0x04ca,
  DeleteObject: 0x04d4,
  SetVariable: 0x04f2,
  GetVariable: 0x04fc,
  AddLink: 0x0506,
  RemoveLink: 0x051a,
  GetLink: 0x0524,
  Notify: 0x052e,
  SetMultiVariables: 0x0542,
  GetMultiVariables: 0x054c,
  BeginSequence: 0x0556,
  EndSequence: 0x0560,
  Invoke: 0x056b,
  SetVarSubStreamed: 0x057c,
  GetVarSubStreamed: 0x0586,
  GetVariablesAddress: 0x0590,
  Abort: 0x059a,
  Error2: 0x05a9,
  InitSsl: 0x05b3,
} as const;

/**
 * Functions that count on the READ integrity id; every other function of a
 * session (but InitSSL and the session's CreateObject) counts on the WRITE
 * one. s7commplus (MIT), protocol.py READ_FUNCTION_CODES and server.py.
 */
export const READ_FUNCTIONS: ReadonlySet<number> = new Set([
  FunctionCode.GetMultiVariables,
  FunctionCode.Explore,
  FunctionCode.GetVarSubStreamed,
  FunctionCode.GetLink,
  FunctionCode.GetVariable,
  FunctionCode.GetVariablesAddress,
]);

/**
 * The transport-flags byte of a request header: 0x30 on InitSSL, 0x36 on the
 * session's CreateObject (0x34 there makes a PLC reset the connection), 0x34
 * on everything else. s7commplus (MIT), protocol.py FLAGS_34_FUNCTION_CODES and
 * connection.py; golden frames (0x34 on explores, subscription create and the write).
 */
export const TransportFlags = {
  InitSsl: 0x30,
  Normal: 0x34,
  SessionCreate: 0x36,
  /** A request the PLC answers not at all: the subscription credit update (connection.py send_subscription_credit). */
  NoAnswer: 0x74,
} as const;

/** The element ids of the object tree. s7commplus (MIT), protocol.py ElementID. */
export const ElementId = {
  StartOfObject: 0xa1,
  TerminatingObject: 0xa2,
  Attribute: 0xa3,
  Relation: 0xa4,
  Error: 0xa5,
  IncludeObject: 0xa6,
  StartOfTagDescription: 0xa7,
  TerminatingTagDescription: 0xa8,
  LinkNamespace: 0xa9,
  /** The variable-type list of a type-info object (block-framed, see object.ts). */
  VartypeList: 0xab,
  /** The variable-name list of a type-info object (block-framed). */
  VarnameList: 0xac,
} as const;

/** The datatype byte of a PValue (the wire type). s7commplus (MIT), protocol.py DataType and codec.py (which are VLQ, which fixed). */
export const DataType = {
  Null: 0x00,
  Bool: 0x01,
  USInt: 0x02,
  UInt: 0x03,
  UDInt: 0x04,
  ULInt: 0x05,
  SInt: 0x06,
  Int: 0x07,
  DInt: 0x08,
  LInt: 0x09,
  Byte: 0x0a,
  Word: 0x0b,
  DWord: 0x0c,
  LWord: 0x0d,
  Real: 0x0e,
  LReal: 0x0f,
  Timestamp: 0x10,
  Timespan: 0x11,
  RID: 0x12,
  AID: 0x13,
  Blob: 0x14,
  WString: 0x15,
  Variant: 0x16,
  Struct: 0x17,
  S7String: 0x19,
} as const;

/**
 * The flags byte in front of the datatype of a PValue. Array: count, then the
 * elements. Address array: the same layout, for address lists (golden frames:
 * `20 04 01 83 1f` in the symbolic write, `20 04 03 …` in the subscription
 * create). Sparse array: (key, element) pairs ending at key 0. s7commplus
 * (MIT), codec.py (0x10) and subscription.py (0x20); the sparse layout is the
 * Wireshark S7CommPlus dissector's (facts only).
 */
export const PValueFlag = {
  Array: 0x10,
  AddressArray: 0x20,
  SparseArray: 0x40,
} as const;

/**
 * Struct ids whose members travel packed, as one blob: ids strictly between
 * these bounds. s7commplus (MIT), codec.py decode_pvalue_to_bytes (STRUCT).
 */
export const PACKED_STRUCT_RANGES: readonly (readonly [number, number])[] = [
  [0x90000000, 0x9fffffff],
  [0x02000000, 0x02ffffff],
];
/** In a packed struct's transport flags: a second element count follows. s7commplus (MIT), codec.py. */
export const PACKED_STRUCT_COUNT2 = 0x400;

/** The type ids of the PLC's type information (the soft data types). s7commplus (MIT), protocol.py SoftDataType. */
export const SoftDataType = {
  Void: 0,
  Bool: 1,
  Byte: 2,
  Char: 3,
  Word: 4,
  Int: 5,
  DWord: 6,
  DInt: 7,
  Real: 8,
  Date: 9,
  TimeOfDay: 10,
  Time: 11,
  S5Time: 12,
  DateAndTime: 14,
  Array: 16,
  Struct: 17,
  String: 19,
  Pointer: 20,
  Any: 22,
  BlockFB: 23,
  BlockFC: 24,
  BlockDB: 25,
  BlockSDB: 26,
  Counter: 28,
  Timer: 29,
  IecCounter: 30,
  IecTimer: 31,
  BlockSFB: 32,
  BlockSFC: 33,
  BlockOB: 36,
  BlockUDT: 37,
  LReal: 48,
  ULInt: 49,
  LInt: 50,
  LWord: 51,
  USInt: 52,
  UInt: 53,
  UDInt: 54,
  SInt: 55,
  WChar: 61,
  WString: 62,
  Variant: 63,
  LTime: 64,
  LTOD: 65,
  LDT: 66,
  DTL: 67,
} as const;

/**
 * Object, class and attribute ids. s7commplus (MIT), protocol.py ObjectId and
 * Ids (which cite thomas-v2/S7CommPlusDriver Core/Ids.cs, LGPL: facts only);
 * the subscription ids also in the golden subscription create.
 */
export const Ids = {
  None: 0,
  /** The RelationId of a new object: the PLC assigns its id. */
  GetNewRIDOnServer: 211,
  ObjectVariableTypeName: 233,
  ClassSubscriptions: 255,
  ClassServerSessionContainer: 284,
  ObjectServerSessionContainer: 285,
  ClassServerSession: 287,
  /** The session id of the request that creates the session. */
  ObjectNullServerSession: 288,
  ServerSessionClientId: 289,
  ServerSessionUser: 296,
  ServerSessionApplication: 297,
  ServerSessionHost: 298,
  ServerSessionRole: 299,
  ServerSessionClientRID: 300,
  ServerSessionComment: 301,
  ServerSessionRequest: 303,
  ServerSessionResponse: 304,
  ServerSessionVersion: 306,
  /** The struct of a Struct-typed ServerSessionVersion, and its PAOM device string member. */
  SessionVersionStruct: 314,
  SessionVersionSystemPaomString: 319,
  /** The credentials of the new legitimation: Struct 40400 of the legitimation type (UDInt), user and password (Blobs). s7commplus (MIT), protocol.py Ids and legitimation.py _build_legitimation_payload. */
  LegitimationPayloadStruct: 40400,
  LegitimationPayloadType: 40401,
  LegitimationPayloadUsername: 40402,
  LegitimationPayloadPassword: 40403,
  ClassTypeInfo: 511,
  VariableTypeStructModificationTime: 529,
  ClassOmsTypeInfoContainer: 534,
  ObjectOmsTypeInfoContainer: 537,
  ClassSubscription: 1001,
  SubscriptionMissedSendings: 1002,
  SubscriptionSubsystemError: 1003,
  SubscriptionReferenceTriggerMode: 1005,
  SubscriptionRouteMode: 1040,
  SubscriptionActive: 1041,
  SubscriptionReferenceList: 1048,
  SubscriptionCycleTime: 1049,
  SubscriptionDelayTime: 1050,
  SubscriptionDisabled: 1051,
  SubscriptionCount: 1052,
  SubscriptionCreditLimit: 1053,
  SubscriptionTicks: 1054,
  /** Sent by TIA and s7commplus as USInt 0 after the ticks; name not public. */
  Subscription1055: 1055,
  SubscriptionFunctionClassId: 1082,
  ObjectQualifier: 1256,
  ParentRID: 1257,
  CompositionAID: 1258,
  KeyQualifier: 1259,
  SessionSetupLegitimation: 1830,
  EffectiveProtectionLevel: 1842,
  Legitimate: 1846,
  PlcProgramClassRID: 2520,
  BlockBlockNumber: 2521,
  DataInterfaceInterfaceDescription: 2544,
  DBValueActual: 2550,
  DBClassRID: 2574,
  ControllerAreaValueActual: 3736,
  /** theCPUexecUnit's operating state: Struct attribute 0x8BD, struct id 0xD99, DInt member 0xD9E (8 RUN, 4 STOP). */
  CpuExecUnitOperatingStateStruct: 0x8bd,
  CpuExecUnitOperatingStateStructId: 0xd99,
  CpuExecUnitOperatingState: 0xd9e,
  /** The ClassId of theCPUexecUnit in an Explore response. s7commplus (MIT), server.py. */
  ClassCpuExecUnit: 0x883,
  /** Native objects to explore. */
  NativeThePlcProgramRID: 3,
  NativeTheAlarmSubsystemRID: 8,
  NativeTheCpuExecUnitRID: 52,
  NativeTheIAreaRID: 80,
  NativeTheQAreaRID: 81,
  NativeTheMAreaRID: 82,
  NativeTheS7CountersRID: 83,
  NativeTheS7TimersRID: 84,
  /** The access area of DB n is this plus n (n < 65536). */
  DBAccessAreaBase: 0x8a0e0000,
  /** The explore id of every DB at once (golden frames: the pair explore). */
  DBWildcardRID: 0x8a11ffff,
  /** A LID path of this marker, a byte offset and a byte count reads a standard DB as bytes. */
  LidClassicBlob: 3,
  // Alarms (issue #33). s7commplus (MIT), protocol.py Ids and alarm.py: the alarm subscription's child
  // (AlarmSubscriptionRef), the alarm subsystem's active-alarm relation, the DAI (alarm) object and its attributes.
  AlarmSubscriptionRefAlarmDomain: 2659,
  AlarmSubscriptionRefItsAlarmSubsystem: 2660,
  AlarmSubscriptionRefClassRid: 2662,
  AlarmSubscriptionRefAlarmDomainFilter: 7731,
  AlarmSubscriptionRefSendTexts: 8173,
  AlarmSubscriptionRefTextLanguages: 8181,
  AlarmSubsystemUpdateRelevantDai: 2667,
  AlarmDaiCpuAlarmId: 2670,
  AlarmDaiAllStatesInfo: 2671,
  AlarmDaiDomain: 2672,
  AlarmDaiComing: 2673,
  AlarmDaiGoing: 2677,
  AlarmDaiClassRid: 2681,
  AlarmDaiTexts: 2715,
  AlarmDaiMessageType: 4079,
  AlarmDaiHmiInfo: 7813,
  AlarmDaiSequenceCounter: 7917,
  /** Members of the coming / going struct (AS_CGS): s7commplus alarm.py (3475, 3476, 3646); 3474 from S7CommPlusDriver's Ids.cs (LGPL, the number only). */
  AsCgsAllStatesInfo: 3474,
  AsCgsTimestamp: 3475,
  AsCgsAssociatedValues: 3476,
  AsCgsAckTimestamp: 3646,
} as const;

/**
 * The type objects of the I, Q and M areas in the type-info container: their
 * members are the PLC tag table's names (LID, software type, byte and bit in
 * the area), read with the area's native object (80, 81, 82) as access area
 * and ControllerAreaValueActual. s7commplus (MIT), client.py _browse_layout;
 * thomas-v2/S7CommPlusDriver (facts only), S7CommPlusConnection.cs Browse.
 */
export const AreaTypeInfoRID = Object.freeze({ I: 0x90010000, Q: 0x90020000, M: 0x90030000 });

/**
 * The PLC's own limits: items of access area ObjectRoot (RID 201) and sub-area SystemLimits (1037), each a DInt:
 * LID 1000 the most tags one read request may carry, 1001 one write request (thomas-v2/S7CommPlusDriver (LGPL,
 * facts only), Core/Ids.cs and Core/CommRessources.cs ReadMax; its issue #71 names both LIDs).
 */
export const SystemLimits = Object.freeze({
  ObjectRoot: 201,
  SubArea: 1037,
  TagsPerReadRequest: 1000,
  TagsPerWriteRequest: 1001,
});

/** The access area of DB `db` (1..65535). s7commplus (MIT), protocol.py DB_ACCESS_AREA_BASE. */
export function dbAccessArea(db: number): number {
  return (Ids.DBAccessAreaBase + (db & 0xffff)) >>> 0;
}

/**
 * The session's protection level as the PLC reports it (attribute 1842,
 * EffectiveProtectionLevel); lower is more privileged, a legitimation lowers
 * it. None: no protection configured. s7commplus (MIT), protocol.py AccessLevel
 * (which cites thomas-v2/S7CommPlusDriver Legitimation/AccessLevel.cs).
 */
export const AccessLevel = {
  None: 0,
  FullAccess: 1,
  ReadAccess: 2,
  HmiAccess: 3,
  NoAccess: 4,
} as const;

/**
 * The two forms of legitimation, also the LegitimationPayloadType of the new
 * form's credentials (1: the password as its SHA-1, 2: user and password).
 * Legacy: SHA-1 of the password XOR the challenge, written to
 * ServerSessionResponse (304); new: AES-256-CBC credentials written to
 * Legitimate (1846). s7commplus (MIT), protocol.py LegitimationType,
 * legitimation.py and connection.py _send_legitimation_legacy/_new.
 */
export const LegitimationType = {
  Legacy: 1,
  New: 2,
} as const;

/**
 * The TLS exporter (RFC 5705 / RFC 8446 7.5) of the new legitimation: label
 * and length of the secret whose SHA-256 is the first AES-256 key. s7commplus
 * (MIT), connection.py _OMS_EXPORTER_LABEL/_OMS_EXPORTER_LENGTH and
 * legitimation.py derive_legitimation_key.
 */
export const OMS_EXPORTER_LABEL = 'EXPERIMENTAL_OMS';
export const OMS_EXPORTER_LENGTH = 32;

/** The operating-state codes of theCPUexecUnit seen on PLCSIM Advanced and a CPU 1215C. s7commplus (MIT), protocol.py. */
export const OperatingState = { Stop: 4, Run: 8 } as const;

/**
 * Service results: the low 16 bits (signed) of a 64-bit return value.
 * Positive: the request succeeded with a remark; negative: it failed.
 * s7commplus (MIT), protocol.py ServiceResult and service_result_code.
 */
export const ServiceResult = {
  Ok: 0,
  UnknownError: -1,
  InvalidValueType: -2,
  InvalidArgumentValue: -3,
  NotEnoughMemory: -4,
  /** An Explore of an object that does not exist (s7commplus (MIT), server.py: 0x8020AB001992FFF4). */
  NoSuchObject: -12,
  SessionPreLegitimized: 17,
  ServiceIgnored: 18,
  ExecutedWithPartialError: 19,
  SubscriptionTooManyNotifies: 21,
  SessionDelegitimated: 22,
  SubscriptionDisabled: 24,
  LegitimatedForLevel2: 25,
  LegitimatedForLevel3: 26,
  LegitimatedForLevel1: 33,
  TemporarilyOutOfResources: 37,
} as const;

/** The per-item error s7commplus's server answers for an item it cannot serve. s7commplus (MIT), server.py _ITEM_ERROR. */
export const ITEM_ERROR_UNRESOLVED = 0x8104n;

/** The ServiceResult code of a 64-bit return value (the low 16 bits, signed). */
export function serviceResultCode(returnValue: bigint): number {
  const low = Number(returnValue & 0xffffn);
  return low & 0x8000 ? low - 0x10000 : low;
}

/**
 * Notification record tags: a value by a u32 reference, a value by a VLQ
 * reference, an error by a u32 reference, the end. s7commplus (MIT),
 * subscription.py parse_subscription_notification; golden frames (0x92).
 */
export const NotificationRecord = {
  End: 0x00,
  Error: 0x03,
  Error2: 0x13,
  Value: 0x92,
  ValueVlq: 0x9b,
} as const;

/** The COTP called TSAPs of the client roles. s7commplus (MIT), protocol.py. */
export const RemoteTsap = {
  hmi: 'SIMATIC-ROOT-HMI',
  es: 'SIMATIC-ROOT-ES',
  pg: 'SIMATIC-ROOT-PG',
} as const;
/** The calling TSAP of an S7CommPlus client. s7commplus (MIT), protocol.py S7COMMPLUS_LOCAL_TSAP. */
export const LOCAL_TSAP = 0x0600;
