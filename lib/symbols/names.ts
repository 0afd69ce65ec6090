/**
 * Names of symbols as users type them, and the index that finds an entry by
 * one. The rules (those of TIA Portal's SCL editor, relaxed where no harm is
 * done):
 *
 * - A name is parts separated by dots: the block (or I/Q/M symbol) first,
 *   then its members: `"Tank".Motor.Speed`.
 * - A part is a plain identifier (letters, umlauts included, digits, `_`; not
 *   starting with a digit) or anything but a double quote between double
 *   quotes. Quotes are optional on plain identifiers and required on names
 *   with spaces, dots or other characters: `"Motor 1"."Speed.Set"`.
 * - A part may carry one index group, `Step[3]`, `A[1,2]`, `T[-2]`; spaces
 *   inside the brackets do not count (`Step[ 3 ]`, `A[1, 2]`).
 * - Case does not count, as in TIA (which refuses two names in one scope that
 *   differ only by case): `"TANK".motor` finds `"Tank".Motor`. The folding is
 *   Unicode's (locale-independent): `FÜLLSTAND` finds `Füllstand`, a composed
 *   `ü` finds a decomposed one.
 * - A STEP 7 data block without a symbolic name is `DB10`: `DB10.Member` and
 *   `"DB10".Member` are the same name.
 * - `%` starts an absolute address (`%MW10`), never a symbol.
 *
 * A malformed name (unterminated quote, empty part, bad index) is simply not
 * found; describeNameProblem() says what is wrong with it for messages.
 */
import { PlcError, SourceError } from '../errors';
import type { SymbolEntry } from './model';
import { distance } from './distance';

/** One part of a name: `Step[3]` is `{ name: 'Step', index: [3] }`. */
export interface SymbolPart {
  /** Unquoted, as written. */
  readonly name: string;
  /** The index group, when the part has one. */
  readonly index?: readonly number[];
}

/** Longer text is not a name (and is not scanned for suggestions). */
const MAX_NAME_LENGTH = 1024;
/** A part that needs no quotes. */
const IDENTIFIER = /^[\p{L}_][\p{L}\p{M}\p{N}_]*$/u;
/** Between the parts of a key: a character no name can hold (control characters are refused). */
const PART_SEPARATOR = '\u0001';

interface Parsed {
  parts: SymbolPart[];
  problem?: undefined;
}
interface Malformed {
  parts?: undefined;
  problem: string;
}

/**
 * Reads a name into its parts. Strict: the problem of a malformed name is
 * returned, never thrown. Lenient (for suggestions): quotes may be missing or
 * unterminated, spaces stand anywhere, empty parts are dropped; only what
 * cannot be read at all is a problem.
 */
