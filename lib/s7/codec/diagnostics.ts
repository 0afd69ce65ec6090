/**
 * The diagnostic buffer (SZL 0x00A0 all entries, 0x01A0 the n most recent),
 * newest entry first. Each entry is 20 bytes, laid out like the start
 * information of an organization block:
 *
 *   0-1    event ID (class in the high byte: 0x43 mode transitions, 0x45 STOP and defect, 0x13 start requests, 0x39/0x38 module events coming/going)
 *   2      priority class
 *   3      OB number
 *   4-5    data ID (DatID 1/2)
 *   6-7    info 1 (word)
 *   8-11   info 2/3 (two words)
 *   12-19  time stamp: DATE_AND_TIME, 8 BCD bytes — the last 8 bytes of the entry
 */
import { ProtocolError } from '../../errors';
import { decodeDateAndTime, encodeDateAndTime } from '../../values/time';
import { SZL, type SzlList } from './szl';
import { hex4 } from '../../values/text';

const DIAGNOSTIC_ENTRY = 20;

export interface DiagnosticEntry {
  /** When the event happened (PLC clock fields as UTC, see readClock); an Invalid Date when the stamp is not a date. */
  time: Date;
  eventId: number;
  /** Plain-text description for the common events; "event 0x…" for an ID this library does not describe. */
  description: string;
  priority: number;
  ob: number;
  /** Data ID (DatID 1/2). */
  dataId: number;
  /** Info 1 (word) and info 2/3 (two words). */
  info1: number;
  info2: number;
  info3: number;
}

/**
 * Short descriptions of the events a user sees most: mode transitions, stop
 * causes, restarts, module failures and power. Written for this library;
 * other IDs keep their number.
 */
export const EVENT_DESCRIPTIONS: Readonly<Record<number, string>> = Object.freeze({
  0x1381: 'Manual warm restart requested',
  0x1382: 'Automatic warm restart requested',
  0x1383: 'Manual hot restart requested',
  0x1384: 'Automatic hot restart requested',
  0x1385: 'Manual cold restart requested',
  0x1386: 'Automatic cold restart requested',
  0x4300: 'Power on with backup',
  0x4301: 'Mode transition STOP to STARTUP',
  0x4302: 'Mode transition STARTUP to RUN',
  0x4303: 'STOP by the mode selector',
  0x4304: 'STOP by a programming device, operator panel or communication (PLC stop)',
  0x4307: 'Memory reset started by a programming device',
  0x4308: 'Memory reset started by the mode selector',
  0x4309: 'Memory reset started automatically (power on without backup)',
  0x430e: 'Memory reset done',
  0x4520: 'DEFECT: STOP not possible',
  0x4548: 'STOP by the I/O management',
  0x4562: 'STOP by a programming error (OB not loaded or not possible)',
  0x4563: 'STOP by an I/O access error (OB not loaded or not possible)',
  0x4568: 'STOP by a time error (OB not loaded or not possible)',
  0x38c4: 'Distributed I/O: station back',
  0x39c4: 'Distributed I/O: station failure',
  0x3861: 'Module inserted, type as configured',
  0x3961: 'Module removed or not responding',
  0x3922: 'Backup voltage failure (battery)',
  0x3822: 'Backup voltage back (battery)',
});

/** The description of an event ID, or "event 0x4711" when this library has none. */
export function describeEvent(eventId: number): string {
  return EVENT_DESCRIPTIONS[eventId] ?? `event 0x${hex4(eventId)}`;
}

/** Entries of a diagnostic buffer list, newest first as the CPU sends them. Throws ProtocolError on a record of the wrong size. */
export function decodeDiagnosticBuffer(list: SzlList): DiagnosticEntry[] {
  if (list.records.length > 0 && list.recordLength !== DIAGNOSTIC_ENTRY) {
    throw new ProtocolError(`diagnostic buffer entries of ${list.recordLength} bytes, expected ${DIAGNOSTIC_ENTRY}`);
  }
  return list.records.map((r) => {
    const eventId = r.readUInt16BE(0);
    return {
      time: decodeDateAndTime(r, 12),
      eventId,
      description: describeEvent(eventId),
      priority: r[2]!,
      ob: r[3]!,
      dataId: r.readUInt16BE(4),
      info1: r.readUInt16BE(6),
      info2: r.readUInt16BE(8),
      info3: r.readUInt16BE(10),
    };
  });
}

/** What the simulator logs: an entry without its description. */
export type DiagnosticEvent = Omit<DiagnosticEntry, 'description'>;

function encodeDiagnosticEntry(e: DiagnosticEvent): Buffer {
  const r = Buffer.alloc(DIAGNOSTIC_ENTRY);
  r.writeUInt16BE(e.eventId, 0);
  r[2] = e.priority;
  r[3] = e.ob;
  r.writeUInt16BE(e.dataId, 4);
  r.writeUInt16BE(e.info1, 6);
  r.writeUInt16BE(e.info2, 8);
  r.writeUInt16BE(e.info3, 10);
  encodeDateAndTime(e.time, r, 12);
  return r;
}

/** The list of `entries` (newest first); `recent` > 0 gives SZL 0x01A0 with that many. */
export function encodeDiagnosticBuffer(entries: readonly DiagnosticEvent[], recent = 0): SzlList {
  const chosen = recent > 0 ? entries.slice(0, recent) : entries;
  return {
    id: recent > 0 ? 0x01a0 : SZL.DIAGNOSTICS,
    index: recent,
    recordLength: DIAGNOSTIC_ENTRY,
    records: chosen.map(encodeDiagnosticEntry),
  };
}
