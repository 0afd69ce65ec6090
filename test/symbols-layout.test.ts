/**
 * The layout engine against known offsets: each rule of docs/symbols.md
 * ("Layout rules") on a block built by hand, and the refusals, each naming
 * the declaration it stops at.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { parseAddress } from '../lib/address';
import { SourceError } from '../lib/errors';
import { compileDeclarations, compileSymbols, pathKey, type EvaluateLiteral } from '../lib/symbols/compile';
import { elementIndex, layoutBlocks, memberRef, type LayoutNode } from '../lib/symbols/layout';
import type { BlockDecl, CompileOptions, SymbolTable, SymbolTableRow } from '../lib/symbols/model';
import { parseBlockSource } from '../lib/symbols/source-parser';
import { arr, at, db, el, list, lit, m, named, str, struct, udt, udtNumber, wstr } from './fixtures/symbols/golden/build';

/** Every node of a block as [path, byte, bit, size], parents before children. */
function rows(node: LayoutNode, path = ''): [string, number, number | null, number][] {
  const out: [string, number, number | null, number][] = path === '' ? [] : [[path, node.byte, node.bit, node.size]];
  if (node.kind === 'struct') for (const c of node.members) out.push(...rows(c.node, `${path}.${memberRef(c.name)}`));
  if (node.kind === 'array') node.elements.forEach((e, k) => out.push(...rows(e, `${path}[${elementIndex(node.dims, k)}]`)));
  return out;
}

function layoutOf(...blocks: BlockDecl[]) {
  const [first] = layoutBlocks(blocks);
  return { length: first!.length, rows: rows(first!.root) };
}

function refusal(blocks: BlockDecl[]): SourceError {
  try {
    layoutBlocks(blocks);
  } catch (err) {
    expect(err).to.be.instanceOf(SourceError);
    return err as SourceError;
  }
  throw new Error('expected a SourceError');
}

