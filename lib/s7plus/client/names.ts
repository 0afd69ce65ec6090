/**
 * Reads and writes by name over S7CommPlus. A name that is not an address
 * parses to a "named tag" (plusSyntax); at a read or write it resolves
 * through the PLC's browsed table to its access path (area and LIDs) and
 * goes with GetMultiVariables / SetMultiVariables by LID: elementary members
 * item by item, a struct or array as its elementary members, put back
 * together as an object or an array. A name the PLC does not have fails
 * with INVALID_ADDRESS naming it and the closest names, never with another
 * member's value. Addresses go on to the by-address path (io.ts).
 * Layouts: s7commplus (MIT), client.py (read_tags / write_tags by access
 * sequence: area, DBValueActual, LIDs).
 */
import { S7_TAG_SYNTAX } from '../../address';
import { PlcError, toPlcError, type TagResult } from '../../errors';
import type { ReadValues, TagSyntax } from '../../link/driver';
import { canonicalName, splitSymbol } from '../../symbols/names';
import type { SymbolEntry, SymbolTable } from '../../symbols/model';
import type { PlcValue, Tag } from '../../types';
import { decodeTag, encodeTag, type TagShape } from '../../values';
import type { PValue } from '../codec/pvalue';
import {
  blobValue,
  decodeGetMultiVariablesResponse,
  decodeSetMultiVariablesResponse,
  encodeGetMultiVariablesRequest,
  encodeSetMultiVariablesRequest,
  readRequest,
  writeRequest,
  type ItemAddress,
} from '../codec/variables';
import { DataType, FunctionCode, Ids } from '../constants';
import { readTags, sized, writeTags, type Limits } from './io';
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

function unknownName(table: SymbolTable, name: string): PlcError {
  const near = table.suggest(name);
  const hint = near.length > 0 ? `; did you mean ${near.join(', ')}?` : '; the PLC has no such name';
  return new PlcError('INVALID_ADDRESS', `unknown name ${name} on the PLC${hint}`, { tag: name });
}

/** Leaves per struct or array entry, worked out once per browsed table (a poll reads the same names again and again). */
const LEAVES = new WeakMap<SymbolEntry, readonly SymbolEntry[]>();

/** The elementary entries of an entry (itself when elementary), in order. */
export function leavesOf(table: SymbolTable, entry: SymbolEntry): readonly SymbolEntry[] {
  if (entry.kind === 'elementary') return [entry];
  let leaves = LEAVES.get(entry);
  if (!leaves) {
    leaves = (entry.children ?? []).flatMap((c) => {
      const child = table.lookup(c);
      return child ? leavesOf(table, child) : [];
    });
    LEAVES.set(entry, leaves);
  }
  return leaves;
}

export function itemOf(entry: SymbolEntry): ItemAddress {
  return { symbolCrc: 0, accessArea: entry.access!.area, accessSubArea: Ids.DBValueActual, lids: [...entry.access!.lids] };
}

function shapeOf(entry: SymbolEntry): TagShape {
  return { address: entry.name, type: entry.dataType!, count: 1, isArray: false, stringLength: entry.stringLength, bitOffset: 0 };
}

const WIDTH: Readonly<Record<number, [number, 'u' | 's' | 'f']>> = Object.freeze({
  [DataType.USInt]: [1, 'u'],
  [DataType.Byte]: [1, 'u'],
  [DataType.SInt]: [1, 's'],
  [DataType.UInt]: [2, 'u'],
  [DataType.Word]: [2, 'u'],
  [DataType.Int]: [2, 's'],
  [DataType.UDInt]: [4, 'u'],
  [DataType.DWord]: [4, 'u'],
  [DataType.DInt]: [4, 's'],
  [DataType.Real]: [4, 'f'],
  [DataType.LReal]: [8, 'f'],
  [DataType.ULInt]: [8, 'u'],
  [DataType.LWord]: [8, 'u'],
  [DataType.LInt]: [8, 's'],
});

/** A leaf's value from the PValue the PLC answered: a BLOB as the member's standard bytes, a typed value by its wire type. */
export function valueOf(entry: SymbolEntry, v: PValue): PlcValue {
  const x = v.value;
  if (v.type === DataType.Bool && typeof x === 'boolean') return x;
  if ((v.type === DataType.WString || v.type === DataType.S7String) && typeof x === 'string') return x;
  let bytes: Buffer | undefined;
  if (x && typeof x === 'object' && 'data' in x && Buffer.isBuffer(x.data)) bytes = x.data;
  const width = WIDTH[v.type];
  if (!bytes && width && (typeof x === 'number' || typeof x === 'bigint')) {
    const [n, kind] = width;
    bytes = Buffer.alloc(n);
    if (kind === 'f') n === 4 ? bytes.writeFloatBE(Number(x)) : bytes.writeDoubleBE(Number(x));
    else if (n === 8) kind === 's' ? bytes.writeBigInt64BE(BigInt(x)) : bytes.writeBigUInt64BE(BigInt.asUintN(64, BigInt(x)));
    else kind === 's' ? bytes.writeIntBE(Number(x), 0, n) : bytes.writeUIntBE(Number(x), 0, n);
  }
  if (!bytes)
    throw new PlcError('PROTOCOL_ERROR', `${entry.name}: the PLC answered a value of wire type 0x${v.type.toString(16)}`, {
      tag: entry.name,
    });
  // A typed value narrower than the member (a BYTE sent as USInt for a CHAR) is its low bytes.
  const want = entry.size;
  if (bytes.length < want && !entry.dataType?.includes('STRING')) bytes = Buffer.concat([Buffer.alloc(want - bytes.length), bytes]);
  return decodeTag(shapeOf(entry), bytes, 0);
}

