/**
 * S7Client: S7comm over ISO-on-TCP on the shared link layer. It uses the PDU
 * size and parallel jobs (AmQ) the PLC negotiated, packs tags into the fewest
 * PDUs (planner.ts), keeps up to AmQ jobs in flight, and gives a result per
 * tag: a missing DB or an address out of range fails only its own tags.
 *
 * Replies are matched by PDU reference. A reply nobody waits for (wrong,
 * duplicated, or late after a timeout) is ignored and counted in
 * stats.ignoredReplies; a job unanswered within the timeout drops the link
 * (the PLC still counts it against AmQ), and the supervisor reconnects.
 */
import { formatAddress, parseAddress } from '../address';
import { ConnectionError, PlcError, ProtocolError, toPlcError, type TagResult } from '../errors';
import { BaseClient, type ClientOptions } from '../link/client-base';
import type { PlcValue, Protocol, Tag } from '../types';
import { endpointName, type S7Endpoint } from '../url';
import { decodeTag } from '../values';
import { decodeS7, encodeReadRequest, encodeWriteRequest, type ReadResponseItem, type S7Message } from './codec';
import { CotpType, describeReturnCode, headerError } from './constants';
import { openS7Session, S7Session } from './client-session';
import { planRead, planWrite, ReadPlanCache, tagData, type ReadPlan } from './planner';

export { S7Session, localTsapFor } from './client-session';

/** Counters for diagnostics and the benchmark (cumulative over reconnects). */
export interface S7Stats {
  /** S7 jobs sent (Read Var / Write Var PDUs). */
  pdusSent: number;
  /** Bytes written to and read from the socket, TPKT headers included. */
  bytesSent: number;
  bytesReceived: number;
  /** read()/write() calls that reached the PLC. */
  requests: number;
  /** Replies that matched no pending job (wrong, duplicated or late PDU reference). */
  ignoredReplies: number;
}

const SUCCESS = 0xff;

export class S7Client extends BaseClient<S7Session, Tag> {
  readonly protocol: Protocol = 's7';
  readonly endpoint: S7Endpoint;
  readonly stats: S7Stats = { pdusSent: 0, bytesSent: 0, bytesReceived: 0, requests: 0, ignoredReplies: 0 };
  private readonly plans = new ReadPlanCache();
  private readonly compiledPlans = new WeakMap<ReadPlan, CompiledRead>();

  constructor(endpoint: S7Endpoint, options: Partial<ClientOptions> = {}) {
    super({
      name: endpointName(endpoint),
      timeout: endpoint.timeout,
      ...(endpoint.readOnly ? { readOnly: true } : {}),
      ...(endpoint.allow ? { allow: endpoint.allow } : {}),
      ...options,
    });
    this.endpoint = endpoint;
  }

  /** The PDU size the PLC negotiated (0 while not connected). */
  get pduSize(): number {
    return this.session?.pduSize ?? 0;
  }

  /** The parallel jobs (AmQ) the PLC negotiated (0 while not connected). */
  get maxJobs(): number {
    return this.session?.maxJobs ?? 0;
  }

  /** The read plan this client uses for `addresses` at the negotiated PDU size (for diagnostics and the benchmark). */
  planFor(addresses: readonly string[]): ReadPlan {
    const pduSize = this.pduSize;
    if (pduSize === 0) throw new ConnectionError('NOT_CONNECTED', `not connected to ${this.name}`);
    return this.plans.get(addresses.map((a) => this.tag(a)), pduSize);
  }

  protected parseTag(address: string): Tag {
    return parseAddress(address);
  }

  protected openSession(signal: AbortSignal): Promise<S7Session> {
    return openS7Session(this.endpoint, {
      name: this.name,
      timeout: this.timeout,
      maxQueued: this.maxQueued,
      requestTimeout: this.timeout,
      signal,
      attach: (session) => this.attach(session),
    });
  }

  private attach(session: S7Session): void {
    const { socket } = session;
    let lost = false;
    const fail = (cause: PlcError) => {
      if (lost) return;
      lost = true;
      const err = this.state === 'closed' ? new ConnectionError('CLOSED', `${this.name}: the client was closed`, { cause }) : cause;
      session.rejectAll(err);
      socket.destroy();
      this.sessionLost(session, err);
    };
    socket.on('data', (chunk: Buffer) => {
      this.stats.bytesReceived += chunk.length;
      let frames: Buffer[];
      try {
        frames = session.reader.push(chunk);
      } catch (err) {
        return fail(linkError(this.name, err));
      }
      for (const frame of frames) {
        if ((frame[5]! & 0xf0) === CotpType.DR) {
          return fail(new ConnectionError('CONNECTION_LOST', `${this.name} disconnected (COTP disconnect request, reason 0x${(frame[10] ?? 0).toString(16)})`));
        }
        let message: S7Message;
        try {
          message = decodeS7(frame);
        } catch (err) {
          return fail(linkError(this.name, err));
        }
        if (!session.answer(message.pduRef, message)) this.stats.ignoredReplies++;
      }
    });
    socket.on('error', (err) => fail(new ConnectionError('CONNECTION_LOST', `${this.name}: ${err.message}`, { cause: err })));
    socket.on('close', () => fail(new ConnectionError('CONNECTION_LOST', `${this.name} closed the connection`)));
    session.lose = fail;
    session.onSend = (frame) => {
      this.stats.pdusSent++;
      this.stats.bytesSent += frame.length;
    };
  }

