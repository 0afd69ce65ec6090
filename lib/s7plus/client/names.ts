/**
 * Reads and writes by name over S7CommPlus. A name that is not an address
 * parses to a "named tag" (plusSyntax); at a read or write it resolves
 * through the PLC's browsed table to its access path (area and LIDs) and
 * goes with GetMultiVariables / SetMultiVariables by LID: elementary members
 * item by item, a struct or array as its elementary members, put back
 * together as an object or an array. A name the PLC does not have fails
 * with INVALID_ADDRESS naming it and the closest names, never with another
 * member's value. Addresses go on to the by-address path (io.ts); writes by
 * name are name-writes.ts.
 * Layouts: s7commplus (MIT), client.py (read_tags / write_tags by access
 * sequence: area, DBValueActual, LIDs).
 */
import { S7_TAG_SYNTAX } from '../../address';
import { PlcError, toPlcError } from '../../errors';
import type { ReadValues, TagSyntax } from '../../link/driver';
import { canonicalName, splitSymbol } from '../../symbols/names';
import { wholeBlock } from '../../symbols/resolve';
import type { SymbolEntry, SymbolTable } from '../../symbols/model';
import type { PlcValue, Tag } from '../../types';
import type { TagShape } from '../../values';
import { isInvalidCrc } from '../codec/symbol-crc';
import { addressBytes, type ItemAddress } from '../codec/variables';
import { readAsk } from './asks';
import { inChunks, type Limits } from './chunks';
import { itemAnswer, itemRefusal, notAnswered, refusedWhole, untrustedValue } from './refusals';
import { readTags } from './io';
import { explainOptimized } from './optimized';
import { assemble, itemOf, leavesOf, shapeOf, valueOf } from './name-values';
import type { S7PlusSession } from './session';

/** A tag that stands for a name of the PLC's program (resolved at the read or write). */
export interface NamedTag extends Tag {
  /** The name's key: canonical, lower case. */
  readonly symbol: string;
}

export const isNamed = (tag: Tag): tag is NamedTag => typeof (tag as Partial<NamedTag>).symbol === 'string';

/**
 * The S7 address syntax, and names: what does not parse as an address but
 * is a well-formed name becomes a named tag, unless the given table
 * (`symbols`) has it with an address, which then resolves it as for s7://.
 */
export function plusSyntax(given: SymbolTable | undefined): TagSyntax<Tag> {
  return Object.freeze({
    parse(address: string): Tag {
      try {
        return S7_TAG_SYNTAX.parse(address);
      } catch (err) {
        const parts = typeof address === 'string' ? splitSymbol(address) : undefined;
        if (!parts || (given?.lookup(address)?.address ?? null) !== null) throw err;
        const named: NamedTag = {
          address,
          symbol: canonicalName(parts).toLowerCase(),
          area: 'DB',
          dbNumber: 0,
          byteOffset: 0,
          bitOffset: 0,
          type: 'BYTE',
          count: 1,
          isArray: false,
          stringLength: 0,
          byteLength: 1,
        };
        return Object.freeze(named);
      }
    },
    areaOf: (tag: Tag) => (isNamed(tag) ? `NAME ${tag.symbol}` : S7_TAG_SYNTAX.areaOf(tag)),
    allowArea: (entry: string) => S7_TAG_SYNTAX.allowArea(entry),
    contains(outer: Tag, inner: Tag): boolean {
      // A name admits itself and what lies under it (its members and elements).
      if (isNamed(outer) || isNamed(inner)) {
        if (!isNamed(outer) || !isNamed(inner)) return false;
        const rest = inner.symbol.slice(outer.symbol.length);
        return inner.symbol.startsWith(outer.symbol) && (rest === '' || rest.startsWith('.') || rest.startsWith('['));
      }
      return S7_TAG_SYNTAX.contains(outer, inner);
    },
  });
}

export function unknownName(table: SymbolTable, name: string): PlcError {
  const near = table.suggest(name);
  const hint = near.length > 0 ? `; did you mean ${near.join(', ')}?` : '; the PLC has no such name';
  return new PlcError('INVALID_ADDRESS', `unknown name ${name} on the PLC${hint}`, { tag: name });
}

export const isAddress = (tag: Tag): boolean => !isNamed(tag);
const slotsOf = (errors: (PlcError | undefined)[]) => ({
  errorAt: (i: number) => errors[i],
  replace: (i: number, err: PlcError) => (errors[i] = err),
});

/** True when `table` has the name: a member, or a data block named alone. */
export function knows(table: SymbolTable, name: string): boolean {
  return table.lookup(name) !== undefined || wholeBlock(table, name) !== undefined;
}

/** What a named tag stands for: the entry, or why not. */
export function resolveName(table: SymbolTable, tag: NamedTag): SymbolEntry | PlcError {
  // A data block named alone ("Recipe") is the struct of its top-level members, as with compiled sources.
  const entry = table.lookup(tag.address) ?? wholeBlock(table, tag.address);
  if (!entry) return unknownName(table, tag.address);
  // What goes on the wire is each elementary member's access path.
  if (leavesOf(table, entry).some((leaf) => !leaf.access || leaf.access.lids.length === 0))
    return new PlcError('NOT_SUPPORTED', `${tag.address}: the PLC's browse gives no access path for it`, { tag: tag.address });
  return entry;
}

