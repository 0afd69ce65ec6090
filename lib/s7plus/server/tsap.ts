/**
 * Which protocol a COTP connection request asks for, as a CPU tells them
 * apart on port 102: an S7CommPlus client calls the TSAP named by its role
 * in ASCII, `SIMATIC-ROOT-HMI` (or `-ES`, `-PG`), where a PUT/GET client
 * calls a 2-byte rack/slot TSAP (s7commplus (MIT) protocol.py
 * S7COMMPLUS_REMOTE_TSAP and ConnectionType; transport.py builds the CR).
 * The CR and CC are lib/iso's (TPKT and COTP), as the client's.
 */
import { CotpParam, CotpType, TPDU_SIZE_CODE, TPKT_HEADER, tpduBytes } from '../../iso/constants';
import { encodeConnectionConfirm } from '../../iso/cotp';
import { RemoteTsap } from '../constants';

/** The CPU's COTP source reference. */
const CPU_REF = 0x0001;
/** The called TSAPs of S7CommPlus roles. */
const PLUS_TSAPS: ReadonlySet<string> = new Set(Object.values(RemoteTsap));

export interface ConnectionRequest {
  readonly sourceRef: number;
  readonly calling: Buffer;
  readonly called: Buffer;
  /** The TPDU size code asked for; 0 when the CR names none. */
  readonly tpduSize: number;
}

/**
 * The parameters of a TPKT + COTP CR frame, or undefined when the frame is not a well-formed CR. The TSAPs are kept
 * as bytes of any length (lib/iso's decodeCotp reads the 2-byte ones of PUT/GET only).
 */
export function connectionRequest(frame: Buffer): ConnectionRequest | undefined {
  if (frame.length < TPKT_HEADER + 7 || frame[TPKT_HEADER + 1] !== CotpType.CR) return undefined;
  const end = TPKT_HEADER + 1 + frame[TPKT_HEADER]!;
  if (end > frame.length) return undefined;
  const sourceRef = frame.readUInt16BE(TPKT_HEADER + 4);
  let calling = Buffer.alloc(0);
  let called = Buffer.alloc(0);
  let tpduSize = 0;
  for (let p = TPKT_HEADER + 7; p + 2 <= end;) {
    const code = frame[p]!;
    const len = frame[p + 1]!;
    if (p + 2 + len > end) return undefined;
    const value = frame.subarray(p + 2, p + 2 + len);
    if (code === CotpParam.CallingTsap) calling = Buffer.from(value);
    else if (code === CotpParam.CalledTsap) called = Buffer.from(value);
    else if (code === CotpParam.TpduSize && len === 1) tpduSize = value[0]!;
    p += 2 + len;
  }
  return { sourceRef, calling, called, tpduSize };
}

/** True when the frame is a COTP CR whose called TSAP names an S7CommPlus role (HMI, ES, PG). */
export function isS7PlusRequest(frame: Buffer): boolean {
  const cr = connectionRequest(frame);
  return cr !== undefined && PLUS_TSAPS.has(cr.called.toString('latin1'));
}

/**
 * The CPU's connection confirm: its reference 1, the TSAPs echoed, the TPDU size asked for up to 1024 bytes (a CR
 * without one: 1024, as the S7 simulator confirms); and that size in bytes, which the tunnel cuts its DT frames to.
 */
export function connectionConfirm(cr: ConnectionRequest): { frame: Buffer; tpduBytes: number } {
  const tpduSize = tpduBytes(cr.tpduSize) ? Math.min(cr.tpduSize, TPDU_SIZE_CODE) : TPDU_SIZE_CODE;
  const frame = encodeConnectionConfirm({
    sourceRef: CPU_REF,
    destinationRef: cr.sourceRef,
    callingTsap: cr.calling,
    calledTsap: cr.called,
    tpduSize,
  });
  return { frame, tpduBytes: tpduBytes(tpduSize) };
}
