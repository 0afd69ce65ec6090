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
import { ConnectionError, PlcError, ProtocolError, TimeoutError, toPlcError, type TagResult } from '../errors';
import { BaseClient, type ClientOptions } from '../link/client-base';
import { abortError } from '../link/pending';
import type { PlcValue, Protocol, Tag } from '../types';
import { endpointName, type S7Endpoint } from '../url';
import { decodeTag } from '../values';
import { decodeS7, encodeReadRequest, encodeWriteRequest, type S7Message } from './codec';
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
      session.pending.rejectAll(err);
      session.jobs.rejectAll(err);
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
        if (!session.pending.resolve(message.pduRef, message)) this.stats.ignoredReplies++;
      }
    });
    socket.on('error', (err) => fail(new ConnectionError('CONNECTION_LOST', `${this.name}: ${err.message}`, { cause: err })));
    socket.on('close', () => fail(new ConnectionError('CONNECTION_LOST', `${this.name} closed the connection`)));
    session.lose = fail;
  }

  /**
   * Sends one job when an AmQ slot is free and waits for its reply. The slot
   * is held until the PLC answers (an aborted caller stops waiting, the PLC
   * still works on it); a timeout drops the link.
   */
  private job(session: S7Session, frameFor: (ref: number) => Buffer, what: string, signal?: AbortSignal): Promise<S7Message> {
    const run = session.jobs.run(async () => {
      const ref = session.ref();
      const frame = frameFor(ref);
      const reply = session.pending.add(ref, this.timeout, `${this.name} ${what}`);
      this.stats.pdusSent++;
      this.stats.bytesSent += frame.length;
      session.socket.write(frame);
      try {
        return await reply;
      } catch (err) {
        if (err instanceof TimeoutError) session.lose?.(new ConnectionError('CONNECTION_LOST', `${this.name} stopped answering: ${err.message}`, { cause: err }));
        throw err;
      }
    }, signal);
    return signal ? withAbort(run, signal, `${this.name} ${what}`) : run;
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

  private async execute(
    session: S7Session,
    tags: readonly Tag[],
    plan: ReadPlan,
    signal?: AbortSignal,
  ): Promise<{ results: TagResult<PlcValue>[]; retry: number[] }> {
    const data: (Buffer | undefined)[][] = plan.pdus.map((p) => new Array<Buffer | undefined>(p.items.length));
    const errors: (PlcError | undefined)[][] = plan.pdus.map((p) => new Array<PlcError | undefined>(p.items.length));
    await Promise.all(
      plan.pdus.map(async (pdu, p) => {
        const n = pdu.items.length;
        const failAll = (err: PlcError) => errors[p]!.fill(err);
        const answer = await this.job(session, (ref) => encodeReadRequest(ref, pdu.items), `read of ${n} item(s)`, signal);
        if (answer.kind === 'error') return failAll(headerError(answer.errorClass, answer.errorCode, 'read'));
        if (answer.kind !== 'read-ack' || answer.items.length !== n) {
          return failAll(new ProtocolError(`the answer to a read of ${n} item(s) does not match it (${answer.kind})`));
        }
        for (let i = 0; i < n; i++) {
          const item = answer.items[i]!;
          const expected = pdu.items[i]!.length;
          if (item.returnCode !== SUCCESS) errors[p]![i] = returnCodeError(item.returnCode);
          else if (item.data.length !== expected) errors[p]![i] = new ProtocolError(`asked for ${expected} bytes, the PLC returned ${item.data.length}`);
          else data[p]![i] = item.data;
        }
      }),
    );
    const results: TagResult<PlcValue>[] = new Array(tags.length);
    const retry: number[] = [];
    let shared: Map<number, number> | undefined;
    for (let t = 0; t < tags.length; t++) {
      const tag = tags[t]!;
      let err: PlcError | undefined;
      let retryAlone = false;
      for (const s of plan.slices[t]!) {
        const itemError = errors[s.pdu]![s.item];
        if (!itemError) continue;
        err ??= itemError;
        // Only a return code of an item that also served other tags can be one tag's fault.
        if (itemError.plcCode !== undefined && itemError.plcCode <= 0xff) {
          shared ??= tagsPerItem(plan);
          if (shared.get(s.pdu * 256 + s.item)! > 1) retryAlone = true;
        }
      }
      if (err) {
        if (retryAlone) retry.push(t);
        results[t] = { ok: false, error: tagError(tag, err) };
        continue;
      }
      try {
        const { data: bytes, offset } = tagData(plan, t, data);
        results[t] = { ok: true, value: decodeTag(tag, bytes, offset) };
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
          answer = await this.job(session, (ref) => encodeWriteRequest(ref, pdu.items), `write of ${n} item(s)`, signal);
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

/** Rejects when `signal` aborts, without cancelling the job (its AmQ slot stays taken until the PLC answers). */
function withAbort<T>(promise: Promise<T>, signal: AbortSignal, what: string): Promise<T> {
  if (signal.aborted) {
    promise.catch(() => undefined);
    return Promise.reject(abortError(what, signal));
  }
  return new Promise<T>((resolve, reject) => {
    const onAbort = () => {
      promise.catch(() => undefined);
      reject(abortError(what, signal));
    };
    signal.addEventListener('abort', onAbort, { once: true });
    promise.then(
      (v) => {
        signal.removeEventListener('abort', onAbort);
        resolve(v);
      },
      (e: unknown) => {
        signal.removeEventListener('abort', onAbort);
        reject(e);
      },
    );
  });
}