/** A struct's or array's value from its leaves' values (by name). */
export function assemble(table: SymbolTable, entry: SymbolEntry, leaf: Map<string, PlcValue>): unknown {
  if (entry.kind === 'elementary') return leaf.get(entry.name);
  const children = (entry.children ?? []).map((c) => table.lookup(c)).filter((c): c is SymbolEntry => c !== undefined);
  if (entry.kind === 'array') return children.map((c) => assemble(table, c, leaf));
  return Object.fromEntries(children.map((c) => [memberKey(entry, c), assemble(table, c, leaf)]));
}

/** A member's key in its struct's object: its name as declared (quotes off). */
function memberKey(parent: SymbolEntry, child: SymbolEntry): string {
  const rest = child.name.slice(parent.name.length + 1);
  return rest.startsWith('"') && rest.endsWith('"') ? rest.slice(1, -1) : rest;
}

/** What a named tag stands for: the entry, or why not. */
export function resolveName(table: SymbolTable, tag: NamedTag): SymbolEntry | PlcError {
  const entry = table.lookup(tag.address);
  if (!entry) return unknownName(table, tag.address);
  if (!entry.access || entry.access.lids.length === 0)
    return new PlcError('NOT_SUPPORTED', `${tag.address}: the PLC's browse gives no access path for it`, { tag: tag.address });
  return entry;
}

/** Sends `count` items in requests of at most the item limit (io.ts `sized`: a reset on a large request lowers it). */
async function requestChunks(
  session: S7PlusSession,
  count: number,
  limits: Limits,
  send: (from: number, to: number) => Promise<Buffer>,
  take: (from: number, to: number, answer: Buffer) => void,
): Promise<void> {
  for (let at = 0; at < count;) {
    const to = Math.min(count, at + limits.maxItems());
    take(at, to, await sized(session, to - at, limits, () => send(at, to)));
    at = to;
  }
}

/** Values of addresses and names, in order; each tag's own failure is its error. */
export async function readMixed(
  session: S7PlusSession,
  tags: readonly Tag[],
  limits: Limits,
  table: () => Promise<SymbolTable>,
  signal?: AbortSignal,
): Promise<ReadValues> {
  const named = tags.flatMap((t, i) => (isNamed(t) ? [i] : []));
  if (named.length === 0) return readTags(session, tags, limits, signal);
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
  }
  const t = await table();
  const leaves: SymbolEntry[] = [];
  const wanted: { i: number; entry: SymbolEntry }[] = [];
  for (const i of named) {
    const entry = resolveName(t, tags[i] as NamedTag);
    if (entry instanceof PlcError) errors[i] = entry;
    else {
      wanted.push({ i, entry });
      leaves.push(...leavesOf(t, entry));
    }
  }
  const leaf = new Map<string, PlcValue>();
  const failed = new Map<string, PlcError>();
  const send = (from: number, to: number) =>
    session.request(
      FunctionCode.GetMultiVariables,
      (sequence, sessionId, integrityId) =>
        encodeGetMultiVariablesRequest({
          ...readRequest(sequence, sessionId, leaves.slice(from, to).map(itemOf)),
          ...(integrityId === undefined ? {} : { integrityId }),
        }),
      { signal },
    );
  await requestChunks(session, leaves.length, limits, send, (from, to, answer) => {
    const chunk = leaves.slice(from, to);
    const { body } = decodeGetMultiVariablesResponse(answer, { integrity: session.integrityOn });
    chunk.forEach((e, k) => {
      const v = body.values.get(k + 1);
      if (!v) {
        const code = body.errors.get(k + 1) ?? body.returnValue;
        failed.set(
          e.name,
          new PlcError('OBJECT_DOES_NOT_EXIST', `${e.name}: the PLC refused it (0x${code.toString(16)}); was its program changed?`, {
            tag: e.name,
          }),
        );
        return;
      }
      try {
        leaf.set(e.name, valueOf(e, v));
      } catch (err) {
        failed.set(e.name, toPlcError(err, 'PROTOCOL_ERROR'));
      }
    });
  });
  for (const { i, entry } of wanted) {
    const bad = leavesOf(t, entry).find((e) => failed.has(e.name));
    if (bad) errors[i] = failed.get(bad.name);
    else values[i] = assemble(t, entry, leaf) as PlcValue;
  }
  return { values, errors: errors.some((e) => e) ? errors : undefined };
}

