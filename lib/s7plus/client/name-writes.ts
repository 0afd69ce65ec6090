/**
 * Writes by name over S7CommPlus (names.ts resolves the names): each
 * elementary member with its LIDs and its path's SymbolCrc in
 * SetMultiVariables, a struct or array as its elementary members. The PLC
 * refuses a member whose CRC is stale (InvalidCRC, nothing of it written):
 * the table is browsed again and the refused names written again through
 * it, so a write never lands in the member a download gave its LID to.
 * Layouts: s7commplus (MIT), client.py (write_tags by access sequence).
 */
import { PlcError, toPlcError, type TagResult } from '../../errors';
import type { SymbolEntry, SymbolTable } from '../../symbols/model';
import type { Tag } from '../../types';
import type { PValue } from '../codec/pvalue';
import { isInvalidCrc } from '../codec/symbol-crc';
import type { ItemAddress } from '../codec/variables';
import type { Limits } from './chunks';
import { writeInChunks, writeTags } from './io';
import { explainOptimized } from './optimized';
import { itemAnswer, itemRefusal, refusedWhole } from './refusals';
import { pvalueOf, writeLeaves } from './name-values';
import { distrusted, isAddress, isNamed, itemIn, knows, MAX_ATTEMPTS, resolveName, type NamedTag, type Program } from './names';
import type { S7PlusSession } from './session';

/** A write's results as explainOptimized() sees them: each item's error, and its replacement. */
const resultSlots = (results: TagResult<void>[]) => ({
  errorAt: (i: number) => {
    const r = results[i]!;
    return r.ok ? undefined : r.error;
  },
  replace: (i: number, error: PlcError) => (results[i] = { ok: false, error }),
});

/** One leaf of a write by name: the item's index, its address (with its SymbolCrc), its value, its name. */
interface WriteLeaf {
  readonly i: number;
  readonly address: ItemAddress;
  readonly value: PValue;
  readonly name: string;
}

/** The leaves of the named items `todo` through table `t`; an item that cannot be written gets its error in `results`. */
function writeLeavesOf(
  t: SymbolTable,
  items: readonly { tag: Tag; value: unknown }[],
  todo: readonly number[],
  results: TagResult<void>[],
): WriteLeaf[] {
  const ready: WriteLeaf[] = [];
  for (const i of todo) {
    const { tag, value } = items[i]!;
    const entry = resolveName(t, tag as NamedTag);
    if (entry instanceof PlcError) {
      results[i] = { ok: false, error: entry };
      continue;
    }
    try {
      const leaves: { entry: SymbolEntry; value: unknown }[] = [];
      writeLeaves(t, entry, value, leaves);
      ready.push(...leaves.map((l) => ({ i, address: itemIn(t, l.entry), value: pvalueOf(l.entry, l.value), name: l.entry.name })));
    } catch (err) {
      results[i] = { ok: false, error: toPlcError(err, 'INVALID_VALUE') };
    }
  }
  return ready;
}

/** One result per item, in order: addresses by io.ts, names by LID. */
export async function writeMixed(
  session: S7PlusSession,
  items: readonly { tag: Tag; value: unknown }[],
  limits: Limits,
  program: Program,
  signal?: AbortSignal,
): Promise<TagResult<void>[]> {
  const tags = items.map((it) => it.tag);
  const explain = (results: TagResult<void>[]) => explainOptimized(tags, resultSlots(results), () => program.table(), isAddress);
  if (!items.some((it) => isNamed(it.tag))) {
    const r = await writeTags(session, items, limits, signal);
    await explain(r);
    return r;
  }
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
    await explain(results);
  }
  // A write by a stale LID would land in another member: each leaf goes with its SymbolCrc, which the PLC checks (a
  // refused leaf writes nothing); a name without one, or one the table lacks, has the program checked first. Names
  // refused for their CRC are written again through the table browsed again.
  let todo = items.flatMap((it, i) => (isNamed(it.tag) ? [i] : []));
  for (let attempt = 1; todo.length > 0; attempt++) {
    const t = await program.table();
    const unknown = todo.some((i) => !knows(t, items[i]!.tag.address));
    const ready = writeLeavesOf(t, items, todo, results);
    if ((unknown || ready.some((c) => c.address.symbolCrc === 0)) && (await program.changed(unknown)) && attempt < MAX_ATTEMPTS) continue;
    const stale = new Map<number, bigint>();
    await writeInChunks(session, ready, limits, signal, (chunk, body) => {
      if (refusedWhole(body) && chunk.length > 1) return 'again';
      chunk.forEach((c, k) => {
        const answer = itemAnswer(body, k + 1);
        if (!answer || !('code' in answer) || !results[c.i]!.ok) return;
        if (isInvalidCrc(answer.code) && attempt < MAX_ATTEMPTS) return void (stale.has(c.i) || stale.set(c.i, answer.code));
        const error = itemRefusal(answer.code, { tag: items[c.i]!.tag.address, name: c.name, write: true, request: answer.request });
        results[c.i] = { ok: false, error };
      });
    });
    if (stale.size === 0) break;
    // Refused for its CRC though the program is the one browsed: that path's CRC is not the PLC's; it goes with 0.
    if (!(await program.changed())) for (const c of ready) if (stale.has(c.i) && c.address.symbolCrc !== 0) distrusted(t).add(c.name);
    todo = [...stale.keys()];
  }
  return results;
}
