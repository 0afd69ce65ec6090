/**
 * The layout against an independent implementation: awlsim, an S7-300/400
 * soft PLC in Python (GPL, run as a foreign tool; only its numbers are used).
 * test/interop/awlsim/layout.py has awlsim's own parser and CPU build lay out
 * a STEP 7 source and prints every member's byte, bit and size and each DB's
 * length; compileSymbols() lays out the same text. Our STEP 7 fixtures and
 * 300 seeded random DBs are compared member by member.
 *
 * awlsim differs from the rules of docs/symbols.md in four constructs
 * (docs/symbols.md, "Where common tools deviate"): the random DBs leave them
 * out, the fixtures' differences are listed exactly, and one test pins each
 * of them, so a new awlsim that changes them is noticed.
 *
 * awlsim is installed into test/interop/.venv by `npm test`'s pretest
 * (test/support/install-peers.js awlsim; .ci/run too), or found on python3;
 * without it the suite skips and says why.
 */
import { expect } from 'chai';
import { spawnSync } from 'node:child_process';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { compileSymbols } from '../lib/symbols/compile';
import type { SymbolTable } from '../lib/symbols/model';
import { skipBecause } from './support/skip';

const ROOT = path.resolve(__dirname, '../..');
const DRIVER = path.join(ROOT, 'test/interop/awlsim/layout.py');
const VENV_PYTHON = path.join(ROOT, 'test/interop/.venv/bin/python');
const FIXTURES = path.join(ROOT, 'test/fixtures/symbols');
/** The awlsim whose differences below are known: the one test/support/install-peers.js installs. */
const { AWLSIM_VERSION } = require(path.join(ROOT, 'test/support/install-peers.js')) as { AWLSIM_VERSION: string };

interface TheirMember {
  readonly name: string;
  readonly type: string;
  readonly kind: 'elementary' | 'array' | 'struct';
  readonly byte: number;
  readonly bit: number | null;
  readonly size: number;
}
interface TheirBlock {
  readonly kind: 'db' | 'udt';
  readonly number: number;
  readonly length: number;
  readonly members: readonly TheirMember[];
}
type TheirResult = { readonly id: string; readonly blocks: readonly TheirBlock[] } | { readonly id: string; readonly error: string };

/** A Python that imports awlsim AWLSIM_VERSION, or why there is none. */
function findAwlsim(): { python: string } | { reason: string } {
  const tried: string[] = [];
  for (const python of [...(fs.existsSync(VENV_PYTHON) ? [VENV_PYTHON] : []), 'python3']) {
    const r = spawnSync(python, ['-c', 'from awlsim_loader.common import VERSION_STRING; print(VERSION_STRING)'], {
      encoding: 'utf8',
      timeout: 20_000,
    });
    const version = r.status === 0 ? r.stdout.trim() : undefined;
    if (version === AWLSIM_VERSION) return { python };
    tried.push(
      r.error
        ? `${python}: ${(r.error as NodeJS.ErrnoException).code ?? r.error.message}`
        : version === undefined
          ? `${python}: no awlsim module`
          : `${python}: awlsim ${version}`,
    );
  }
  return {
    reason:
      `awlsim ${AWLSIM_VERSION} is not installed (${tried.join('; ')}); ` +
      '`node test/support/install-peers.js awlsim` installs it (npm test does), with python3 and PyPI',
  };
}

/** awlsim's layout of each source, each built as a program of its own. */
function awlsimLayouts(python: string, cases: readonly { id: string; source: string }[]): Map<string, TheirResult> {
  const r = spawnSync(python, [DRIVER, '--batch'], {
    input: JSON.stringify(cases),
    encoding: 'utf8',
    timeout: 60_000,
    maxBuffer: 256 * 1024 * 1024,
  });
  if (r.status !== 0) throw new Error(`layout.py exited ${r.status ?? r.signal}: ${r.error?.message ?? r.stderr}`);
  const results = JSON.parse(r.stdout) as TheirResult[];
  return new Map(results.map((x) => [x.id, x]));
}

interface Comparison {
  /** Elementary members whose byte, bit and size were compared. */
  members: number;
  /** Structs and arrays whose start byte was compared. */
  starts: number;
  blocks: number;
  /** `DB10.Tail: byte 22, awlsim 21`, one per difference. */
  differences: string[];
}

