/**
 * SZL 0x0131, the communication capability parameters, one record per index,
 * each index with a layout of its own (Siemens, "System Software for
 * S7-300/400 System and Standard Functions", section "SSL-ID W#16#xy31 -
 * Communication Capability Parameters"; the same fields in Wireshark's s7comm
 * dissector, packet-s7comm_szl_ids.c, s7comm_decode_szl_id_0131_idx_000n):
 *
 *   index 1  general communication data: max PDU, connections, MPI and bus rates
 *   index 2  test and commissioning functions (TIS): function and trigger bits, force count
 *   index 3  operator interface functions: read/write/cyclic-read bits, consistent data, cyclic jobs
 *   others   (object management, time system, …): the record as the CPU sent it, undecoded
 *
 * Every record is 40 bytes, its first word the index. A record is decoded by
 * the index it carries, never by the one asked for.
 */
import { ProtocolError } from '../../errors';
import { hex4 } from '../../values/text';
import { decodeCommunication, type CommunicationCapabilities } from './szl-state';
import type { SzlList } from './szl-list';

/** Index 2: the test and commissioning functions the CPU offers. */
interface TestFunctions {
  index: 2;
  /** The functions whose bit is set in funkt_0..funkt_2, by name. */
  functions: string[];
  /** The trigger events whose bit is set in trgereig_0/1, by name. */
  triggers: string[];
  /** force: the number of variables that can be forced. */
  forceableVariables: number;
  /** time: the upper limit of a run-time measurement, seconds (bits 0-11 value, 12-15 base 10^(n-10) s). */
  runtimeLimitSeconds: number;
}

/** Index 3: the operator interface functions (what an HMI may do). */
export interface OperatorFunctions {
  index: 3;
  /** The functions and areas whose bit is set in funkt_0..funkt_3, by name. */
  functions: string[];
  /** data: the largest block of data read consistently, bytes. */
  maxConsistentBytes: number;
  /** anz: cyclic read jobs at once. */
  maxCyclicReadJobs: number;
  /** per_min, per_max: the period of a cyclic read job, ms (the record counts 100 ms). */
  cyclicPeriodMinMs: number;
  cyclicPeriodMaxMs: number;
}

/** An index whose layout this library does not decode: its bytes as hex. */
interface RawCapabilities {
  index: number;
  record: string;
}

export type CommunicationRecord = (CommunicationCapabilities & { index: 1 }) | TestFunctions | OperatorFunctions | RawCapabilities;

const RECORD = 40;

/** Bit names of funkt_0..funkt_2 (index 2), bit 0 first; undefined = reserved. */
const TIS_FUNCTIONS: readonly (readonly (string | undefined)[])[] = [
  [undefined, 'block status', 'variable status', 'output ISTACK', 'output BSTACK', 'output LSTACK', 'time measurement', 'force selection'],
  ['modify variable', 'force', 'breakpoint', 'exit HOLD', 'memory reset', 'disable job', 'enable job', 'delete job'],
  ['read job list', 'read job', 'replace job'],
];

/** Bit names of trgereig_0/1 (index 2). */
const TIS_TRIGGERS: readonly (readonly (string | undefined)[])[] = [
  [
    'immediately',
    'system trigger',
    'main cycle start',
    'main cycle end',
    'RUN-STOP transition',
    'after code address',
    'code address area',
    'data address',
  ],
  ['data address area', 'local data address', 'local data address area', 'range trigger', 'before code address'],
];

/** Bit names of funkt_0..funkt_3 (index 3). */
const OPERATOR_FUNCTIONS: readonly (readonly (string | undefined)[])[] = [
  [
    'read once',
    'write once',
    'initialize cyclic reading (implicit start)',
    'initialize cyclic reading (explicit start)',
    'start cyclic reading',
    'stop cyclic reading',
    'clear cyclic reading',
  ],
  [undefined, undefined, undefined, undefined, 'peripheral I/O', 'inputs', 'outputs', 'bit memory'],
  ['user DB', 'data record', undefined, undefined, undefined, undefined, undefined, 'S7 counter'],
  ['S7 timer', 'IEC counter', 'IEC timer', 'high-speed counter'],
];

/** The names of the set bits of `bytes`, named by `table` (one row per byte). */
function setBits(bytes: Buffer, table: readonly (readonly (string | undefined)[])[]): string[] {
  const names: string[] = [];
  table.forEach((row, i) => {
    for (let bit = 0; bit < 8; bit++) {
      const name = row[bit];
      if (name !== undefined && (bytes[i]! & (1 << bit)) !== 0) names.push(name);
    }
  });
  return names;
}

/** Seconds of a run-time limit word: bits 0-11 the value, bits 12-15 the base, 0 = 10^-10 s … 0xF = 10^5 s. */
function runtimeSeconds(word: number): number {
  return Number(((word & 0x0fff) * 10 ** ((word >> 12) - 10)).toPrecision(6));
}

function testFunctions(r: Buffer): TestFunctions {
  // index 0-1, funkt_0..5 2-7, aseg 8-13, eseg 14-19, trgereig_0..2 20-22, trgbed 23, pfad 24, tiefe 25,
  // systrig 26, erg_par 27, erg_pat_1 28-29, erg_pat_2 30-31, force 32-33, time 34-35, res 36-39.
  return {
    index: 2,
    functions: setBits(r.subarray(2, 5), TIS_FUNCTIONS),
    triggers: setBits(r.subarray(20, 22), TIS_TRIGGERS),
    forceableVariables: r.readUInt16BE(32),
    runtimeLimitSeconds: runtimeSeconds(r.readUInt16BE(34)),
  };
}

function operatorFunctions(r: Buffer): OperatorFunctions {
  // index 0-1, funkt_0..3 2-5, data 6-7, anz 8-9, per_min 10-11, per_max 12-13, res 14-39.
  return {
    index: 3,
    functions: setBits(r.subarray(2, 6), OPERATOR_FUNCTIONS),
    maxConsistentBytes: r.readUInt16BE(6),
    maxCyclicReadJobs: r.readUInt16BE(8),
    cyclicPeriodMinMs: r.readUInt16BE(10) * 100,
    cyclicPeriodMaxMs: r.readUInt16BE(12) * 100,
  };
}

/** One record of SZL 0x0131, by the index its first word carries. */
function decodeCommunicationRecord(r: Buffer): CommunicationRecord {
  if (r.length < RECORD) throw new ProtocolError(`SZL 0x0131: a record of ${r.length} bytes, expected ${RECORD}`);
  const index = r.readUInt16BE(0);
  switch (index) {
    case 1:
      return { index: 1, ...decodeCommunication({ id: 0x0131, index: 1, recordLength: r.length, records: [r] }) };
    case 2:
      return testFunctions(r);
    case 3:
      return operatorFunctions(r);
    default:
      return { index, record: r.toString('hex') };
  }
}

/** Every record of an SZL 0x0131 answer (one per index asked; 0x0031 gives them all). */
export function decodeCommunicationRecords(list: SzlList): CommunicationRecord[] {
  if ((list.id & 0xff) !== 0x31) throw new ProtocolError(`SZL 0x${hex4(list.id)} is not a communication capabilities list (xy31)`);
  return list.records.map(decodeCommunicationRecord);
}
