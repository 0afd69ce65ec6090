/**
 * Cyclic data of S7-300/400 CPUs as a TagSubscription (client.subscribe()):
 * the tags become cyclic jobs (codec/cyclic.ts; one item per tag, as many
 * jobs as the PDU size and item limit need), registered on the live session
 * and again on every session after a reconnect (a CPU forgets a closed
 * connection's jobs). The CPU's pushes come through the client's PushHub;
 * each item is decoded by the tag's decoder, the one a read uses.
 *
 * The cycle is what the CPU can do: time base 100 ms, 1 s or 10 s times a
 * factor 1..255 (cyclicInterval: the nearest, a larger base on a tie), so
 * 100 ms … 42.5 min, in steps of the base. `onChange`: the change-driven
 * variant (the CPU checks every cycle and sends only when a value changed).
 *
 * Events: `active` (registered on a session: its first data carries every
 * value), `data` (SubscriptionNotice), `lost` (the link went; registered
 * again when it is back), `error` (PlcError; only when someone listens),
 * `closed`.
 */
import { EventEmitter } from 'node:events';
import { isDeepStrictEqual } from 'node:util';
import { ConnectionError, PlcError, ProtocolError, TagErrors, tagError, toPlcError, type TagResult } from '../../errors';
import type { PlcValue, SubscriptionNotice, Tag } from '../../types';
import { tagDecoder } from '../../values';
import { decodeShape, type SymbolShape } from '../../symbols/resolve';
import {
  CYCLIC_ANSWER_HEAD,
  CYCLIC_ERROR_TEXT,
  CYCLIC_REQUEST_HEAD,
  CYCLIC_TIME_BASE_MS,
  CyclicSubfunction,
  decodeCyclicValues,
  encodeCyclicSubscribe,
  encodeCyclicUnsubscribe,
} from '../codec/cyclic';
import type { ReadResponseItem, S7Item } from '../codec/pdu';
import { decodeUserdata } from '../codec/userdata';
import {
  READ_ITEM,
  ReturnCode,
  S7_JOB_HEADER,
  TransportSize,
  UserdataGroup,
  UserdataType,
  returnCodeError,
  serviceError,
} from '../constants';
import { areaCode, isCounterOrTimer } from '../plan/atoms';
import type { PushHub } from './pushes';
import type { S7Session } from './session';

export interface CyclicOptions {
  /** The period asked for, ms (default 100): the CPU sends every time base × factor nearest to it (cyclicInterval). */
  cycle?: number;
  /** true: change-driven, the CPU sends a job's values only when one changed (checked every cycle). */
  onChange?: boolean;
}

/** What the subscription needs from S7Client. */
export interface CyclicHost {
  readonly name: string;
  readonly pushes: PushHub;
  /** Items per job at most (the client's item limit). */
  readonly maxItems: number;
  tag(address: string): Tag;
  on(event: string, listener: (...args: never[]) => void): unknown;
  off(event: string, listener: (...args: never[]) => void): unknown;
}

/**
 * client.subscribe() of an S7 client: the subscription, registered on the
 * live session (`current`); rejects as register() does, having closed it.
 */
export async function subscribeCyclic(
  host: CyclicHost,
  current: () => S7Session | undefined,
  tags: readonly string[],
  options: CyclicOptions = {},
): Promise<S7CyclicSubscription> {
  const sub = new S7CyclicSubscription(host, current, tags, options);
  try {
    await sub.register();
  } catch (err) {
    await sub.close();
    throw err;
  }
  return sub;
}

/** A period in the CPU's terms: the time base code and the factor whose product is nearest to `ms`. */
export function cyclicInterval(ms: number): { timeBase: number; factor: number; ms: number } {
  let best = { timeBase: 0, factor: 1, ms: CYCLIC_TIME_BASE_MS[0]! };
  CYCLIC_TIME_BASE_MS.forEach((base, timeBase) => {
    const factor = Math.min(255, Math.max(1, Math.round(ms / base)));
    if (Math.abs(base * factor - ms) <= Math.abs(best.ms - ms)) best = { timeBase, factor, ms: base * factor };
  });
  return best;
}