/** Compares every DB of our table with awlsim's: elementary members (byte, bit, size), struct and array starts, lengths. */
function compare(table: SymbolTable, theirs: readonly TheirBlock[], into: Comparison): string[] {
  const found: string[] = [];
  for (const block of table.blocks) {
    const their = theirs.find((b) => b.kind === 'db' && b.number === block.db);
    if (!their) {
      found.push(`DB${block.db}: awlsim has no such block`);
      continue;
    }
    into.blocks++;
    if (their.length !== block.length) found.push(`DB${block.db}: length ${block.length}, awlsim ${their.length}`);
    const byName = new Map(their.members.map((m) => [m.name, m]));
    const prefix = `DB${block.db}.`;
    let elementary = 0;
    for (const e of table.entries) {
      if (e.db !== block.db) continue;
      expect(e.name.startsWith(prefix), e.name).to.equal(true);
      const name = e.name.slice(prefix.length);
      const m = byName.get(name);
      if (!m) {
        found.push(`DB${block.db}.${name}: awlsim has no such member`);
        continue;
      }
      if (e.kind === 'elementary') {
        elementary++;
        into.members++;
        const ours = `${e.byte}.${e.bit ?? '-'}+${e.size}`;
        const awl = `${m.byte}.${m.bit ?? '-'}+${m.size}`;
        if (m.kind !== 'elementary' || ours !== awl) found.push(`${e.name}: ${ours}, awlsim ${awl}`);
      } else {
        into.starts++;
        if (m.kind !== e.kind || m.byte !== e.byte) found.push(`${e.name}: ${e.kind} at ${e.byte}, awlsim ${m.kind} at ${m.byte}`);
      }
    }
    const theirElementary = their.members.filter((m) => m.kind === 'elementary').length;
    if (theirElementary !== elementary) found.push(`DB${block.db}: ${elementary} elementary members, awlsim ${theirElementary}`);
  }
  into.differences.push(...found);
  return found;
}

const empty = (): Comparison => ({ members: 0, starts: 0, blocks: 0, differences: [] });

// ---------------------------------------------------------------- the fixtures

function awlFiles(dir: string): string[] {
  return fs
    .readdirSync(dir, { withFileTypes: true })
    .flatMap((d) => (d.isDirectory() ? awlFiles(path.join(dir, d.name)) : /\.awl$/i.test(d.name) ? [path.join(dir, d.name)] : []));
}

/**
 * A fixture without the blocks neither side can lay out from it alone: DBs
 * that are instances of an FB (the FB's interface is not among the sources;
 * we refuse them, awlsim needs the FB) and blocks named by symbol (a
 * symbol table gives their numbers; awlsim reads no table here).
 */
function layoutable(text: string): string {
  return text.replace(/\b(?:DATA_BLOCK|TYPE)\b[\s\S]*?\bEND_(?:DATA_BLOCK|TYPE)\b/gi, (block) =>
    /^DATA_BLOCK\s+"/i.test(block) || /^DATA_BLOCK\s+DB\s*\d+[\s\S]*?^\s*S?FB\s*\d+\s*$/im.test(block) ? '' : block,
  );
}

/** Where a fixture differs from awlsim, each a construct of docs/symbols.md "Where common tools deviate". */
const FIXTURE_DIFFERENCES: Readonly<Record<string, readonly string[]>> = {
  // A BYTE right after an odd STRING[7] (12..20): on 21 for both (no pad after a string).
  'golden/step7.awl': [],
  'parser/step7-tank.awl': [],
  'client/Recipe.awl': [],
};

/**
 * Where awlsim 0.77.1 deviates, one DB each, with our offsets and awlsim's
 * (docs/symbols.md "Where common tools deviate" says which is right and why).
 */
