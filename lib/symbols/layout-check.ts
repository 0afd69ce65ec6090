/**
 * Stale layout detection: the sources a SymbolTable was compiled from say
 * how long each data block is (table.blocks); the PLC says how long its
 * block is (S7: block info). A block changed in the PLC (a member added, a
 * type changed) and not in the sources shifts every offset after the
 * change: reads by name would return neighbours' bytes. The client checks
 * every block of the table on each (re)connect and on demand
 * (client.checkLayout()), tells what it found in events, and with
 * `strictSymbols` refuses reads and writes by name in a block that does not
 * match (LAYOUT_MISMATCH); absolute addresses of that block stay allowed.
 *
 * A PLC that cannot tell (no block functions, as S7-1200/1500 over PUT/GET;
 * FETCH/WRITE, which has no such service) gives `layoutUnknown` and no
 * refusal: nothing contradicts the sources.
 *
 * Blocks with optimized access are not checked (no check, no event, no
 * refusal): they have no standard-access length to compare, and their
 * members are read by name over S7CommPlus, which finds them by the PLC's
 * own identifiers rather than by offsets that could shift.
 */
import type { EventEmitter } from 'node:events';
import { abortError, isLinkError, PlcError, toPlcError } from '../errors';
import type { LayoutCheck, LayoutMismatchEvent, LayoutOkEvent, LayoutUnknownEvent } from '../types';
import type { BlockSummary, SymbolTable } from './model';

/** A DB's length as the PLC reports it; null when it has no such block; throws when it cannot tell. */
type BlockLength = (db: number, signal: AbortSignal | undefined) => Promise<number | null>;

export interface LayoutMonitorOptions {
  table: SymbolTable;
  strict: boolean;
  events: EventEmitter;
  /** Absent: the protocol cannot tell block lengths (`unsupported` says why). */
  blockLength: BlockLength | undefined;
  /** The numbers of the DBs the PLC has, when it can list them: a DB it does not list is not asked for. */
  dbNumbers?: ((signal: AbortSignal | undefined) => Promise<number[]>) | undefined;
  unsupported: string;
  /** Block infos asked at once (the PLC's parallel jobs). */
  parallel: () => number;
}

/** The blocks a check compares: those with a standard-access length (optimized blocks have none). */
function checkedBlocks(table: SymbolTable): (BlockSummary & { readonly length: number })[] {
  return table.blocks.filter((b): b is BlockSummary & { readonly length: number } => b.length !== null);
}

/** Errors that say the PLC refuses the service itself, not one block: the other blocks are not asked. */
const SERVICE_REFUSED = new Set(['NOT_SUPPORTED', 'ACCESS_DENIED']);

export class LayoutMonitor {
  /** Counts connections: a check of an earlier one reports nothing. */
  private generation = 0;
  private readonly pending = new Set<Promise<unknown>>();
  private readonly mismatches = new Map<number, LayoutCheck>();
  /** What was reported on this connection: a mismatch per DB, and whether layoutOk / layoutUnknown were. */
  private readonly reported = new Map<number, string>();
  private okReported = false;
  private unknownReported = false;
  /**
   * Blocks whose block info the PLC answered with a frame the client could
   * not read (which drops the link): not asked again by this client, or
   * every reconnect would drop the link again. snap7's server answers
   * block info of a DB it does not have so: a TPKT frame 78 bytes longer
   * than its S7 lengths, its header left over from earlier answers
   * (test/fixtures/s7-userdata.ts, SNAP7).
   */
  private readonly unreadable = new Map<number, PlcError>();
  /** The check under way that check() may share (one started without a signal of its own). */
  private running: { generation: number; checks: Promise<LayoutCheck[]> } | undefined;

  constructor(private readonly o: LayoutMonitorOptions) {}

  /** Each connect and reconnect: a fresh check of every block, in the background. */
  linkUp(): void {
    this.reset();
    if (checkedBlocks(this.o.table).length > 0) this.run(undefined).catch(() => undefined);
  }

  /** The client was closed: a check under way reports nothing. */
  stop(): void {
    this.reset();
  }

  private reset(): void {
    this.generation++;
    this.mismatches.clear();
    this.reported.clear();
    this.okReported = false;
    this.unknownReported = false;
  }

  /**
   * Checks every block now (and reports as on connect). A check of this
   * connection already under way (the one each connect starts) is shared
   * rather than asked again: its answers are as fresh, and the PLC is not
   * asked every block's info twice.
   */
  check(signal?: AbortSignal): Promise<LayoutCheck[]> {
    const running = this.running;
    if (!running || running.generation !== this.generation) return this.run(signal);
    if (!signal) return running.checks;
    if (signal.aborted) return Promise.reject(abortError('the layout check', signal));
    return new Promise((resolve, reject) => {
      const onAbort = () => reject(abortError('the layout check', signal));
      signal.addEventListener('abort', onAbort, { once: true });
      running.checks.then(
        (checks) => (signal.removeEventListener('abort', onAbort), resolve(checks)),
        (err: unknown) => (signal.removeEventListener('abort', onAbort), reject(err)),
      );
    });
  }

  /** True when reads and writes by name must wait for a check, or may be refused (strictSymbols only). */
  get gating(): boolean {
    return this.o.strict && (this.pending.size > 0 || this.mismatches.size > 0);
  }

  /** Resolves when no check is under way (strictSymbols: a read by name waits for the check of its connection). */
  async settled(signal?: AbortSignal): Promise<void> {
    while (this.o.strict && this.pending.size > 0) {
      const all = Promise.allSettled([...this.pending]);
      if (!signal) {
        await all;
        continue;
      }
      if (signal.aborted) throw abortError('a read waiting for the layout check', signal);
      let onAbort: (() => void) | undefined;
      const aborted = new Promise<never>((_, reject) => {
        onAbort = () => reject(abortError('a read waiting for the layout check', signal));
        signal.addEventListener('abort', onAbort, { once: true });
      });
      try {
        await Promise.race([all, aborted]);
      } finally {
        signal.removeEventListener('abort', onAbort!);
      }
    }
  }

