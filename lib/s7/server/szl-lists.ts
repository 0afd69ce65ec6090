/**
 * The SZL lists a simulated CPU answers (read SZL, userdata group 4): what
 * the CPU says about itself, its state, protection, LEDs and diagnostic
 * buffer, built from a snapshot of CpuServices. An ID or index it does not
 * offer is answered with the CPU's error code instead of a list.
 */
import {
  SZL,
  encodeCommunication,
  encodeComponentIdentification,
  encodeCpuState,
  encodeLeds,
  encodeModuleIdentification,
  encodeProtection,
  encodeSzlIds,
  type SzlList,
} from '../codec/szl';
import { encodeDiagnosticBuffer, type DiagnosticEvent } from '../codec/diagnostics';
import type { CpuIdentity } from './profiles';
import { SERVICE_CODE as E } from './service-codes';

/** What the lists tell, as CpuServices knows it for one connection. */
export interface SzlView {
  identity: Readonly<CpuIdentity>;
  maxConnections: number;
  /** The connection's negotiated PDU size. */
  pduSize: number;
  /** The protection level in force for the connection (1 once it gave the password). */
  level: number;
  /** The protection level set on the CPU. */
  configuredLevel: number;
  mode: 'RUN' | 'STOP';
  lastTransition: { eventId: number; time: Date };
  /** The diagnostic buffer, newest first. */
  log: readonly DiagnosticEvent[];
}

/** The SZL IDs served (0x0Fxx header-only extracts of the 0x00xx lists included). */
export const SZL_IDS: readonly number[] = Object.freeze([
  0x0000, 0x0011, 0x0111, 0x001c, 0x011c, 0x0131, 0x0232, 0x0424, 0x0074, 0x00a0, 0x01a0, 0x0f00, 0x0f11, 0x0f1c, 0x0f74, 0x0fa0,
]);

/** The list `id` (index `index`), or the service error code the CPU answers instead. */
export function szlList(id: number, index: number, v: SzlView): SzlList | number {
  const i = v.identity;
  switch (id) {
    case SZL.IDS:
      return encodeSzlIds(SZL_IDS);
    case SZL.MODULE_ID:
    case 0x0111: {
      if (id === 0x0111 && ![1, 6, 7].includes(index)) return E.SZL_INDEX;
      return encodeModuleIdentification(i.orderCode, i.hardwareVersion, i.firmware, id === 0x0111 ? index : 0);
    }
    case SZL.COMPONENT_ID:
    case 0x011c: {
      const fields = {
        asName: i.asName,
        moduleName: i.moduleName,
        plantId: i.plantId,
        copyright: i.copyright,
        serialNumber: i.serialNumber,
        moduleTypeName: i.moduleTypeName,
      };
      const list = encodeComponentIdentification(fields, id === 0x011c ? index : 0);
      return list.records.length === 0 ? E.SZL_INDEX : list;
    }
    case SZL.COMMUNICATION: {
      if (index === 1)
        return encodeCommunication({ maxPdu: v.pduSize, maxConnections: v.maxConnections, mpiRate: 187_500, busRate: 10_000_000 });
      // Other indexes as the profile's CPU sends them (profiles.ts, communicationRecords).
      const record = i.communicationRecords?.[index];
      if (record === undefined) return E.SZL_INDEX;
      return { id, index, recordLength: record.length / 2, records: [Buffer.from(record, 'hex')] };
    }
    case SZL.PROTECTION:
      if (index !== 4) return E.SZL_INDEX;
      return encodeProtection({
        level: v.level,
        switchLevel: 1,
        configuredLevel: v.configuredLevel > 1 ? v.configuredLevel : 0,
        keySwitch: i.blockFunctions ? 'RUN-P' : 'RUN',
      });
    case SZL.CPU_STATE:
      return encodeCpuState(v.mode === 'RUN' ? 8 : 4, v.lastTransition.eventId, v.lastTransition.time);
    case SZL.LEDS: {
      const run = v.mode === 'RUN';
      return encodeLeds([
        { id: 0x01, on: false },
        { id: 0x04, on: run },
        { id: 0x05, on: !run },
        { id: 0x06, on: false },
      ]);
    }
    case SZL.DIAGNOSTICS:
      return encodeDiagnosticBuffer(v.log);
    case 0x01a0:
      if (index === 0) return E.SZL_INDEX;
      return encodeDiagnosticBuffer(v.log, index);
    default:
      return E.SZL_ID;
  }
}
