/**
 * A client's symbols: names resolved to tags of the driver's syntax, what
 * each resolved tag is (its data block, the shape of a struct), struct values
 * decoded from their bytes, and the layout check that gates names
 * (strictSymbols) in a data block whose length differs from the sources'.
 */
import { PlcError, tagError, toPlcError, type TagResult } from '../errors';
import type { DriverTag } from '../link/driver';
import { LayoutMonitor, type LayoutMonitorOptions } from '../symbols/layout-check';
import type { SymbolTable } from '../symbols/model';
import { decodeShape, type ResolvedSymbol, type SymbolShape } from '../symbols/resolve';
import type { PlcValue } from '../types';

/** What the client keeps of a tag resolved from a symbol: its data block (null outside DBs) and, for a struct, its shape. */
export interface SymbolUse<T> {
  db: number | null;
  shape: SymbolShape<T> | undefined;
}

export interface ListSymbols<T> {
  dbs: Set<number>;
  /** Tags (by index) whose bytes are decoded into an object. */
  shaped: { index: number; shape: SymbolShape<T> }[];
}

/** What gating needs of a read list (lib/client/lists.ts): its addresses, its tags and those that did not parse. */
interface GatedList<T> {
  readonly addresses: readonly string[];
  readonly tags: readonly T[];
  readonly bad: readonly { address: string; error: PlcError }[];
}

/** The layout check's options other than the table and strictness: the driver's services, asked at first use. */
export type LayoutServices = Omit<LayoutMonitorOptions, 'table' | 'strict'>;

export class ClientSymbols<T extends DriverTag> {
  private readonly uses = new WeakMap<T, SymbolUse<T>>();
  private monitor: LayoutMonitor | undefined;

  /** `services` is called once, at the layout check's first use (the driver is a field of the client's subclass). */
  constructor(
    readonly table: SymbolTable,
    private readonly strict: boolean,
    private readonly services: () => LayoutServices,
  ) {}

  /** The layout check of the table's blocks (made at first use). */
  get layout(): LayoutMonitor {
    return (this.monitor ??= new LayoutMonitor({ table: this.table, strict: this.strict, ...this.services() }));
  }

  /** Stops a layout check made so far; makes none. */
  stop(): void {
    this.monitor?.stop();
  }

  /** Remembers a tag resolved from a name (addressOrSymbol) as that symbol's: its data block and struct shape. */
  remember({ entry, tag, shape }: ResolvedSymbol<T>): void {
    this.uses.set(tag, { db: entry.area === 'DB' ? entry.db : null, shape });
  }

  /** What a tag resolved from a name is; undefined for an absolute address. */
  use(tag: T): SymbolUse<T> | undefined {
    return this.uses.get(tag);
  }

  /** The symbols among a list's tags: their data blocks and structs; undefined when none is one. */
  ofList(tags: readonly T[]): ListSymbols<T> | undefined {
    let symbols: ListSymbols<T> | undefined;
    tags.forEach((tag, index) => {
      const use = this.uses.get(tag);
      if (!use) return;
      symbols ??= { dbs: new Set(), shaped: [] };
      if (use.db !== null) symbols.dbs.add(use.db);
      if (use.shape) symbols.shaped.push({ index, shape: use.shape });
    });
    return symbols;
  }

  /**
   * strictSymbols: waits for a layout check under way, then the list
   * without the symbols of blocks that do not match (their LAYOUT_MISMATCH
   * among the unparsable ones, a list made by `relist`); the list itself
   * when none is refused.
   */
  async gated<L extends GatedList<T>>(
    list: L,
    signal: AbortSignal | undefined,
    relist: (addresses: readonly string[], tags: T[], bad: { address: string; error: PlcError }[]) => L,
  ): Promise<L> {
    const { layout } = this;
    await layout.settled(signal);
    let kept: T[] | undefined;
    const refused: { address: string; error: PlcError }[] = [];
    list.tags.forEach((tag, i) => {
      const refusal = layout.refusal(this.uses.get(tag)?.db ?? null);
      if (refusal) {
        kept ??= list.tags.slice(0, i);
        refused.push({ address: tag.address, error: tagError(tag.address, refusal) });
      } else kept?.push(tag);
    });
    if (!kept) return list;
    return relist(list.addresses, kept, [...list.bad, ...refused]);
  }
}

/** Struct values from their bytes, in place (tags that failed keep their error); the errors, with any of decoding. */
export function shapeValues<T>(
  symbols: ListSymbols<T>,
  tags: readonly DriverTag[],
  values: unknown[],
  errors: (PlcError | undefined)[] | undefined,
): (PlcError | undefined)[] | undefined {
  for (const { index, shape } of symbols.shaped) {
    if (errors?.[index]) continue;
    try {
      values[index] = decodeShape(shape, values[index] as PlcValue);
    } catch (err) {
      (errors ??= new Array<PlcError | undefined>(values.length))[index] = tagError(
        tags[index]!.address,
        toPlcError(err, 'PROTOCOL_ERROR'),
      );
    }
  }
  return errors;
}

export function shapeResults<T>(symbols: ListSymbols<T>, tags: readonly DriverTag[], results: TagResult<PlcValue>[]): void {
  for (const { index, shape } of symbols.shaped) {
    const r = results[index]!;
    if (!r.ok) continue;
    try {
      results[index] = { ok: true, value: decodeShape(shape, r.value) as PlcValue };
    } catch (err) {
      results[index] = { ok: false, error: tagError(tags[index]!.address, toPlcError(err, 'PROTOCOL_ERROR')) };
    }
  }
}