describe('symbols layout: standard access offsets', () => {
  it('packs a run of nine BOOLs into bits, the ninth in the next byte, and an INT after them on the next even byte', () => {
    const bits = Array.from({ length: 9 }, (_, i) => m(`b${i}`, el('BOOL')));
    expect(layoutOf(db('Bits', [...bits, m('n', el('INT'))]))).to.deep.equal({
      length: 4,
      rows: [
        ...Array.from({ length: 8 }, (_, i): [string, number, number, number] => [`.b${i}`, 0, i, 1]),
        ['.b8', 1, 0, 1],
        ['.n', 2, null, 2],
      ],
    });
  });

  it('puts a BYTE after a BOOL on the next byte, a BOOL after it on the byte after, and a WORD on the next even byte', () => {
    const decl = db('Mixed', [m('x', el('BOOL')), m('y', el('BYTE')), m('z', el('BOOL')), m('w', el('WORD')), m('c', el('CHAR'))]);
    expect(layoutOf(decl)).to.deep.equal({
      length: 8,
      rows: [
        ['.x', 0, 0, 1],
        ['.y', 1, null, 1],
        ['.z', 2, 0, 1],
        ['.w', 4, null, 2],
        ['.c', 6, null, 1],
      ],
    });
  });

  it('gives a STRING[11] 13 bytes on an even byte and puts a BYTE after it on the very next byte, an INT on the next even one', () => {
    const decl = db('Text', [m('b', el('BYTE')), m('s', str(11)), m('n', el('INT')), m('t', str(11)), m('after', el('BYTE'))]);
    expect(layoutOf(decl)).to.deep.equal({
      length: 32,
      rows: [
        ['.b', 0, null, 1],
        ['.s', 2, null, 13],
        ['.n', 16, null, 2],
        ['.t', 18, null, 13],
        ['.after', 31, null, 1],
      ],
    });
  });

  it('puts a BOOL, CHAR, SINT or USINT after an odd STRING[n] on the very next byte, and still pads a struct that ends with one', () => {
    const decl = db('Odd', [
      m('s', str(3)),
      m('x', el('BOOL')),
      m('t', str(5)),
      m('c', el('CHAR')),
      m('u', str(1)),
      m('i', el('SINT')),
      m('v', str(7)),
      m('k', el('USINT')),
      m('st', struct([m('w', str(3))])),
      m('after', el('BOOL')),
    ]);
    expect(layoutOf(decl)).to.deep.equal({
      length: 36,
      rows: [
        ['.s', 0, null, 5],
        ['.x', 5, 0, 1],
        ['.t', 6, null, 7],
        ['.c', 13, null, 1],
        ['.u', 14, null, 3],
        ['.i', 17, null, 1],
        ['.v', 18, null, 9],
        ['.k', 27, null, 1],
        ['.st', 28, null, 6],
        ['.st.w', 28, null, 5],
        ['.after', 34, 0, 1],
      ],
    });
  });

  it('ends an Array[1..10] of Bool at a word limit: the next BOOL starts on byte 2', () => {
    const decl = db('Flags', [m('f', arr([[1, 10]], el('BOOL'))), m('after', el('BOOL'))]);
    const { length, rows: r } = layoutOf(decl);
    expect(length).to.equal(4);
    expect(r[0]).to.deep.equal(['.f', 0, 0, 2]);
    expect(r.slice(1, 11).map((x) => `${x[0]}@${x[1]}.${x[2]}`)).to.deep.equal([
      '.f[1]@0.0',
      '.f[2]@0.1',
      '.f[3]@0.2',
      '.f[4]@0.3',
      '.f[5]@0.4',
      '.f[6]@0.5',
      '.f[7]@0.6',
      '.f[8]@0.7',
      '.f[9]@1.0',
      '.f[10]@1.1',
    ]);
    expect(r[11]).to.deep.equal(['.after', 2, 0, 1]);
  });

  it('lays out 2-D arrays row by row (last index fastest); a BOOL array starts each row on a new byte', () => {
    const decl = db('Grid', [
      m(
        'i',
        arr(
          [
            [1, 2],
            [1, 3],
          ],
          el('INT'),
        ),
      ),
      m(
        'b',
        arr(
          [
            [1, 2],
            [1, 3],
          ],
          el('BOOL'),
        ),
      ),
      m('n', el('BYTE')),
    ]);
    expect(layoutOf(decl)).to.deep.equal({
      length: 16,
      rows: [
        ['.i', 0, null, 12],
        ['.i[1,1]', 0, null, 2],
        ['.i[1,2]', 2, null, 2],
        ['.i[1,3]', 4, null, 2],
        ['.i[2,1]', 6, null, 2],
        ['.i[2,2]', 8, null, 2],
        ['.i[2,3]', 10, null, 2],
        ['.b', 12, 0, 2],
        ['.b[1,1]', 12, 0, 1],
        ['.b[1,2]', 12, 1, 1],
        ['.b[1,3]', 12, 2, 1],
        ['.b[2,1]', 13, 0, 1],
        ['.b[2,2]', 13, 1, 1],
        ['.b[2,3]', 13, 2, 1],
        ['.n', 14, null, 1],
      ],
    });
  });

  it('pads each element of an array of a UDT that ends in a BOOL to an even length', () => {
    const point = udt('Point', [m('x', el('REAL')), m('ok', el('BOOL'))]);
    const decl = db('Track', [m('p', arr([[0, 2]], named('Point'))), m('n', el('INT'))]);
    expect(layoutOf(decl, point)).to.deep.equal({
      length: 20,
      rows: [
        ['.p', 0, null, 18],
        ['.p[0]', 0, null, 6],
        ['.p[0].x', 0, null, 4],
        ['.p[0].ok', 4, 0, 1],
        ['.p[1]', 6, null, 6],
        ['.p[1].x', 6, null, 4],
        ['.p[1].ok', 10, 0, 1],
        ['.p[2]', 12, null, 6],
        ['.p[2].x', 12, null, 4],
        ['.p[2].ok', 16, 0, 1],
        ['.n', 18, null, 2],
      ],
    });
  });

  it('starts nested structs on even bytes and pads each to an even length', () => {
    const decl = db('Nest', [
      m('a', el('BOOL')),
      m('s1', struct([m('b', el('BOOL')), m('s2', struct([m('c', el('BYTE'))])), m('d', el('BYTE'))])),
      m('e', el('BYTE')),
    ]);
    expect(layoutOf(decl)).to.deep.equal({
      length: 10,
      rows: [
        ['.a', 0, 0, 1],
        ['.s1', 2, null, 6],
        ['.s1.b', 2, 0, 1],
        ['.s1.s2', 4, null, 2],
        ['.s1.s2.c', 4, null, 1],
        ['.s1.d', 6, null, 1],
        ['.e', 8, null, 1],
      ],
    });
  });

  it('lays out a UDT that uses a UDT, as the block body (an instance DB of a UDT)', () => {
    const inner = udt('Inner', [m('v', el('INT')), m('f', el('BOOL'))]);
    const outer = udt('Outer', [m('flag', el('BOOL')), m('inner', named('Inner')), m('n', el('BYTE'))]);
    const [layout] = layoutBlocks([inner, outer, db('Inst', named('Outer'))]);
    expect(layout!.instanceOf).to.equal('"Outer"');
    expect(layout!.length).to.equal(8);
    expect(rows(layout!.root)).to.deep.equal([
      ['.flag', 0, 0, 1],
      ['.inner', 2, null, 4],
      ['.inner.v', 2, null, 2],
      ['.inner.f', 4, 0, 1],
      ['.n', 6, null, 1],
    ]);
  });

  it('places WSTRING, DTL, DATE_AND_TIME and LREAL on the next even byte with their sizes', () => {
    const decl = db('Wide', [
      m('a', el('BYTE')),
      m('w', wstr(10)),
      m('b', el('BOOL')),
      m('t', el('DTL')),
      m('c', el('CHAR')),
      m('dt', el('DATE_AND_TIME')),
      m('d', el('BYTE')),
      m('r', el('LREAL')),
    ]);
    expect(layoutOf(decl)).to.deep.equal({
      length: 60,
      rows: [
        ['.a', 0, null, 1],
        ['.w', 2, null, 24],
        ['.b', 26, 0, 1],
        ['.t', 28, null, 12],
        ['.c', 40, null, 1],
        ['.dt', 42, null, 8],
        ['.d', 50, null, 1],
        ['.r', 52, null, 8],
      ],
    });
  });

  it('indexes an Array[-2..2] from its low bound', () => {
    const { rows: r } = layoutOf(db('Neg', [m('a', arr([[-2, 2]], el('INT')))]));
    expect(r.map((x) => `${x[0]}@${x[1]}`)).to.deep.equal(['.a@0', '.a[-2]@0', '.a[-1]@2', '.a[0]@4', '.a[1]@6', '.a[2]@8']);
  });

  it('starts a STRUCT after a BOOL on the next even byte; an empty STRUCT takes no bytes', () => {
    const decl = db('Empty', [m('b', el('BOOL')), m('s', struct([m('x', el('BYTE'))])), m('e', struct([])), m('c', el('BOOL'))]);
    expect(layoutOf(decl)).to.deep.equal({
      length: 6,
      rows: [
        ['.b', 0, 0, 1],
        ['.s', 2, null, 2],
        ['.s.x', 2, null, 1],
        ['.e', 4, null, 0],
        ['.c', 4, 0, 1],
      ],
    });
  });

  it('gives a block whose last member is a BYTE at offset 4 a length of 6 (the block is a STRUCT)', () => {
    expect(layoutOf(db('Odd', [m('a', el('DINT')), m('b', el('BYTE'))])).length).to.equal(6);
    expect(layoutOf(db('NoMembers', [])).length).to.equal(0);
  });

  it('ends byte arrays at a word limit and pads STRING elements of odd length to an even one', () => {
    const decl = db('Bytes', [m('a', arr([[1, 3]], el('BYTE'))), m('b', el('BYTE')), m('s', arr([[1, 3]], str(5))), m('c', el('BYTE'))]);
    const [layout] = layoutBlocks([decl]);
    expect(rows(layout!.root)).to.deep.equal([
      ['.a', 0, null, 3],
      ['.a[1]', 0, null, 1],
      ['.a[2]', 1, null, 1],
      ['.a[3]', 2, null, 1],
      ['.b', 4, null, 1],
      ['.s', 6, null, 23],
      ['.s[1]', 6, null, 7],
      ['.s[2]', 14, null, 7],
      ['.s[3]', 22, null, 7],
      ['.c', 30, null, 1],
    ]);
    const [a, , s] = layout!.root.members.map((x) => x.node);
    expect(a!.kind === 'array' && a.contiguous).to.equal(true);
    expect(s!.kind === 'array' && s.contiguous).to.equal(false);
  });

  it('finds a STEP 7 UDT by number, and by the symbol a symbol table gives it', () => {
    const u5 = udt('UDT5', [m('v', el('INT'))], { number: 5 });
    const blocks = [u5, db('DB10', [m('a', udtNumber(5)), m('b', named('Valve'))], { number: 10 })];
    const [layout] = layoutBlocks(blocks, { typeNumbers: new Map([['valve', 5]]) });
    expect(rows(layout!.root)).to.deep.equal([
      ['.a', 0, null, 2],
      ['.a.v', 0, null, 2],
      ['.b', 2, null, 2],
      ['.b.v', 2, null, 2],
    ]);
    expect(layout!.root.members[0]!.node.typeText).to.equal('UDT 5');
  });

  it('shows types as TIA does', () => {
    const decl = db('Types', [
      m('a', arr([[1, 10]], el('BOOL'))),
      m('b', str(20)),
      m(
        'c',
        arr(
          [
            [0, 1],
            [-1, 1],
          ],
          el('TIME_OF_DAY'),
        ),
      ),
      m('d', struct([m('x', el('UDINT'))])),
    ]);
    expect(layoutBlocks([decl])[0]!.root.members.map((x) => x.node.typeText)).to.deep.equal([
      'Array[1..10] of Bool',
      'String[20]',
      'Array[0..1, -1..1] of Time_Of_Day',
      'Struct',
    ]);
  });
});

