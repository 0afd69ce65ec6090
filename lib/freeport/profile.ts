/**
 * A freeport frame profile: every S7-200 freeport program defines its own
 * frame, so the layout is data, not code. The default is the frame of
 * docs/protocols.md ("S7-200 freeport"):
 *
 *   master → station  start DT DA LE DU FC end    q W 05 04 00000000 FC Q
 *   station → master  start DU FC end             q 00000000 FC Q
 *
 * To describe your own PLC program's frame, override only what differs:
 *
 *   const profile = defineProfile({ start: ':', end: '\r', readCommand: 'R', writeCommand: 'W',
 *                                   checksum: 'sum-mod-256', replyEchoesAddress: true });
 *
 * - `start`/`end`: one character each (the PLC's SMB88 start and SMB89 end character).
 * - `readCommand`/`writeCommand`: the DT letter of each command. The default
 *   protocol defines 0x57 'W' as read and 0x52 'R' as write — the reverse of what the
 *   letters suggest, but it is what its PLC program decodes.
 * - `addressWidth`, `lengthWidth`: hex characters of DA and LE (2 each).
 * - `dataBytes`: bytes in DU (4; DU is twice as many hex characters).
 * - `checksum` (FC, two hex characters unless 'none'):
 *     'xor-chars'   XOR of the ASCII codes of the characters it covers (the default)
 *     'xor-bytes'   XOR of the values the fields encode: DT's code, then each hex pair as one byte
 *     'sum-mod-256' sum of the ASCII codes of the characters it covers, modulo 256
 *     'none'        no FC field at all
 *   A request's FC covers DT..DU, a reply's FC covers (DA and) DU.
 * - `replyEchoesAddress`: the reply carries DA after the start character, so
 *   the master can tell which station answered (the default's does not).
 * - `verifyWrites`: the station answers a write with the data it now holds;
 *   the master checks the bytes it wrote are there (else a PLC_ERROR).
 */
import { PlcError } from '../errors';

export type ChecksumKind = 'xor-chars' | 'xor-bytes' | 'sum-mod-256' | 'none';

export const CHECKSUM_KINDS: readonly ChecksumKind[] = ['xor-chars', 'xor-bytes', 'sum-mod-256', 'none'];

export interface FreeportProfile {
  readonly start: string;
  readonly end: string;
  readonly readCommand: string;
  readonly writeCommand: string;
  readonly addressWidth: number;
  readonly lengthWidth: number;
  readonly dataBytes: number;
  readonly checksum: ChecksumKind;
  readonly replyEchoesAddress: boolean;
  readonly verifyWrites: boolean;
}

/** The default frame (docs/protocols.md; its station program sets SMB88 = 113 'q', SMB89 = 81 'Q'). */
export const DEFAULT_FREEPORT_PROFILE: FreeportProfile = Object.freeze({
  start: 'q',
  end: 'Q',
  readCommand: 'W',
  writeCommand: 'R',
  addressWidth: 2,
  lengthWidth: 2,
  dataBytes: 4,
  checksum: 'xor-chars',
  replyEchoesAddress: false,
  verifyWrites: true,
});

/** Width of FC in hex characters. */
export function checksumWidth(profile: FreeportProfile): number {
  return profile.checksum === 'none' ? 0 : 2;
}

/** Characters of a master's request frame (17 for the default profile). */
export function requestLength(p: FreeportProfile): number {
  return 2 + 1 + p.addressWidth + p.lengthWidth + 2 * p.dataBytes + checksumWidth(p);
}

/** Characters of a station's reply frame (12 for the default profile). */
export function replyLength(p: FreeportProfile): number {
  return 2 + (p.replyEchoesAddress ? p.addressWidth : 0) + 2 * p.dataBytes + checksumWidth(p);
}

/** Highest station address DA can carry. */
export function maxStation(p: FreeportProfile): number {
  return 16 ** p.addressWidth - 1;
}

const HEX = /^[0-9A-Fa-f]$/;

/** Fills in the defaults (DEFAULT_FREEPORT_PROFILE) and checks the result; throws PlcError INVALID_VALUE naming the field. */
export function defineProfile(overrides: Partial<FreeportProfile> = {}): FreeportProfile {
  const p: FreeportProfile = { ...DEFAULT_FREEPORT_PROFILE, ...overrides };
  const bad = (field: string, why: string): never => {
    throw new PlcError('INVALID_VALUE', `invalid freeport profile: ${field} ${why}`);
  };
  for (const field of ['start', 'end', 'readCommand', 'writeCommand'] as const) {
    const c = p[field];
    if (typeof c !== 'string' || c.length !== 1 || c.charCodeAt(0) > 0x7f) bad(field, 'must be one ASCII character');
    // A hex digit here could never be told apart from the fields around it.
    if (HEX.test(c)) bad(field, `must not be a hex digit (got "${c}")`);
  }
  if (p.start === p.end) bad('end', 'must differ from start');
  if (p.readCommand === p.writeCommand) bad('writeCommand', 'must differ from readCommand');
  for (const c of [p.readCommand, p.writeCommand]) {
    if (c === p.start || c === p.end) bad('readCommand/writeCommand', 'must differ from the start and end characters');
  }
  const width = (field: 'addressWidth' | 'lengthWidth' | 'dataBytes', max: number) => {
    const v = p[field];
    if (!Number.isInteger(v) || v < 1 || v > max) bad(field, `must be a whole number 1–${max}`);
  };
  width('addressWidth', 4);
  width('lengthWidth', 4);
  width('dataBytes', 64);
  if (p.dataBytes > 16 ** p.lengthWidth - 1) bad('lengthWidth', `is too narrow for ${p.dataBytes} data bytes`);
  if (!CHECKSUM_KINDS.includes(p.checksum)) bad('checksum', `must be one of ${CHECKSUM_KINDS.join(', ')}`);
  return Object.freeze(p);
}
