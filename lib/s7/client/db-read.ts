/** A DB's bytes by Read Var jobs on a session: one item per job, as many jobs as the PDU size needs (sent at once, queued past AmQ). */
import { ProtocolError } from '../../errors';
import { encodeReadRequest } from '../codec';
import { headerError, ReturnCode, returnCodeError, S7Area, TransportSize } from '../constants';
import { maxReadItemData } from '../plan/limits';
import type { S7Session } from './session';

/** Reads `length` bytes of DB `db` from byte 0. */
export async function readDbBytes(session: S7Session, db: number, length: number, signal?: AbortSignal): Promise<Buffer> {
  const chunk = maxReadItemData(session.pduSize);
  const parts: Promise<Buffer>[] = [];
  for (let start = 0; start < length; start += chunk) parts.push(readChunk(session, db, start, Math.min(chunk, length - start), signal));
  return Buffer.concat(await Promise.all(parts));
}

async function readChunk(session: S7Session, db: number, start: number, count: number, signal?: AbortSignal): Promise<Buffer> {
  const what = `read of DB${db} bytes ${start}..${start + count - 1}`;
  const item = { area: S7Area.DB, dbNumber: db, transportSize: TransportSize.BYTE, count, address: start * 8 };
  const answer = session.decode(await session.exchange(encodeReadRequest(0, [item]), what, signal));
  if (answer.kind === 'error') throw headerError(answer.errorClass, answer.errorCode, what);
  if (answer.kind !== 'read-ack' || answer.items.length !== 1) {
    throw session.malformed(new ProtocolError(`the answer to a ${what} does not match it (${answer.kind})`));
  }
  const { returnCode, data } = answer.items[0]!;
  if (returnCode !== ReturnCode.Success) throw returnCodeError(returnCode, what);
  if (data.length !== count) throw new ProtocolError(`${what}: asked for ${count} bytes, the PLC returned ${data.length}`);
  return Buffer.from(data);
}