const DEVIATIONS = `
DATA_BLOCK DB 1
TITLE = a BYTE right after an odd STRING (no deviation: both put it on the very next byte)
  STRUCT
   s : STRING  [11 ] ;
   b : BYTE ;
   t : STRING  [3 ] ;
   x : BOOL ;
  END_STRUCT ;
BEGIN
END_DATA_BLOCK

DATA_BLOCK DB 2
TITLE = a BOOL right after an ARRAY OF BOOL
  STRUCT
   f : ARRAY  [1 .. 3 ] OF BOOL ;
   x : BOOL ;
  END_STRUCT ;
BEGIN
END_DATA_BLOCK

DATA_BLOCK DB 3
TITLE = a CHAR right after a STRUCT that ends on an odd byte
  STRUCT
   st : STRUCT
    a : INT ;
    c : CHAR ;
   END_STRUCT ;
   y : CHAR ;
  END_STRUCT ;
BEGIN
END_DATA_BLOCK

DATA_BLOCK DB 4
TITLE = an ARRAY of a STRUCT that ends on an odd byte
  STRUCT
   e : ARRAY  [1 .. 2 ] OF STRUCT
    a : INT ;
    b : BYTE ;
   END_STRUCT ;
  END_STRUCT ;
BEGIN
END_DATA_BLOCK

DATA_BLOCK DB 5
TITLE = a 2-D ARRAY OF BOOL with rows of 3
  STRUCT
   g : ARRAY  [1 .. 2, 1 .. 3 ] OF BOOL ;
  END_STRUCT ;
BEGIN
END_DATA_BLOCK

DATA_BLOCK DB 6
TITLE = an ARRAY of one BOOL
  STRUCT
   w : WORD ;
   o : ARRAY  [1 .. 1 ] OF BOOL ;
  END_STRUCT ;
BEGIN
END_DATA_BLOCK

DATA_BLOCK DB 7
TITLE = an ARRAY of 8 bits in all after a BYTE
  STRUCT
   b : BYTE ;
   a : ARRAY  [1 .. 8 ] OF BOOL ;
  END_STRUCT ;
BEGIN
END_DATA_BLOCK
`;

// ---------------------------------------------------------------- random DBs

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

/** A declared type as the generator builds it. */
type Decl =
  | { kind: 'el'; type: string; length?: number }
  | { kind: 'array'; dims: [number, number][]; element: Decl }
  | { kind: 'struct'; members: Member[] }
  | { kind: 'udt'; number: number };
interface Member {
  name: string;
  type: Decl;
}

/** STEP 7's elementary types a DB can hold (S7-300/400: no 64-bit types, no unsigned ones). */
const WIDE = ['INT', 'WORD', 'DINT', 'DWORD', 'REAL', 'TIME', 'S5TIME', 'DATE', 'TIME_OF_DAY', 'DATE_AND_TIME'] as const;
const NARROW = ['BOOL', 'BYTE', 'CHAR'] as const;

/** Renders a declaration as STEP 7 writes sources (`ARRAY  [1 .. 3 ] OF INT`, `STRING  [20 ]`). */
function render(type: Decl, indent: string): string {
  switch (type.kind) {
    case 'el':
      return type.length === undefined ? type.type : `${type.type}  [${type.length} ]`;
    case 'udt':
      return `UDT ${type.number}`;
    case 'array':
      return `ARRAY  [${type.dims.map(([lo, hi]) => `${lo} .. ${hi}`).join(', ')} ] OF ${render(type.element, indent)}`;
    case 'struct':
      return `STRUCT \t\n${renderMembers(type.members, `${indent} `)}${indent}END_STRUCT`;
  }
}

function renderMembers(members: readonly Member[], indent: string): string {
  return members.map((m) => `${indent}${m.name} : ${render(m.type, indent)} ;\t\n`).join('');
}

/** What a case holds, to show the comparison covered each construct. */
type Construct =
  | (typeof WIDE)[number]
  | (typeof NARROW)[number]
  | 'BOOL run'
  | 'STRING odd'
  | 'BOOL, BYTE or CHAR after an odd STRING'
  | 'STRING even'
  | 'ARRAY 1-D'
  | 'ARRAY 2-D'
  | 'ARRAY 2-D OF BOOL'
  | 'ARRAY negative bounds'
  | 'ARRAY OF STRING'
  | 'ARRAY OF STRUCT'
  | 'ARRAY OF UDT'
  | 'STRUCT nested'
  | 'UDT member'
  | 'DB of a UDT';

