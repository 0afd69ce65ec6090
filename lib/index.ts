/**
 * @plcwire/node-red-siemens — connect Node.js to Siemens PLCs over S7comm
 * (ISO-on-TCP, PUT/GET), S7CommPlus over TLS (S7-1200/1500: optimized blocks
 * by name), FETCH/WRITE and S7-200 freeport, with a simulator for each (the
 * S7 simulator of an S7-1200/1500 profile serves S7CommPlus on its port).
 *
 *   const plc = await connect('s7://192.168.0.2?rack=0&slot=1');
 *   await plc.read(['DB1,INT2', 'DB1.DBD4:REAL', 'M0.1']);
 *   const cpu = await connect('s7plus://192.168.0.1?fingerprint=<SHA-256 of its certificate>');
 *   await cpu.read(['"Tank".Level']);
 */
export { connect, createClient, type AnyClient, type ClientFor, type ConnectOptions } from './connect';
export * from './errors';
export * from './types';
export * from './url';

export { parseAddress, parseTypeSpec, formatAddress, type TypeSpec, type TagLocation } from './address';
export {
  compileSymbols,
  type BlockSummary,
  type CompileOptions,
  type SymbolAccess,
  type SymbolEntry,
  type SymbolSource,
  type SymbolTable,
  type SymbolTableRow,
  type SourcePosition,
} from './symbols';
export {
  tagsFromCsv,
  tagsToCsv,
  addressWithType,
  duplicateNames,
  type TagRow,
  type CsvImport,
  type TagTableProblem,
  type TagTableProblemCode,
  type AddressParser,
} from './tags/table';
export {
  tagTable,
  tagsOfMessage,
  errorInfo,
  outcomes,
  tagFailure,
  valueChanged,
  ChangeFilter,
  PolledTable,
  realsForPeople,
  writeRequest,
  LifeSignWatch,
  nextLifeSign,
  LIFE_SIGN_COUNTER_MAX,
  type TagErrorInfo,
  type TagOutcome,
  type TagFailure,
  type WriteRequest,
  type LifeSignMode,
  type LifeSignEvent,
  type LifeSignState,
  type LifeSignReport,
} from './flows';
export * as values from './values';
export { decodeTag, encodeTag, encodeInto, validateValue, elementByteLength, tagByteLength } from './values';

export {
  BaseClient,
  type ClientOptions,
  type PreparedRead,
  type Driver,
  type DriverSession,
  type DriverTag,
  type ReadValues,
  type TagSyntax,
} from './client/base';
export type { BackoffOptions } from './link/backoff';
export type { FrameCheck } from './link/framer';