/**
 * The PLC's program as the names see it: the browsed table, and the check whether the program changed since
 * (client/program.ts): true when it did, and the table is then browsed again. Every name goes with its SymbolCrc, so
 * the PLC itself refuses a LID a download gave to another member (InvalidCRC); the check runs only after such a
 * refusal, for a name the table lacks, or for a name without a CRC (a path no public rule covers: issue #32).
 */
export interface Program {
  table(): Promise<SymbolTable>;
  /** `unknownName`: the read had a name the table does not have (a renamed block keeps its types' times). */
  changed(unknownName?: boolean): Promise<boolean>;
}

/** Reads of a program that keeps changing give up after this many attempts. */
export const MAX_ATTEMPTS = 3;

/** Values of addresses and names, in order; each tag's own failure is its error. */
export async function readMixed(
  session: S7PlusSession,
  tags: readonly Tag[],
  limits: Limits,
  program: Program,
  signal?: AbortSignal,
): Promise<ReadValues> {
  const named = tags.flatMap((t, i) => (isNamed(t) ? [i] : []));
  if (named.length === 0) {
    const r = await readTags(session, tags, limits, signal);
    if (r.errors) await explainOptimized(tags, slotsOf(r.errors), () => program.table(), isAddress);
    return r;
  }
  const values: PlcValue[] = new Array<PlcValue>(tags.length);
  const errors: (PlcError | undefined)[] = new Array<PlcError | undefined>(tags.length);
  const addressed = tags.flatMap((t, i) => (isNamed(t) ? [] : [i]));
  if (addressed.length > 0) {
    const r = await readTags(
      session,
      addressed.map((i) => tags[i]!),
      limits,
      signal,
    );
    addressed.forEach((i, k) => ((values[i] = r.values[k]!), (errors[i] = r.errors?.[k])));
    await explainOptimized(tags, slotsOf(errors), () => program.table(), isAddress);
  }
  // A value read by LID counts only when the PLC checked its SymbolCrc, or the program had not changed by the time it
  // came (the check runs after the read, so a download before or during it is seen); a refused item is never a value:
  // the names are read again through the table browsed again.
  for (let attempt = 1; ; attempt++) {
    const t = await program.table();
    const read = await readNamed(session, tags, named, t, limits, values, errors, signal);
    const unknown = named.some((i) => !knows(t, tags[i]!.address));
    if (read.refused.length === 0 && !read.unchecked && !unknown) break;
    if (!(await program.changed(unknown))) {
      // InvalidCRC though the program is the one browsed: the CRC of that path is not the PLC's (no public rule
      // covers it): it goes with 0 from now on, and the program check covers it.
      if (read.crcRefused.length === 0 || attempt === MAX_ATTEMPTS) break;
      for (const name of read.crcRefused) distrusted(t).add(name);
      continue;
    }
    if (attempt === MAX_ATTEMPTS) {
      for (const i of named) {
        values[i] = undefined as unknown as PlcValue;
        errors[i] = new PlcError('LAYOUT_MISMATCH', `${tags[i]!.address}: the PLC's program changed during each of ${MAX_ATTEMPTS} reads`, {
          tag: tags[i]!.address,
        });
      }
      break;
    }
  }
  return { values, errors: errors.some((e) => e) ? errors : undefined };
}

/**
 * What a read of one tag list by name needs from a browsed table, worked out
 * once per list and table (a poll reads the same names again and again):
 * each name's entry (or why not) and the range of its elementary members in
 * `leaves`, each leaf's item address and shape. A new table (a reconnect, a
 * program change) makes a new plan.
 */
interface NamedPlan {
  readonly table: SymbolTable;
  /** How many of the table's CRCs were distrusted when the plan was made (a plan is made again after more). */
  readonly distrusted: number;
  /** True when a leaf goes without a SymbolCrc: the PLC checks nothing of it, the program check must. */
  readonly unchecked: boolean;
  readonly wanted: readonly { readonly i: number; readonly entry: SymbolEntry; readonly from: number; readonly to: number }[];
  readonly unresolved: readonly { readonly i: number; readonly error: PlcError }[];
  readonly leaves: readonly SymbolEntry[];
  /** 0 … leaves.length - 1: what the chunker cuts. */
  readonly indexes: readonly number[];
  readonly items: readonly ItemAddress[];
  readonly shapes: readonly TagShape[];
}

/** Plans by tag list: the client hands the same array back for the same list (client/base.ts ReadList), so a poll finds its plan. */
const PLANS = new WeakMap<readonly Tag[], NamedPlan>();

/** Per browsed table, the leaves whose SymbolCrc the PLC refused while its program was the one browsed. */
const DISTRUSTED = new WeakMap<SymbolTable, Set<string>>();

export function distrusted(table: SymbolTable): Set<string> {
  let names = DISTRUSTED.get(table);
  if (!names) DISTRUSTED.set(table, (names = new Set<string>()));
  return names;
}

