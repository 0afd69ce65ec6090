/**
 * The client's way into the COTP tunnel of an S7CommPlus connection: TCP to
 * port 102, COTP CR with the S7CommPlus TSAPs (calling 0x0600, called the
 * ASCII name of the role) → CC, then the transport's CotpTunnel
 * (lib/s7plus/transport/tunnel.ts) over the socket, at the TPDU size the CC
 * confirmed. TLS runs over the tunnel, not over the raw socket, so TPKT and
 * COTP stay plain as the PLC expects (s7commplus (MIT), transport.py
 * _build_cotp_cr, connection.py _activate_tls).
 */
import { ConnectionError } from '../../errors';
import { IsoConnectError, isoConnect } from '../../iso/connect';
import { TPDU_SIZE_CODE } from '../../iso/constants';
import { CotpTunnel } from '../transport/tunnel';
import { LOCAL_TSAP, RemoteTsap as REMOTE_TSAP } from '../constants';
import type { S7PlusRole } from '../url';

/**
 * TCP and COTP CR → CC by the ISO connect step every driver over ISO-on-TCP
 * uses (lib/iso/connect.ts), with the S7CommPlus TSAPs: calling 0x0600,
 * called the role's name in ASCII. Rejects with a PlcError (CONNECT_FAILED
 * when the PLC refuses the TSAPs) and leaves no socket behind.
 */
export async function openTunnel(
  e: { host: string; port: number; role: S7PlusRole },
  o: { name: string; timeout: number; signal: AbortSignal },
): Promise<CotpTunnel> {
  let iso;
  try {
    iso = await isoConnect({
      name: o.name,
      host: e.host,
      port: e.port,
      timeout: o.timeout,
      answerTimeout: o.timeout,
      signal: o.signal,
      callingTsap: LOCAL_TSAP,
      calledTsap: Buffer.from(REMOTE_TSAP[e.role], 'latin1'),
      tpduSize: TPDU_SIZE_CODE,
    });
  } catch (err) {
    if (
      err instanceof IsoConnectError &&
      (err.refusal.kind === 'disconnect' || err.refusal.kind === 'error' || err.refusal.kind === 'unexpected')
    ) {
      throw new ConnectionError(
        'CONNECT_FAILED',
        `${o.name} refused the S7CommPlus connection (called TSAP "${REMOTE_TSAP[e.role]}"): the CPU does not speak S7CommPlus on this port, or its connection limit is reached`,
        { cause: err },
      );
    }
    throw err;
  }
  const tunnel = new CotpTunnel(iso.socket, { tpduSize: iso.tpduBytes || 1 << TPDU_SIZE_CODE, reader: iso.frames.reader, peer: o.name });
  iso.frames.stop();
  return tunnel;
}