describe('symbols layout: refusals', () => {
  it('lays out a block with optimized access (no longer refused: its table gives no offsets) and refuses what cannot be laid out in it', () => {
    const [layout] = layoutBlocks([db('Tank', [m('a', el('INT')), m('b', el('BOOL'))], { optimized: true, at: at(1, 1, 'Tank.db') })]);
    expect(layout!.decl.optimized).to.equal(true);
    expect(layout!.root.members.map((x) => [x.name, x.node.typeText])).to.deep.equal([
      ['a', 'Int'],
      ['b', 'Bool'],
    ]);
    const err = refusal([db('Tank', [m('a', named('Nope', at(3, 11, 'Tank.db')))], { optimized: true, at: at(1, 1, 'Tank.db') })]);
    expect(err.message).to.match(/^Tank\.db:3:11: unknown type "Nope"/);
    expect(err.code).to.equal('INVALID_SOURCE');
  });

  it('refuses an unknown type, naming it and the member that uses it, at the type', () => {
    const err = refusal([db('Tank', [m('Inlet', struct([m('v', named('Valve', at(4, 12)))]))])]);
    expect(err.message).to.equal('hand.db:4:12: unknown type "Valve" (used by "Tank".Inlet.v): no UDT of that name is among the sources');
  });

  it('refuses a UDT that contains itself, directly or through another, naming the chain', () => {
    expect(refusal([udt('Loop', [m('me', named('Loop'))], { at: at(2) })]).message).to.equal(
      'hand.db:2:1: UDT "Loop" contains itself ("Loop" → "Loop"): a type cannot be laid out inside itself',
    );
    const a = udt('A', [m('b', arr([[1, 2]], named('B')))], { at: at(1) });
    const b = udt('B', [m('a', named('A'))], { at: at(5) });
    expect(refusal([a, b]).message).to.contain('UDT "A" contains itself ("A" → "B" → "A")');
  });

  it('refuses an instance DB of a function block that is not among the sources', () => {
    const err = refusal([db('Pump_DB', named('FB_Pump'), { at: at(3, 1, 'Pump_DB.db') })]);
    expect(err.message).to.match(/^Pump_DB\.db:3:1: DB "Pump_DB" is an instance of "FB_Pump", which is not a UDT of the sources/);
  });

  it('refuses array bounds low > high, arrays over 65535 elements and blocks over 64 KB', () => {
    expect(refusal([db('G', [m('x', arr([[1, 2]], arr([[1, 2]], el('INT'), at(6, 20))))])]).message).to.match(
      /^hand\.db:6:20: "G"\.x: an array of arrays is not an S7 type/,
    );
    expect(refusal([db('A', [m('x', arr([[5, 1]], el('INT'), at(7, 9)))])]).message).to.equal(
      'hand.db:7:9: "A".x: array bounds 5..1: the low bound is above the high bound',
    );
    expect(refusal([db('B', [m('x', arr([[0, 65535]], el('BOOL')))])]).message).to.contain('more than 65535 elements');
    expect(
      refusal([
        db('C', [
          m(
            'x',
            arr(
              [
                [1, 300],
                [1, 300],
              ],
              el('BYTE'),
            ),
          ),
        ]),
      ]).message,
    ).to.contain('more than 65535 elements');
    expect(layoutBlocks([db('D', [m('x', arr([[1, 32768]], el('INT')))])])[0]!.length).to.equal(65536);
    expect(refusal([db('E', [m('x', arr([[1, 32768]], el('INT'))), m('y', el('BOOL'), { at: at(8) })])]).message).to.equal(
      'hand.db:8:1: "E".y ends beyond byte 65535: a block with standard access holds at most 65536 bytes (64 KB)',
    );
    // Refused while it is built, not after 40 million elements.
    const huge = Array.from({ length: 1000 }, (_, i) => m(`a${i}`, arr([[1, 65535]], el('LREAL'))));
    expect(refusal([db('F', huge)]).message).to.contain('"F".a0 ends beyond byte 65535');
  });

  it('refuses a member declared twice, a UDT declared twice, and timers in a DB', () => {
    expect(refusal([db('A', [m('x', el('INT')), m('X', el('INT'), { at: at(3) })])]).message).to.match(
      /^hand\.db:3:1: "A"\.X is declared twice/,
    );
    expect(refusal([udt('T', []), udt('t', [], { at: at(9) })]).message).to.match(/^hand\.db:9:1: UDT "t" is declared twice/);
    expect(refusal([db('A', [m('x', el('TIMER'))])]).message).to.contain('Timer is a block parameter type');
  });
});

