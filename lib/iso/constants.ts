/**
 * ISO-on-TCP constants: TPKT (RFC 1006 §6) and COTP class 0 (ISO 8073 =
 * RFC 905) as RFC 1006 carries it. Every driver over ISO-on-TCP (S7comm,
 * and the next one) reads its framing and handshake sizes and codes here;
 * the bytes are in docs/protocols.md, "TPKT" and "COTP".
 */

export const TPKT_VERSION = 3;
export const TPKT_HEADER = 4;
export const COTP_DT_HEADER = 3;
/** TPKT + COTP DT in front of every payload (an S7 PDU, ...). */
export const FRAME_OVERHEAD = TPKT_HEADER + COTP_DT_HEADER;
/**
 * The largest frame the client, the doctor and the simulator buffer: more
 * than a TPKT's 16-bit length field can announce, so a peer can never make
 * them hold more than one whole TPKT packet.
 */
export const MAX_FRAME = 0x10000 + 16;

/**
 * The TPDU size code S7 clients ask for in a COTP CR and S7 CPUs confirm at most: 0x0A = 1024 bytes (an S7-1500
 * offers PDU 960 only with it; S7CommPlus clients ask for it too: s7commplus (MIT) transport.py).
 */
export const TPDU_SIZE_CODE = 0x0a;

/** COTP disconnect reasons (ISO 8073 = RFC 905, §13.5.3, class 0): 1 congestion at the TSAP (all connections in use). */
export const DR_CONGESTION = 1;
/** 3: the called TSAP (address) is unknown. */
export const DR_ADDRESS_UNKNOWN = 3;

export const enum CotpType {
  CR = 0xe0,
  CC = 0xd0,
  DR = 0x80,
  DC = 0xc0,
  DT = 0xf0,
  ER = 0x70,
}

export const enum CotpParam {
  TpduSize = 0xc0,
  CallingTsap = 0xc1,
  CalledTsap = 0xc2,
}

/** COTP TPDU size code → bytes (0x07 = 128 … 0x0D = 8192). */
export function tpduBytes(code: number): number {
  return code >= 0x07 && code <= 0x0d ? 1 << code : 0;
}
