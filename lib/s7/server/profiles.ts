/** CPU profiles and memory layouts of the S7 simulator. */
import type { MemoryLayout } from '../../sim/memory';
import { rackSlotOf } from '../tsap';
import { hex4 } from '../../values/text';

export type S7Profile = 's7-300' | 's7-400' | 's7-1200' | 's7-1500' | 's7-200' | 'logo';

/** A TSAP the CPU accepts: the bits of `mask` must equal those of `value`. */
interface TsapMatch {
  value: number;
  mask: number;
}

export interface CpuProfile {
  /** PDU size the CPU offers; it answers min(requested, offered). */
  pduSize: number;
  /** Parallel jobs (AmQ) the CPU offers; it answers min(requested calling, offered). */
  maxJobs: number;
  /** Connections the CPU serves at once; the next connection request is refused with a COTP DR. */
  maxConnections: number;
  /** Slots (rack 0) whose called TSAP the CPU accepts. */
  slots: readonly number[];
  /**
   * A CPU addressed by configured TSAPs instead of rack/slot (S7-200 with a CP 243-1, LOGO!): the
   * called TSAP (the CPU's) and the calling TSAP (the client's) it accepts; any other is refused.
   */
  tsaps?: { readonly called: TsapMatch; readonly calling: TsapMatch };
  /** Memory when the server is given neither `memory` nor `layout`. */
  layout?: MemoryLayout;
  /** false: the S5 counter and timer areas (0x1C/0x1D) answer 0x03, as on an S7-200; default true. */
  s5CountersTimers?: boolean;
}

/**
 * An S7-200 reached through a CP 243-1. The CP's TSAP (the one a client calls)
 * is the connection number in its first byte, 0x10 for the Ethernet wizard's
 * first connection up to 0x17 for its eighth (Micro/WIN greys it out:
 * S7NetPlus/s7netplus#332), and "the structure of the second byte is not
 * checked by the CP 243-1" (SIMATIC NET CP 243-1 manual, §4.2.3 TSAPs); "up to
 * 8 such connections can be maintained" (same manual, the wizard's connection
 * count). S7NetPlus's default pair for an S7-200 is local 0x1000, remote 0x1001
 * (S7.Net/Protocol/TsapPair.cs). The client's TSAP is whatever the wizard was
 * given, so the simulator accepts any. V memory is DB1 on the wire (nodes7's
 * README and plcpeople/nodeS7#49: "V0.0 … use DB1,X0.0"), 10240 bytes as a
 * CPU 226 has; I, Q 16 bytes and M 32 bytes as a CPU 22x. Its counters and
 * timers are not the S5 areas: S7-200 SMART CPUs answer 0x03 there (see
 * COUNTERS_AND_TIMERS in jobs.ts). PDU 240 and one job at a time are
 * the simulator's choice (no capture of a CP 243-1's setup answer was found).
 */
const S7_200: CpuProfile = Object.freeze({
  pduSize: 240,
  maxJobs: 1,
  maxConnections: 8,
  slots: Object.freeze([]),
  tsaps: Object.freeze({ called: Object.freeze({ value: 0x1000, mask: 0xf800 }), calling: Object.freeze({ value: 0, mask: 0 }) }),
  layout: Object.freeze({
    dataBlocks: Object.freeze({ 1: 10240 }),
    inputs: 16,
    outputs: 16,
    flags: 32,
    peripheral: 0,
    counters: 0,
    timers: 0,
  }),
  s5CountersTimers: false,
});

/**
 * A LOGO! 0BA7/0BA8 with an S7 server connection set up in LOGO!Soft Comfort.
 * Both TSAPs are the ones configured there, so public sources disagree on
 * "the" pair: nodes7's README connects a LOGO with local 0x0100 / remote
 * 0x0200, python-snap7's LOGO example (after snap7's LOGO page) with 0x1000 /
 * 0x2000, S7NetPlus with 0x0100 / 0x0102 ("probably on a per-project basis").
 * The profile takes nodes7's pair, checks both TSAPs as a configured
 * connection does, and a CpuProfile with a project's own pair serves another.
 * "A LOGO! 0BA7 Base Module can support a maximum of eight network
 * connections" (LOGO!Soft Comfort online help, Ethernet connections). The VM
 * is DB1; the inputs, outputs and flags are read through their VM images
 * (I1 at V1024.0 on a 0BA8, V923.0 on a 0BA7: python-snap7 example/logo_7_8.py;
 * AM1 at VW1118: nodes7's README), so DB1 is the only area served: 1470 bytes
 * (through the 0BA8 image) is the simulator's choice, as are PDU 240 and one
 * job at a time. Counters and timers as for the S7-200.
 */
