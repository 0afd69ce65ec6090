/** The execution of a write plan's jobs on a session. */
import { PlcError, ProtocolError, toPlcError } from '../../errors';
import { encodeWriteRequest, type S7Message } from '../codec';
import { headerError, ReturnCode, returnCodeError } from '../constants';
import type { PlannedWriteItem } from '../plan';
import type { S7Session } from './session';

/**
 * One Write Var job; `tags[i]` is the index in `errors` of item i's tag,
 * which gets the tag's first error. A PLC that answers fewer return codes
 * than the job had items (at least one) served those first items (return
 * codes come in item order): the limit is learnt and the items it left
 * out are sent again in jobs it serves. The items it answered are not
 * sent twice (a second write of a command bit could act twice).
 */
export async function writeJob(
  session: S7Session,
  items: PlannedWriteItem[],
  tags: number[],
  errors: (PlcError | undefined)[],
  signal: AbortSignal | undefined,
  learnItemLimit: (served: number) => number,
): Promise<void> {
  const n = items.length;
  const failAll = (err: PlcError) => tags.forEach((t) => (errors[t] ??= err));
  let answer: S7Message;
  try {
    answer = session.decode(await session.exchange(encodeWriteRequest(0, items), `write of ${n} item(s)`, signal));
  } catch (err) {
    // The write may or may not have reached the PLC: its tags get the error, it is never silently dropped.
    return failAll(toPlcError(err));
  }
  if (answer.kind === 'error') return failAll(headerError(answer.errorClass, answer.errorCode, 'write'));
  const served = answer.kind === 'write-ack' ? answer.returnCodes.length : 0;
  if (answer.kind !== 'write-ack' || served === 0 || served > n) {
    return failAll(new ProtocolError(`the answer to a write of ${n} item(s) does not match it (${answer.kind})`));
  }
  answer.returnCodes.forEach((rc, i) => {
    if (rc !== ReturnCode.Success) errors[tags[i]!] ??= returnCodeError(rc);
  });
  if (served === n) return;
  const size = learnItemLimit(served);
  const rest: Promise<void>[] = [];
  for (let i = served; i < n; i += size)
    rest.push(writeJob(session, items.slice(i, i + size), tags.slice(i, i + size), errors, signal, learnItemLimit));
  await Promise.all(rest);
}
