/**
 * The execution of a read plan on a session: its request frames compiled
 * once (CompiledRead), sent as jobs, and the tags' values located and
 * decoded straight from the answer frames, errors per tag.
 */
import { formatAddress } from '../../address';
import { PlcError, ProtocolError, tagError as namedTagError, toPlcError } from '../../errors';
import type { ReadValues } from '../../link/driver';
import type { PlcValue, Tag } from '../../types';
import { decodeTag, tagDecoder, type TagDecoder } from '../../values';
import { encodeReadRequest, scanReadAck, type ReadItemTable } from '../codec';
import { headerError, ReturnCode, returnCodeError } from '../constants';
import { tagData, type ReadPlan } from '../plan';
import type { S7Session } from './session';

export function executeRead(session: S7Session, tags: readonly Tag[], c: CompiledRead, signal?: AbortSignal): Promise<CollectedRead> {
  const { plan } = c;
  const n = plan.pdus.length;
  const answers: Buffer[] = new Array<Buffer>(n);
  if (n === 0) return Promise.resolve(collect(session, tags, plan, c, answers));
  return new Promise((resolve, reject) => {
    let left = n;
    let failed = false;
    for (let p = 0; p < n; p++) {
      let frame = c.frames[p]!;
      let release: (() => void) | undefined;
      if (c.busy[p]) {
        // The same plan is being polled concurrently: this poll gets its own frame.
        frame = Buffer.from(frame);
      } else {
        c.busy[p] = 1;
        release = c.release[p];
      }
      session.send(
        frame,
        c.what[p]!,
        (err, answer) => {
          if (failed) return;
          if (err) {
            failed = true;
            return reject(err);
          }
          answers[p] = answer!;
          if (--left > 0) return;
          try {
            resolve(collect(session, tags, plan, c, answers));
          } catch (e) {
            reject(e);
          }
        },
        signal,
        release,
      );
    }
  });
}

/**
 * Values straight from the answer frames: each item is located in place
 * (scanReadAck, into the plan's scratch table: collect runs synchronously,
 * so polls of the same plan never share it at once), each tag decoded at
 * its offset. No object per item or per tag; a tag split across items is
 * reassembled. Errors are per tag: a failed PDU fails its tags, a failed
 * item the tags in it. `served` > 0: a PDU was answered with only that
 * many of its items (the fewest of such PDUs).
 */
function collect(session: S7Session, tags: readonly Tag[], plan: ReadPlan, c: CompiledRead, answers: readonly Buffer[]): CollectedRead {
  const n = plan.pdus.length;
  const { table, itemBase, itemLength } = c;
  let pduErrors: (PlcError | undefined)[] | undefined;
  let itemsFailed = false;
  let served = 0;
  for (let p = 0; p < n; p++) {
    const count = plan.pdus[p]!.items.length;
    const base = itemBase[p]!;
    const frame = answers[p]!;
    if (!scanReadAck(frame, count, table, base)) {
      const unusual = unusualReadAnswer(session, frame, count, table, base);
      if (typeof unusual === 'number') {
        served = served === 0 ? unusual : Math.min(served, unusual);
        (pduErrors ??= new Array<PlcError | undefined>(n))[p] = new ProtocolError(
          `the PLC answered ${unusual} of the ${count} items of a read`,
        );
        continue;
      }
      if (unusual) {
        (pduErrors ??= new Array<PlcError | undefined>(n))[p] = unusual;
        continue;
      }
    }
    for (let i = base; i < base + count; i++)
      if (table.code[i] !== ReturnCode.Success || table.length[i] !== itemLength[i]) itemsFailed = true;
  }
  const values = new Array<PlcValue>(tags.length);
  const { tagPdu, tagItem, tagOffset, decoders } = c;
  if (!pduErrors && !itemsFailed) {
    try {
      for (let t = 0; t < tags.length; t++) {
        const p = tagPdu[t]!;
        values[t] =
          p >= 0
            ? decoders[t]!(answers[p]!, table.start[itemBase[p]! + tagItem[t]!]! + tagOffset[t]!)
            : splitValue(tags[t]!, t, plan, c, answers);
      }
      return { values, errors: undefined, retry: [], served: 0 };
    } catch {
      // A decoder threw (no decoder should): tag by tag below, so only that tag fails.
    }
  }
  const errors = new Array<PlcError | undefined>(tags.length);
  const retry: number[] = [];
  const itemError = (p: number, i: number): PlcError | undefined => {
    const failAll = pduErrors?.[p];
    if (failAll) return failAll;
    const k = itemBase[p]! + i;
    const rc = table.code[k]!;
    if (rc !== ReturnCode.Success) return returnCodeError(rc);
    if (table.length[k] !== itemLength[k])
      return new ProtocolError(`asked for ${itemLength[k]} bytes, the PLC returned ${table.length[k]}`);
    return undefined;
  };
  for (let t = 0; t < tags.length; t++) {
    const tag = tags[t]!;
    let err: PlcError | undefined;
    let retryAlone = false;
    const { pieces } = plan;
    for (let k = pieces.start[t]!; k < pieces.start[t + 1]!; k++) {
      const e = itemError(pieces.pdu[k]!, pieces.item[k]!);
      if (!e) continue;
      err ??= e;
      // Only a return code of an item that also served other tags can be one tag's fault.
      if (e.plcCode !== undefined && e.plcCode <= 0xff && c.tagsPerItem().get(pieces.pdu[k]! * 256 + pieces.item[k]!)! > 1)
        retryAlone = true;
    }
    if (err) {
      if (retryAlone) retry.push(t);
      errors[t] = tagError(tag, err);
      continue;
    }
    try {
      const p = tagPdu[t]!;
      values[t] =
        p >= 0 ? decoders[t]!(answers[p]!, table.start[itemBase[p]! + tagItem[t]!]! + tagOffset[t]!) : splitValue(tag, t, plan, c, answers);
    } catch (e) {
      errors[t] = tagError(tag, toPlcError(e, 'PROTOCOL_ERROR'));
    }
  }
  return { values, errors, retry, served };
}