/** One job: its items, the tags they carry (by index into the subscription's tags) and each item's length. */
interface JobPlan {
  items: S7Item[];
  tags: number[];
  lengths: number[];
}

/** The item of a tag: its bytes (BYTE × length) or its counters/timers, as a read asks for them unmerged. */
function itemOf(tag: Tag): { item: S7Item; length: number } {
  const area = areaCode(tag);
  if (isCounterOrTimer(area)) {
    const transportSize = tag.area === 'C' ? TransportSize.COUNTER : TransportSize.TIMER;
    return { item: { area, dbNumber: 0, transportSize, count: tag.count, address: tag.byteOffset }, length: 2 * tag.count };
  }
  const length = tag.byteLength;
  return { item: { area, dbNumber: tag.dbNumber, transportSize: TransportSize.BYTE, count: length, address: tag.byteOffset * 8 }, length };
}

/** Bytes of a registration request and of a push besides the items (userdata header, parameters, item head, job head). */
const REQUEST_BASE = S7_JOB_HEADER + 8 + 4 + CYCLIC_REQUEST_HEAD;
const PUSH_BASE = S7_JOB_HEADER + 12 + 4 + CYCLIC_ANSWER_HEAD;

/** The tags in jobs that fit the PDU (request and push) and the item limit; a tag too large for any job is an error of its own. */
export function planCyclic(tags: readonly Tag[], pduSize: number, maxItems: number): { jobs: JobPlan[]; errors: Map<number, PlcError> } {
  const jobs: JobPlan[] = [];
  const errors = new Map<number, PlcError>();
  let job: JobPlan | undefined;
  let push = 0;
  tags.forEach((tag, t) => {
    const { item, length } = itemOf(tag);
    const cost = 4 + length + (length & 1);
    if (PUSH_BASE + cost > pduSize || REQUEST_BASE + READ_ITEM > pduSize) {
      errors.set(
        t,
        new PlcError('NOT_SUPPORTED', `${length} bytes do not fit one cyclic job at PDU size ${pduSize}: poll this tag`, {
          tag: tag.address,
        }),
      );
      return;
    }
    if (!job || job.items.length >= maxItems || REQUEST_BASE + READ_ITEM * (job.items.length + 1) > pduSize || push + cost > pduSize) {
      job = { items: [], tags: [], lengths: [] };
      jobs.push(job);
      push = PUSH_BASE;
    }
    job.items.push(item);
    job.tags.push(t);
    job.lengths.push(length);
    push += cost;
  });
  return { jobs, errors };
}

const STRICT_NAME = (tag: string) =>
  new PlcError('NOT_SUPPORTED', "strictSymbols checks this name's block on every connection, which reads do", { tag });

export class S7CyclicSubscription extends EventEmitter {
  readonly tags: readonly string[];
  /** The period the CPU was asked for, ms. */
  readonly cycle: number;
  private readonly interval: { timeBase: number; factor: number };
  private readonly subfunction: CyclicSubfunction.Memory | CyclicSubfunction.ChangeDriven;
  private readonly parsed: Tag[];
  private readonly decoders: ((data: Buffer, offset: number) => PlcValue)[];
  private readonly results = new Map<string, TagResult<PlcValue>>();
  /** The jobs registered on `session`, by job id. */
  private live = new Map<number, JobPlan>();
  private session: S7Session | undefined;
  private closed = false;
  private readonly unlisten: () => void;

  constructor(
    private readonly host: CyclicHost,
    private readonly current: () => S7Session | undefined,
    tags: readonly string[],
    options: CyclicOptions,
  ) {
    super();
    this.tags = Object.freeze([...tags]);
    const interval = cyclicInterval(options.cycle ?? 100);
    this.interval = interval;
    this.cycle = interval.ms;
    this.subfunction = options.onChange ? CyclicSubfunction.ChangeDriven : CyclicSubfunction.Memory;
    const bad: Record<string, TagResult<PlcValue>> = {};
    this.parsed = [];
    const symbols = symbolsOf(host);
    for (const address of tags) {
      try {
        const tag = host.tag(address);
        // A name whose block strictSymbols checks is gated by each read: it is polled.
        if (symbols?.strict && symbols.use(tag)) bad[address] = { ok: false, error: STRICT_NAME(address) };
        else this.parsed.push(tag);
      } catch (err) {
        bad[address] = { ok: false, error: toPlcError(err) };
      }
    }
    if (Object.keys(bad).length > 0) throw new TagErrors(bad);
    this.decoders = this.parsed.map((tag) => {
      const shape = symbols?.use(tag)?.shape;
      // A struct by name: its bytes into the object, as a read shapes it (lib/client/symbols.ts).
      return shape ? (data: Buffer) => decodeShape(shape, data) as PlcValue : tagDecoder(tag);
    });
    const unpush = host.pushes.listen((frame) => this.onPush(frame));
    const unlink = linkEvents(host, this);
    this.unlisten = () => {
      unpush();
      unlink();
    };
  }