/** Until the literal evaluator is wired in: the literal's text, so a test sees which start value won. */
const asText: EvaluateLiteral = (literal) => literal.text;

function compiled(blocks: BlockDecl[], options: CompileOptions = {}, rows: SymbolTableRow[] = []) {
  return compileDeclarations(blocks, rows, options, asText);
}

function compileRefusal(blocks: BlockDecl[], options: CompileOptions = {}, rows: SymbolTableRow[] = []): SourceError {
  try {
    compiled(blocks, options, rows);
  } catch (err) {
    expect(err).to.be.instanceOf(SourceError);
    return err as SourceError;
  }
  throw new Error('expected a SourceError');
}

function row(name: string, address: string, dataType = '', line = 1): SymbolTableRow {
  return { name, address, dataType, comment: '', at: at(line, 1, 'Symbols.sdf') };
}

describe('symbols compile: names, numbers, addresses, start values', () => {
  it('names members as TIA writes them, quoting what is not a plain identifier, with addresses that read back', () => {
    const motor = udt('Motor', [m('Run', el('BOOL')), m('Speed.Set', el('REAL'))]);
    const recipe = db('Recipe', [m('Step', arr([[1, 3]], struct([m('Temp', el('REAL'))])))]);
    const table = compiled([motor, db('Motor 1', named('Motor')), recipe], { db: { '"Motor 1"': 2, recipe: 3 } });
    expect(table.entries.map((e) => [e.name, e.type, e.address, e.byte, e.bit, e.size])).to.deep.equal([
      ['"Motor 1".Run', 'BOOL', 'DB2.DBX0.0', 0, 0, 1],
      ['"Motor 1"."Speed.Set"', 'REAL', 'DB2.DBD2:REAL', 2, null, 4],
      ['"Recipe".Step', 'ARRAY[1..3] OF STRUCT', 'DB3.DBB0:BYTE[12]', 0, null, 12],
      ['"Recipe".Step[1]', 'STRUCT', 'DB3.DBB0:BYTE[4]', 0, null, 4],
      ['"Recipe".Step[1].Temp', 'REAL', 'DB3.DBD0:REAL', 0, null, 4],
      ['"Recipe".Step[2]', 'STRUCT', 'DB3.DBB4:BYTE[4]', 4, null, 4],
      ['"Recipe".Step[2].Temp', 'REAL', 'DB3.DBD4:REAL', 4, null, 4],
      ['"Recipe".Step[3]', 'STRUCT', 'DB3.DBB8:BYTE[4]', 8, null, 4],
      ['"Recipe".Step[3].Temp', 'REAL', 'DB3.DBD8:REAL', 8, null, 4],
    ]);
    expect(table.entries[2]!.children).to.deep.equal(['"Recipe".Step[1]', '"Recipe".Step[2]', '"Recipe".Step[3]']);
    expect(table.blocks).to.deep.equal([
      { name: 'Motor 1', db: 2, length: 6, file: 'hand.db', instanceOf: '"Motor"' },
      { name: 'Recipe', db: 3, length: 12, file: 'hand.db' },
    ]);
    expect(table.types).to.deep.equal(['Motor']);
    expect(table.lookup('"recipe".step[2].temp')?.address).to.equal('DB3.DBD4:REAL');
  });

  it('gives whole arrays of elementary types one address of their elements, and gapped ones their bytes', () => {
    const table = compiled([
      db(
        'A',
        [
          m('f', arr([[1, 10]], el('BOOL'))),
          m('s', arr([[0, 1]], str(4))),
          m('o', arr([[0, 1]], str(5))),
          m(
            'g',
            arr(
              [
                [1, 2],
                [1, 3],
              ],
              el('BOOL'),
            ),
          ),
        ],
        {
          number: 4,
        },
      ),
    ]);
    const whole = table.entries.filter((e) => e.kind === 'array').map((e) => [e.name, e.address]);
    expect(whole).to.deep.equal([
      ['"A".f', 'DB4.DBX0.0:BOOL[10]'],
      ['"A".s', 'DB4.DBB2:STRING[4][2]'],
      ['"A".o', 'DB4.DBB14:BYTE[15]'],
      ['"A".g', 'DB4.DBB30:BYTE[2]'],
    ]);
  });

  it('names a STEP 7 DB without symbol DB10, and by its symbol when a symbol table gives one', () => {
    const decl = db('DB10', [m('x', el('INT'))], { number: 10 });
    expect(compiled([decl]).entries.map((e) => e.name)).to.deep.equal(['DB10.x']);
    const named10 = compiled([decl], {}, [row('Tank', 'DB10', 'DB10')]);
    expect(named10.entries.map((e) => e.name)).to.deep.equal(['"Tank".x']);
    expect(named10.blocks[0]!.name).to.equal('Tank');
  });

  it('numbers a TIA block from the db option (keys as users type them) or from a symbol table row', () => {
    expect(compiled([db('Tank', [])], { db: { TANK: 7 } }).blocks[0]!.db).to.equal(7);
    expect(compiled([db('Tank', [])], { db: { '"Tank"': 8 } }).blocks[0]!.db).to.equal(8);
    expect(compiled([db('Tank', [])], {}, [row('tank', 'DB9')]).blocks[0]!.db).to.equal(9);
    // The option wins over the table.
    expect(compiled([db('Tank', [])], { db: { Tank: 1 } }, [row('Tank', 'DB9')]).blocks[0]!.db).to.equal(1);
  });

  it('refuses a block without number, two blocks with one number, and a number for a block not in the sources', () => {
    expect(compileRefusal([db('Tank', [], { at: at(1, 1, 'Tank.db') })]).message).to.match(
      /^Tank\.db:1:1: DB "Tank" has no number: .*--db "Tank"=1/,
    );
    expect(compileRefusal([db('A', []), db('B', [], { at: at(4) })], { db: { A: 1, B: 1 } }).message).to.match(
      /^hand\.db:4:1: DB "B" and DB "A" \(hand\.db:1:1\) both have the number 1/,
    );
    expect(compileRefusal([db('A', [])], { db: { A: 1, Tnk: 2 } }).message).to.contain(
      'a number is given for "Tnk", which is not a DB of the sources (DBs: "A")',
    );
    // A misspelt name is what is wrong, not the block left without its number.
    expect(compileRefusal([db('Tank', []), db('Mix', [])], { db: { Tnak: 7 } }).message).to.equal(
      'options.db:0:0: a number is given for "Tnak", which is not a DB of the sources (did you mean "Tank"? DBs: "Tank", "Mix")',
    );
    expect(compileRefusal([db('A', [])], { db: { A: 0 } }).message).to.contain('a DB number is 1..65535');
    expect(compileRefusal([db('DB10', [], { number: 10 })], { db: { DB10: 11 } }).message).to.contain('is DB 10 in its source');
  });

  it('gives types by their IEC names in capitals, and user types by their own names in quotes (STEP 7: UDT n)', () => {
    const motor = udt('Motor', [m('Run', el('BOOL'))]);
    const valve = udt('UDT5', [m('Open', el('BOOL'))], { number: 5 });
    const decl = db('Types', [
      m('Level', el('REAL')),
      m('Name', str(20)),
      m('Label', wstr(10)),
      m('Stamp', el('DATE_AND_TIME')),
      m('Day', el('TIME_OF_DAY')),
      m('Flags', arr([[1, 10]], el('BOOL'))),
      m(
        'Grid',
        arr(
          [
            [1, 2],
            [0, 3],
          ],
          el('INT'),
        ),
      ),
      m('Texts', arr([[0, 1]], str(4))),
      m('Part', struct([m('X', el('INT'))])),
      m('Drive', named('Motor')),
      m('Drives', arr([[1, 2]], named('Motor'))),
      m('Valve', udtNumber(5)),
    ]);
    const table = compiled([motor, valve, decl], { db: { Types: 1 } }, [
      row('Start button', 'I0.0', 'Bool'),
      row('Text', 'MB4:STRING[8]', 'String[8]'),
    ]);
    const type = (name: string) => table.lookup(name)!.type;
    expect(
      ['Level', 'Name', 'Label', 'Stamp', 'Day', 'Flags', 'Grid', 'Texts', 'Part', 'Drive', 'Drives', 'Drives[1]', 'Valve'].map((n) =>
        type(`"Types".${n}`),
      ),
    ).to.deep.equal([
      'REAL',
      'STRING[20]',
      'WSTRING[10]',
      'DATE_AND_TIME',
      'TIME_OF_DAY',
      'ARRAY[1..10] OF BOOL',
      'ARRAY[1..2, 0..3] OF INT',
      'ARRAY[0..1] OF STRING[4]',
      'STRUCT',
      '"Motor"',
      'ARRAY[1..2] OF "Motor"',
      '"Motor"',
      'UDT 5',
    ]);
    // A symbol table's rows as TIA's tag table spells them (`Bool`) get the IEC name too.
    expect([type('"Start button"'), type('"Text"')]).to.deep.equal(['BOOL', 'STRING[8]']);
    // The block's instanceOf keeps the UDT's own name.
    expect(compiled([motor, db('Motor 1', named('Motor'))], { db: { '"Motor 1"': 2 } }).blocks[0]!.instanceOf).to.equal('"Motor"');
  });

  it('makes I/Q/M rows of a symbol table entries with db null, skipping other blocks', () => {
    const table = compiled([], {}, [
      row('Start button', 'I0.0', 'BOOL'),
      row('Level', 'MW10:INT', 'INT'),
      row('Main', 'OB1'),
      row('Motor', 'UDT5'),
    ]);
    expect(table.entries.map((e) => [e.name, e.area, e.db, e.byte, e.bit, e.address, e.type])).to.deep.equal([
      ['"Start button"', 'I', null, 0, 0, 'I0.0', 'BOOL'],
      ['"Level"', 'M', null, 10, null, 'MW10:INT', 'INT'],
    ]);
    expect(compileRefusal([], {}, [row('Bad', 'X7', '', 3)]).message).to.match(/^Symbols\.sdf:3:1: symbol "Bad": invalid address/);
  });

  it('takes start values from the declarations, the UDT for every instance, and the BEGIN section, which wins', () => {
    const motor = udt('Motor', [m('Speed', el('REAL'), { initial: lit('1.5') }), m('On', el('BOOL'))]);
    const decl = db(
      'Line',
      [
        m('M', arr([[1, 2]], named('Motor'))),
        m('Count', el('INT'), { initial: lit('3') }),
        m('Steps', arr([[0, 4]], el('INT')), { initial: list([2, lit('7')], lit('8')) }),
        m('Speed.Set', el('REAL')),
      ],
      {
        startValues: [
          { path: 'M[2].Speed', value: lit('9.5') },
          { path: 'steps[1]', value: lit('70') },
          { path: '"Speed.Set"', value: lit('4.0') },
        ],
      },
    );
    const table = compiled([motor, decl], { db: { Line: 5 } });
    const initial = Object.fromEntries(table.entries.filter((e) => e.initial !== undefined).map((e) => [e.name, e.initial]));
    expect(initial).to.deep.equal({
      '"Line".M[1].Speed': '1.5',
      '"Line".M[2].Speed': '9.5',
      '"Line".Count': '3',
      '"Line".Steps[0]': '7',
      '"Line".Steps[1]': '70',
      '"Line".Steps[2]': '8',
      '"Line"."Speed.Set"': '4.0',
    });
  });

  it('refuses a start value for a member that does not exist, and more values than an array has elements', () => {
    const a = db('A', [m('x', el('INT'))], { number: 1, startValues: [{ path: 'y', value: lit('1'), at: at(9, 3) }] });
    expect(compileRefusal([a]).message).to.equal('hand.db:9:3: start value for "A".y: DB "A" has no such member');
    const b = db('B', [m('x', arr([[1, 2]], el('INT')), { initial: list([3, lit('0')]), at: at(2, 5) })], { number: 2 });
    expect(compileRefusal([b]).message).to.equal('hand.db:2:5: start value for "B".x: more values than its 2 elements');
  });

  it('reads BEGIN paths written with spaces, quotes and several indices', () => {
    expect(pathKey('Motor.Speed')).to.equal('.motor.speed');
    expect(pathKey(' Grid[1, -2] . "Speed.Set" ')).to.equal('.grid[1,-2]."speed.set"');
    expect(pathKey('Step[x]')).to.equal(undefined);
  });
});

