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
import { describeEvent } from './event-texts';

const DIAGNOSTIC_ENTRY = 20;

export interface DiagnosticEntry {
  /** When the event happened (PLC clock fields as UTC, see readClock); an Invalid Date when the stamp is not a date. */
  time: Date;
  eventId: number;
  /** The event's text (event-texts.ts): its own, or its class and whether it is coming or going. */
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

export { EVENT_DESCRIPTIONS, describeEvent } from './event-texts';

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
