/**
 * S7Client: S7comm over ISO-on-TCP on the shared link layer. It uses the PDU
 * size and parallel jobs (AmQ) the PLC negotiated, packs tags into the fewest
 * PDUs (lib/s7/plan/), keeps up to AmQ jobs in flight, and gives a result per
 * tag: a missing DB or an address out of range fails only its own tags.
 *
 * Replies are matched by PDU reference. A reply nobody waits for (wrong,
 * duplicated, or late after a timeout) is ignored and counted in
 * stats.ignoredReplies; a job unanswered within the timeout drops the link
 * (the PLC still counts it against AmQ), and the supervisor reconnects.
 *
 * A job carries at most the URL's maxItems items (default 20, what snap7's
 * server and VIPA CPUs serve; DEFAULT_MAX_ITEMS). A PLC that answers fewer
 * items than a job asked for has told its limit: the client keeps it for as
 * long as it lives (reconnects included: it is the same PLC), emits
 * `itemLimit` ({ limit, was }), and reads again with a plan for that limit,
 * or sends the items of a write the answer left out again.
 */
import { formatAddress, S7_TAG_SYNTAX } from '../../address';
import { ConnectionError, isLinkError, PlcError, ProtocolError, tagError as namedTagError, toPlcError, type TagResult } from '../../errors';
import { BaseClient, endpointOptions, toResults, type ClientOptions } from '../../link/client-base';
import type { Driver, ReadValues } from '../../link/driver';
import type { PlcValue, Protocol, RequestOptions, Tag } from '../../types';
import { endpointName, type S7Endpoint } from '../../url';
import { decodeTag, tagDecoder, type TagDecoder } from '../../values';
import { decodeS7, encodeReadRequest, encodeWriteRequest, s7AnswerRef, scanReadAck, type ReadItemTable, type S7Message } from '../codec';
import { CotpType, DEFAULT_MAX_ITEMS, describeReturnCode, headerError } from '../constants';
import { openS7Session, S7Session } from './session';
import { maxReadItems, planRead, planWrite, ReadPlanCache, tagData, type PlannedWriteItem, type PlanOptions, type ReadPlan } from '../plan';
import type { BlockCounts, BlockInfo, UploadedBlock } from '../codec/blocks';
import type { BlockType } from '../constants';
import type { DiagnosticEntry } from '../codec/diagnostics';
import { S7Services, type ClockOptions, type PlcInfo } from './services';
import type { CpuState, SzlList } from '../codec/szl';

export { S7Session } from './session';
export { localTsapFor } from '../tsap';

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
  /**
   * Read plans computed. A prepared list (client.prepare, or the same array
   * given to read() again) keeps its plan and request frames: polling it
   * plans nothing until the PDU size or the item limit changes.
   */
  plansMade: number;
}

const SUCCESS = 0xff;

/** The `itemLimit` event: the PLC answered only `limit` items of a job; jobs had up to `was`. */
export interface ItemLimitEvent {
  limit: number;
  was: number;
}

/** Counters start at 0; plansMade is the plan cache's own count. */
function newStats(plans: ReadPlanCache): S7Stats {
  return {
    pdusSent: 0,
    bytesSent: 0,
    bytesReceived: 0,
    requests: 0,
    ignoredReplies: 0,
    get plansMade() {
      return plans.misses;
    },
  };
}

/**
 * What a prepared tag list keeps (Driver.prepareRead): its merged plan and
 * the plan's request frames, for the PDU size and item limit the plan was
 * made for. A read at another PDU size (a reconnect to another CPU) or after
 * the item limit was learnt plans again.
 */
interface S7Prepared {
  compiled: CompiledRead | undefined;
}