  /** LAYOUT_MISMATCH for a symbol in `db` (strictSymbols and a mismatch found on this connection), else undefined. */
  refusal(db: number | null): PlcError | undefined {
    if (!this.o.strict || db === null) return undefined;
    const c = this.mismatches.get(db);
    return c ? new PlcError('LAYOUT_MISMATCH', mismatchText(c)) : undefined;
  }

  private run(signal: AbortSignal | undefined): Promise<LayoutCheck[]> {
    const generation = this.generation;
    const run = this.checkAll(generation, signal).then((checks) => {
      if (generation === this.generation) this.apply(checks);
      return checks;
    });
    this.pending.add(run);
    // Only a check without a signal of its own is shared: an aborted one must not fail the others.
    if (!signal) this.running = { generation, checks: run };
    const done = () => {
      this.pending.delete(run);
      if (this.running?.checks === run) this.running = undefined;
    };
    run.then(done, done);
    return run;
  }

  private async checkAll(generation: number, signal: AbortSignal | undefined): Promise<LayoutCheck[]> {
    const blocks = checkedBlocks(this.o.table);
    const { blockLength } = this.o;
    if (!blockLength) {
      const error = new PlcError('NOT_SUPPORTED', this.o.unsupported);
      return blocks.map((b) => unknown(b, error));
    }
    const checks = new Array<LayoutCheck>(blocks.length);
    const present = await this.listed(signal);
    let refused: PlcError | undefined;
    let next = 0;
    const worker = async (): Promise<void> => {
      while (next < blocks.length) {
        const i = next++;
        const b = blocks[i]!;
        if (generation !== this.generation) throw new PlcError('CLOSED', 'the connection the layout check ran on ended');
        const known = refused ?? this.unreadable.get(b.db);
        if (known) {
          checks[i] = unknown(b, known);
          continue;
        }
        if (present && !present.has(b.db)) {
          checks[i] = { block: b.name, db: b.db, declared: b.length, actual: null, status: 'mismatch' };
          continue;
        }
        try {
          const actual = await blockLength(b.db, signal);
          checks[i] = { block: b.name, db: b.db, declared: b.length, actual, status: actual === b.length ? 'ok' : 'mismatch' };
        } catch (err) {
          const e = toPlcError(err);
          if (e.code === 'PROTOCOL_ERROR') this.unreadable.set(b.db, e);
          // The link went, or the caller gave up: no verdict (a reconnect checks again).
          if (isLinkError(e) || e.code === 'ABORTED' || e.code === 'TIMEOUT') throw e;
          if (SERVICE_REFUSED.has(e.code)) refused = e;
          checks[i] = unknown(b, e);
        }
      }
    };
    const n = Math.max(1, Math.min(this.o.parallel(), blocks.length));
    await Promise.all(Array.from({ length: n }, worker));
    return checks;
  }

  /** The DBs the PLC lists, or undefined when it cannot list them (each is then asked for). */
  private async listed(signal: AbortSignal | undefined): Promise<Set<number> | undefined> {
    if (!this.o.dbNumbers) return undefined;
    try {
      return new Set(await this.o.dbNumbers(signal));
    } catch (err) {
      const e = toPlcError(err);
      if (isLinkError(e) || e.code === 'ABORTED' || e.code === 'TIMEOUT') throw e;
      return undefined;
    }
  }

  /** Keeps the mismatches (for strictSymbols) and emits what this connection has not been told yet. */
  private apply(checks: readonly LayoutCheck[]): void {
    const { events } = this.o;
    this.mismatches.clear();
    const unknowns: LayoutCheck[] = [];
    for (const c of checks) {
      if (c.status === 'unknown') unknowns.push(c);
      if (c.status !== 'mismatch') {
        this.reported.delete(c.db);
        continue;
      }
      this.mismatches.set(c.db, c);
      const key = `${c.declared}/${String(c.actual)}`;
      if (this.reported.get(c.db) === key) continue;
      this.reported.set(c.db, key);
      events.emit('layoutMismatch', {
        block: c.block,
        db: c.db,
        declared: c.declared,
        actual: c.actual ?? null,
      } satisfies LayoutMismatchEvent);
    }
    if (unknowns.length > 0 && !this.unknownReported)
      events.emit('layoutUnknown', { checks: unknowns, error: unknowns[0]!.error! } satisfies LayoutUnknownEvent);
    this.unknownReported = unknowns.length > 0;
    const ok = checks.every((c) => c.status === 'ok');
    if (ok && !this.okReported) events.emit('layoutOk', { checks: checks.slice() } satisfies LayoutOkEvent);
    this.okReported = ok;
  }
}

function unknown(b: BlockSummary & { readonly length: number }, error: PlcError): LayoutCheck {
  return { block: b.name, db: b.db, declared: b.length, actual: undefined, status: 'unknown', error };
}

/** `DB1 "Tank": the PLC's block is 24 bytes, the sources declare 20; recompile the sources or download the block`. */
function mismatchText(c: LayoutCheck): string {
  const which = `DB${c.db} "${c.block}"`;
  if (c.actual === null || c.actual === undefined) {
    return `${which}: the PLC has no DB${c.db}, the sources declare it with ${c.declared} bytes; download the block or give the sources its number`;
  }
  return `${which}: the PLC's block is ${c.actual} bytes, the sources declare ${c.declared}; recompile the sources or download the block`;
}
