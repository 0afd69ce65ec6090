/**
 * Cuts a freeport byte stream into frames. An RS-485 line carries noise,
 * half frames (a station reset mid-reply), other stations' traffic and the
 * master's own echo: the framer skips to the next start character whenever a
 * character cannot belong to the frame at its position, so one bad byte
 * costs at most the frame it hits. It never throws on input.
 */
import { FrameReader, type FrameCheck } from '../link/framer';
import { ProtocolError, toPlcError } from '../errors';
import { decodeReply, decodeRequest, type FreeportReply, type FreeportRequest } from './codec';
import { checksumWidth, replyLength, requestLength, type FreeportProfile } from './profile';

export type FreeportDirection = 'request' | 'reply';

export type FreeportFrame =
  | { kind: 'request'; request: FreeportRequest; raw: Buffer }
  | { kind: 'reply'; reply: FreeportReply; raw: Buffer }
  /** Framed like a frame but invalid (bad checksum, LE too large, …): a receiver ignores it or retries. */
  | { kind: 'corrupt'; error: ProtocolError; raw: Buffer };

const enum CharClass {
  Hex,
  Command,
  End,
}

/** The framer function for FrameReader: which character class each position of a frame takes. */
export function freeportFramer(profile: FreeportProfile, direction: FreeportDirection): (buffered: Buffer) => FrameCheck {
  const layout = positions(profile, direction);
  const length = layout.length + 2;
  const start = profile.start.charCodeAt(0);
  const end = profile.end.charCodeAt(0);
  const commands = [profile.readCommand.charCodeAt(0), profile.writeCommand.charCodeAt(0)];
  const fits = (c: number, cls: CharClass): boolean =>
    cls === CharClass.Hex ? isHex(c) : cls === CharClass.Command ? commands.includes(c) : c === end;
  return (buf) => {
    if (buf[0] !== start) {
      const next = buf.indexOf(start, 1);
      return { kind: 'skip', length: next < 0 ? buf.length : next };
    }
    const upTo = Math.min(buf.length, length);
    for (let i = 1; i < upTo; i++) {
      const cls = i === length - 1 ? CharClass.End : layout[i - 1]!;
      if (!fits(buf[i]!, cls)) return { kind: 'skip', length: 1 };
    }
    return buf.length < length ? { kind: 'need' } : { kind: 'frame', length };
  };
}

/** Frames of one direction from a byte stream; push() never throws. */
export class FreeportParser {
  private readonly reader: FrameReader;
  private skipped = 0;

  constructor(
    private readonly profile: FreeportProfile,
    private readonly direction: FreeportDirection,
  ) {
    const check = freeportFramer(profile, direction);
    this.reader = new FrameReader((buf) => {
      const verdict = check(buf);
      if (verdict.kind === 'skip') this.skipped += verdict.length;
      return verdict;
    });
  }

  /** Bytes dropped as noise so far (diagnostics). */
  get skippedBytes(): number {
    return this.skipped;
  }

  get buffered(): number {
    return this.reader.buffered;
  }

  push(chunk: Buffer): FreeportFrame[] {
    let raws: Buffer[];
    try {
      raws = this.reader.push(chunk);
    } catch {
      // Cannot happen with this framer (it never buffers more than one frame); stay alive regardless.
      this.reader.reset();
      return [];
    }
    return raws.map((raw) => this.decode(raw));
  }

  /** Forgets a partial frame (the master does this before each request, so a late half reply cannot join the next). */
  reset(): void {
    this.reader.reset();
  }

  private decode(raw: Buffer): FreeportFrame {
    try {
      return this.direction === 'request'
        ? { kind: 'request', request: decodeRequest(raw, this.profile), raw }
        : { kind: 'reply', reply: decodeReply(raw, this.profile), raw };
    } catch (err) {
      const error = err instanceof ProtocolError ? err : new ProtocolError(toPlcError(err).message, { cause: err });
      return { kind: 'corrupt', error, raw };
    }
  }
}

function positions(p: FreeportProfile, direction: FreeportDirection): CharClass[] {
  const hexRun = (n: number) => new Array<CharClass>(n).fill(CharClass.Hex);
  const layout =
    direction === 'request'
      ? [CharClass.Command, ...hexRun(p.addressWidth + p.lengthWidth + 2 * p.dataBytes + checksumWidth(p))]
      : hexRun((p.replyEchoesAddress ? p.addressWidth : 0) + 2 * p.dataBytes + checksumWidth(p));
  const expected = (direction === 'request' ? requestLength(p) : replyLength(p)) - 2;
  if (layout.length !== expected) throw new Error('freeport frame layout out of step with the profile');
  return layout;
}

function isHex(c: number): boolean {
  return (c >= 0x30 && c <= 0x39) || (c >= 0x41 && c <= 0x46) || (c >= 0x61 && c <= 0x66);
}
