/**
 * SZL (system status list, "SSL" in English manuals): the list format and
 * decoders for the common lists, with the encoders the simulator builds its
 * answers with, so both sides read one layout. This file gathers them: the
 * format in szl-list.ts, the identity lists in szl-identity.ts, the
 * capability and state lists in szl-state.ts, the records of every index
 * of 0x0131 in szl-capabilities.ts.
 *
 * A list as the CPU sends it: SZL ID (2), index (2), record length in bytes
 * (LENTHDR, 2), record count (N_DR, 2), then N_DR records. An answer larger
 * than the PDU comes in several userdata parts; the header is in the first
 * part only, the records continue in the next parts byte for byte.
 * The ID's high byte selects the extract: 0x00xx all records, 0x01xx one
 * record or group given by the index, 0x0Fxx the header only.
 */
export { SZL, parseSzl, encodeSzl, decodeSzlIds, encodeSzlIds, type SzlList } from './szl-list';
export {
  decodeModuleIdentification,
  encodeModuleIdentification,
  decodeComponentIdentification,
  encodeComponentIdentification,
  type ModuleIdRecord,
  type ModuleIdentification,
  type ComponentIdentification,
} from './szl-identity';
export {
  decodeCommunication,
  encodeCommunication,
  decodeProtection,
  encodeProtection,
  cpuModeOf,
  decodeCpuState,
  encodeCpuState,
  decodeLeds,
  encodeLeds,
  type CommunicationCapabilities,
  type KeySwitch,
  type Protection,
  type CpuMode,
  type CpuState,
  type Led,
} from './szl-state';
export { decodeCommunicationRecords, type OperatorFunctions } from './szl-capabilities';