// ---------------------------------------------------------------- goldens from source files

const GOLDEN = path.join(__dirname, '../../test/fixtures/symbols/golden');
/** The numbers the golden TIA blocks get (a STEP 7 block carries its own). */
const GOLDEN_NUMBERS: Record<string, number> = { Guideline: 1, TestStruct: 1, Corners: 3, Tank: 7, Valve1: 8, conn: 9, Conn: 10, Comm: 11 };

/** A compiled table as the golden files write it: one line per block, then one per entry. */
function goldenText(table: SymbolTable): string {
  const lines = table.blocks.map((b) => `# DB ${b.db} "${b.name}" length ${b.length}${b.instanceOf ? ` instance of ${b.instanceOf}` : ''}`);
  for (const e of table.entries) lines.push([e.name, e.type, e.address, e.byte, e.bit ?? '-', e.size].join(' | '));
  return `${lines.join('\n')}\n`;
}

describe('symbols layout: golden tables from source files', () => {
  const sources = fs.readdirSync(GOLDEN).filter((f) => /\.(db|udt|scl|awl)$/.test(f));

  it('has the golden sources', () => {
    expect(sources).to.include.members([
      'siemens-guideline.db',
      's7netplus-teststruct.db',
      'corners.db',
      'step7.awl',
      'tia-var.db',
      'tia-instance.db',
      'tia-system.db',
    ]);
  });

  for (const file of sources) {
    it(`${file}: every entry at the byte, bit and size of ${file}.expected, with an address that reads back`, () => {
      const blocks = parseBlockSource({ name: file, content: fs.readFileSync(path.join(GOLDEN, file)) });
      const names = blocks.filter((b) => b.kind === 'db' && b.number === undefined).map((b) => b.name);
      const table = compileDeclarations(blocks, [], { db: Object.fromEntries(names.map((n) => [n, GOLDEN_NUMBERS[n]!])) }, asText);
      const expected = path.join(GOLDEN, `${file}.expected`);
      if (process.env.UPDATE_GOLDEN === '1') fs.writeFileSync(expected, goldenText(table));
      expect(goldenText(table)).to.equal(fs.readFileSync(expected, 'utf8'));
      for (const e of table.entries) {
        const tag = parseAddress(e.address!);
        expect([tag.dbNumber, tag.byteOffset, tag.bitOffset, tag.byteLength], e.name).to.deep.equal([e.db, e.byte, e.bit ?? 0, e.size]);
        if (e.kind === 'elementary') expect([tag.type, tag.stringLength], e.name).to.deep.equal([e.dataType, e.stringLength]);
        expect(table.lookup(e.name), e.name).to.equal(e);
      }
    });
  }
});