/**
 * An answer scanReadAck did not take: decodes it (malformed drops the
 * link and throws). A header error, another kind of answer or too many
 * items is the error of the whole PDU; a read ack of fewer items (at least
 * one) returns how many the PLC served; a read ack in an unusual framing
 * fills the table like scanReadAck.
 */
function unusualReadAnswer(
  session: S7Session,
  frame: Buffer,
  count: number,
  table: ReadItemTable,
  base: number,
): PlcError | number | undefined {
  const answer = session.decode(frame);
  if (answer.kind === 'error') return headerError(answer.errorClass, answer.errorCode, 'read');
  if (answer.kind === 'read-ack' && answer.items.length > 0 && answer.items.length < count) return answer.items.length;
  if (answer.kind !== 'read-ack' || answer.items.length !== count) {
    return new ProtocolError(`the answer to a read of ${count} item(s) does not match it (${answer.kind})`);
  }
  answer.items.forEach((item, i) => {
    table.code[base + i] = item.returnCode;
    table.start[base + i] = item.data.byteOffset - frame.byteOffset;
    table.length[base + i] = item.data.length;
  });
  return undefined;
}

/** A tag whose bytes the planner split over several items (a STRING longer than an item can carry). */
function splitValue(tag: Tag, t: number, plan: ReadPlan, c: CompiledRead, answers: readonly Buffer[]): PlcValue {
  const data = plan.pdus.map((pdu, p) =>
    pdu.items.map((_, i) => {
      const k = c.itemBase[p]! + i;
      return answers[p]!.subarray(c.table.start[k]!, c.table.start[k]! + c.table.length[k]!);
    }),
  );
  const { data: bytes, offset } = tagData(plan, t, data);
  return decodeTag(tag, bytes, offset);
}

/** What a read of one plan found: values and errors per tag, the tags to read alone, and `served` (see collect). */
export type CollectedRead = ReadValues & { retry: number[]; served: number };

/** A plan ready to send: its request frames (reused while not in flight) and where each tag's bytes lie. */
export interface CompiledRead {
  plan: ReadPlan;
  /** Per PDU: the Read Var frame (its PDU reference is set when sent), reused while not in flight. */
  frames: Buffer[];
  busy: Uint8Array;
  release: (() => void)[];
  what: string[];
  /** Per PDU: the index of its first item in the item arrays. */
  itemBase: Int32Array;
  /** Per item (all PDUs): the bytes asked for; `table` is scratch for the answers' items. */
  itemLength: Int32Array;
  table: ReadItemTable;
  /** Per tag: the PDU, item and offset of its bytes; PDU −1 when the tag was split across items. */
  tagPdu: Int32Array;
  tagItem: Int32Array;
  tagOffset: Int32Array;
  decoders: TagDecoder[];
  tagsPerItem(): Map<number, number>;
}

export function compileRead(plan: ReadPlan, tags: readonly Tag[]): CompiledRead {
  const busy = new Uint8Array(plan.pdus.length);
  const itemBase = new Int32Array(plan.pdus.length);
  let items = 0;
  plan.pdus.forEach((pdu, p) => {
    itemBase[p] = items;
    items += pdu.items.length;
  });
  const itemLength = new Int32Array(items);
  plan.pdus.forEach((pdu, p) => pdu.items.forEach((item, i) => (itemLength[itemBase[p]! + i] = item.length)));
  const { pieces } = plan;
  const tagPdu = new Int32Array(tags.length);
  const tagItem = new Int32Array(tags.length);
  const tagOffset = new Int32Array(tags.length);
  for (let t = 0; t < tags.length; t++) {
    const k = pieces.start[t]!;
    const whole = pieces.start[t + 1]! - k === 1;
    tagPdu[t] = whole ? pieces.pdu[k]! : -1;
    tagItem[t] = whole ? pieces.item[k]! : 0;
    tagOffset[t] = whole ? pieces.offset[k]! : 0;
  }
  let shared: Map<number, number> | undefined;
  return {
    plan,
    frames: plan.pdus.map((pdu) => encodeReadRequest(0, pdu.items)),
    busy,
    release: plan.pdus.map((_, p) => () => (busy[p] = 0)),
    what: plan.pdus.map((pdu) => `read of ${pdu.items.length} item(s)`),
    itemBase,
    itemLength,
    table: { code: new Uint8Array(items), start: new Int32Array(items), length: new Int32Array(items) },
    tagPdu,
    tagItem,
    tagOffset,
    decoders: tags.map(tagDecoder),
    tagsPerItem: () => (shared ??= tagsPerItem(plan)),
  };
}

/** How many tags each item of a plan serves, keyed pdu × 256 + item (a PDU has at most 255 items). */
function tagsPerItem(plan: ReadPlan): Map<number, number> {
  const counts = new Map<number, number>();
  const { pdu, item } = plan.pieces;
  for (let k = 0; k < pdu.length; k++) counts.set(pdu[k]! * 256 + item[k]!, (counts.get(pdu[k]! * 256 + item[k]!) ?? 0) + 1);
  return counts;
}

/** The same error for one tag, naming where it lies when the address was written another way (DB1,INT2 → DB1.DBW2). */
export function tagError(tag: Tag, err: PlcError): PlcError {
  const canonical = formatAddress(tag);
  return namedTagError(tag.address, err, canonical === tag.address ? undefined : canonical);
}