/**
 * Random STEP 7 sources without the constructs where awlsim deviates
 * (docs/symbols.md "Where common tools deviate"):
 *  - a BOOL, BYTE or CHAR right after an ARRAY, STRUCT or UDT (awlsim
 *    packs it right after the composite's last byte; these end on a word
 *    limit): after one only a 16-bit-or-wider member or another composite
 *    follows. After a STRING anything may follow: no pad follows a string,
 *    in awlsim as in our rules;
 *  - an array of a STRUCT or UDT whose members end on an odd byte or inside
 *    a byte (awlsim starts the next element right there, even with an INT on
 *    an odd byte): every UDT and every STRUCT used as an element ends with a
 *    16-bit-or-wider member;
 *  - a 2-D ARRAY OF BOOL whose last dimension is not a multiple of 8 (awlsim
 *    runs the bits on without starting each row on a new byte): the last
 *    dimension of a 2-D BOOL array spans 8 or 16;
 *  - an array of 1 or 8 bits in all (ARRAY[1..1] OF BOOL, ARRAY[1..8] OF
 *    BOOL, ARRAY[1..1] OF BYTE): awlsim aligns it as the BOOL or BYTE its
 *    size matches (an odd start byte; a lone element on bit 1): such arrays
 *    get one element more.
 * A STRUCT nested in a UDT holds no UDT: awlsim crashes on it (it gives no
 * offsets to compare).
 */
class Generator {
  readonly seen = new Map<Construct, number>();
  private names = 0;
  private inUdt = false;

  constructor(private readonly random: () => number) {}

  private int(lo: number, hi: number): number {
    return lo + Math.floor(this.random() * (hi - lo + 1));
  }

  private pick<T>(items: readonly T[]): T {
    return items[this.int(0, items.length - 1)]!;
  }

  private see(c: Construct): void {
    this.seen.set(c, (this.seen.get(c) ?? 0) + 1);
  }

  /**
   * The UDTs a STRUCT nested in a UDT may use: none. awlsim 0.77.1 builds
   * such a STRUCT without its CPU and fails on a UDT inside it (an error of
   * awlsim's, not a layout: it crashes, it gives no offsets).
   */
  private nested(udts: readonly number[]): readonly number[] {
    return this.inUdt ? [] : udts;
  }

  private name(): string {
    return `m${this.names++}`;
  }

  private wide(): Decl {
    const type = this.pick(WIDE);
    this.see(type);
    return { kind: 'el', type };
  }

  private string(): Decl {
    const length = this.random() < 0.05 ? undefined : this.int(1, 30);
    this.see(length !== undefined && length % 2 === 1 ? 'STRING odd' : 'STRING even');
    return length === undefined ? { kind: 'el', type: 'STRING' } : { kind: 'el', type: 'STRING', length };
  }

  private array(depth: number, udts: readonly number[]): Decl {
    const r = this.random();
    if (r < 0.2) {
      // 2-D BOOL: rows of 8 or 16 bits.
      // Rows of 8 or 16 bits, 16 bits or more in all (awlsim aligns an array of 8 bits as a BYTE).
      const lo = this.int(-2, 1);
      const rows = this.int(1, 3);
      const row = rows === 1 ? 16 : this.pick([8, 16]);
      this.see('ARRAY 2-D OF BOOL');
      return {
        kind: 'array',
        dims: [
          [lo, lo + rows - 1],
          [1, row],
        ],
        element: { kind: 'el', type: 'BOOL' },
      };
    }
    const dims: [number, number][] = Array.from({ length: this.random() < 0.25 ? this.int(2, 3) : 1 }, () => {
      const lo = this.int(-3, 2);
      return [lo, lo + this.int(0, 4)];
    });
    this.see(dims.length > 1 ? 'ARRAY 2-D' : 'ARRAY 1-D');
    if (dims.some(([lo]) => lo < 0)) this.see('ARRAY negative bounds');
    let element: Decl;
    const e = this.random();
    if (depth < 2 && e < 0.15) {
      this.see('ARRAY OF STRUCT');
      element = {
        kind: 'struct',
        members: [...this.members(depth + 1, this.nested(udts), 1, 4), { name: this.name(), type: this.wide() }],
      };
    } else if (udts.length > 0 && e < 0.3) {
      this.see('ARRAY OF UDT');
      element = { kind: 'udt', number: this.pick(udts) };
    } else if (e < 0.4) {
      this.see('ARRAY OF STRING');
      element = this.string();
    } else if (e < 0.65 && dims.length === 1) {
      const type = this.pick(NARROW);
      this.see(type);
      element = { kind: 'el', type };
      // Arrays of 1 or 8 bits in all (ARRAY[1..1] OF BYTE, ARRAY[1..8] OF BOOL): awlsim aligns them as a BOOL or a BYTE.
      const bits = (dims[0]![1] - dims[0]![0] + 1) * (type === 'BOOL' ? 1 : 8);
      if (bits === 1 || bits === 8) dims[0]![1]++;
    } else element = this.wide();
    return { kind: 'array', dims, element };
  }