  /** The link is up again: registers on the new session. */
  linkUp(): void {
    this.register().catch((err: unknown) => this.fail(toPlcError(err)));
  }

  /** The link went: the CPU forgot the jobs. */
  linkDown(err: PlcError): void {
    this.live.clear();
    this.session = undefined;
    this.emit('lost', err);
  }

  /** Registers the jobs on the live session; rejects (NOT_SUPPORTED for a CPU without cyclic data, as TagErrors) when the CPU refuses. */
  async register(): Promise<void> {
    const session = this.current();
    if (!session) throw new ConnectionError('NOT_CONNECTED', `not connected to ${this.host.name}`);
    const { jobs, errors } = planCyclic(this.parsed, session.pduSize, this.host.maxItems);
    if (errors.size > 0) throw new TagErrors(Object.fromEntries([...errors].map(([t, e]) => [this.tags[t]!, { ok: false, error: e }])));
    this.session = session;
    this.live = new Map();
    const first: [JobPlan, ReadResponseItem[]][] = [];
    for (const job of jobs) {
      const frame = encodeCyclicSubscribe({ subfunction: this.subfunction, ...this.interval, items: job.items });
      const answer = decodeUserdata(await session.exchange(frame, 'cyclic data registration'));
      const p = answer.params;
      if (p.type !== UserdataType.Response || p.group !== UserdataGroup.Cyclic) {
        throw session.malformed(new ProtocolError(`the answer to a cyclic registration is group ${p.group}, type ${p.type}`));
      }
      if (p.errorCode) throw this.refusal(p.errorCode);
      if (this.closed || this.session !== session) return this.unsubscribe(session, p.sequence);
      this.live.set(p.sequence, job);
      first.push([job, decodeCyclicValues(answer.data)]);
    }
    // The first values once the caller of subscribe() has its listeners on (it awaited this).
    setImmediate(() => {
      if (this.closed || this.session !== session) return;
      this.emit('active');
      const changed: string[] = [];
      for (const [job, items] of first) this.apply(job, items, changed, true);
      this.emitData(changed, true);
    });
  }

  /** Ends the jobs on the CPU (when the link is up) and stops listening. Always resolves. */
  async close(): Promise<void> {
    if (this.closed) return;
    this.closed = true;
    this.unlisten();
    const session = this.session;
    const ids = [...this.live.keys()];
    this.live.clear();
    if (session && this.current() === session) await Promise.all(ids.map((id) => this.unsubscribe(session, id)));
    this.emit('closed');
  }

  private async unsubscribe(session: S7Session, jobId: number): Promise<void> {
    await session.exchange(encodeCyclicUnsubscribe(jobId), 'cyclic data unsubscribe').catch(() => undefined);
  }

  /** The CPU's refusal: a CPU without the service gets the tags' errors, so a watch polls them. */
  private refusal(code: number): PlcError {
    const text = CYCLIC_ERROR_TEXT[code];
    const context = `${this.host.name} cyclic data`;
    if (text) return new PlcError('PLC_ERROR', `${context}: the PLC answered 0x${code.toString(16)}: ${text}`, { plcCode: code });
    const err = serviceError(code, context);
    if (err.code !== 'NOT_SUPPORTED') return err;
    const why = new PlcError(
      'NOT_SUPPORTED',
      `${this.host.name} does not offer cyclic data (0x${code.toString(16)}): an S7-300/400 does; on an S7-1200/1500 subscribe over s7plus://, an S7-200 or LOGO! is polled`,
      { plcCode: code },
    );
    return new TagErrors(Object.fromEntries(this.tags.map((t) => [t, { ok: false, error: tagError(t, why) }])));
  }