const LOGO: CpuProfile = Object.freeze({
  pduSize: 240,
  maxJobs: 1,
  maxConnections: 8,
  slots: Object.freeze([]),
  tsaps: Object.freeze({ called: Object.freeze({ value: 0x0200, mask: 0xffff }), calling: Object.freeze({ value: 0x0100, mask: 0xffff }) }),
  layout: Object.freeze({ dataBlocks: Object.freeze({ 1: 1470 }), inputs: 0, outputs: 0, flags: 0, peripheral: 0, counters: 0, timers: 0 }),
  s5CountersTimers: false,
});

/**
 * Why the CPU refuses a connection request with these TSAPs, or undefined when
 * it accepts them. Rack/slot CPUs check a called TSAP of the rack/slot form
 * (connection type PG 1, OP 2, basic 3) against their slots and accept other
 * TSAPs; TSAP-addressed CPUs (profile.tsaps) accept only their own.
 */
export function tsapRefusal(profile: CpuProfile, callingTsap: number, calledTsap: number): string | undefined {
  const own = profile.tsaps;
  if (own) {
    if ((calledTsap & own.called.mask) !== own.called.value) return `no connection configured for called TSAP 0x${hex4(calledTsap)}`;
    if ((callingTsap & own.calling.mask) !== own.calling.value)
      return `calling TSAP 0x${hex4(callingTsap)} is not the configured partner's`;
    return undefined;
  }
  const at = rackSlotOf(calledTsap);
  if (!at) return undefined;
  const { rack, slot } = at;
  if (rack !== 0 || !profile.slots.includes(slot)) return `no CPU at rack ${rack} slot ${slot} (called TSAP 0x${hex4(calledTsap)})`;
  return undefined;
}

/**
 * Figures as real CPUs negotiate them. PDU sizes: S7-300 and S7-1200 240,
 * S7-400 480, S7-1500 960 (e.g. a 1212C answers a request for 480 with 240:
 * robinson/gos7#56; a 1500 gives 960 only with a TPDU of 1024 or more, 480
 * with 512: S7NetPlus/s7netplus#21, #145). The S7-1200 takes 3 parallel jobs
 * (plcpeople/nodeS7#72); its 8 connections are the simulator's choice (the
 * count varies by model and firmware). The AmQ of S7-300 (1), S7-400 and S7-1500 (8) and the connection
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
  's7-200': S7_200,
  logo: LOGO,
});

/**
 * The JSON layout form (e.g. from a file given to `plcwire serve s7 --layout`):
 * `{ "dbs": { "1": 2048, "5": 100 }, "areas": { "M": 4096, "C": 64 } }`.
 * `dbs` replaces the default DB1–DB100 (so a DB not listed does not exist);
 * areas are in bytes, except C and T which are numbers of counters/timers.
 * V of an S7-200 address is DB1: keep DB1 in `dbs` to serve V addresses.
 */
interface S7JsonLayout {
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
    if (typeof v !== 'number' || !Number.isInteger(v) || v < 0 || v > 0x1fffff)
      throw new TypeError(`layout: ${what} must be a whole number of bytes (0..2097151), got ${JSON.stringify(v)}`);
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
  /**
   * SZL 0x0131 records beyond index 1 (which the simulator builds from the connection), as the CPU
   * sends them (40 bytes, hex), by index; an index not here is refused as the CPU refuses it.
   */
  communicationRecords?: Readonly<Record<number, string>>;
}

const COPYRIGHT = 'Original Siemens Equipment';

/**
 * Identity defaults per profile: catalogue CPUs of each family; serial numbers are made up. The S7-1200 and
 * S7-1500 run firmware that has secure PG/HMI communication and the password exchange keyed by TLS (S7-1200
 * V4.7, S7-1500 V3.1: docs/s7commplus.md), as the S7CommPlus side of the simulator serves them.
 */