  private composite(depth: number, udts: readonly number[]): Decl {
    const r = this.random();
    if (r < 0.3) return this.string();
    if (r < 0.65) return this.array(depth, udts);
    if (udts.length > 0 && r < 0.8) {
      this.see('UDT member');
      return { kind: 'udt', number: this.pick(udts) };
    }
    if (depth < 2) {
      this.see('STRUCT nested');
      return { kind: 'struct', members: this.members(depth + 1, this.nested(udts), 1, 5) };
    }
    return this.string();
  }

  /** Members of a struct: runs of BOOLs, BYTE/CHAR, wide types and composites, none narrow right after an array, struct or UDT. */
  members(depth: number, udts: readonly number[], min: number, max: number): Member[] {
    const out: Member[] = [];
    const count = this.int(min, max);
    let afterComposite = false;
    while (out.length < count) {
      const r = this.random();
      const last = out.at(-1)?.type;
      if (!afterComposite && r < 0.35 && last?.kind === 'el' && last.type === 'STRING' && (last.length ?? 254) % 2 === 1)
        this.see('BOOL, BYTE or CHAR after an odd STRING');
      if (!afterComposite && r < 0.2) {
        const run = this.int(1, 10);
        if (run > 1) this.see('BOOL run');
        for (let i = 0; i < run; i++) out.push({ name: this.name(), type: { kind: 'el', type: 'BOOL' } });
        this.see('BOOL');
      } else if (!afterComposite && r < 0.35) {
        const type = this.pick(['BYTE', 'CHAR'] as const);
        this.see(type);
        out.push({ name: this.name(), type: { kind: 'el', type } });
      } else if (r < 0.6) {
        out.push({ name: this.name(), type: this.wide() });
        afterComposite = false;
        continue;
      } else {
        const type = this.composite(depth, udts);
        out.push({ name: this.name(), type });
        // A STRING is followed by no pad: a BOOL, BYTE or CHAR may come right after it.
        afterComposite = !(type.kind === 'el' && type.type === 'STRING');
        continue;
      }
      afterComposite = false;
    }
    return out;
  }

  /** One STEP 7 source: a few UDTs (each ending with a wide member), a DB, sometimes a DB of a UDT. */
  source(n: number): string {
    const udts: number[] = [];
    let text = '';
    for (let u = 0; u < this.int(0, 3); u++) {
      const number = 10 * n + u + 1;
      this.inUdt = true;
      const members = [...this.members(1, udts, 1, 5), { name: this.name(), type: this.wide() }];
      this.inUdt = false;
      text += `TYPE UDT ${number}\nVERSION : 0.1\n\n\n  STRUCT \t\n${renderMembers(members, '   ')}  END_STRUCT ;\t\nEND_TYPE\n\n`;
      udts.push(number);
    }
    const body = this.members(0, udts, 1, 12);
    text += `DATA_BLOCK DB ${n}\nTITLE =\nVERSION : 0.1\n\n\n  STRUCT \t\n${renderMembers(body, '   ')}  END_STRUCT ;\t\nBEGIN\nEND_DATA_BLOCK\n\n`;
    if (udts.length > 0 && this.random() < 0.3) {
      this.see('DB of a UDT');
      text += `DATA_BLOCK DB ${1000 + n}\nTITLE =\nVERSION : 0.1\n\n ${`UDT ${this.pick(udts)}`}\nBEGIN\nEND_DATA_BLOCK\n\n`;
    }
    return text;
  }
}

// ---------------------------------------------------------------- the tests

