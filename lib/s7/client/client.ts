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
import { S7_TAG_SYNTAX } from '../../address';
import { ConnectionError, isLinkError, PlcError, type TagResult } from '../../errors';
import { BaseClient, endpointOptions, toResults, type ClientOptions } from '../../client/base';
import type { Driver, ReadValues } from '../../link/driver';
import type { PlcValue, Protocol, RequestOptions, Tag } from '../../types';
import { S7_URLS, type S7Endpoint } from '../url';
import { DEFAULT_MAX_ITEMS } from '../constants';
import { openS7Session } from './handshake';
import { PushHub } from './pushes';
import { S7Alarms } from './alarms';
import { subscribeCyclic, type CyclicHost, type CyclicOptions, type S7CyclicSubscription } from './cyclic';
import type { S7Session, WireCounters } from './session';
import { compileRead, executeRead, tagError, type CollectedRead, type CompiledRead } from './read';
import { writeJob } from './write';
import { maxReadItems, planRead, planWrite, PlanStore, type PlanOptions, type ReadPlan } from '../plan';
import type { BlockCounts, BlockInfo, UploadedBlock } from '../codec/blocks';
import type { BlockType } from '../constants';
import type { DiagnosticEntry } from '../codec/diagnostics';
import { S7Services, type ClockOptions, type PlcInfo } from './services';
import type { CpuState, SzlList } from '../codec/szl';

export { S7Session } from './session';
export { localTsapFor } from '../tsap';

/**
 * Counters for diagnostics and the benchmark (cumulative over reconnects).
 * The session counts the wire: S7 jobs sent (pdusSent: Read Var, Write Var
 * and the services' jobs), bytes sent and received (TPKT headers included),
 * replies that matched no pending job (ignoredReplies).
 */
export interface S7Stats extends WireCounters {
  /** read()/write() calls that reached the PLC. */
  requests: number;
  /**
   * Read plans computed. A prepared list (client.prepare, or the same array
   * given to read() again) keeps its plan and request frames: polling it
   * plans nothing until the PDU size or the item limit changes.
   */
  plansMade: number;
}

/** The `itemLimit` event: the PLC answered only `limit` items of a job; jobs had up to `was`. */
export interface ItemLimitEvent {
  limit: number;
  was: number;
}

/** S7Client's events besides every client's (ClientEvents). */
export interface S7ClientEvents {
  itemLimit: [event: ItemLimitEvent];
}

