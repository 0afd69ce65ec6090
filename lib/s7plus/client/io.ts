/**
 * Reads and writes by address over S7CommPlus: a standard DB's bytes by
 * access area and the classic-blob LIDs (DB number, byte offset, byte
 * count), and the I, Q and M areas by their native objects; values decoded
 * and encoded with the S7 value rules (lib/values), so DB10.DBW2 gives over
 * s7plus:// what it gives over s7://. Items go in requests of at most the
 * item limit; each item's own refusal is its tag's result. Layouts from
 * s7commplus (MIT), client.py (_build_read_payload, _build_area_read_payload,
 * _build_write_payload).
 */
import { PlcError, toPlcError, type TagResult } from '../../errors';
import type { ReadValues } from '../../link/driver';
import type { PlcValue, Tag } from '../../types';
import { decodeTag, encodeTag } from '../../values';
import { addressBytes, blobValue, classicBlobAddress, writeValueBytes, type ItemAddress, type SetResults } from '../codec/variables';
import type { PValue } from '../codec/pvalue';
import { Ids } from '../constants';
import { readAsk, writeAsk } from './asks';
import { inChunks, type Limits } from './chunks';
import { itemAnswer, itemRefusal, notAnswered, refusedWhole, untrustedValue } from './refusals';
import type { S7PlusSession } from './session';

/** The native objects of the I, Q and M areas (s7commplus (MIT), protocol.py Ids.NATIVE_THE_*_AREA_RID). */
const AREA_OBJECT: Partial<Record<Tag['area'], number>> = {
  I: Ids.NativeTheIAreaRID,
  Q: Ids.NativeTheQAreaRID,
  M: Ids.NativeTheMAreaRID,
};

/** Where a tag's bytes are, as an item address; a PlcError for an area S7CommPlus does not reach by address. */
export function itemAddress(tag: Tag): ItemAddress | PlcError {
  if (tag.area === 'DB') return classicBlobAddress(tag.dbNumber, tag.byteOffset, tag.byteLength);
  const area = AREA_OBJECT[tag.area];
  if (area === undefined) {
    return new PlcError(
      'NOT_SUPPORTED',
      `${tag.address}: S7CommPlus reaches data blocks and the I, Q and M areas by address, not ${tag.area}`,
      {
        tag: tag.address,
      },
    );
  }
  return {
    symbolCrc: 0,
    accessArea: area,
    accessSubArea: Ids.ControllerAreaValueActual,
    lids: [Ids.LidClassicBlob, tag.byteOffset, tag.byteLength],
  };
}

export function bytesOf(v: PValue): Buffer | undefined {
  const blob = v.value as { data?: unknown } | undefined;
  return blob && Buffer.isBuffer(blob.data) ? blob.data : undefined;
}

/** One value per tag, in order, in the fewest requests the item limit allows; a tag's own failure is its error. */
export async function readTags(session: S7PlusSession, tags: readonly Tag[], limits: Limits, signal?: AbortSignal): Promise<ReadValues> {
  const values: PlcValue[] = new Array<PlcValue>(tags.length);
  let errors: (PlcError | undefined)[] | undefined;
  const fail = (i: number, err: PlcError) => ((errors ??= new Array<PlcError | undefined>(tags.length))[i] = err);
  const addresses: (ItemAddress | undefined)[] = tags.map((tag, i) => {
    const a = itemAddress(tag);
    if (a instanceof PlcError) return void fail(i, a);
    return a;
  });
  const wanted = addresses.flatMap((a, i) => (a ? [i] : []));
  const send = (chunk: number[]) => session.request(readAsk(chunk.map((i) => addresses[i]!)), { signal });
  await inChunks(
    wanted,
    limits,
    send,
    (chunk, body) => {
      if (refusedWhole(body)) {
        if (chunk.length > 1) return 'again';
        fail(chunk[0]!, itemRefusal(body.returnValue, { tag: tags[chunk[0]!]!.address }));
        return;
      }
      chunk.forEach((i, k) => {
        const tag = tags[i]!;
        const answer = itemAnswer(body, k + 1);
        if (answer === undefined) return fail(i, notAnswered(tag.address));
        if ('code' in answer) return fail(i, itemRefusal(answer.code, { tag: tag.address, request: answer.request }));
        const untrusted = untrustedValue(answer, tag.address);
        if (untrusted) return fail(i, untrusted);
        const data = bytesOf(answer);
        if (!data) {
          const what = `${tag.address}: the PLC answered a value of type 0x${answer.type.toString(16)}, not the bytes asked for`;
          return fail(i, new PlcError('PROTOCOL_ERROR', what, { tag: tag.address }));
        }
        try {
          values[i] = decodeTag(tag, data, 0);
        } catch (err) {
          fail(i, err as PlcError);
        }
      });
    },
    (i) => addressBytes(addresses[i]!),
  );
  return { values, errors };
}

/** One result per item, in order. A BOOL is refused: a classic-blob write is whole bytes, and would overwrite the byte's other bits. */
export async function writeTags(
  session: S7PlusSession,
  items: readonly { tag: Tag; value: unknown }[],
  limits: Limits,
  signal?: AbortSignal,
): Promise<TagResult<void>[]> {
  const results: TagResult<void>[] = items.map(() => ({ ok: true, value: undefined }));
  const ready: { i: number; address: ItemAddress; value: PValue }[] = [];
  items.forEach(({ tag, value }, i) => {
    if (tag.type === 'BOOL') {
      results[i] = {
        ok: false,
        error: new PlcError('NOT_SUPPORTED', `${tag.address}: S7CommPlus writes whole bytes by address; write the bit by name`, {
          tag: tag.address,
        }),
      };
      return;
    }
    const address = itemAddress(tag);
    if (address instanceof PlcError) return void (results[i] = { ok: false, error: address });
    try {
      ready.push({ i, address, value: blobValue(encodeTag(tag, value)) });
    } catch (err) {
      results[i] = { ok: false, error: toPlcError(err, 'INVALID_VALUE') };
    }
  });
  await writeInChunks(session, ready, limits, signal, (chunk, body) => {
    if (refusedWhole(body)) {
      if (chunk.length > 1) return 'again';
      results[chunk[0]!.i] = { ok: false, error: itemRefusal(body.returnValue, { tag: items[chunk[0]!.i]!.tag.address, write: true }) };
      return;
    }
    chunk.forEach((c, k) => {
      const answer = itemAnswer(body, k + 1);
      if (answer && 'code' in answer) {
        const error = itemRefusal(answer.code, { tag: items[c.i]!.tag.address, write: true, request: answer.request });
        results[c.i] = { ok: false, error };
      }
    });
  });
  return results;
}

/** One item of a SetMultiVariables: where, and the value. */
interface WriteItem {
  readonly address: ItemAddress;
  readonly value: PValue;
}

/**
 * Writes `items` as SetMultiVariables requests through the one chunker
 * (chunks.ts: the item limit and the frame), `take` reading each answer; the
 * writes by address and by name both send this way.
 */
export function writeInChunks<C extends WriteItem>(
  session: S7PlusSession,
  items: readonly C[],
  limits: Limits,
  signal: AbortSignal | undefined,
  take: (chunk: C[], body: SetResults) => 'again' | void,
): Promise<void> {
  const send = (chunk: C[]) =>
    session.request(
      writeAsk(
        chunk.map((c) => c.address),
        chunk.map((c) => c.value),
      ),
      { signal },
    );
  return inChunks(items, limits, send, take, (c) => addressBytes(c.address) + writeValueBytes(c.value));
}