export * as s7 from './s7/codec';
export { S7Client, type ItemLimitEvent, type S7ClientEvents, type S7Stats } from './s7/client';
export type { S7Session } from './s7/client';
export {
  planRead,
  planWrite,
  ReadPlanCache,
  type PlannedReadItem,
  type ReadPdu,
  type ReadPlan,
  type TagPieces,
  type TagSlice,
  type WritePdu,
  type WritePlan,
} from './s7/plan';
export {
  S7Server,
  PROFILES as S7_PROFILES,
  type S7ServerOptions,
  type S7Faults,
  type S7Profile,
  type CpuProfile,
  type S7RequestEvent,
} from './s7/server';
export { IDENTITIES as S7_IDENTITIES, STOP_CAUSES, type CpuIdentity, type SimulatorMode, type StopCause } from './s7/server';
export type { CpuServices, ServiceSession } from './s7/server/services';
/** S7CommPlus on the S7 simulator's port (`new S7Server({ s7plus: new S7PlusService({ sources, tls }) })`), issue #25. */
export { S7PlusService, type S7PlusOptions } from './s7plus/server';
/** The simulator's certificate kept in a directory: `new S7PlusService({ sources, tls: await certificateInDirectory(dir) })`. */
export { certificateInDirectory, CERTIFICATE_FILES } from './s7plus/transport/cert-dir';
/** The S7CommPlus client (`connect('s7plus://…')` gives one) and its subscriptions: `client.subscribe(tags, { cycle })`. */
export {
  S7PlusClient,
  type S7PlusClientEvents,
  type InsecureEvent,
  S7PlusSubscription,
  type SubscribeOptions,
  type SubscriptionChange,
  type SubscriptionData,
  type SubscriptionState,
} from './s7plus/client';
export { type PlcInfo, type ClockOptions } from './s7/client';
export { diagnose, type DoctorStep, type DoctorReport, type DiagnoseOptions } from './doctor';
export {
  SZL,
  parseSzl,
  decodeSzlIds,
  decodeModuleIdentification,
  decodeComponentIdentification,
  decodeCommunication,
  decodeProtection,
  decodeCpuState,
  decodeLeds,
  cpuModeOf,
  type SzlList,
  type ModuleIdentification,
  type ModuleIdRecord,
  type ComponentIdentification,
  type CommunicationCapabilities,
  type Protection,
  type KeySwitch,
  type CpuState,
  type CpuMode,
  type Led,
} from './s7/codec/szl';
export {
  decodeDiagnosticBuffer,
  describeEvent,
  EVENT_DESCRIPTIONS,
  type DiagnosticEntry,
  type DiagnosticEvent,
} from './s7/codec/diagnostics';
export {
  decodeBlockInfo,
  decodeBlockCounts,
  decodeLoadBlock,
  type BlockInfo,
  type BlockCounts,
  type UploadedBlock,
} from './s7/codec/blocks';
export { BLOCK_TYPES, BLOCK_LANGUAGES, SERVICE_ERRORS, type BlockType } from './s7/constants';
export * as fetchwrite from './fetchwrite/codec';
export { FetchWriteClient } from './fetchwrite/client';
export { FetchWriteServer, type FetchWriteServerOptions, type FetchWriteFaults, type FetchWriteRequestEvent } from './fetchwrite/server';
export * as freeport from './freeport';
export { FreeportClient, type FreeportClientOptions } from './freeport/client';
export type { FreeportSession } from './freeport/session';
export { FreeportBus, type FreeportBusOptions, type FreeportBusFaults, type SerialAttachOptions } from './freeport/bus';
export { FreeportStation } from './freeport/station';
export { DEFAULT_FREEPORT_PROFILE, defineProfile, type FreeportProfile } from './freeport/profile';
export { parseFreeportAddress, type FreeportTag } from './freeport/address';

export { PlcMemory, DEFAULT_LAYOUT, type MemoryLayout, type MemoryAccess, type MemoryFault } from './sim/memory';
export { DemoProcess, DEMO_SYMBOLS, DEMO_TAGS, type ProcessSnapshot } from './plant/process';
export { PLANT_DB_NUMBERS, PLANT_SOURCE, TANK_DB_NUMBERS, TANK_SOURCE } from './plant/source';
export { TankBlock, TANK_SYMBOLS, type TankSnapshot } from './plant/tank';
export { startPlant, DEMO_PORTS, DEMO_STATIONS, type Plant, type PlantOptions, type PlantPorts } from './plant/plant';
export { demoCertificateDir } from './plant/certificate-dir';
export type {
  AlarmDefinition,
  AlarmEvent,
  AlarmKind,
  AlarmPort,
  AlarmSubscribeOptions,
  AlarmSubscription,
  AlarmTexts,
  AlarmValue,
  PlcAlarm,
} from './alarms/model';
// Sparkplug B edge node (issue #34)
export * as sparkplug from './sparkplug';
export { SparkplugEdgeNode, type SparkplugEdgeNodeOptions, type SparkplugDeviceOptions } from './sparkplug';
// Classic alarms (issue #33, h-alm7): the --alarms file's parser.
export { parseAlarmDefinitions } from './alarms/definitions';
