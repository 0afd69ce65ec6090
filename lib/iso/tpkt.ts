/** TPKT (RFC 1006 §6): version 3, reserved 0, 16-bit length of the whole packet. */
import { ProtocolError, ValueError } from '../errors';
import type { FrameCheck } from '../link/framer';
import { COTP_DT_HEADER, TPKT_HEADER, TPKT_VERSION } from './constants';

/** Smallest TPKT that can carry a COTP header (LI + code + at least one byte). */
const MIN_TPKT = TPKT_HEADER + COTP_DT_HEADER;

/**
 * Framer for link/FrameReader: cuts TPKT packets. A wrong version or a length
 * shorter than a COTP header is 'bad' (the stream cannot be resynchronised).
 */
export function checkTpkt(buf: Buffer): FrameCheck {
  if (buf.length === 0) return { kind: 'need' };
  if (buf[0] !== TPKT_VERSION) return bad(`TPKT version ${buf[0]}, expected 3`);
  if (buf.length < TPKT_HEADER) return { kind: 'need' };
  const length = (buf[2]! << 8) | buf[3]!;
  if (length < MIN_TPKT) return bad(`TPKT length ${length} is shorter than a COTP header`);
  return buf.length >= length ? { kind: 'frame', length } : { kind: 'need' };
}

function bad(message: string): FrameCheck {
  return { kind: 'bad', error: new ProtocolError(message) };
}

/** A new frame of `payloadLength` bytes after the TPKT header, header filled in. Contents after byte 4 are not zeroed. */
export function tpktFrame(payloadLength: number): Buffer {
  const length = TPKT_HEADER + payloadLength;
  if (length > 0xffff) throw new ValueError('TPKT packet', `${length} bytes exceed 65535`);
  const frame = Buffer.allocUnsafe(length);
  frame[0] = TPKT_VERSION;
  frame[1] = 0;
  frame[2] = length >> 8;
  frame[3] = length & 0xff;
  return frame;
}

/** Checks that `frame` is exactly one TPKT packet; returns its length. */
export function assertTpkt(frame: Buffer, what: string): number {
  if (frame.length < MIN_TPKT) throw new ProtocolError(`${what}: frame of ${frame.length} bytes is too short`);
  if (frame[0] !== TPKT_VERSION) throw new ProtocolError(`${what}: TPKT version ${frame[0]}, expected 3`);
  const length = (frame[2]! << 8) | frame[3]!;
  if (length !== frame.length) throw new ProtocolError(`${what}: TPKT length ${length} but ${frame.length} bytes`);
  return length;
}