describe('symbols compileSymbols: files by extension', () => {
  it('compiles a STEP 7 source with a symbol table that names its DB and gives its I/Q/M symbols', () => {
    const sdf = [
      '"Tank                    ","DB     10   ","DB     10  ","tank data"',
      '"Start                   ","E       0.0 ","BOOL      ","start"',
    ].join('\r\n');
    const table = compileSymbols([
      { name: 'step7.awl', content: fs.readFileSync(path.join(GOLDEN, 'step7.awl')) },
      { name: 'Symbols.sdf', content: `${sdf}\r\n` },
    ]);
    expect(table.blocks).to.deep.equal([{ name: 'Tank', db: 10, length: 22, file: 'step7.awl' }]);
    expect(table.lookup('Tank.Motor.Run')?.address).to.equal('DB10.DBX10.0');
    expect(table.lookup('"Start"')?.address).to.equal('I0.0');
    expect(table.suggest('"Tank".Levle')).to.deep.equal(['"Tank".Level']);
  });

  it('refuses a file of a kind it does not read, naming the kinds it does', () => {
    expect(() => compileSymbols([{ name: 'notes.txt', content: '' }])).to.throw(
      SourceError,
      /^notes\.txt:1:1: not a source this compiler reads: .*\.awl.*\.xlsx/,
    );
  });
});