  /**
   * Sends one job when an AmQ slot is free and waits for its reply. The slot
   * is held until the PLC answers (an aborted caller stops waiting, the PLC
   * still works on it); a timeout drops the link (S7Session).
   */
  private job(session: S7Session, frame: Buffer, what: string, signal?: AbortSignal): Promise<S7Message> {
    return new Promise((resolve, reject) => session.send(frame, what, (err, answer) => (err ? reject(err) : resolve(answer!)), signal));
  }

  // ---------------------------------------------------------------- reads

  protected async readTags(session: S7Session, tags: readonly Tag[], signal?: AbortSignal): Promise<TagResult<PlcValue>[]> {
    this.stats.requests++;
    const plan = this.plans.get(tags, session.pduSize);
    const { results, retry } = await this.execute(session, tags, plan, signal);
    if (retry.length > 0) {
      // An item merged from several tags failed (e.g. one tag past the end of a DB): read those tags alone.
      const alone = retry.map((i) => tags[i]!);
      const again = await this.execute(session, alone, planRead(alone, session.pduSize, { merge: false }), signal);
      retry.forEach((i, k) => (results[i] = again.results[k]!));
    }
    return results;
  }

  /** A plan's request frames (reused while not in flight) and where each tag's bytes lie, computed once per plan. */
  private compiled(plan: ReadPlan): CompiledRead {
    let c = this.compiledPlans.get(plan);
    if (!c) {
      c = compileRead(plan);
      this.compiledPlans.set(plan, c);
    }
    return c;
  }