/** Counters start at 0; plansMade is the plan store's own count. */
function newStats(plans: { readonly misses: number }): S7Stats {
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
 * What a prepared tag list keeps (Driver.prepareRead): a reference to its
 * merged plan with the plan's request frames, owned by the client's plan
 * store, for the PDU size and item limit the plan was made for. A read at
 * another PDU size (a reconnect to another CPU) or after the item limit was
 * learnt takes the store's entry for those instead.
 */
interface S7Prepared {
  compiled: CompiledRead | undefined;
}

export class S7Client extends BaseClient<S7Session, Tag, S7Prepared, S7ClientEvents> {
  readonly protocol: Protocol = 's7';
  readonly endpoint: S7Endpoint;
  /**
   * The one owner of this client's merged read plans, each with its request
   * frames (a list in a new array with the same addresses finds both); a
   * prepared list holds a reference to its entry (S7Prepared).
   */
  private readonly plans = new PlanStore<CompiledRead>(64, compileRead, (c) => c.plan);
  readonly stats: S7Stats = newStats(this.plans);
  /** Items per job: the URL's maxItems or 20, lowered when the PLC serves fewer (learnItemLimit). */
  private itemLimit: number;
  private planOptions: PlanOptions;
  /** The PDUs the CPU pushes (alarms, mode changes, diagnostic messages, cyclic data), on every session: lib/s7/client/pushes.ts. */
  readonly pushes = new PushHub();
  private readonly services: S7Services;
  private readonly alarmService: S7Alarms;
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
    super(endpointOptions(S7_URLS.name(endpoint), endpoint, options));
    this.endpoint = endpoint;
    this.itemLimit = endpoint.maxItems ?? DEFAULT_MAX_ITEMS;
    this.planOptions = { maxItems: this.itemLimit };
    const host = { name: this.name, endpoint, session: () => this.liveS7Session(), current: () => this.session };
    this.services = new S7Services(host);
    this.alarmService = new S7Alarms(host, this);
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
    ).plan;
  }

  /** A session wired to this client: its counters are the client's stats, its loss goes to the supervisor, its pushes to `pushes`. */
  private openSession(signal: AbortSignal): Promise<S7Session> {
    return openS7Session(this.endpoint, {
      name: this.name,
      timeout: this.timeout,
      maxQueued: this.maxQueued,
      requestTimeout: this.timeout,
      signal,
      stats: this.stats,
      lossError: (cause) => this.lossError(cause),
      lost: (session, err) => this.sessionLost(session, err),
    }).then((session) => this.pushes.wire(session));
  }

  /** The live session, for the services (NOT_CONNECTED when there is none). */
  private liveS7Session(): S7Session {
    const session = this.session;
    if (!session) throw new ConnectionError('NOT_CONNECTED', `not connected to ${this.name} (the link is ${this.state})`);
    return session;
  }

  /** Cyclic data of an S7-300/400 (lib/s7/client/cyclic.ts): the CPU sends `tags` every cycle, registered again after a reconnect. */
  subscribe(tags: readonly string[], options: CyclicOptions = {}): Promise<S7CyclicSubscription> {
    return subscribeCyclic(this as unknown as CyclicHost, () => this.session, tags, options);
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

  /** Identity and state in one object: order code, firmware, module type, serial number, AS and module names, mode, protection, PDU size, AmQ, clock (a list the CPU lacks: undefined fields). */
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

  /** Puts the CPU in STOP; refused (WRITE_NOT_ALLOWED) before anything is sent unless the URL says `control=true`, never on a read-only connection. Already in STOP: no error. */
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
  /** The active alarms of an S7-300/400 (the alarm query, every part): lib/s7/client/alarms.ts, docs/alarms.md. */
  readonly alarms: S7Alarms['list'] = (options) => this.alarmService.list(options);
  /** Alarm, mode and diagnostic events as the CPU pushes them; registered again after every reconnect. */
  readonly subscribeAlarms: S7Alarms['subscribe'] = (options, listener) => this.alarmService.subscribe(options, listener);
  /** Acknowledges an alarm (an operator's write: refused read-only or outside the allow-list); done when the CPU confirmed it. */
  readonly acknowledge: S7Alarms['acknowledge'] = (id, options) => this.alarmService.acknowledge(id, options);

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
      const read = await executeRead(session, tags, c, signal);
      if (read.served === 0) return read;
      this.learnItemLimit(read.served);
    }
  }

  /**
   * A prepared list's plan and frames: the plan store's entry it refers to,
   * looked up again (found, or planned) when the PDU size or the item limit
   * differs from the one they were made for. The new reference replaces the
   * old; a poll still in flight keeps the one it started with.
   */
  private preparedPlan(pduSize: number, tags: readonly Tag[], prepared: S7Prepared): CompiledRead {
    const known = prepared.compiled;
    if (known && known.plan.pduSize === pduSize && known.plan.maxItems === maxReadItems(pduSize, this.itemLimit)) return known;
    return (prepared.compiled = this.plans.get(tags, pduSize, this.planOptions));
  }

  /** The PLC served only `served` items of a job: jobs carry at most that many from now on. */
  private learnItemLimit(served: number): number {
    if (served >= this.itemLimit) return this.itemLimit;
    const was = this.itemLimit;
    this.itemLimit = served;
    this.planOptions = { maxItems: served };
    // The plans for the old limit are of no more use.
    this.plans.clear();
    this.emit('itemLimit', { limit: served, was } satisfies ItemLimitEvent);
    return served;
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
    await Promise.all(
      plan.pdus.map((pdu) => writeJob(session, pdu.items, pdu.tags, errors, signal, (served) => this.learnItemLimit(served))),
    );
    return items.map(({ tag }, i) => {
      const err = errors[i];
      if (!err) return { ok: true, value: undefined };
      return { ok: false, error: tagError(tag, err) };
    });
  }
}