export class S7Client extends BaseClient<S7Session, Tag, S7Prepared> {
  readonly protocol: Protocol = 's7';
  readonly endpoint: S7Endpoint;
  private readonly plans = new ReadPlanCache();
  readonly stats: S7Stats = newStats(this.plans);
  /** Each cached plan's request frames, for a list that finds its plan in the cache (the same addresses in a new array). */
  private readonly compiledPlans = new WeakMap<ReadPlan, CompiledRead>();
  /** Items per job: the URL's maxItems or 20, lowered when the PLC serves fewer (learnItemLimit). */
  private itemLimit: number;
  private planOptions: PlanOptions;
  private readonly services: S7Services;
  protected readonly driver: Driver<S7Session, Tag, S7Prepared> = {
    syntax: S7_TAG_SYNTAX,
    openSession: (signal) => this.openSession(signal),
    prepareRead: () => ({ compiled: undefined }),
    readTags: (session, tags, signal, prepared) => this.readTags(session, tags, signal, prepared),
    readValues: (session, tags, signal, prepared) => this.readValues(session, tags, signal, prepared),
    writeTags: (session, items, signal) => this.writeTags(session, items, signal),
    blockLength: (_session, db, signal) => this.dbLength(db, signal),
    dbNumbers: (_session, signal) => this.services.listBlocksOfType('DB', signal ? { signal } : {}),
    isLinkError,
  };

  constructor(endpoint: S7Endpoint, options: Partial<ClientOptions> = {}) {
    super(endpointOptions(endpointName(endpoint), endpoint, options));
    this.endpoint = endpoint;
    this.itemLimit = endpoint.maxItems ?? DEFAULT_MAX_ITEMS;
    this.planOptions = { maxItems: this.itemLimit };
    const client = this;
    this.services = new S7Services({
      name: this.name,
      endpoint,
      get pduSize() {
        return client.pduSize;
      },
      get maxJobs() {
        return client.maxJobs;
      },
      exchange: (frame, what, signal) => this.exchange(frame, what, signal),
      malformed: (err) => this.malformed(err),
      readBytes: async (db, length, options) => {
        const address = `DB${db},B0.${length}`;
        const values = await this.read([address], options);
        return Buffer.from(values[address] as number[]);
      },
    });
  }

  /** The most items this client puts into one job (the PDU size may allow fewer). */
  get maxItems(): number {
    return this.itemLimit;
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
    return this.plans.get(
      addresses.map((a) => this.tag(a)),
      pduSize,
      this.planOptions,
    );
  }

