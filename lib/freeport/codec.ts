/**
 * Pure encode/decode of freeport frames (docs/protocols.md, "S7-200 freeport"). Every field is
 * ASCII hex so data can never look like the start or end character.
 * Decoders throw ProtocolError for a frame that is not valid under the profile;
 * the stream parser (parser.ts) turns that into a 'corrupt' event instead.
 */
import { PlcError, ProtocolError } from '../errors';
import { checksumWidth, DEFAULT_FREEPORT_PROFILE, replyLength, requestLength, type ChecksumKind, type FreeportProfile } from './profile';

export type FreeportCommand = 'read' | 'write';

/** What the master sends: DT, DA, LE, DU. `data` always has profile.dataBytes bytes (zeros when unused). */
export interface FreeportRequest {
  readonly command: FreeportCommand;
  readonly station: number;
  /** LE: bytes to read, or the first bytes of DU the station stores. */
  readonly length: number;
  readonly data: Buffer;
}

/** What a station answers: its data area (after a write, what it now holds). */
export interface FreeportReply {
  /** Only when the profile's reply carries DA. */
  readonly station?: number;
  readonly data: Buffer;
}

/**
 * FC over `covered` (the frame's characters it protects). The first
 * `commandChars` characters are not hex (DT); 'xor-bytes' takes them by their
 * code and every following hex pair as one byte.
 */
export function computeChecksum(kind: ChecksumKind, covered: string, commandChars = 0): number {
  let fc = 0;
  switch (kind) {
    case 'xor-chars':
      for (let i = 0; i < covered.length; i++) fc ^= covered.charCodeAt(i);
      return fc;
    case 'sum-mod-256':
      for (let i = 0; i < covered.length; i++) fc = (fc + covered.charCodeAt(i)) & 0xff;
      return fc;
    case 'xor-bytes':
      for (let i = 0; i < commandChars; i++) fc ^= covered.charCodeAt(i);
      for (let i = commandChars; i + 1 < covered.length; i += 2) fc ^= parseInt(covered.slice(i, i + 2), 16);
      return fc;
    case 'none':
      return 0;
  }
}

/** A read of the station's whole data area: LE = dataBytes, DU zeros. */
export function readRequest(station: number, profile: FreeportProfile = DEFAULT_FREEPORT_PROFILE): FreeportRequest {
  return { command: 'read', station, length: profile.dataBytes, data: Buffer.alloc(profile.dataBytes) };
}

/** A write of `data` to the first data.length bytes of the station's area; DU padded with zeros. */
export function writeRequest(station: number, data: Buffer, profile: FreeportProfile = DEFAULT_FREEPORT_PROFILE): FreeportRequest {
  if (data.length < 1 || data.length > profile.dataBytes) {
    throw new PlcError('INVALID_VALUE', `a freeport write carries 1–${profile.dataBytes} bytes, not ${data.length}`);
  }
  const du = Buffer.alloc(profile.dataBytes);
  data.copy(du);
  return { command: 'write', station, length: data.length, data: du };
}

export function encodeRequest(request: FreeportRequest, profile: FreeportProfile = DEFAULT_FREEPORT_PROFILE): Buffer {
  const p = profile;
  const dt = request.command === 'read' ? p.readCommand : p.writeCommand;
  if (request.length < 0 || request.length > p.dataBytes) {
    throw new PlcError('INVALID_VALUE', `LE ${request.length} is more than the ${p.dataBytes} bytes of DU`);
  }
  const body = dt + hex(request.station, p.addressWidth, 'station') + hex(request.length, p.lengthWidth, 'LE') + du(request.data, p);
  return frame(p, body, 1);
}

export function encodeReply(reply: FreeportReply, profile: FreeportProfile = DEFAULT_FREEPORT_PROFILE): Buffer {
  const p = profile;
  let body = '';
  if (p.replyEchoesAddress) {
    if (reply.station === undefined) throw new PlcError('INVALID_VALUE', "this profile's replies carry the station address");
    body += hex(reply.station, p.addressWidth, 'station');
  }
  return frame(p, body + du(reply.data, p), 0);
}

