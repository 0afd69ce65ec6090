/**
 * SZL (system status list, "SSL" in English manuals): the list format and
 * decoders for the common lists, with the encoders the simulator builds its
 * answers with, so both sides read one layout.
 *
 * A list as the CPU sends it: SZL ID (2), index (2), record length in bytes
 * (LENTHDR, 2), record count (N_DR, 2), then N_DR records. An answer larger
 * than the PDU comes in several userdata parts; the header is in the first
 * part only, the records continue in the next parts byte for byte.
 * The ID's high byte selects the extract: 0x00xx all records, 0x01xx one
 * record or group given by the index, 0x0Fxx the header only.
 */
import { ProtocolError, ValueError } from '../../errors';
import { hex4 } from '../../values/text';

/** One SZL list as read (`readSzl`). Records are copies (they do not keep the frames alive). */
export interface SzlList {
  id: number;
  index: number;
  /** Bytes per record (LENTHDR). */
  recordLength: number;
  records: Buffer[];
  /**
   * The record count the CPU announced (N_DR). For a header-only extract
   * (0x0Fxx: "how many records exist") it is the answer itself, with no
   * records sent; otherwise records.length. Absent on lists built here.
   */
  count?: number;
}

/** SZL IDs this library decodes. */
export const SZL = Object.freeze({
  /** The SZL IDs the CPU offers. */
  IDS: 0x0000,
  /** Module identification: order code, hardware and firmware version. */
  MODULE_ID: 0x0011,
  /** Component identification: names, serial number, copyright. */
  COMPONENT_ID: 0x001c,
  /** Communication capabilities (index 1: max PDU, connections, rates). */
  COMMUNICATION: 0x0131,
  /** Protection level and key switch (index 4). */
  PROTECTION: 0x0232,
  /** Current mode and the last mode transition. */
  CPU_STATE: 0x0424,
  /** LEDs. */
  LEDS: 0x0074,
  /** Diagnostic buffer (0x01A0: the n most recent entries, n = index). */
  DIAGNOSTICS: 0x00a0,
} as const);

const HEADER = 8;

/** The list from the bytes of a whole answer (first part's data and every next part's, concatenated). Throws ProtocolError. */
export function parseSzl(bytes: Buffer): SzlList {
  if (bytes.length < HEADER) throw new ProtocolError(`SZL answer of ${bytes.length} bytes is shorter than its 8-byte header`);
  const id = bytes.readUInt16BE(0);
  const index = bytes.readUInt16BE(2);
  const recordLength = bytes.readUInt16BE(4);
  const count = bytes.readUInt16BE(6);
  const body = bytes.length - HEADER;
  const name = `SZL 0x${hex4(id)} index 0x${hex4(index)}`;
  // A header-only extract (0x0Fxx) announces N_DR records and sends none.
  const headerOnly = (id & 0x0f00) === 0x0f00;
  if (headerOnly ? body !== 0 : recordLength * count !== body) {
    throw new ProtocolError(`${name} announces ${count} records of ${recordLength} bytes, ${body} bytes arrived`);
  }
  if (!headerOnly && count > 0 && recordLength === 0) throw new ProtocolError(`${name} announces ${count} records of 0 bytes`);
  const records: Buffer[] = [];
  if (!headerOnly)
    for (let i = 0; i < count; i++) records.push(Buffer.from(bytes.subarray(HEADER + i * recordLength, HEADER + (i + 1) * recordLength)));
  return { id, index, recordLength, records, count };
}

/** The bytes of a list (header and records), as the simulator sends them before splitting into parts. */
export function encodeSzl(list: SzlList, headerOnly = false): Buffer {
  const out = Buffer.alloc(HEADER + (headerOnly ? 0 : list.recordLength * list.records.length));
  out.writeUInt16BE(list.id, 0);
  out.writeUInt16BE(list.index, 2);
  out.writeUInt16BE(list.recordLength, 4);
  out.writeUInt16BE(headerOnly ? (list.count ?? list.records.length) : list.records.length, 6);
  if (!headerOnly) {
    list.records.forEach((r, i) => {
      if (r.length !== list.recordLength)
        throw new ValueError(`SZL record ${i}`, `it has ${r.length} bytes, the list's records ${list.recordLength}`);
      r.copy(out, HEADER + i * list.recordLength);
    });
  }
  return out;
}

export function need(list: SzlList, min: number, what: string): void {
  if (list.recordLength < min)
    throw new ProtocolError(`SZL 0x${hex4(list.id)} (${what}): records of ${list.recordLength} bytes, expected at least ${min}`);
}

/** Text of a fixed-width field: up to the first NUL, trailing spaces removed. */
export function text(b: Buffer, start: number, end: number): string {
  const field = b.subarray(start, Math.min(end, b.length));
  const nul = field.indexOf(0);
  return (nul < 0 ? field : field.subarray(0, nul)).toString('latin1').replace(/\s+$/, '');
}

/** Text into a fixed-width field, padded with `pad` (module identification pads with spaces, component identification with NULs, as CPUs send them). */
export function putText(b: Buffer, start: number, width: number, value: string, pad = 0x20): void {
  b.fill(pad, start, start + width);
  b.write(value.slice(0, width), start, 'latin1');
}

// ---------------------------------------------------------------- 0x0000: SZL IDs

/** SZL 0x0000: the IDs the CPU offers (2-byte records). */
export function decodeSzlIds(list: SzlList): number[] {
  need(list, 2, 'available SZL IDs');
  return list.records.map((r) => r.readUInt16BE(0));
}

export function encodeSzlIds(ids: readonly number[]): SzlList {
  return { id: SZL.IDS, index: 0, recordLength: 2, records: ids.map((id) => Buffer.of(id >> 8, id & 0xff)) };
}