  private onPush(frame: Buffer): void {
    if (this.closed) return;
    let u;
    try {
      u = decodeUserdata(frame);
    } catch {
      return;
    }
    if (u.params.group !== UserdataGroup.Cyclic) return;
    const job = this.live.get(u.params.sequence);
    if (!job) return;
    try {
      const changed: string[] = [];
      this.apply(job, decodeCyclicValues(u.data), changed, false);
      this.emitData(changed, false);
    } catch (err) {
      this.fail(toPlcError(err));
    }
  }

  /** One answer's or push's items into the tags' results; the tags that changed (all of them when `initial`) into `changed`. */
  private apply(job: JobPlan, items: ReadResponseItem[], changed: string[], initial: boolean): void {
    if (items.length !== job.items.length)
      throw new ProtocolError(`cyclic data with ${items.length} items for a job of ${job.items.length}`);
    items.forEach((it, i) => {
      const t = job.tags[i]!;
      const address = this.tags[t]!;
      const result = this.result(t, it, job.lengths[i]!);
      const before = this.results.get(address);
      if (initial || !before || !same(before, result)) changed.push(address);
      this.results.set(address, result);
    });
  }

  private emitData(changed: string[], initial: boolean): void {
    this.emit('data', { results: Object.fromEntries(this.results), changed, initial } satisfies SubscriptionNotice);
  }

  private result(t: number, it: ReadResponseItem, length: number): TagResult<PlcValue> {
    const address = this.tags[t]!;
    if (it.returnCode !== (ReturnCode.Success as number)) return { ok: false, error: returnCodeError(it.returnCode, address, address) };
    if (it.data.length !== length) {
      return {
        ok: false,
        error: new ProtocolError(`${address}: asked for ${length} bytes, the PLC sent ${it.data.length}`, { tag: address }),
      };
    }
    try {
      return { ok: true, value: this.decoders[t]!(it.data, 0) };
    } catch (err) {
      return { ok: false, error: tagError(address, toPlcError(err)) };
    }
  }

  private fail(err: PlcError): void {
    if (this.listenerCount('error') > 0) this.emit('error', err);
  }
}

/**
 * What the client's symbols say of a tag resolved from a name (its struct
 * shape), and whether the client checks names' blocks (strictSymbols).
 * BaseClient keeps both to itself; its read() shapes and gates with them.
 */
function symbolsOf(host: CyclicHost): { strict: boolean; use(tag: Tag): { shape: SymbolShape<Tag> | undefined } | undefined } | undefined {
  const h = host as unknown as { strictSymbols?: boolean; symbols?: { use(t: Tag): { shape: SymbolShape<Tag> | undefined } | undefined } };
  const symbols = h.symbols;
  return symbols && { strict: h.strictSymbols === true, use: (tag) => symbols.use(tag) };
}

/** A client's subscriptions: one listener per link event on the client, whatever their number. */
const linked = new WeakMap<CyclicHost, { all: Set<S7CyclicSubscription>; detach: () => void }>();

function linkEvents(host: CyclicHost, sub: S7CyclicSubscription): () => void {
  let entry = linked.get(host);
  if (!entry) {
    const all = new Set<S7CyclicSubscription>();
    const up = () => all.forEach((s) => s.linkUp());
    const down = (err: PlcError) => all.forEach((s) => s.linkDown(err));
    const closed = () => all.forEach((s) => void s.close());
    host.on('connected', up);
    host.on('disconnected', down);
    host.on('closed', closed);
    entry = {
      all,
      detach: () => {
        host.off('connected', up);
        host.off('disconnected', down);
        host.off('closed', closed);
        linked.delete(host);
      },
    };
    linked.set(host, entry);
  }
  const { all, detach } = entry;
  all.add(sub);
  return () => {
    all.delete(sub);
    if (all.size === 0) detach();
  };
}

function same(a: TagResult<PlcValue>, b: TagResult<PlcValue>): boolean {
  if (a.ok && b.ok) return isDeepStrictEqual(a.value, b.value);
  return !a.ok && !b.ok && a.error.message === b.error.message;
}
