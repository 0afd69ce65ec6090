/**
 * The edge node's own payloads (Sparkplug 3.0, sections 4.1.2 and 4.1.3):
 * NBIRTH with the bdSeq and `Node Control/Rebirth` metrics, and NDEATH (the
 * MQTT Will) with the bdSeq metric only and no seq.
 */
import { DataType } from './datatypes';
import type { SparkplugPayload } from './model';

/** The metric a host writes true (in an NCMD) to ask for new births (section 5.6 "Rebirth"). */
export const REBIRTH_METRIC = 'Node Control/Rebirth';
/** The birth/death sequence metric (tck-id-topics-nbirth-bdseq-included). */
export const BDSEQ_METRIC = 'bdSeq';

/** NDEATH: only the bdSeq, as an Int64 (tck-id-topics-ndeath-payload, tck-id-topics-ndeath-seq). */
export function ndeathPayload(bdSeq: number, now = Date.now()): SparkplugPayload {
  return { timestamp: now, metrics: [{ name: BDSEQ_METRIC, timestamp: now, datatype: DataType.Int64, value: BigInt(bdSeq) }] };
}

/** NBIRTH: seq 0, the bdSeq of this session's Will, Node Control/Rebirth false (tck-id-topics-nbirth-*). */
export function nbirthPayload(bdSeq: number, now = Date.now()): SparkplugPayload {
  return {
    timestamp: now,
    seq: 0,
    metrics: [
      { name: BDSEQ_METRIC, timestamp: now, datatype: DataType.Int64, value: BigInt(bdSeq) },
      { name: REBIRTH_METRIC, timestamp: now, datatype: DataType.Boolean, value: false },
    ],
  };
}