/** Decodes one complete request frame (as cut by the parser). Throws ProtocolError. */
export function decodeRequest(bytes: Buffer, profile: FreeportProfile = DEFAULT_FREEPORT_PROFILE): FreeportRequest {
  const p = profile;
  const text = open(bytes, p, requestLength(p), 'request');
  let at = 1;
  const dt = text[at++]!;
  const command: FreeportCommand | undefined = dt === p.readCommand ? 'read' : dt === p.writeCommand ? 'write' : undefined;
  if (!command) throw new ProtocolError(`freeport request with unknown command "${printable(dt)}"`);
  const station = field(text, at, p.addressWidth, 'DA');
  at += p.addressWidth;
  const length = field(text, at, p.lengthWidth, 'LE');
  at += p.lengthWidth;
  if (length > p.dataBytes) throw new ProtocolError(`freeport request LE ${length} exceeds the ${p.dataBytes}-byte data area`);
  const data = hexBytes(text, at, p.dataBytes);
  verify(text, p, 1);
  return { command, station, length, data };
}

/** Decodes one complete reply frame. Throws ProtocolError. */
export function decodeReply(bytes: Buffer, profile: FreeportProfile = DEFAULT_FREEPORT_PROFILE): FreeportReply {
  const p = profile;
  const text = open(bytes, p, replyLength(p), 'reply');
  let at = 1;
  let station: number | undefined;
  if (p.replyEchoesAddress) {
    station = field(text, at, p.addressWidth, 'DA');
    at += p.addressWidth;
  }
  const data = hexBytes(text, at, p.dataBytes);
  verify(text, p, 0);
  return station === undefined ? { data } : { station, data };
}

function frame(p: FreeportProfile, body: string, commandChars: number): Buffer {
  const fc = p.checksum === 'none' ? '' : hex(computeChecksum(p.checksum, body, commandChars), 2, 'FC');
  return Buffer.from(p.start + body + fc + p.end, 'latin1');
}

function du(data: Buffer, p: FreeportProfile): string {
  if (data.length > p.dataBytes) throw new PlcError('INVALID_VALUE', `DU holds ${p.dataBytes} bytes, not ${data.length}`);
  const padded = Buffer.alloc(p.dataBytes);
  data.copy(padded);
  return padded.toString('hex').toUpperCase();
}

function hex(value: number, width: number, what: string): string {
  if (!Number.isInteger(value) || value < 0 || value >= 16 ** width) {
    throw new PlcError('INVALID_VALUE', `${what} ${value} does not fit ${width} hex characters`);
  }
  return value.toString(16).toUpperCase().padStart(width, '0');
}

function open(bytes: Buffer, p: FreeportProfile, length: number, what: string): string {
  const text = bytes.toString('latin1');
  if (text.length !== length) throw new ProtocolError(`freeport ${what} of ${text.length} characters (expected ${length})`);
  if (text[0] !== p.start || text[length - 1] !== p.end) {
    throw new ProtocolError(`freeport ${what} not framed by "${p.start}" … "${p.end}"`);
  }
  return text;
}

const HEX_RUN = /^[0-9A-Fa-f]*$/;

function field(text: string, at: number, width: number, name: string): number {
  const s = text.slice(at, at + width);
  if (!HEX_RUN.test(s)) throw new ProtocolError(`freeport ${name} "${printable(s)}" is not hex`);
  return parseInt(s, 16);
}

function hexBytes(text: string, at: number, count: number): Buffer {
  const s = text.slice(at, at + 2 * count);
  if (!HEX_RUN.test(s)) throw new ProtocolError(`freeport DU "${printable(s)}" is not hex`);
  return Buffer.from(s, 'hex');
}

function verify(text: string, p: FreeportProfile, commandChars: number): void {
  const width = checksumWidth(p);
  if (width === 0) return;
  const fcAt = text.length - 1 - width;
  const sent = field(text, fcAt, width, 'FC');
  const computed = computeChecksum(p.checksum, text.slice(1, fcAt), commandChars);
  if (sent !== computed) {
    throw new ProtocolError(
      `freeport checksum mismatch: frame carries ${hex(sent, 2, 'FC')}, its characters give ${hex(computed, 2, 'FC')} (${p.checksum})`,
    );
  }
}

function printable(s: string): string {
  return s.replace(/[^\x20-\x7e]/g, (c) => `\\x${c.charCodeAt(0).toString(16).padStart(2, '0')}`);
}
