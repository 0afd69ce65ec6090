/**
 * The layout's invariants over random declarations (a seeded PRNG, so a
 * failure repeats): elementary members never overlap, everything lies inside
 * the block, 16-bit types and up, strings, structs and arrays start on even
 * bytes, a struct's or array's members lie inside it, and every address reads
 * back to the entry's location and type.
 */
import { expect } from 'chai';
import { parseAddress } from '../lib/address';
import type { DataTypeName } from '../lib/types';
import { compileDeclarations } from '../lib/symbols/compile';
import type { BlockDecl, MemberDecl, SymbolEntry, TypeRef } from '../lib/symbols/model';
import { arr, db, el, m, named, struct, udt } from './fixtures/symbols/golden/build';

function prng(seed: number): () => number {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

const TYPES: readonly DataTypeName[] = [
  'BOOL',
  'BOOL',
  'BOOL',
  'BYTE',
  'CHAR',
  'SINT',
  'USINT',
  'WORD',
  'INT',
  'UINT',
  'WCHAR',
  'S5TIME',
  'DATE',
  'DWORD',
  'DINT',
  'UDINT',
  'REAL',
  'TIME',
  'TIME_OF_DAY',
  'LWORD',
  'LINT',
  'ULINT',
  'LREAL',
  'LTIME',
  'DATE_AND_TIME',
  'DTL',
  'STRING',
  'WSTRING',
];

class Generator {
  constructor(private readonly random: () => number) {}

  int(lo: number, hi: number): number {
    return lo + Math.floor(this.random() * (hi - lo + 1));
  }

  pick<T>(items: readonly T[]): T {
    return items[this.int(0, items.length - 1)]!;
  }

  type(depth: number, udts: readonly string[]): TypeRef {
    const r = this.random();
    if (depth < 3 && r < 0.12) return struct(this.members(depth + 1, udts, 0, 5));
    if (depth < 3 && r < 0.24) {
      const dims = Array.from({ length: this.int(1, 2) }, (): [number, number] => {
        const low = this.int(-3, 3);
        return [low, low + this.int(0, 4)];
      });
      const element = this.random() < 0.3 ? this.type(depth + 1, udts) : this.elementary();
      return arr(dims, element.kind === 'array' ? struct([m('inner', element)]) : element);
    }
    if (udts.length > 0 && r < 0.3) return named(this.pick(udts));
    return this.elementary();
  }

  elementary(): TypeRef {
    const t = this.pick(TYPES);
    return el(t, t === 'STRING' ? this.int(1, 40) : t === 'WSTRING' ? this.int(1, 20) : 0);
  }

  members(depth: number, udts: readonly string[], min: number, max: number): MemberDecl[] {
    return Array.from({ length: this.int(min, max) }, (_, i) => m(`m${i}`, this.type(depth, udts)));
  }

  blocks(n: number): BlockDecl[] {
    const udts: string[] = [];
    const out: BlockDecl[] = [];
    for (let u = 0; u < this.int(0, 3); u++) {
      out.push(udt(`T${u}`, this.members(1, udts, 1, 5)));
      udts.push(`T${u}`);
    }
    out.push(db(`B${n}`, this.members(0, udts, 0, 12)));
    return out;
  }
}

/** Bit range an elementary entry occupies. */
function bits(e: SymbolEntry): [number, number] {
  const byte = e.byte!;
  return e.bit === null ? [byte * 8, (byte + e.size) * 8] : [byte * 8 + e.bit, byte * 8 + e.bit + 1];
}

const noLiterals = (): never => {
  throw new Error('no start values are generated');
};

/** The budget: a fixed number of random blocks (with a fixed seed), never a time. */
const NUM_RUNS = 2000;
/**
 * Far above what the budget takes (~1.5 s on an idle 2-core machine, a few
 * seconds at a load of 10), so that only a hang trips it, not a slow machine.
 */
const TIMEOUT_PER_RUN_MS = 100;

describe(`symbols layout: properties over ${NUM_RUNS.toLocaleString('en-US')} random blocks`, () => {
  it('keeps elementary members apart, inside the block, aligned, inside their parents, with addresses that read back', function () {
    this.timeout(NUM_RUNS * TIMEOUT_PER_RUN_MS);
    const gen = new Generator(prng(0x5eed));
    let entries = 0;
    for (let n = 1; n <= NUM_RUNS; n++) {
      const blocks = gen.blocks(n);
      const table = compileDeclarations(blocks, [], { db: { [`B${n}`]: n } }, noLiterals);
      const length = table.blocks[0]!.length!;
      const where = (e: SymbolEntry) => `block ${n} (length ${length}) ${e.name} ${e.type} @${e.byte}.${e.bit ?? ''}+${e.size}`;
      expect(length % 2, `block ${n} length`).to.equal(0);
      const byName = new Map(table.entries.map((e) => [e.name, e]));
      const elementary = table.entries.filter((e) => e.kind === 'elementary').map((e) => [bits(e), e] as const);
      elementary.sort((a, b) => a[0][0] - b[0][0]);
      for (let i = 1; i < elementary.length; i++)
        expect(elementary[i]![0][0], `${where(elementary[i]![1])} overlaps ${where(elementary[i - 1]![1])}`).to.be.at.least(
          elementary[i - 1]![0][1],
        );
      for (const e of table.entries) {
        entries++;
        expect(e.byte! + e.size, `${where(e)} ends beyond the block`).to.be.at.most(length);
        const wide = e.kind !== 'elementary' || !['BOOL', 'BYTE', 'CHAR', 'SINT', 'USINT'].includes(e.dataType!);
        if (wide) expect(e.byte! % 2, `${where(e)} starts on an odd byte`).to.equal(0);
        for (const c of e.children ?? []) {
          const k = byName.get(c)!;
          expect(k.byte! >= e.byte! && k.byte! + k.size <= e.byte! + e.size, `${where(k)} outside ${where(e)}`).to.equal(true);
        }
        const tag = parseAddress(e.address!);
        expect([tag.dbNumber, tag.byteOffset, tag.bitOffset], `${where(e)} ${e.address}`).to.deep.equal([n, e.byte, e.bit ?? 0]);
        expect(tag.byteLength, `${where(e)} ${e.address}`).to.equal(e.size);
        if (e.kind === 'elementary')
          expect([tag.type, tag.stringLength, tag.isArray], `${where(e)} ${e.address}`).to.deep.equal([e.dataType, e.stringLength, false]);
      }
    }
    expect(entries).to.be.greaterThan(40000);
  });
});