  private openSession(signal: AbortSignal): Promise<S7Session> {
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
    const fail = this.attachStream(session, socket, (err) => {
      session.rejectAll(err);
      socket.destroy();
    });
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
          return fail(
            new ConnectionError(
              'CONNECTION_LOST',
              `${this.name} disconnected (COTP disconnect request, reason 0x${(frame[10] ?? 0).toString(16)})`,
            ),
          );
        }
        // The headers are checked here (a frame that is not S7 drops the link);
        // the job that asked decodes the rest (S7Client.decode, scanReadAck).
        let ref = s7AnswerRef(frame);
        if (ref < 0) {
          try {
            ref = decodeS7(frame).pduRef;
          } catch (err) {
            return fail(linkError(this.name, err));
          }
        }
        if (!session.answer(ref, frame)) this.stats.ignoredReplies++;
      }
    });
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
    return new Promise((resolve, reject) =>
      session.send(frame, what, (err, answer) => (err ? reject(err) : resolve(this.decode(session, answer!))), signal),
    );
  }

  /** Decodes an answer; a malformed one drops the link, as any frame the client cannot make sense of does. */
  private decode(session: S7Session, frame: Buffer): S7Message {
    try {
      return decodeS7(frame);
    } catch (err) {
      const e = linkError(this.name, err);
      session.lose?.(e);
      throw e;
    }
  }

  /** One request frame as a job on the live session; resolves the raw answer frame. */
  private exchange(frame: Buffer, what: string, signal?: AbortSignal): Promise<Buffer> {
    const session = this.session;
    if (!session) return Promise.reject(new ConnectionError('NOT_CONNECTED', `not connected to ${this.name} (the link is ${this.state})`));
    return new Promise((resolve, reject) => session.send(frame, what, (err, answer) => (err ? reject(err) : resolve(answer!)), signal));
  }

  /** A malformed answer to a system service: the link drops, as for any frame the client cannot make sense of. */
  private malformed(err: unknown): PlcError {
    const e = linkError(this.name, err);
    if (e.code === 'PROTOCOL_ERROR') this.session?.lose?.(e);
    return e;
  }

  // ---------------------------------------------------------------- system services

  /**
   * Reads one SZL (system status list) by ID and index, every part of a
   * multi-part answer included. Decoders for the common lists are exported
   * (`decodeModuleIdentification`, `decodeDiagnosticBuffer` …).
   * Rejects with SZL_NOT_AVAILABLE when the CPU has no such list.
   */
  readSzl(id: number, index = 0, options?: RequestOptions): Promise<SzlList> {
    return this.services.readSzl(id, index, options);
  }

  /**
   * Identity and state in one object: order code, firmware, module type,
   * serial number, AS and module names, mode, protection, the negotiated
   * PDU size and AmQ, and the clock. Lists the CPU does not offer leave
   * their fields undefined.
   */
  info(options?: RequestOptions): Promise<PlcInfo> {
    return this.services.info(options);
  }

  /** The diagnostic buffer, newest entry first; `max` limits it to the most recent entries. */
  diagnosticBuffer(options?: RequestOptions & { max?: number }): Promise<DiagnosticEntry[]> {
    return this.services.diagnosticBuffer(options);
  }

  /**
   * The PLC clock. A PLC clock has no time zone: its fields are read as UTC
   * by default (S7-1200/1500 keep UTC), or as this host's local time with
   * `{ timeZone: 'local' }` (an S7-300/400 set to local time).
   */
  readClock(options?: ClockOptions): Promise<Date> {
    return this.services.readClock(options);
  }

  /** Sets the PLC clock (UTC fields by default, local with `{ timeZone: 'local' }`). Refused with WRITE_NOT_ALLOWED on a read-only connection. */
  setClock(date: Date, options?: ClockOptions): Promise<void> {
    return this.services.setClock(date, options);
  }

  /** Mode (RUN, STOP …) and the last mode transition (SZL 0x0424). */
  cpuState(options?: RequestOptions): Promise<CpuState> {
    return this.services.cpuState(options);
  }

  /**
   * Puts the CPU in STOP. Refused with WRITE_NOT_ALLOWED before anything is
   * sent unless the URL says `control=true` (and never on a read-only
   * connection). A CPU already in STOP is not an error.
   */
  stop(options?: RequestOptions): Promise<void> {
    return this.services.stop(options);
  }

  /** Starts the CPU program without the cold-start argument (a warm/hot restart). Needs `control=true`, like stop(). */
  hotStart(options?: RequestOptions): Promise<void> {
    return this.services.hotStart(options);
  }

  /** Starts the CPU with a cold restart (data blocks back to their initial values). Needs `control=true`, like stop(). */
  coldStart(options?: RequestOptions): Promise<void> {
    return this.services.coldStart(options);
  }

  /** How many blocks of each type the CPU holds. */
  listBlocks(options?: RequestOptions): Promise<BlockCounts> {
    return this.services.listBlocks(options);
  }

  /** The numbers of the blocks of one type, ascending as the CPU lists them (an empty list when there are none). */
  listBlocksOfType(type: BlockType, options?: RequestOptions): Promise<number[]> {
    return this.services.listBlocksOfType(type, options);
  }

  /** Block info: sizes (a DB's data length), author, family, name, version, time stamps, checksum, language. */
  blockInfo(type: BlockType, number: number, options?: RequestOptions): Promise<BlockInfo> {
    return this.services.blockInfo(type, number, options);
  }

  /** Uploads a block in its load-memory form (header, MC7 code — a DB's data —, footer). */
  uploadBlock(type: BlockType, number: number, options?: RequestOptions): Promise<UploadedBlock> {
    return this.services.uploadBlock(type, number, options);
  }

  /** The data of a whole DB: its length from block info, its bytes by Read Var. */
  readDb(number: number, options?: RequestOptions): Promise<Buffer> {
    return this.services.readDb(number, options);
  }

  /** Gives the CPU's password (protection levels 2 and 3): this connection then works unprotected. */
  setPassword(password: string, options?: RequestOptions): Promise<void> {
    return this.services.setPassword(password, options);
  }

  /** Withdraws the password given on this connection. */
  clearPassword(options?: RequestOptions): Promise<void> {
    return this.services.clearPassword(options);
  }

  /**
   * A DB's data length from its block info, for the layout check of symbols
   * (null: the PLC has no such DB). A CPU without block functions (S7-1200
   * and S7-1500 answer "not implemented") rejects: the layout is unknown.
   */
  private async dbLength(db: number, signal?: AbortSignal): Promise<number | null> {
    try {
      const info = await this.services.blockInfo('DB', db, signal ? { signal } : {});
      return info.dataLength ?? info.mc7Size;
    } catch (err) {
      if (err instanceof PlcError && err.code === 'OBJECT_DOES_NOT_EXIST') return null;
      throw err;
    }
  }

  // ---------------------------------------------------------------- reads

  private async readTags(
    session: S7Session,
    tags: readonly Tag[],
    signal?: AbortSignal,
    prepared?: S7Prepared,
  ): Promise<TagResult<PlcValue>[]> {
    const { values, errors } = await this.readValues(session, tags, signal, prepared);
    return toResults(values, errors);
  }

  private async readValues(session: S7Session, tags: readonly Tag[], signal?: AbortSignal, prepared?: S7Prepared): Promise<ReadValues> {
    this.stats.requests++;
    const read = await this.readServed(session, tags, true, signal, prepared);
    if (read.retry.length > 0) {
      // An item merged from several tags failed (e.g. one tag past the end of a DB): read those tags alone.
      const alone = read.retry.map((i) => tags[i]!);
      const again = await this.readServed(session, alone, false, signal);
      const errors = read.errors!;
      read.retry.forEach((i, k) => {
        errors[i] = again.errors?.[k];
        if (!errors[i]) read.values[i] = again.values[k]!;
      });
      if (errors.every((e) => e === undefined)) read.errors = undefined;
    }
    return read;
  }

  /**
   * Reads `tags` with the plan for the current item limit: merged, the one
   * `prepared` keeps for the list; not merged (every tag its own item, for
   * the tags of failed merged items), a plan of its own. When the PLC
   * answered fewer items than a job asked for, that is its limit: learnt,
   * and the tags are read again with a plan for it (each round plans for
   * fewer items than the one before, so this ends).
   */
  private async readServed(
    session: S7Session,
    tags: readonly Tag[],
    merge: boolean,
    signal?: AbortSignal,
    prepared?: S7Prepared,
  ): Promise<CollectedRead> {
    for (;;) {
      const c = merge
        ? this.preparedPlan(session.pduSize, tags, prepared ?? { compiled: undefined })
        : compileRead(planRead(tags, session.pduSize, { merge: false, maxItems: this.itemLimit }), tags);
      const read = await this.execute(session, tags, c, signal);
      if (read.served === 0) return read;
      this.learnItemLimit(read.served);
    }
  }

  /**
   * A prepared list's plan and frames, made again (found in the plan cache,
   * or planned) when the PDU size or the item limit differs from the one
   * they were made for. Re-planning replaces them; a poll still in flight
   * keeps the ones it started with.
   */
  private preparedPlan(pduSize: number, tags: readonly Tag[], prepared: S7Prepared): CompiledRead {
    const known = prepared.compiled;
    if (known && known.plan.pduSize === pduSize && known.plan.maxItems === maxReadItems(pduSize, this.itemLimit)) return known;
    const fresh = this.plans.get(tags, pduSize, this.planOptions);
    let c = this.compiledPlans.get(fresh);
    if (!c) {
      c = compileRead(fresh, tags);
      this.compiledPlans.set(fresh, c);
    }
    return (prepared.compiled = c);
  }

  /** The PLC served only `served` items of a job: jobs carry at most that many from now on. */
  private learnItemLimit(served: number): void {
    if (served >= this.itemLimit) return;
    const was = this.itemLimit;
    this.itemLimit = served;
    this.planOptions = { maxItems: served };
    // The plans for the old limit are of no more use.
    this.plans.clear();
    this.emit('itemLimit', { limit: served, was } satisfies ItemLimitEvent);
  }

  private execute(session: S7Session, tags: readonly Tag[], c: CompiledRead, signal?: AbortSignal): Promise<CollectedRead> {
    const { plan } = c;
    const n = plan.pdus.length;
    const answers: Buffer[] = new Array<Buffer>(n);
    if (n === 0) return Promise.resolve(this.collect(session, tags, plan, c, answers));
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
              resolve(this.collect(session, tags, plan, c, answers));
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
  private collect(session: S7Session, tags: readonly Tag[], plan: ReadPlan, c: CompiledRead, answers: readonly Buffer[]): CollectedRead {
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
        const unusual = this.unusualReadAnswer(session, frame, count, table, base);
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
      for (let i = base; i < base + count; i++) if (table.code[i] !== SUCCESS || table.length[i] !== itemLength[i]) itemsFailed = true;
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
              : this.splitValue(tags[t]!, t, plan, c, answers);
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
      if (rc !== SUCCESS) return returnCodeError(rc);
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
          p >= 0
            ? decoders[t]!(answers[p]!, table.start[itemBase[p]! + tagItem[t]!]! + tagOffset[t]!)
            : this.splitValue(tag, t, plan, c, answers);
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
  private unusualReadAnswer(
    session: S7Session,
    frame: Buffer,
    count: number,
    table: ReadItemTable,
    base: number,
  ): PlcError | number | undefined {
    const answer = this.decode(session, frame);
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
  private splitValue(tag: Tag, t: number, plan: ReadPlan, c: CompiledRead, answers: readonly Buffer[]): PlcValue {
    const data = plan.pdus.map((pdu, p) =>
      pdu.items.map((_, i) => {
        const k = c.itemBase[p]! + i;
        return answers[p]!.subarray(c.table.start[k]!, c.table.start[k]! + c.table.length[k]!);
      }),
    );
    const { data: bytes, offset } = tagData(plan, t, data);
    return decodeTag(tag, bytes, offset);
  }

  // ---------------------------------------------------------------- writes

  private async writeTags(
    session: S7Session,
    items: readonly { tag: Tag; value: unknown }[],
    signal?: AbortSignal,
  ): Promise<TagResult<void>[]> {
    this.stats.requests++;
    const plan = planWrite(items, session.pduSize, this.planOptions);
    const errors: (PlcError | undefined)[] = plan.errors.slice();
    await Promise.all(plan.pdus.map((pdu) => this.writeJob(session, pdu.items, pdu.tags, errors, signal)));
    return items.map(({ tag }, i) => {
      const err = errors[i];
      if (!err) return { ok: true, value: undefined };
      return { ok: false, error: tagError(tag, err) };
    });
  }

  /**
   * One Write Var job; `tags[i]` is the index in `errors` of item i's tag,
   * which gets the tag's first error. A PLC that answers fewer return codes
   * than the job had items (at least one) served those first items (return
   * codes come in item order): the limit is learnt and the items it left
   * out are sent again in jobs it serves. The items it answered are not
   * sent twice (a second write of a command bit could act twice).
   */
  private async writeJob(
    session: S7Session,
    items: PlannedWriteItem[],
    tags: number[],
    errors: (PlcError | undefined)[],
    signal?: AbortSignal,
  ): Promise<void> {
    const n = items.length;
    const failAll = (err: PlcError) => tags.forEach((t) => (errors[t] ??= err));
    let answer: S7Message;
    try {
      answer = await this.job(session, encodeWriteRequest(0, items), `write of ${n} item(s)`, signal);
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
      if (rc !== SUCCESS) errors[tags[i]!] ??= returnCodeError(rc);
    });
    if (served === n) return;
    this.learnItemLimit(served);
    const size = this.itemLimit;
    const rest: Promise<void>[] = [];
    for (let i = served; i < n; i += size)
      rest.push(this.writeJob(session, items.slice(i, i + size), tags.slice(i, i + size), errors, signal));
    await Promise.all(rest);
  }
}

/** What a read of one plan found: values and errors per tag, the tags to read alone, and `served` (see collect). */
type CollectedRead = ReadValues & { retry: number[]; served: number };

/** A plan ready to send: its request frames (reused while not in flight) and where each tag's bytes lie. */
interface CompiledRead {
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

function compileRead(plan: ReadPlan, tags: readonly Tag[]): CompiledRead {
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

function returnCodeError(rc: number): PlcError {
  const { code, text } = describeReturnCode(rc);
  return new PlcError(code, `the PLC answered return code 0x${rc.toString(16).padStart(2, '0').toUpperCase()}: ${text}`, { plcCode: rc });
}

/** The same error for one tag, naming where it lies when the address was written another way (DB1,INT2 → DB1.DBW2). */
function tagError(tag: Tag, err: PlcError): PlcError {
  const canonical = formatAddress(tag);
  return namedTagError(tag.address, err, canonical === tag.address ? undefined : canonical);
}

function linkError(name: string, err: unknown): PlcError {
  const e = toPlcError(err, 'PROTOCOL_ERROR');
  return e instanceof ProtocolError ? new ProtocolError(`${name}: ${e.message}`, { cause: e }) : e;
}