describe('symbols layout against awlsim (an independent S7-300/400 soft PLC)', function () {
  this.timeout(60_000);
  let python = '';

  before(function () {
    const found = findAwlsim();
    if ('reason' in found) skipBecause(this, found.reason);
    python = found.python;
  });

  it('lays out every STEP 7 fixture as awlsim does, but for the listed deviations', () => {
    const files = awlFiles(FIXTURES);
    expect(files.map((f) => path.relative(FIXTURES, f)).sort()).to.deep.equal(Object.keys(FIXTURE_DIFFERENCES).sort());
    const cases = files.map((f) => ({ id: path.relative(FIXTURES, f), source: layoutable(fs.readFileSync(f).toString('latin1')) }));
    const theirs = awlsimLayouts(python, cases);
    const total = empty();
    for (const c of cases) {
      const result = theirs.get(c.id)!;
      if ('error' in result) throw new Error(`${c.id}: awlsim: ${result.error}`);
      const table = compileSymbols([{ name: path.basename(c.id), content: c.source }]);
      expect(compare(table, result.blocks, total), c.id).to.deep.equal(FIXTURE_DIFFERENCES[c.id]);
    }
    expect(total.blocks).to.equal(4);
    expect(total.members).to.be.greaterThan(60);
  });

  it('deviates from awlsim exactly where docs/symbols.md says it does', () => {
    const result = awlsimLayouts(python, [{ id: 'deviations', source: DEVIATIONS }]).get('deviations')!;
    if ('error' in result) throw new Error(`awlsim: ${result.error}`);
    const table = compileSymbols([{ name: 'deviations.awl', content: DEVIATIONS }]);
    expect(compare(table, result.blocks, empty())).to.deep.equal([
      // DB1 (a BYTE or BOOL after an odd STRING) agrees: no pad follows a string.
      // What follows an array or a struct: it ends on a word limit; awlsim packs a BOOL, BYTE or CHAR right after it.
      'DB2: length 4, awlsim 2',
      'DB2.x: 2.0+1, awlsim 1.0+1',
      'DB3: length 6, awlsim 4',
      'DB3.y: 4.-+1, awlsim 3.-+1',
      // Elements of 3 bytes: awlsim starts the second on byte 3 (an INT on an odd byte), and its DB is shorter than its array (8 bytes).
      'DB4: length 8, awlsim 6',
      'DB4.e[2]: struct at 4, awlsim struct at 3',
      'DB4.e[2].a: 4.-+2, awlsim 3.-+2',
      'DB4.e[2].b: 6.-+1, awlsim 5.-+1',
      // Rows of a 2-D BOOL array: we start each on a new byte, awlsim runs the bits on.
      ...[0, 1, 2].map((k) => `DB5.g[2,${k + 1}]: 1.${k}+1, awlsim 0.${k + 3}+1`),
      // The one element of an ARRAY[1..1] OF BOOL: awlsim puts it on bit 1 of the array's byte.
      'DB6.o[1]: 2.0+1, awlsim 2.1+1',
      // An array of 8 bits in all: awlsim aligns it as a BYTE, on an odd byte.
      'DB7: length 4, awlsim 2',
      'DB7.a: array at 2, awlsim array at 1',
      ...Array.from({ length: 8 }, (_, k) => `DB7.a[${k + 1}]: 2.${k}+1, awlsim 1.${k}+1`),
    ]);
  });

  it('lays out 300 random STEP 7 DBs as awlsim does: every elementary member, struct and array start, and each length', () => {
    const gen = new Generator(prng(0xa771));
    const cases = Array.from({ length: 300 }, (_, i) => ({ id: String(i + 1), source: gen.source(i + 1) }));
    const theirs = awlsimLayouts(python, cases);
    const total = empty();
    for (const c of cases) {
      const result = theirs.get(c.id)!;
      if ('error' in result) throw new Error(`case ${c.id}: awlsim: ${result.error}\n${c.source}`);
      const table = compileSymbols([{ name: `case${c.id}.awl`, content: c.source }]);
      const found = compare(table, result.blocks, total);
      expect(found, `case ${c.id}:\n${c.source}`).to.deep.equal([]);
    }
    // Each construct was compared many times over.
    for (const construct of [...WIDE, ...NARROW, 'BOOL run', 'STRING odd', 'STRING even', 'ARRAY 1-D', 'ARRAY 2-D'] as const)
      expect(gen.seen.get(construct) ?? 0, construct).to.be.at.least(20);
    for (const construct of [
      'ARRAY 2-D OF BOOL',
      'BOOL, BYTE or CHAR after an odd STRING',
      'ARRAY negative bounds',
      'ARRAY OF STRING',
      'ARRAY OF STRUCT',
      'ARRAY OF UDT',
      'STRUCT nested',
      'UDT member',
      'DB of a UDT',
    ] as const)
      expect(gen.seen.get(construct) ?? 0, construct).to.be.at.least(10);
    expect(total.blocks).to.be.greaterThan(300);
    expect(total.members).to.be.greaterThan(10_000);
  });
});
