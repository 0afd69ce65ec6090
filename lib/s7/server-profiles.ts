/** CPU profiles and memory layouts of the S7 simulator. */
import type { MemoryLayout } from '../sim/memory';

export type S7Profile = 's7-300' | 's7-400' | 's7-1200' | 's7-1500';

export interface CpuProfile {
  /** PDU size the CPU offers; it answers min(requested, offered). */
  pduSize: number;
  /** Parallel jobs (AmQ) the CPU offers; it answers min(requested calling, offered). */
  maxJobs: number;
  /** Connections the CPU serves at once; the next connection request is refused with a COTP DR. */
  maxConnections: number;
  /** Slots (rack 0) whose called TSAP the CPU accepts. */
  slots: readonly number[];
}

/**
 * Figures as real CPUs negotiate them. PDU sizes: S7-300 and S7-1200 240,
 * S7-400 480, S7-1500 960 (e.g. a 1212C answers a request for 480 with 240:
 * robinson/gos7#56; a 1500 gives 960 only with a TPDU of 1024 or more, 480
 * with 512: S7NetPlus/s7netplus#21, #145). The S7-1200 takes 8 PG/OP/S7
 * connections (the source document: "8 active and 8 passive") and 3 parallel
 * jobs. The AmQ of S7-300 (1), S7-400 and S7-1500 (8) and the connection
 * limits of 300/400/1500 are the simulator's choices, in the range of the CPU
 * families' manuals (they vary by CPU model).
 * S7-300/400 CPUs sit in slot 2 (an S7-400 CPU may sit in 3 or 4 behind a
 * wide power supply); S7-1200/1500 answer on slot 0 or 1.
 */
export const PROFILES: Readonly<Record<S7Profile, CpuProfile>> = Object.freeze({
  's7-300': Object.freeze({ pduSize: 240, maxJobs: 1, maxConnections: 16, slots: Object.freeze([2]) }),
  's7-400': Object.freeze({ pduSize: 480, maxJobs: 8, maxConnections: 32, slots: Object.freeze([2, 3, 4]) }),
  's7-1200': Object.freeze({ pduSize: 240, maxJobs: 3, maxConnections: 8, slots: Object.freeze([0, 1]) }),
  's7-1500': Object.freeze({ pduSize: 960, maxJobs: 8, maxConnections: 32, slots: Object.freeze([0, 1]) }),
});

/**
 * The JSON layout form (e.g. from a file given to `plcwire serve s7 --layout`):
 * `{ "dbs": { "1": 2048, "5": 100 }, "areas": { "M": 4096, "C": 64 } }`.
 * `dbs` replaces the default DB1–DB100 (so a DB not listed does not exist);
 * areas are in bytes, except C and T which are numbers of counters/timers.
 * V of an S7-200 address is DB1: keep DB1 in `dbs` to serve V addresses.
 */
export interface S7JsonLayout {
  dbs?: Record<string, number>;
  areas?: Partial<Record<'I' | 'Q' | 'M' | 'PE' | 'PA' | 'P' | 'C' | 'T', number>>;
}

export type S7Layout = MemoryLayout | S7JsonLayout;

/** Converts either layout form to the memory's layout; throws TypeError naming a bad entry. */
export function toMemoryLayout(layout: S7Layout): MemoryLayout {
  if (!('dbs' in layout) && !('areas' in layout)) return layout as MemoryLayout;
  const json = layout as S7JsonLayout;
  const out: MemoryLayout = {};
  const size = (what: string, v: unknown): number => {
    if (typeof v !== 'number' || !Number.isInteger(v) || v < 0 || v > 0x1fffff) throw new TypeError(`layout: ${what} must be a whole number of bytes (0..2097151), got ${JSON.stringify(v)}`);
    return v;
  };
  if (json.dbs !== undefined) {
    const blocks: Record<number, number> = {};
    for (const [key, bytes] of Object.entries(json.dbs)) {
      const db = Number(key);
      if (!Number.isInteger(db) || db < 1 || db > 65535) throw new TypeError(`layout: DB number "${key}" must be 1..65535`);
      blocks[db] = size(`DB${key}`, bytes);
    }
    out.dataBlocks = blocks;
  }
  for (const [area, bytes] of Object.entries(json.areas ?? {})) {
    const n = size(area, bytes);
    if (area === 'I') out.inputs = n;
    else if (area === 'Q') out.outputs = n;
    else if (area === 'M') out.flags = n;
    else if (area === 'PE' || area === 'PA' || area === 'P') out.peripheral = n;
    else if (area === 'C') out.counters = n;
    else if (area === 'T') out.timers = n;
    else throw new TypeError(`layout: unknown area "${area}" (I, Q, M, PE, PA, C, T)`);
  }
  return out;
}

/**
 * What the simulated CPU says about itself (SZL 0x0011, 0x001C) and which
 * service families it offers. S7-1200 and S7-1500 CPUs do not serve the
 * classic block functions (list, block info, upload) nor the connection
 * password over S7comm: the simulator refuses them as those CPUs do.
 */
export interface CpuIdentity {
  /** Order code (MLFB), e.g. "6ES7 315-2EH14-0AB0". */
  orderCode: string;
  /** Firmware version, "V3.2.6". */
  firmware: string;
  hardwareVersion: number;
  moduleTypeName: string;
  serialNumber: string;
  asName: string;
  moduleName: string;
  plantId: string;
  copyright: string;
  /** Block list, block info and upload over S7comm. */
  blockFunctions: boolean;
  /** Connection password (userdata group 5). */
  passwordFunctions: boolean;
}

const COPYRIGHT = 'Original Siemens Equipment';

/** Identity defaults per profile: catalogue CPUs of each family; serial numbers are made up. */
export const IDENTITIES: Readonly<Record<S7Profile, Readonly<CpuIdentity>>> = Object.freeze({
  's7-300': Object.freeze({ orderCode: '6ES7 315-2EH14-0AB0', firmware: 'V3.2.6', hardwareVersion: 4, moduleTypeName: 'CPU 315-2 PN/DP', serialNumber: 'S C-PW0000012019', asName: 'PLCWIRE-SIM', moduleName: 'CPU 315-2 PN/DP', plantId: '', copyright: COPYRIGHT, blockFunctions: true, passwordFunctions: true }),
  's7-400': Object.freeze({ orderCode: '6ES7 416-3ES07-0AB0', firmware: 'V7.0.1', hardwareVersion: 3, moduleTypeName: 'CPU 416-3 PN/DP', serialNumber: 'S Q-PW0000022019', asName: 'PLCWIRE-SIM', moduleName: 'CPU 416-3 PN/DP', plantId: '', copyright: COPYRIGHT, blockFunctions: true, passwordFunctions: true }),
  's7-1200': Object.freeze({ orderCode: '6ES7 214-1AG40-0XB0', firmware: 'V4.4.0', hardwareVersion: 5, moduleTypeName: 'CPU 1214C DC/DC/DC', serialNumber: 'S V-PW0000032019', asName: 'PLCWIRE-SIM', moduleName: 'PLC_1', plantId: '', copyright: COPYRIGHT, blockFunctions: false, passwordFunctions: false }),
  's7-1500': Object.freeze({ orderCode: '6ES7 516-3AN02-0AB0', firmware: 'V2.9.2', hardwareVersion: 2, moduleTypeName: 'CPU 1516-3 PN/DP', serialNumber: 'S V-PW0000042019', asName: 'PLCWIRE-SIM', moduleName: 'PLC_1', plantId: '', copyright: COPYRIGHT, blockFunctions: false, passwordFunctions: false }),
});