/** The leaves of a write: each elementary member with its value (a struct's from the object's members, an array's by index). */
function writeLeaves(table: SymbolTable, entry: SymbolEntry, value: unknown, out: { entry: SymbolEntry; value: unknown }[]): void {
  if (entry.kind === 'elementary') return void out.push({ entry, value });
  const children = (entry.children ?? []).map((c) => table.lookup(c)).filter((c): c is SymbolEntry => c !== undefined);
  if (entry.kind === 'array') {
    if (!Array.isArray(value) || value.length !== children.length)
      throw new PlcError('INVALID_VALUE', `${entry.name} is ${entry.type}: write an array of ${children.length} values`, {
        tag: entry.name,
      });
    children.forEach((c, k) => writeLeaves(table, c, value[k], out));
    return;
  }
  if (value === null || typeof value !== 'object' || Array.isArray(value))
    throw new PlcError('INVALID_VALUE', `${entry.name} is a ${entry.type}: write an object of its members`, { tag: entry.name });
  for (const c of children) {
    const k = memberKey(entry, c);
    if (!(k in value)) throw new PlcError('INVALID_VALUE', `${entry.name}: the value has no member ${k}`, { tag: entry.name });
    writeLeaves(table, c, (value as Record<string, unknown>)[k], out);
  }
}

function pvalueOf(entry: SymbolEntry, value: unknown): PValue {
  if (entry.dataType === 'BOOL') {
    if (typeof value !== 'boolean')
      throw new PlcError('INVALID_VALUE', `${entry.name} is a BOOL: write true or false`, { tag: entry.name });
    return { flags: 0, type: DataType.Bool, value };
  }
  return blobValue(encodeTag(shapeOf(entry), value));
}

/** One result per item, in order: addresses by io.ts, names by LID. */
export async function writeMixed(
  session: S7PlusSession,
  items: readonly { tag: Tag; value: unknown }[],
  limits: Limits,
  table: () => Promise<SymbolTable>,
  signal?: AbortSignal,
): Promise<TagResult<void>[]> {
  if (!items.some((it) => isNamed(it.tag))) return writeTags(session, items, limits, signal);
  const results: TagResult<void>[] = items.map(() => ({ ok: true, value: undefined }));
  const addressed = items.flatMap((it, i) => (isNamed(it.tag) ? [] : [i]));
  if (addressed.length > 0) {
    const r = await writeTags(
      session,
      addressed.map((i) => items[i]!),
      limits,
      signal,
    );
    addressed.forEach((i, k) => (results[i] = r[k]!));
  }
  const t = await table();
  const ready: { i: number; address: ItemAddress; value: PValue; name: string }[] = [];
  items.forEach(({ tag, value }, i) => {
    if (!isNamed(tag)) return;
    const entry = resolveName(t, tag);
    if (entry instanceof PlcError) return void (results[i] = { ok: false, error: entry });
    try {
      const leaves: { entry: SymbolEntry; value: unknown }[] = [];
      writeLeaves(t, entry, value, leaves);
      const mine = leaves.map((l) => ({ i, address: itemOf(l.entry), value: pvalueOf(l.entry, l.value), name: l.entry.name }));
      ready.push(...mine);
    } catch (err) {
      results[i] = { ok: false, error: toPlcError(err, 'INVALID_VALUE') };
    }
  });
  const send = (from: number, to: number) =>
    session.request(
      FunctionCode.SetMultiVariables,
      (sequence, sessionId, integrityId) =>
        encodeSetMultiVariablesRequest({
          ...writeRequest(
            sequence,
            sessionId,
            ready.slice(from, to).map((c) => c.address),
            ready.slice(from, to).map((c) => c.value),
          ),
          ...(integrityId === undefined ? {} : { integrityId }),
        }),
      { signal },
    );
  await requestChunks(session, ready.length, limits, send, (from, to, answer) => {
    const chunk = ready.slice(from, to);
    const { body } = decodeSetMultiVariablesResponse(answer, { integrity: session.integrityOn });
    chunk.forEach((c, k) => {
      const code = body.errors.get(k + 1) ?? (body.returnValue !== 0n ? body.returnValue : undefined);
      if (code !== undefined && results[c.i]!.ok)
        results[c.i] = {
          ok: false,
          error: new PlcError('PLC_ERROR', `${c.name}: the PLC refused the write (0x${code.toString(16)})`, {
            tag: items[c.i]!.tag.address,
          }),
        };
    });
  });
  return results;
}