/** A leaf's item address through `table`: with its SymbolCrc, or 0 (no check) where the PLC refused ours. */
export function itemIn(table: SymbolTable, leaf: SymbolEntry): ItemAddress {
  const item = itemOf(leaf);
  return DISTRUSTED.get(table)?.has(leaf.name) ? { ...item, symbolCrc: 0 } : item;
}

function planOf(tags: readonly Tag[], named: readonly number[], table: SymbolTable): NamedPlan {
  const known = PLANS.get(tags);
  if (known?.table === table && known.distrusted === (DISTRUSTED.get(table)?.size ?? 0)) return known;
  const wanted: { i: number; entry: SymbolEntry; from: number; to: number }[] = [];
  const unresolved: { i: number; error: PlcError }[] = [];
  const leaves: SymbolEntry[] = [];
  for (const i of named) {
    const entry = resolveName(table, tags[i] as NamedTag);
    if (entry instanceof PlcError) {
      unresolved.push({ i, error: entry });
      continue;
    }
    const from = leaves.length;
    leaves.push(...leavesOf(table, entry));
    wanted.push({ i, entry, from, to: leaves.length });
  }
  const items = leaves.map((leaf) => itemIn(table, leaf));
  const plan: NamedPlan = {
    table,
    distrusted: DISTRUSTED.get(table)?.size ?? 0,
    unchecked: items.some((a) => a.symbolCrc === 0),
    wanted,
    unresolved,
    leaves,
    indexes: leaves.map((_, k) => k),
    items,
    shapes: leaves.map(shapeOf),
  };
  PLANS.set(tags, plan);
  return plan;
}

/** What a read by name saw: the leaves the PLC refused (each its error), those of them for their SymbolCrc. */
interface NamedRead {
  readonly refused: readonly string[];
  readonly crcRefused: readonly string[];
  readonly unchecked: boolean;
}

/** Reads the named tags `named` through table `t` into `values` / `errors` (each slot overwritten). */
async function readNamed(
  session: S7PlusSession,
  tags: readonly Tag[],
  named: readonly number[],
  t: SymbolTable,
  limits: Limits,
  values: PlcValue[],
  errors: (PlcError | undefined)[],
  signal?: AbortSignal,
): Promise<NamedRead> {
  for (const i of named) {
    values[i] = undefined as unknown as PlcValue;
    errors[i] = undefined;
  }
  const refused: string[] = [];
  const crcRefused: string[] = [];
  const plan = planOf(tags, named, t);
  const { leaves } = plan;
  for (const { i, error } of plan.unresolved) errors[i] = error;
  // Each leaf's value, or its error, by its index in plan.leaves.
  const leafValues = new Array<PlcValue>(leaves.length);
  let failed: (PlcError | undefined)[] | undefined;
  const send = (chunk: number[]) => session.request(readAsk(chunk.map((k) => plan.items[k]!)), { signal });
  const bytes = (k: number) => addressBytes(plan.items[k]!);
  await inChunks(
    plan.indexes,
    limits,
    send,
    (chunk, body) => {
      if (refusedWhole(body) && chunk.length > 1) return 'again';
      chunk.forEach((k, n) => {
        const e = leaves[k]!;
        const fail = (err: PlcError) => ((failed ??= new Array<PlcError | undefined>(leaves.length))[k] = err);
        const answer = itemAnswer(body, n + 1);
        if (answer === undefined) return void fail(notAnswered(e.name));
        if ('code' in answer) {
          // A refused item is never a value: its name is read again once the program is known (InvalidCRC: changed).
          refused.push(e.name);
          if (!isInvalidCrc(answer.code))
            return void fail(itemRefusal(answer.code, { tag: e.name, name: e.name, request: answer.request }));
          crcRefused.push(e.name);
          const why = `${e.name}: the PLC refused its symbol CRC (0x${answer.code.toString(16)}, InvalidCRC): the PLC's program changed`;
          return void fail(new PlcError('OBJECT_DOES_NOT_EXIST', why, { tag: e.name, plcCode: Number(answer.code & 0xffffn) }));
        }
        const untrusted = untrustedValue(answer, e.name);
        if (untrusted) return void fail(untrusted);
        try {
          leafValues[k] = valueOf(e, answer, plan.shapes[k]);
        } catch (err) {
          fail(toPlcError(err, 'PROTOCOL_ERROR'));
        }
      });
    },
    bytes,
  );
  for (const { i, entry, from, to } of plan.wanted) {
    let bad: PlcError | undefined;
    if (failed) for (let k = from; !bad && k < to; k++) bad = failed[k];
    if (bad) errors[i] = bad;
    else if (entry.kind === 'elementary') values[i] = leafValues[from]!;
    else {
      const leaf = new Map<string, PlcValue>();
      for (let k = from; k < to; k++) leaf.set(leaves[k]!.name, leafValues[k]!);
      values[i] = assemble(t, entry, leaf) as PlcValue;
    }
  }
  return { refused, crcRefused, unchecked: plan.unchecked };
}
