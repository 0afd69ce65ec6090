/**
 * A CPU that serves at most N items per Read/Write Var job, as snap7's
 * server does (N = 20, `MaxVars` in its s7_types.h): it takes the first N
 * items of a longer job and answers them as if they were the whole job.
 * Captured from snap7 as node-snap7 1.0.9 builds it, a read of 21 one-byte
 * items in DB1 is answered
 *
 *   32 03 0000 <ref> 0002 0077 0000 | 04 14 | ff 04 0008 <byte> <fill> …
 *
 * — a read ack with item count 0x14 = 20 and the data of the first 20 items
 * (test/interop/client-vs-snap7.test.js compares our simulator's answer with
 * snap7's byte for byte; snap7's fill bytes are whatever its answer buffer
 * held, ours are 0). A longer write overruns snap7's fixed table of 20
 * items (it crashed its process); the simulator writes the first N and
 * answers N return codes, the same shape as its reads.
 */
import { S7_JOB_HEADER, S7Function, READ_ITEM } from '../constants';
import { FRAME_OVERHEAD } from '../../iso/constants';
import { dataLengthBytes } from '../codec/pdu';

/** Where the parameters of a job start (TPKT, COTP DT, S7 job header). */
const PARAMS = FRAME_OVERHEAD + S7_JOB_HEADER;

/**
 * The job `frame` cut to its first `n` items (lengths in TPKT and S7 header
 * adjusted; a write keeps the data of those items), or `frame` itself when it
 * has no more than `n` items or does not parse: the job server then refuses a
 * malformed job as it would anyway.
 */
export function firstItems(frame: Buffer, n: number): Buffer {
  if (frame.length < PARAMS + 2) return frame;
  const func = frame[PARAMS]!;
  const count = frame[PARAMS + 1]!;
  if (count <= n || (func !== S7Function.ReadVar && func !== S7Function.WriteVar)) return frame;
  const paramLength = frame.readUInt16BE(13);
  if (paramLength !== 2 + READ_ITEM * count || PARAMS + paramLength > frame.length) return frame;
  const keptParams = 2 + READ_ITEM * n;
  let keptData = 0;
  if (func === S7Function.WriteVar) {
    // Every data item must be there (a malformed job changes no memory); the first n are kept.
    let p = PARAMS + paramLength;
    for (let i = 0; i < count; i++) {
      if (p + 4 > frame.length) return frame;
      const len = dataLengthBytes(frame[p + 1]!, frame.readUInt16BE(p + 2));
      if (p + 4 + len > frame.length) return frame;
      // The last item kept carries no fill byte.
      if (i < n) keptData += 4 + len + (len & 1 && i < n - 1 ? 1 : 0);
      p += 4 + len + (len & 1 ? 1 : 0);
    }
  }
  const out = Buffer.allocUnsafe(PARAMS + keptParams + keptData);
  frame.copy(out, 0, 0, PARAMS + keptParams);
  if (keptData > 0) frame.copy(out, PARAMS + keptParams, PARAMS + paramLength, PARAMS + paramLength + keptData);
  out.writeUInt16BE(out.length, 2);
  out.writeUInt16BE(keptParams, 13);
  out.writeUInt16BE(keptData, 15);
  out[PARAMS + 1] = n;
  return out;
}
