/**
 * Which protocol a COTP connection request asks for, as a CPU tells them
 * apart on port 102: an S7CommPlus client calls the TSAP named by its role
 * in ASCII, `SIMATIC-ROOT-HMI` (or `-ES`, `-PG`), where a PUT/GET client
 * calls a 2-byte rack/slot TSAP (s7commplus (MIT) protocol.py
 * S7COMMPLUS_REMOTE_TSAP and ConnectionType; transport.py builds the CR).
 */
import { RemoteTsap } from '../constants';

/** COTP parameter codes in a connection request (ISO 8073). */
const CALLING_TSAP = 0xc1;
const CALLED_TSAP = 0xc2;
const TPDU_SIZE = 0xc0;
/** The called TSAPs of S7CommPlus roles. */
const PLUS_TSAPS: ReadonlySet<string> = new Set(Object.values(RemoteTsap));

export interface ConnectionRequest {
  readonly sourceRef: number;
  readonly calling: Buffer;
  readonly called: Buffer;
}

/** The parameters of a TPKT + COTP CR frame, or undefined when the frame is not a well-formed CR. */
export function connectionRequest(frame: Buffer): ConnectionRequest | undefined {
  if (frame.length < 11 || frame[5] !== 0xe0) return undefined;
  const end = 5 + frame[4]!;
  if (end > frame.length) return undefined;
  const sourceRef = frame.readUInt16BE(8);
  let calling = Buffer.alloc(0);
  let called = Buffer.alloc(0);
  for (let p = 11; p + 2 <= end;) {
    const code = frame[p]!;
    const len = frame[p + 1]!;
    if (p + 2 + len > end) return undefined;
    const value = frame.subarray(p + 2, p + 2 + len);
    if (code === CALLING_TSAP) calling = Buffer.from(value);
    else if (code === CALLED_TSAP) called = Buffer.from(value);
    p += 2 + len;
  }
  return { sourceRef, calling, called };
}

/** True when the frame is a COTP CR whose called TSAP names an S7CommPlus role (HMI, ES, PG). */
export function isS7PlusRequest(frame: Buffer): boolean {
  const cr = connectionRequest(frame);
  return cr !== undefined && PLUS_TSAPS.has(cr.called.toString('latin1'));
}

/** The CPU's connection confirm: its reference 1, the TSAPs echoed, TPDU size 1024. */
export function connectionConfirm(cr: ConnectionRequest): Buffer {
  const params = Buffer.concat([
    Buffer.from([TPDU_SIZE, 1, 0x0a]),
    Buffer.from([CALLING_TSAP, cr.calling.length]),
    cr.calling,
    Buffer.from([CALLED_TSAP, cr.called.length]),
    cr.called,
  ]);
  const cotp = Buffer.concat([Buffer.from([6 + params.length, 0xd0, cr.sourceRef >> 8, cr.sourceRef & 0xff, 0x00, 0x01, 0x00]), params]);
  const tpkt = Buffer.from([3, 0, 0, 0]);
  tpkt.writeUInt16BE(4 + cotp.length, 2);
  return Buffer.concat([tpkt, cotp]);
}

/** Data in one TPKT + COTP DT frame, last of its unit (EOT). */
export function dataFrame(payload: Buffer): Buffer {
  const head = Buffer.from([3, 0, 0, 0, 2, 0xf0, 0x80]);
  head.writeUInt16BE(7 + payload.length, 2);
  return Buffer.concat([head, payload]);
}