  private execute(session: S7Session, tags: readonly Tag[], plan: ReadPlan, signal?: AbortSignal): Promise<{ results: TagResult<PlcValue>[]; retry: number[] }> {
    const c = this.compiled(plan);
    const n = plan.pdus.length;
    const answers: S7Message[] = new Array<S7Message>(n);
    if (n === 0) return Promise.resolve(this.collect(tags, plan, c, answers));
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
              resolve(this.collect(tags, plan, c, answers));
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

  /** Per-tag results straight from the answers' frames; values are decoded from subarrays of the frames, never copied unless split. */
  private collect(tags: readonly Tag[], plan: ReadPlan, c: CompiledRead, answers: readonly S7Message[]): { results: TagResult<PlcValue>[]; retry: number[] } {
    const n = plan.pdus.length;
    const items: (ReadResponseItem[] | undefined)[] = new Array<ReadResponseItem[] | undefined>(n);
    let errors: (PlcError | undefined)[][] | undefined;
    const setError = (p: number, i: number, err: PlcError) => {
      errors ??= plan.pdus.map((pd) => new Array<PlcError | undefined>(pd.items.length));
      errors[p]![i] = err;
    };
    for (let p = 0; p < n; p++) {
      const pdu = plan.pdus[p]!;
      const count = pdu.items.length;
      const answer = answers[p]!;
      let failAll: PlcError | undefined;
      if (answer.kind === 'error') failAll = headerError(answer.errorClass, answer.errorCode, 'read');
      else if (answer.kind !== 'read-ack' || answer.items.length !== count) {
        failAll = new ProtocolError(`the answer to a read of ${count} item(s) does not match it (${answer.kind})`);
      }
      if (failAll || answer.kind !== 'read-ack') {
        for (let i = 0; i < count; i++) setError(p, i, failAll!);
        continue;
      }
      for (let i = 0; i < count; i++) {
        const item = answer.items[i]!;
        const expected = pdu.items[i]!.length;
        if (item.returnCode !== SUCCESS) setError(p, i, returnCodeError(item.returnCode));
        else if (item.data.length !== expected) setError(p, i, new ProtocolError(`asked for ${expected} bytes, the PLC returned ${item.data.length}`));
      }
      items[p] = answer.items;
    }
    const results: TagResult<PlcValue>[] = new Array<TagResult<PlcValue>>(tags.length);
    const retry: number[] = [];
    for (let t = 0; t < tags.length; t++) {
      const tag = tags[t]!;
      if (errors) {
        let err: PlcError | undefined;
        let retryAlone = false;
        for (const s of plan.slices[t]!) {
          const itemError = errors[s.pdu]![s.item];
          if (!itemError) continue;
          err ??= itemError;
          // Only a return code of an item that also served other tags can be one tag's fault.
          if (itemError.plcCode !== undefined && itemError.plcCode <= 0xff && c.tagsPerItem().get(s.pdu * 256 + s.item)! > 1) retryAlone = true;
        }
        if (err) {
          if (retryAlone) retry.push(t);
          results[t] = { ok: false, error: tagError(tag, err) };
          continue;
        }
      }
      try {
        const p = c.tagPdu[t]!;
        let value: PlcValue;
        if (p >= 0) value = decodeTag(tag, items[p]![c.tagItem[t]!]!.data, c.tagOffset[t]!);
        else {
          const data = items.map((list) => (list ? list.map((x) => x.data) : []));
          const { data: bytes, offset } = tagData(plan, t, data);
          value = decodeTag(tag, bytes, offset);
        }
        results[t] = { ok: true, value };
      } catch (e) {
        results[t] = { ok: false, error: tagError(tag, toPlcError(e, 'PROTOCOL_ERROR')) };
      }
    }
    return { results, retry };
  }

  // ---------------------------------------------------------------- writes

  protected async writeTags(session: S7Session, items: readonly { tag: Tag; value: unknown }[], signal?: AbortSignal): Promise<TagResult<void>[]> {
    this.stats.requests++;
    const plan = planWrite(items, session.pduSize);
    const errors: (PlcError | undefined)[] = plan.errors.slice();
    await Promise.all(
      plan.pdus.map(async (pdu) => {
        const n = pdu.items.length;
        const failAll = (err: PlcError) => pdu.tags.forEach((t) => (errors[t] ??= err));
        let answer: S7Message;
        try {
          answer = await this.job(session, encodeWriteRequest(0, pdu.items), `write of ${n} item(s)`, signal);
        } catch (err) {
          // The write may or may not have reached the PLC: its tags get the error, it is never silently dropped.
          return failAll(toPlcError(err));
        }
        if (answer.kind === 'error') return failAll(headerError(answer.errorClass, answer.errorCode, 'write'));
        if (answer.kind !== 'write-ack' || answer.returnCodes.length !== n) {
          return failAll(new ProtocolError(`the answer to a write of ${n} item(s) does not match it (${answer.kind})`));
        }
        answer.returnCodes.forEach((rc, i) => {
          if (rc !== SUCCESS) errors[pdu.tags[i]!] ??= returnCodeError(rc);
        });
      }),
    );
    return items.map(({ tag }, i) => {
      const err = errors[i];
      if (!err) return { ok: true, value: undefined };
      return { ok: false, error: err.tag === tag.address ? err : tagError(tag, err) };
    });
  }
}

interface CompiledRead {
  /** Per PDU: the Read Var frame (its PDU reference is set when sent), reused while not in flight. */
  frames: Buffer[];
  busy: Uint8Array;
  release: (() => void)[];
  what: string[];
  /** Per tag: the PDU, item and offset of its bytes; PDU −1 when the tag was split across items. */
  tagPdu: Int32Array;
  tagItem: Int32Array;
  tagOffset: Int32Array;
  tagsPerItem(): Map<number, number>;
}

function compileRead(plan: ReadPlan): CompiledRead {
  const busy = new Uint8Array(plan.pdus.length);
  const tagPdu = new Int32Array(plan.slices.length);
  const tagItem = new Int32Array(plan.slices.length);
  const tagOffset = new Int32Array(plan.slices.length);
  plan.slices.forEach((slices, t) => {
    const s = slices.length === 1 ? slices[0]! : undefined;
    tagPdu[t] = s ? s.pdu : -1;
    tagItem[t] = s ? s.item : 0;
    tagOffset[t] = s ? s.offset : 0;
  });
  let shared: Map<number, number> | undefined;
  return {
    frames: plan.pdus.map((pdu) => encodeReadRequest(0, pdu.items)),
    busy,
    release: plan.pdus.map((_, p) => () => (busy[p] = 0)),
    what: plan.pdus.map((pdu) => `read of ${pdu.items.length} item(s)`),
    tagPdu,
    tagItem,
    tagOffset,
    tagsPerItem: () => (shared ??= tagsPerItem(plan)),
  };
}

/** How many tags each item of a plan serves, keyed pdu × 256 + item (a PDU has at most 255 items). */
function tagsPerItem(plan: ReadPlan): Map<number, number> {
  const counts = new Map<number, number>();
  for (const slices of plan.slices) for (const s of slices) counts.set(s.pdu * 256 + s.item, (counts.get(s.pdu * 256 + s.item) ?? 0) + 1);
  return counts;
}

function returnCodeError(rc: number): PlcError {
  const { code, text } = describeReturnCode(rc);
  return new PlcError(code, `the PLC answered return code 0x${rc.toString(16).padStart(2, '0').toUpperCase()}: ${text}`, { plcCode: rc });
}

/** The same error for one tag: names the tag, where it is, and keeps the code and the PLC's return code. */
function tagError(tag: Tag, err: PlcError): PlcError {
  const canonical = formatAddress(tag);
  const where = canonical === tag.address ? '' : ` (${canonical})`;
  return new PlcError(err.code, `${tag.address}${where}: ${err.message}`, {
    tag: tag.address,
    ...(err.plcCode === undefined ? {} : { plcCode: err.plcCode }),
    cause: err,
  });
}

function linkError(name: string, err: unknown): PlcError {
  const e = toPlcError(err, 'PROTOCOL_ERROR');
  return e instanceof ProtocolError ? new ProtocolError(`${name}: ${e.message}`, { cause: e }) : e;
}