export const IDENTITIES: Readonly<Record<S7Profile, Readonly<CpuIdentity>>> = Object.freeze({
  's7-300': Object.freeze({
    orderCode: '6ES7 315-2EH14-0AB0',
    firmware: 'V3.2.6',
    hardwareVersion: 4,
    moduleTypeName: 'CPU 315-2 PN/DP',
    serialNumber: 'S C-PW0000012019',
    asName: 'PLCWIRE-SIM',
    moduleName: 'CPU 315-2 PN/DP',
    plantId: '',
    copyright: COPYRIGHT,
    blockFunctions: true,
    passwordFunctions: true,
    // SZL 0x0131 index 2 (test and commissioning: block and variable status, force of 10 variables, breakpoints) and
    // index 3 (operator interface: read, write and cyclic reading of I/O, bit memory, DBs, timers and counters; 16
    // cyclic jobs of 100 ms to 52.1 s) of a CPU 315-2 PN/DP (6ES7 315-2EH14-0AB0), as published in snap7's server
    // data (src/core/s7_firmware.h, "they come from a physical CPU"; field layout: Siemens, "System Software for
    // S7-300/400 System and Standard Functions", SSL-ID W#16#xy31). Index 3's consistent data, 240 bytes, is the PDU.
    // No such record of the other profiles' CPUs was found: they refuse indexes 2 and 3 rather than invent them.
    communicationRecords: Object.freeze({
      // index, funkt_0..5, aseg, eseg, trgereig_0..2, trgbed, pfad, tiefe, systrig, erg_par, erg_pat_1/2, force, time, res
      2: [
        '0002',
        'befd4f000000',
        '000008000000',
        '3c0108000000',
        '7d0000',
        '05',
        '03',
        '0f',
        '00',
        '00',
        '0800',
        '000c',
        '000a',
        '0000',
        '00010000',
      ].join(''),
      // index, funkt_0..3, data, anz, per_min, per_max, 26 bytes reserved
      3: ['0003', '7ffc8301', '00f0', '0010', '0001', '0209', '00'.repeat(26)].join(''),
    }),
  }),
  's7-400': Object.freeze({
    orderCode: '6ES7 416-3ES07-0AB0',
    firmware: 'V7.0.1',
    hardwareVersion: 3,
    moduleTypeName: 'CPU 416-3 PN/DP',
    serialNumber: 'S Q-PW0000022019',
    asName: 'PLCWIRE-SIM',
    moduleName: 'CPU 416-3 PN/DP',
    plantId: '',
    copyright: COPYRIGHT,
    blockFunctions: true,
    passwordFunctions: true,
  }),
  's7-1200': Object.freeze({
    orderCode: '6ES7 214-1AG40-0XB0',
    firmware: 'V4.7.0',
    hardwareVersion: 5,
    moduleTypeName: 'CPU 1214C DC/DC/DC',
    serialNumber: 'S V-PW0000032019',
    asName: 'PLCWIRE-SIM',
    moduleName: 'PLC_1',
    plantId: '',
    copyright: COPYRIGHT,
    blockFunctions: false,
    passwordFunctions: false,
  }),
  's7-1500': Object.freeze({
    orderCode: '6ES7 516-3AN02-0AB0',
    firmware: 'V3.1.0',
    hardwareVersion: 2,
    moduleTypeName: 'CPU 1516-3 PN/DP',
    serialNumber: 'S V-PW0000042019',
    asName: 'PLCWIRE-SIM',
    moduleName: 'PLC_1',
    plantId: '',
    copyright: COPYRIGHT,
    blockFunctions: false,
    passwordFunctions: false,
  }),
  // S7-200 (through a CP 243-1) and LOGO!: public descriptions cover their data
  // access only; they get no block or password functions here, and SZL, clock
  // and state are answered as the S7-1200 model answers them.
  's7-200': Object.freeze({
    orderCode: '6ES7 214-2BD23-0XB0',
    firmware: 'V2.2.0',
    hardwareVersion: 1,
    moduleTypeName: 'CPU 224XP',
    serialNumber: 'S C-PW0000052019',
    asName: 'PLCWIRE-SIM',
    moduleName: 'CPU 224XP',
    plantId: '',
    copyright: COPYRIGHT,
    blockFunctions: false,
    passwordFunctions: false,
  }),
  logo: Object.freeze({
    orderCode: '6ED1052-1MD08-0BA1',
    firmware: 'V1.83.1',
    hardwareVersion: 1,
    moduleTypeName: 'LOGO! 12/24RCE',
    serialNumber: 'S L-PW0000062019',
    asName: 'PLCWIRE-SIM',
    moduleName: 'LOGO!',
    plantId: '',
    copyright: COPYRIGHT,
    blockFunctions: false,
    passwordFunctions: false,
  }),
});