function parse(text: string, lenient: boolean): Parsed | Malformed {
  const name = text.trim();
  if (name === '') return { problem: 'empty name' };
  if (name.length > MAX_NAME_LENGTH) return { problem: `longer than ${MAX_NAME_LENGTH} characters` };
  if (name.startsWith('%')) return { problem: `"%" starts an absolute address (e.g. %MW10), not a symbol name` };
  // eslint-disable-next-line no-control-regex
  const control = /[\u0000-\u001f\u007f]/.exec(name);
  if (control) return { problem: `unexpected control character ${JSON.stringify(control[0])}` };

  const parts: SymbolPart[] = [];
  let i = 0;
  for (;;) {
    // One part: a quoted name or a run up to the next dot or bracket.
    let partName: string;
    const start = i;
    if (name[i] === '"') {
      const close = name.indexOf('"', i + 1);
      if (close < 0) {
        if (!lenient) return { problem: `unterminated quote at column ${i + 1}` };
        // Read on as if the stray quote were not there.
        i += 1;
        continue;
      } else {
        partName = name.slice(i + 1, close);
        i = close + 1;
        if (!lenient && partName === '') return { problem: `empty quoted name at column ${start + 1}` };
      }
    } else {
      const m = (lenient ? /^[^.[\]"]*/ : /^[^.[\]"\s]*/).exec(name.slice(i))![0];
      partName = lenient ? m.trim() : m;
      i += m.length;
      if (!lenient) {
        if (partName === '') {
          if (name[i] === undefined || name[i] === '.' || name[i] === '[')
            return { problem: start === 0 ? 'a name cannot start with a dot or a bracket' : `empty part at column ${start + 1}` };
        } else if (!IDENTIFIER.test(partName)) {
          const rest = /^[^.[\]"]*/.exec(name.slice(start))![0].trimEnd();
          return { problem: `${JSON.stringify(rest)} needs quotes (it is not a plain identifier): write "${rest}"` };
        }
        if (/\s/.test(name[i] ?? '')) {
          const rest = /^[^.[\]"]*/.exec(name.slice(start))![0].trimEnd();
          return { problem: `${JSON.stringify(rest)} has a space: write it in quotes, "${rest}"` };
        }
      }
    }
    let index: number[] | undefined;
    if (name[i] === '[') {
      const close = name.indexOf(']', i);
      const inner = close < 0 ? name.slice(i + 1) : name.slice(i + 1, close);
      if (close < 0 && !lenient) return { problem: `unclosed "[" at column ${i + 1}` };
      const items = inner.split(',').map((s) => s.trim());
      if (items.every((s) => /^[+-]?\d{1,10}$/.test(s))) index = items.map(Number);
      else if (!lenient) return { problem: `bad index "[${inner}]": expected integers separated by commas, e.g. [3] or [1,2]` };
      i = close < 0 ? name.length : close + 1;
    }
    if (partName !== '' || index) parts.push(index ? { name: partName, index } : { name: partName });
    if (i >= name.length) break;
    if (name[i] === '.') {
      i += 1;
      if (!lenient && i >= name.length) return { problem: 'a name cannot end with a dot' };
      continue;
    }
    if (lenient) {
      // Stray text after a quote or a bracket: read on as a new part.
      if (name[i] === ']') i += 1;
      continue;
    }
    return {
      problem:
        name[i] === '['
          ? `a second index group at column ${i + 1}: write all indices in one, e.g. [1,2]`
          : `unexpected ${JSON.stringify(name[i])} at column ${i + 1}: expected ".", "[" or the end`,
    };
  }
  if (parts.length === 0) return { problem: 'empty name' };
  return { parts };
}

/**
 * The parts of a name as users type it, or undefined when it is malformed
 * (describeNameProblem() says why).
 */
export function splitSymbol(name: string): SymbolPart[] | undefined {
  return parse(name, false).parts;
}

/** What is malformed in a name, for messages; undefined when the name is well formed (found or not). */
export function describeNameProblem(name: string): string | undefined {
  return parse(name, false).problem;
}

/**
 * A name written as TIA writes it: quotes around the block name always,
 * around members only when they need them, the index group after its part:
 * `"Tank".Motor`, `"Motor 1"."Speed.Set"`, `"Recipe".Step[3].Temp`, `A[1,2]`.
 */
export function canonicalName(parts: readonly SymbolPart[]): string {
  return parts
    .map((p, i) => {
      const name = i === 0 || !IDENTIFIER.test(p.name) ? `"${p.name}"` : p.name;
      return p.index ? `${name}[${p.index.join(',')}]` : name;
    })
    .join('.');
}

/** Case folding without locale: NFC, lower case, and the one letter whose lower case depends on its place (final sigma). */
function fold(text: string): string {
  // eslint-disable-next-line no-control-regex
  if (/^[\x00-\x7f]*$/.test(text)) return text.toLowerCase();
  return text.normalize('NFC').toLowerCase().replace(/ς/g, 'σ');
}

/** Each part's key: its folded name and its index. */
function partKeys(parts: readonly SymbolPart[]): string[] {
  return parts.map((p) => (p.index ? `${fold(p.name)}[${p.index.join(',')}]` : fold(p.name)));
}

function keyOf(parts: readonly SymbolPart[]): string {
  return partKeys(parts).join(PART_SEPARATOR);
}

/** Suggestions further than this many edits away from a text of this length are not worth showing. */
function maxDistance(length: number): number {
  return Math.max(1, Math.min(4, Math.floor(length / 3)));
}

/**
 * Whether `candidate`, `edits` away from `typed`, is close enough: the edits
 * are measured against the parts that differ, not the whole name (two edits
 * make `Run` of `Sped`, however long the block's name).
 */
function closeEnough(typed: string, candidate: string, edits: number): boolean {
  if (edits === 0) return true;
  const shorter = Math.min(typed.length, candidate.length);
  let pre = 0;
  while (pre < shorter && typed[pre] === candidate[pre]) pre++;
  pre = typed.lastIndexOf(PART_SEPARATOR, pre - 1) + 1;
  let suf = 0;
  while (suf < shorter - pre && typed[typed.length - 1 - suf] === candidate[candidate.length - 1 - suf]) suf++;
  const next = suf === 0 ? -1 : typed.indexOf(PART_SEPARATOR, typed.length - suf);
  suf = next < 0 ? 0 : typed.length - next;
  return edits <= maxDistance(Math.max(typed.length, candidate.length) - pre - suf);
}

interface Candidate {
  entry: number;
  distance: number;
  /** 0: a sibling of the name (same parent), 1: elsewhere in the same block, 2: another block. */
  tier: number;
}

/**
 * The entries of a compiled table by name: lookup() is one Map access after
 * reading the name; suggest() proposes the closest existing names, looking
 * in the name's own block first.
 *
 * Two entries whose names differ only by case (or by quotes, or by spaces in
 * an index) would make lookup() depend on spelling: TIA refuses such names in
 * one scope, and so does the constructor (a SourceError at the second one).
 */
export class NameIndex {
  private readonly entries: readonly SymbolEntry[];
  private readonly byKey = new Map<string, number>();
  /** Entry indices by the key of their first part (block or I/Q/M symbol). */
  private readonly byBlock = new Map<string, number[]>();
  /** Entry indices by the key of all parts but the last. */
  private readonly byParent = new Map<string, number[]>();
  /** Each entry's key, for suggestions. */
  private readonly keys: string[] = [];
  /** Each entry's first part's key. */
  private readonly blockKeys: string[] = [];

  constructor(entries: readonly SymbolEntry[]) {
    this.entries = entries;
    entries.forEach((entry, i) => {
      const parsed = parse(entry.name, false);
      if (!parsed.parts) {
        const problem = `symbol name ${JSON.stringify(entry.name)} is malformed: ${parsed.problem}`;
        throw entry.at ? new SourceError(entry.at, problem) : new PlcError('INVALID_SOURCE', problem, { tag: entry.name });
      }
      const keys = partKeys(parsed.parts);
      const key = keys.join(PART_SEPARATOR);
      const earlier = this.byKey.get(key);
      if (earlier !== undefined) {
        const other = entries[earlier]!;
        const where = other.at ? ` (${other.at.file}:${other.at.line}:${other.at.column})` : '';
        const problem =
          other.name === entry.name
            ? `${entry.name} is declared twice${where}`
            : `${entry.name} and ${other.name}${where} differ only by case or spelling; names are matched regardless of case, as in TIA`;
        throw entry.at ? new SourceError(entry.at, problem) : new PlcError('INVALID_SOURCE', problem, { tag: entry.name });
      }
      this.byKey.set(key, i);
      this.keys.push(key);
      const blockKey = keys[0]!;
      this.blockKeys.push(blockKey);
      push(this.byBlock, blockKey, i);
      push(this.byParent, key.slice(0, key.length - keys[keys.length - 1]!.length), i);
    });
  }

  /** The entry a name stands for, or undefined (also for a malformed name). */
  lookup(name: string): SymbolEntry | undefined {
    if (typeof name !== 'string') return undefined;
    const parsed = parse(name, false);
    if (!parsed.parts) return undefined;
    const i = this.byKey.get(keyOf(parsed.parts));
    return i === undefined ? undefined : this.entries[i];
  }

  /**
   * Up to `max` existing names closest to `name`: those the fewest edits
   * away (swapped neighbours count as one), a sibling of the name before the
   * rest of its block, then in table order. Only the name's
   * own block is searched (or, when no block has its first part, the blocks
   * closest to it), so the work stays bounded by one block's size. The name
   * may be malformed: `Tank.Motor 1.Run` suggests `"Tank"."Motor 1".Run`.
   */
  suggest(name: string, max = 3): string[] {
    if (typeof name !== 'string' || max <= 0) return [];
    const parsed = parse(name, true);
    if (!parsed.parts) return [];
    const keys = partKeys(parsed.parts);
    const key = keys.join(PART_SEPARATOR);
    const blockKey = keys[0]!;
    const parentKey = key.slice(0, key.length - keys[keys.length - 1]!.length);
    let limit = maxDistance(key.length);
    const found: Candidate[] = [];

    const scan = (indices: readonly number[], tierOf: (i: number) => number, typed: string, keyAt: (i: number) => string) => {
      for (const i of indices) {
        const d = distance(typed, keyAt(i), limit);
        if (d <= limit) found.push({ entry: i, distance: d, tier: tierOf(i) });
      }
    };

    const block = this.byBlock.get(blockKey);
    if (block) {
      // Siblings first: when one is close, the rest of the block need only be searched for closer names.
      const siblings = this.byParent.get(parentKey) ?? [];
      scan(
        siblings,
        () => 0,
        key,
        (i) => this.keys[i]!,
      );
      const sibling = found.filter((c) => closeEnough(key, this.keys[c.entry]!, c.distance));
      if (sibling.length > 0) limit = fewest(sibling) - 1;
      const isSibling = new Set(siblings);
      if (limit >= 0)
        scan(
          block.filter((i) => !isSibling.has(i)),
          () => 1,
          key,
          (i) => this.keys[i]!,
        );
    } else {
      // The block itself is misspelt: find the closest blocks, then the rest of the name in them.
      const blockLimit = maxDistance(blockKey.length);
      const near: { key: string; distance: number }[] = [];
      for (const other of this.byBlock.keys()) {
        const d = distance(blockKey, other, blockLimit);
        if (d <= blockLimit) near.push({ key: other, distance: d });
      }
      near.sort((a, b) => a.distance - b.distance);
      const rest = key.slice(blockKey.length);
      for (const b of near.slice(0, max)) {
        scan(
          this.byBlock.get(b.key)!,
          () => 2,
          rest,
          (i) => this.keys[i]!.slice(this.blockKeys[i]!.length),
        );
        for (const c of found) if (this.blockKeys[c.entry] === b.key && c.tier === 2) c.distance += b.distance;
      }
    }
    const close = found.filter((c) => closeEnough(key, this.keys[c.entry]!, c.distance));
    // The closest only: one edit away, a name two edits away is noise.
    const best = fewest(close);
    return close
      .filter((c) => c.distance === best)
      .sort((a, b) => a.tier - b.tier || a.entry - b.entry)
      .slice(0, max)
      .map((c) => this.entries[c.entry]!.name);
  }
}

/** The smallest distance of the candidates (no spread: a block can have 100,000 of them). */
function fewest(candidates: readonly Candidate[]): number {
  let best = Infinity;
  for (const c of candidates) if (c.distance < best) best = c.distance;
  return best;
}

function push(map: Map<string, number[]>, key: string, value: number): void {
  const list = map.get(key);
  if (list) list.push(value);
  else map.set(key, [value]);
}