describe('symbols compileSymbols: start values evaluated', () => {
  it('evaluates declarations, UDT defaults and BEGIN (which wins) for the member types', () => {
    const table = compileSymbols([{ name: 'corners.db', content: fs.readFileSync(path.join(GOLDEN, 'corners.db')) }], {
      db: { Corners: 3 },
    });
    const initial = (name: string) => table.lookup(name)?.initial;
    expect(initial('"Corners".Name')).to.equal('corner');
    expect(initial('"Corners".Count')).to.equal(8);
    expect(initial('"Corners".Points[0].X')).to.equal(1.5);
    expect(initial('"Corners".Points[1].X')).to.equal(2.5);
    expect(initial('"Corners".Axis.Target.X')).to.equal(1.5);
    expect([1, 2, 3].map((j) => initial(`"Corners".Matrix[1,${j}]`))).to.deep.equal([1, 2, 3]);
    expect([1, 2, 3].map((j) => initial(`"Corners".Matrix[2,${j}]`))).to.deep.equal([0, 0, 23]);
    expect(initial('"Corners".Flag')).to.equal(undefined);
  });
});

describe('symbols layout: system types (lib/symbols/system-types.ts)', () => {
  it('names the members of a system type as Siemens does and evaluates the BEGIN values for them', () => {
    const table = compileSymbols([{ name: 'tia-system.db', content: fs.readFileSync(path.join(GOLDEN, 'tia-system.db')) }], {
      db: { Conn: 10, Comm: 11 },
    });
    expect(table.blocks.map((b) => [b.name, b.length, b.instanceOf])).to.deep.equal([
      ['Conn', 14, 'TCON_IP_v4'],
      ['Comm', 106, undefined],
    ]);
    expect(table.lookup('"Conn".RemoteAddress.ADDR[1]')).to.include({ address: 'DB10.DBB6', initial: 192 });
    expect(table.lookup('conn.remoteport')).to.include({ address: 'DB10.DBW10:UINT', initial: 2000 });
    expect(table.lookup('"Conn".ActiveEstablished')).to.include({ address: 'DB10.DBX5.0', initial: true });
    expect(table.lookup('"Comm".Links[2].LocalPort')?.address).to.equal('DB11.DBW104:UINT');
  });

  it('takes a UDT of the sources over the system type of the same name', () => {
    const own = udt('TCON_IP_v4', [m('Mine', el('DINT'))]);
    const table = compiled([own, db('C', named('TCON_IP_v4'))], { db: { C: 1 } });
    expect(table.blocks[0]).to.include({ length: 4, instanceOf: '"TCON_IP_v4"' });
    expect(table.entries.map((e) => e.name)).to.deep.equal(['"C".Mine']);
  });

  it('refuses a system type whose standard layout it does not know by name, as a member and as an instance DB', () => {
    const member = refusal([db('T', [m('t', named('IEC_DCOUNTER', at(3, 9)))])]);
    expect(member.message).to.match(
      /^hand\.db:3:9: "T"\.t is of type IEC_DCOUNTER, a system type whose layout .* does not know \(it knows TCON_IP_v4/,
    );
    const instance = refusal([db('T1', named('TONR_TIME'), { at: at(1, 1, 'T1.db') })]);
    expect(instance.message).to.match(
      /^T1\.db:1:1: DB "T1" is an instance of TONR_TIME, a system type whose layout .*read the block by absolute address/,
    );
    // A name that is no system type keeps the refusal of an unknown UDT.
    expect(refusal([db('X', named('NoSuchType'))]).message).to.match(
      /DB "X" is an instance of "NoSuchType", which is not a UDT of the sources/,
    );
  });

  it('lays out IEC timers (16 bytes, the reserve after the bits) and INT counters (6 bytes) inside a DB, and what follows them', () => {
    const table = compiled(
      [
        db('Line', [
          m('Start', el('BOOL')),
          m('Delay', named('IEC_TIMER')),
          m('Off', named('TOF_TIME')),
          m('Count', named('IEC_COUNTER')),
          m('After', el('BYTE')),
        ]),
        db('T1', named('TON_TIME')),
      ],
      { db: { Line: 5, T1: 6 } },
    );
    const address = (name: string) => table.lookup(name)?.address;
    expect(['"Line".Delay.ST', '"Line".Delay.PT', '"Line".Delay.ET'].map(address)).to.deep.equal([
      'DB5.DBD2:TIME',
      'DB5.DBD6:TIME',
      'DB5.DBD10:TIME',
    ]);
    expect(['"Line".Delay.RU', '"Line".Delay.IN', '"Line".Delay.Q'].map(address)).to.deep.equal([
      'DB5.DBX14.0',
      'DB5.DBX14.1',
      'DB5.DBX14.2',
    ]);
    // The next timer starts 16 bytes after the first, not at the word after its bits (16).
    expect(address('"Line".Off.PT')).to.equal('DB5.DBD22:TIME');
    expect(['"Line".Count.CU', '"Line".Count.QD', '"Line".Count.PV', '"Line".Count.CV'].map(address)).to.deep.equal([
      'DB5.DBX34.0',
      'DB5.DBX34.5',
      'DB5.DBW36:INT',
      'DB5.DBW38:INT',
    ]);
    expect(address('"Line".After')).to.equal('DB5.DBB40');
    expect(table.lookup('"Line".Delay')).to.include({ size: 16 });
    expect(table.blocks.map((b) => [b.name, b.length])).to.deep.equal([
      ['Line', 42],
      ['T1', 16],
    ]);
    expect(table.lookup('"T1".Q')?.address).to.equal('DB6.DBX12.2');
  });
});
