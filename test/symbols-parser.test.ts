import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { SourceError } from '../lib/errors';
import type { BlockDecl, DataBlockDecl, MemberDecl, StartValue, TypeDecl, TypeRef } from '../lib/symbols/model';
import { parseBlockSource } from '../lib/symbols/source-parser';

const FIXTURES = path.resolve(__dirname, '../../test/fixtures/symbols/parser');

function fixture(name: string): Buffer {
  return fs.readFileSync(path.join(FIXTURES, name));
}

function parse(content: string | Uint8Array, name = 'test.db'): BlockDecl[] {
  return parseBlockSource({ name, content });
}

/** The SourceError a source throws; fails when it parses. */
function failure(content: string, name = 'bad.db'): SourceError {
  try {
    parse(content, name);
  } catch (err) {
    expect(err).to.be.instanceOf(SourceError);
    return err as SourceError;
  }
  expect.fail(`expected a SourceError for:\n${content}`);
}

function db(blocks: BlockDecl[], name: string): DataBlockDecl {
  const b = blocks.find((x) => x.name === name);
  expect(b?.kind, name).to.equal('db');
  return b as DataBlockDecl;
}

function udt(blocks: BlockDecl[], name: string): TypeDecl {
  const b = blocks.find((x) => x.name === name);
  expect(b?.kind, name).to.equal('type');
  return b as TypeDecl;
}

function members(t: TypeRef): readonly MemberDecl[] {
  expect(t.kind).to.equal('struct');
  return (t as Extract<TypeRef, { kind: 'struct' }>).members;
}

function member(t: TypeRef, name: string): MemberDecl {
  const m = members(t).find((x) => x.name === name);
  expect(m, name).to.not.equal(undefined);
  return m!;
}

/** A TypeRef without positions, to compare shapes. */
function shape(t: TypeRef): unknown {
  switch (t.kind) {
    case 'elementary':
      return t.stringLength ? `${t.type}[${t.stringLength}]` : t.type;
    case 'array':
      return { array: t.dims.map((d) => `${d.low}..${d.high}`).join(','), of: shape(t.element) };
    case 'named':
      return t.number === undefined ? `"${t.name}"` : `${t.name}#${t.number}`;
    case 'struct':
      return Object.fromEntries(t.members.map((m) => [m.name, shape(m.type)]));
  }
}

/** A StartValue as text: literals as written, lists as [n(v), …]. */
function value(v: StartValue | undefined): string {
  if (v === undefined) return '';
  if (v.kind === 'literal') return v.literal.text;
  return `[${v.items.map((i) => (i.repeat === 1 ? value(i.value) : `${i.repeat}(${value(i.value)})`)).join(', ')}]`;
}

describe('symbols: TIA Portal sources (parseBlockSource)', () => {
  const plant = parse(fixture('tia-plant.db'), 'tia-plant.db');

  it('reads every block of a generated source in order, UTF-8 with BOM and CRLF line ends', () => {
    expect(plant.map((b) => `${b.kind} ${b.name}`)).to.deep.equal([
      'type Motor',
      'type Recipe step',
      'db Tank',
      'db Motor_DB',
      'db Conveyor_DB',
    ]);
    expect(plant.every((b) => b.number === undefined)).to.equal(true);
    expect(plant[0]!.at).to.deep.equal({ file: 'tia-plant.db', line: 1, column: 1 });
    expect(plant[2]!.at).to.deep.equal({ file: 'tia-plant.db', line: 23, column: 1 });
  });

  it('reads a UDT: members, types, attributes, start values and trailing comments', () => {
    const motor = udt(plant, 'Motor');
    expect(motor.attributes).to.deep.equal({ VERSION: '0.1' });
    expect(shape(motor.body)).to.deep.equal({ Run: 'BOOL', Speed: 'REAL', Current: 'REAL', Label: 'STRING[20]' });
    const speed = member(motor.body, 'Speed');
    expect(speed.attributes).to.deep.equal({ ExternalAccessible: 'False', ExternalVisible: 'False', ExternalWritable: 'False' });
    expect(value(speed.initial)).to.equal('12.5');
    expect(speed.initial).to.deep.equal({ kind: 'literal', literal: { text: '12.5', at: { file: 'tia-plant.db', line: 5, column: 113 } } });
    expect(speed.comment).to.equal('set point in rpm');
    expect(speed.at).to.deep.equal({ file: 'tia-plant.db', line: 5, column: 7 });
    expect(member(motor.body, 'Run').comment).to.equal('motor runs');
    expect(member(motor.body, 'Current').comment).to.equal('');
    expect(value(member(motor.body, 'Label').initial)).to.equal("'M1'");
    expect(udt(plant, 'Recipe step').attributes.S7_Optimized_Access).to.equal('FALSE');
  });

  it('reads a DB: header, retentivity, quoted names, arrays, nested structs and strings', () => {
    const tank = db(plant, 'Tank');
    expect(tank.attributes).to.deep.equal({ S7_Optimized_Access: 'FALSE', AUTHOR: 'Plant', FAMILY: 'Tanks', NAME: 'Tank', VERSION: '0.1' });
    expect(tank.optimized).to.equal(false);
    expect(tank.retain).to.equal(false);
    expect(shape(tank.body)).to.deep.equal({
      Level: 'REAL',
      'Motor 1': '"Motor"',
      'Speed.Set': 'INT',
      Valves: { array: '1..10', of: 'BOOL' },
      Grid: { array: '-5..5,0..2', of: 'INT' },
      Pumps: { array: '0..3', of: '"Motor"' },
      Step: { array: '1..2', of: { Temp: 'REAL', Hold: 'TIME' } },
      Text: 'STRING[254]',
      WText: 'WSTRING[10]',
      Data: { A: 'DINT', B: 'DATE_AND_TIME', C: 'DTL', D: 'TIME_OF_DAY' },
      Counts: { array: '1..5', of: 'INT' },
      Negative: 'LREAL',
    });
    expect(member(tank.body, 'Level').comment).to.equal('% of capacity');
    expect(member(tank.body, 'Step').comment).to.equal('the two heating steps');
    expect(member(tank.body, 'Data').comment).to.equal('nested');
    const step = member(tank.body, 'Step').type as Extract<TypeRef, { kind: 'array' }>;
    expect(value(member(step.element, 'Hold').initial)).to.equal('T#1m30s');
    const data = member(tank.body, 'Data').type;
    expect(['A', 'B', 'D'].map((n) => value(member(data, n).initial))).to.deep.equal([
      '16#7FFF_FFFF',
      'DT#2024-01-31-12:00:00',
      'TOD#12:00:00.5',
    ]);
    expect(value(member(tank.body, 'WText').initial)).to.equal("WSTRING#'Grüße'");
    expect(value(member(tank.body, 'Negative').initial)).to.equal('-1.5E3');
  });

  it('keeps array start values with their repeat factors', () => {
    const counts = member(db(plant, 'Tank').body, 'Counts');
    expect(counts.initial!.kind).to.equal('list');
    expect(value(counts.initial)).to.equal('[1, 2, 3(0)]');
    const items = (counts.initial as Extract<StartValue, { kind: 'list' }>).items;
    expect(items.map((i) => i.repeat)).to.deep.equal([1, 1, 3]);
  });

  it('reads the BEGIN section: paths as written, positions', () => {
    const tank = db(plant, 'Tank');
    expect(tank.startValues.map((s) => `${s.path} := ${value(s.value)}`)).to.deep.equal([
      'Level := 50.0',
      '"Motor 1".Speed := 1500.0',
      'Step[2].Temp := 1.0',
      'Grid[-5,0] := 7',
    ]);
    expect(tank.startValues[1]!.at).to.deep.equal({ file: 'tia-plant.db', line: 57, column: 4 });
  });

  it('reads instance DBs of a UDT and of an FB as a named type, with block retentivity', () => {
    const motorDb = db(plant, 'Motor_DB');
    expect(shape(motorDb.body)).to.equal('"Motor"');
    expect(motorDb.optimized).to.equal(true);
    expect(motorDb.retain).to.equal(false);
    expect(motorDb.startValues.map((s) => s.path)).to.deep.equal(['Speed']);
    const conveyor = db(plant, 'Conveyor_DB');
    expect(shape(conveyor.body)).to.equal('"Conveyor"');
    expect(conveyor.retain).to.equal(true);
    expect(conveyor.startValues).to.deep.equal([]);
  });

  it('skips the code blocks of an .scl file and reads lower-case keywords, tabs and all comment kinds', () => {
    const blocks = parse(fixture('tia-mixed.scl'), 'tia-mixed.scl');
    expect(blocks.map((b) => b.name)).to.deep.equal(['Conveyor_DB', 'Settings']);
    const settings = db(blocks, 'Settings');
    expect(settings.attributes).to.deep.equal({ TITLE: 'Settings of line 2 (hand-written)', VERSION: '0.1' });
    expect(shape(settings.body)).to.deep.equal({
      Enabled: 'BOOL',
      Limit: 'INT',
      Ratio: 'REAL',
      Letter: 'CHAR',
      Wide: 'WCHAR',
      Phrase: 'STRING[30]',
      Big: 'LINT',
      Dur: 'LTIME',
      Day: 'DATE',
      Mask: 'WORD',
      Oct: 'BYTE',
      Timer1: 'S5TIME',
    });
    const body = settings.body;
    expect(member(body, 'Enabled').comment).to.equal('on by default');
    expect(member(body, 'Limit').comment).to.equal('a (* is no nesting');
    expect(member(body, 'Limit').at).to.deep.equal({ file: 'tia-mixed.scl', line: 26, column: 3 });
    expect(value(member(body, 'Phrase').initial)).to.equal("'it''s $'ok$' $$5$N'");
    expect(value(member(body, 'Big').initial)).to.equal('LINT#-9223372036854775808');
    expect(settings.startValues.map((s) => s.path)).to.deep.equal(['Ratio']);
  });

  it('decides S7_Optimized_Access when a source does not write it: quoted TIA name optimized, DB n standard', () => {
    const settings = db(parse(fixture('tia-mixed.scl')), 'Settings');
    expect(settings.attributes).to.not.have.property('S7_Optimized_Access');
    expect(settings.optimized).to.equal(true);
    const written = parse(`DATA_BLOCK "A" { S7_Optimized_Access := 'false' } STRUCT x : Int; END_STRUCT; BEGIN END_DATA_BLOCK`);
    expect((written[0] as DataBlockDecl).optimized).to.equal(false);
    const numbered = parse(`DATA_BLOCK DB 3 STRUCT x : INT; END_STRUCT; BEGIN END_DATA_BLOCK`);
    expect((numbered[0] as DataBlockDecl).optimized).to.equal(false);
    const mixed = parse(
      `TYPE UDT 1 STRUCT x : INT; END_STRUCT; END_TYPE DATA_BLOCK "Sym" STRUCT x : INT; END_STRUCT; BEGIN END_DATA_BLOCK`,
    );
    expect((mixed[1] as DataBlockDecl).optimized, 'a STEP 7 file (numbers in its headers)').to.equal(false);
    const symbolic = `DATA_BLOCK "Sym" STRUCT x : INT; END_STRUCT; BEGIN END_DATA_BLOCK`;
    const awl = parseBlockSource({ name: 'Sym.AWL', content: symbolic })[0] as DataBlockDecl;
    expect(awl.optimized, 'a STEP 7 file (named .awl)').to.equal(false);
    expect((parseBlockSource({ name: 'Sym.db', content: symbolic })[0] as DataBlockDecl).optimized).to.equal(true);
  });

  it('reads UTF-16LE with BOM, tabs and a source given as a string with a BOM alike', () => {
    const text = fixture('tia-plant.db').toString('utf8');
    const utf16 = Buffer.concat([Buffer.from([0xff, 0xfe]), Buffer.from(text.replace(/^\uFEFF/, ''), 'utf16le')]);
    expect(parse(utf16, 'tia-plant.db')).to.deep.equal(plant);
    expect(parse(text, 'tia-plant.db')).to.deep.equal(plant);
    expect(parse(text.replace(/\r\n/g, '\n').replace(/ {3}/g, '\t'), 'tia-plant.db').map((b) => b.name)).to.deep.equal(
      plant.map((b) => b.name),
    );
  });

  it('reads a source without BOM that is not UTF-8 as Windows-1252 (what STEP 7 writes)', () => {
    const bytes = Buffer.from(`DATA_BLOCK DB 1 STRUCT x : INT ; //Füllstand\n END_STRUCT ; BEGIN END_DATA_BLOCK`, 'latin1');
    const [b] = parse(bytes) as DataBlockDecl[];
    expect(member(b!.body, 'x').comment).to.equal('Füllstand');
  });

  it('an empty source (or one of comments only) has no blocks', () => {
    expect(parse('')).to.deep.equal([]);
    expect(parse('// nothing\n(* here *)')).to.deep.equal([]);
  });
});

describe('symbols: STEP 7 AWL sources (parseBlockSource)', () => {
  const blocks = parse(fixture('step7-tank.awl'), 'step7-tank.awl');

  it('reads numbered and symbolic blocks of a Windows-1252 source with CRLF line ends', () => {
    expect(blocks.map((b) => `${b.kind} ${b.name} ${b.number ?? '-'}`)).to.deep.equal([
      'type UDT1 1',
      'db DB10 10',
      'db DB11 11',
      'db DB12 12',
      'db Recipe -',
    ]);
    expect(blocks.filter((b) => b.kind === 'db').map((b) => (b as DataBlockDecl).optimized)).to.deep.equal([false, false, false, false]);
    const udt1 = udt(blocks, 'UDT1');
    expect(udt1.attributes).to.deep.equal({ TITLE: '', VERSION: '0.0' });
    expect(shape(udt1.body)).to.deep.equal({ Speed: 'REAL', Run: 'BOOL', Name: 'STRING[20]' });
    expect(member(udt1.body, 'Speed').comment).to.equal('Drehzahl-Sollwert für den Motor');
  });

  it('reads a DB: header, spaced brackets, UDT references and the start value literals STEP 7 writes', () => {
    const db10 = db(blocks, 'DB10');
    expect(db10.attributes).to.deep.equal({ TITLE: 'Tank data', AUTHOR: 'PLANT', FAMILY: 'TANKS', NAME: 'TANK10', VERSION: '0.1' });
    expect(db10.retain).to.equal(undefined);
    expect(shape(db10.body)).to.deep.equal({
      Level: 'REAL',
      Count: 'DINT',
      Flags: 'WORD',
      Mask: 'DWORD',
      Small: 'BYTE',
      Delay: 'S5TIME',
      Run_Time: 'TIME',
      Stamp: 'DATE_AND_TIME',
      Text: 'STRING[20]',
      Valves: { array: '1..10', of: 'BOOL' },
      Motor: 'UDT1#1',
      Motors: { array: '1..2', of: 'UDT1#1' },
      Pair: 'WORD',
      Grid: { array: '-2..2,1..3', of: 'INT' },
      Data: { A: 'INT', B: 'CHAR' },
      Table: { array: '1..3', of: 'INT' },
      Zeros: { array: '1..8', of: 'INT' },
    });
    const initial = (name: string) => value(member(db10.body, name).initial);
    expect(['Level', 'Count', 'Flags', 'Mask', 'Small', 'Delay', 'Run_Time', 'Stamp', 'Text', 'Pair'].map(initial)).to.deep.equal([
      '1.000000e+000',
      'L#10',
      'W#16#FF',
      'DW#16#FFFF0000',
      'B#16#FF',
      'S5T#1S',
      'T#1S',
      'DT#90-1-1-0:0:0.000',
      "'abc'",
      'B#(1, 2)',
    ]);
    expect(initial('Table'), 'a list without brackets').to.equal('[1, 2, 3]');
    expect(initial('Zeros'), 'a repeat without brackets').to.equal('[8(0)]');
    expect(member(db10.body, 'Level').comment).to.equal('Level in %');
    expect(member(db10.body, 'Data').comment).to.equal('a nested structure');
    expect(member(db10.body, 'Valves').comment).to.equal('');
  });

  it('reads the BEGIN section of a STEP 7 DB', () => {
    expect(db(blocks, 'DB10').startValues.map((s) => `${s.path} := ${value(s.value)}`)).to.deep.equal([
      'Level := 1.000000e+000',
      'Count := L#10',
      'Valves[1] := TRUE',
      'Valves[2] := FALSE',
      'Motor.Speed := 0.000000e+000',
      'Motors[2].Run := TRUE',
      'Grid[-2,1] := 4',
    ]);
  });

  it('reads instance DBs of UDT n and FB n, and a symbolic DB with a symbolic UDT', () => {
    expect(shape(db(blocks, 'DB11').body)).to.equal('UDT1#1');
    expect(db(blocks, 'DB11').startValues.map((s) => s.path)).to.deep.equal(['Speed', 'Run', 'Name']);
    // No number: a numbered named type is a UDT, and DB 12 is no instance of UDT 5.
    expect(db(blocks, 'DB12').body).to.deep.equal({ kind: 'named', name: 'FB5', at: { file: 'step7-tank.awl', line: 68, column: 2 } });
    expect(shape(db(blocks, 'Recipe').body)).to.deep.equal({ Steps: { array: '1..3', of: '"Step"' }, Name: 'STRING[16]' });
  });

  it('takes the glued forms DB10, UDT1 and the type aliases DT and TOD', () => {
    const [t, d] = parse('TYPE UDT2 STRUCT a : DT ; b : tod ; END_STRUCT ; END_TYPE DATA_BLOCK DB10 UDT2 BEGIN END_DATA_BLOCK');
    expect([t!.name, t!.number, d!.name, d!.number]).to.deep.equal(['UDT2', 2, 'DB10', 10]);
    expect(shape((t as TypeDecl).body)).to.deep.equal({ a: 'DATE_AND_TIME', b: 'TIME_OF_DAY' });
    expect(shape((d as DataBlockDecl).body)).to.equal('UDT2#2');
  });

  it('keeps system types (IEC timers, DB_ANY) and TIMER/COUNTER as types for the layout to judge', () => {
    const [b] = parse('DATA_BLOCK "D" STRUCT t : IEC_TIMER; a : DB_ANY; c : Counter; d : Timer; END_STRUCT; BEGIN END_DATA_BLOCK');
    expect(shape((b as DataBlockDecl).body)).to.deep.equal({ t: '"IEC_TIMER"', a: '"DB_ANY"', c: 'COUNTER', d: 'TIMER' });
    const [inst] = parse('DATA_BLOCK "T1" TON_TIME BEGIN END_DATA_BLOCK');
    expect(shape((inst as DataBlockDecl).body)).to.equal('"TON_TIME"');
  });
});

describe('symbols: the VAR form TIA Portal writes today', () => {
  it('reads a DB of several VAR sections (VAR, VAR RETAIN) as one block of members, with per-member attributes', () => {
    const blocks = parse(fixture('tia-var.db'), 'tia-var.db');
    const d = db(blocks, 'Mixed');
    expect(d.retain).to.equal(false);
    expect(d.optimized).to.equal(true);
    expect(shape(d.body)).to.deep.equal({ Speed: 'REAL', Recipe: 'DTL', Total: 'DINT', Steps: { First: 'INT' } });
    expect(member(d.body, 'Recipe').attributes).to.deep.equal({
      InstructionName: 'DTL',
      LibVersion: '1.0',
      ExternalAccessible: 'False',
      ExternalVisible: 'False',
      ExternalWritable: 'False',
    });
    expect(member(d.body, 'Total').comment).to.equal('retentive');
    expect(member(d.body, 'Total').at).to.deep.include({ line: 10, column: 7 });
    expect(d.startValues.map((v) => v.path)).to.deep.equal(['Speed']);
  });

  it('leaves out the members of VAR CONSTANT (no data of the block) and takes a ; after END_VAR', () => {
    const d = db(parse('DATA_BLOCK "D"\nVAR\n  a : Int;\nEND_VAR;\nVAR CONSTANT\n  N : Int := 3;\nEND_VAR\nBEGIN\nEND_DATA_BLOCK'), 'D');
    expect(members(d.body).map((m) => m.name)).to.deep.equal(['a']);
  });

  it('reads an instance DB of a type TIA writes unquoted, whatever its name (looked up later, sources first)', () => {
    const d = db(parse('DATA_BLOCK "conn"\nNON_RETAIN\nTCON_PAR\n\nBEGIN\nEND_DATA_BLOCK'), 'conn');
    expect(shape(d.body)).to.equal('"TCON_PAR"');
  });
});

describe('symbols: declarations in detail', () => {
  it('takes RETAIN / NON_RETAIN before a member, and a member named Retain', () => {
    const [t] = parse('TYPE "T" STRUCT RETAIN a : Int; NON_RETAIN "b c" : Bool; Retain : Bool; END_STRUCT; END_TYPE') as TypeDecl[];
    expect(shape(t!.body)).to.deep.equal({ a: 'INT', 'b c': 'BOOL', Retain: 'BOOL' });
  });

  it('reads lists, nested lists and repeats of lists in BEGIN and in declarations', () => {
    const source = `DATA_BLOCK "D"
STRUCT
  A : Array[1..6] of Int := [2(1, 2), 2(0)];
  B : Array[1..2, 1..2] of Int := [[1, 2], [3, 4]];
END_STRUCT;
BEGIN
  A := [6(7)];
  B[1, 2] := -16#10;
END_DATA_BLOCK`;
    const [d] = parse(source) as DataBlockDecl[];
    expect(value(member(d!.body, 'A').initial)).to.equal('[2([1, 2]), 2(0)]');
    expect(value(member(d!.body, 'B').initial)).to.equal('[[1, 2], [3, 4]]');
    expect(d!.startValues.map((s) => `${s.path} := ${value(s.value)}`)).to.deep.equal(['A := [6(7)]', 'B[1,2] := -16#10']);
  });

  it('refuses nesting deeper than 64 levels with a SourceError, not a stack overflow', () => {
    const deep = `TYPE "T" STRUCT ${'a : Struct '.repeat(100_000)}`;
    expect(failure(deep).message).to.match(/a is nested deeper than 64 levels/);
    expect(failure(`TYPE "T" STRUCT a : Array[1..2] of Int := ${'['.repeat(100_000)}`).message).to.match(/nested deeper than 64 levels/);
    expect(failure(`TYPE "T" STRUCT a : Array[1..2] of Int := ${'2('.repeat(100_000)}`).message).to.match(/nested deeper than 64 levels/);
    const fine = `TYPE "T" STRUCT ${'a : Struct '.repeat(60)}x : Int; ${'END_STRUCT; '.repeat(60)}END_STRUCT; END_TYPE`;
    expect(parse(fine)).to.have.length(1);
  });

  it('reads a 10,000-member DB without trouble', () => {
    const lines = Array.from({ length: 10_000 }, (_, i) => `   m${i} : Real := ${i}.5;   // member ${i}`);
    const [d] = parse(`DATA_BLOCK "Big"\nSTRUCT\n${lines.join('\n')}\nEND_STRUCT;\nBEGIN\nEND_DATA_BLOCK`) as DataBlockDecl[];
    expect(members(d!.body)).to.have.length(10_000);
    expect(member(d!.body, 'm9999').comment).to.equal('member 9999');
  });
});

describe('symbols: source errors name the place and the problem', () => {
  const cases: [name: string, source: string, line: number, column: number, message: RegExp][] = [
    [
      'a missing semicolon',
      'TYPE "T"\nSTRUCT\n  Speed : Real\n  Run : Bool;\nEND_STRUCT;\nEND_TYPE',
      4,
      3,
      /expected ';' after the declaration of Speed, found Run/,
    ],
    [
      'an unterminated comment',
      'TYPE "T"\nSTRUCT\n    (* open\n  Run : Bool;\nEND_STRUCT;\nEND_TYPE',
      3,
      5,
      /unterminated comment started at 3:5/,
    ],
    ['an unterminated /* comment', 'TYPE "T"\nSTRUCT\n /* open\n', 3, 2, /unterminated comment started at 3:2/],
    [
      'a missing END_STRUCT',
      'TYPE "T"\nSTRUCT\n  Run : Bool;\n  Inner : Struct\n    x : Int;\nEND_STRUCT;\nEND_TYPE',
      7,
      1,
      /END_STRUCT missing for STRUCT opened at 2:1/,
    ],
    [
      'a missing END_STRUCT before BEGIN',
      'DATA_BLOCK "D"\n  STRUCT\n  x : Int;\nBEGIN\nEND_DATA_BLOCK',
      4,
      1,
      /END_STRUCT missing for STRUCT opened at 2:3, found BEGIN/,
    ],
    [
      'a missing END_DATA_BLOCK',
      'DATA_BLOCK "D"\nSTRUCT x : Int; END_STRUCT;\nBEGIN\n x := 1;\n',
      5,
      1,
      /END_DATA_BLOCK missing for DATA_BLOCK D opened at 1:1/,
    ],
    ['a missing END_TYPE', 'TYPE "T"\nSTRUCT x : Int; END_STRUCT;\nTYPE "U"', 3, 1, /END_TYPE missing for TYPE T opened at 1:1/],
    [
      'a misspelt type',
      'TYPE "T"\nSTRUCT\n  Level : Reel;\nEND_STRUCT;\nEND_TYPE',
      3,
      11,
      /unknown type Reel for member Level \(did you mean REAL\?\)/,
    ],
    [
      'an unknown unquoted type',
      'TYPE "T"\nSTRUCT\n  M : Motor;\nEND_STRUCT;\nEND_TYPE',
      3,
      7,
      /unknown type Motor for member M \(a UDT is written in quotes/,
    ],
    ['a VARIANT', 'TYPE "T"\nSTRUCT\n  P : Variant;\nEND_STRUCT;\nEND_TYPE', 3, 7, /member P has the type Variant/],
    ['a POINTER', 'DATA_BLOCK DB 1\nSTRUCT\n  P : POINTER ;\nEND_STRUCT ;\nBEGIN\nEND_DATA_BLOCK', 3, 7, /member P has the type POINTER/],
    ['an ANY', 'DATA_BLOCK DB 1\nSTRUCT\n  P : ANY ;\nEND_STRUCT ;\nBEGIN\nEND_DATA_BLOCK', 3, 7, /member P has the type ANY/],
    [
      'a missing colon',
      'TYPE "T"\nSTRUCT\n  Level Real;\nEND_STRUCT;\nEND_TYPE',
      3,
      9,
      /expected ':' and a type after the member name Level, found Real/,
    ],
    [
      'reversed array bounds',
      'TYPE "T"\nSTRUCT\n  A : Array[5..1] of Int;\nEND_STRUCT;\nEND_TYPE',
      3,
      13,
      /ARRAY bounds 5\.\.1 of A are reversed/,
    ],
    ['a missing OF', 'TYPE "T"\nSTRUCT\n  A : Array[1..2] Int;\nEND_STRUCT;\nEND_TYPE', 3, 19, /expected OF and the element type/],
    [
      'a string too long',
      'TYPE "T"\nSTRUCT\n  S : String[255];\nEND_STRUCT;\nEND_TYPE',
      3,
      14,
      /STRING\[255\] of S: the length must be 1\.\.254/,
    ],
    [
      'a wstring too long',
      'TYPE "T"\nSTRUCT\n  S : WString[16383];\nEND_STRUCT;\nEND_TYPE',
      3,
      15,
      /WSTRING\[16383\] of S: the length must be 1\.\.16382/,
    ],
    [
      'a duplicate member',
      'TYPE "T"\nSTRUCT\n  A : Int;\n  a : Real;\nEND_STRUCT;\nEND_TYPE',
      4,
      3,
      /a is declared twice in this STRUCT \(first at 3:3\)/,
    ],
    ['an unterminated string', 'TYPE "T"\nSTRUCT\n  S : String := \'abc;\nEND_STRUCT;\nEND_TYPE', 3, 17, /unterminated string/],
    ['an unterminated name', 'TYPE "T\nSTRUCT', 1, 6, /unterminated name/],
    ['a stray character', 'TYPE "T"\nSTRUCT\n  A : Int; ?\nEND_STRUCT;\nEND_TYPE', 3, 12, /unexpected character \?/],
    ['something that is no block', 'FOO "T"', 1, 1, /expected TYPE or DATA_BLOCK, found FOO/],
    [
      'a start value that is no literal',
      'TYPE "T"\nSTRUCT\n  A : Int := Limit;\nEND_STRUCT;\nEND_TYPE',
      3,
      14,
      /expected a start value for A \(such as 12\.5/,
    ],
    [
      'a bad BEGIN assignment',
      'DATA_BLOCK "D"\nSTRUCT x : Int; END_STRUCT;\nBEGIN\n  x = 1;\nEND_DATA_BLOCK',
      4,
      5,
      /expected ':=' after x, found =/,
    ],
    [
      'a BEGIN assignment without semicolon',
      'DATA_BLOCK "D"\nSTRUCT x : Int; END_STRUCT;\nBEGIN\n  x := 1\nEND_DATA_BLOCK',
      5,
      1,
      /expected ';' after the start value of x, found END_DATA_BLOCK/,
    ],
    [
      'a DB without body',
      'DATA_BLOCK "D"\nVERSION : 0.1\nBEGIN\nEND_DATA_BLOCK',
      3,
      1,
      /expected VAR, STRUCT, or the UDT or FB that DATA_BLOCK D is an instance of, found BEGIN/,
    ],
    [
      "a DB's END_STRUCT without ';'",
      'DATA_BLOCK "D"\n{ S7_Optimized_Access := \'FALSE\' }\n   STRUCT\n      x : Int;\n   END_STRUCT\nBEGIN\nEND_DATA_BLOCK',
      5,
      4,
      /';' missing after END_STRUCT: the STRUCT of DATA_BLOCK D \(opened at 3:4\) must end with END_STRUCT; \(found BEGIN\)/,
    ],
    [
      "a UDT's END_STRUCT without ';'",
      'TYPE "T"\nVERSION : 0.1\n   STRUCT\n      x : Int;\n   END_STRUCT\n\nEND_TYPE',
      5,
      4,
      /';' missing after END_STRUCT: the STRUCT of TYPE T \(opened at 3:4\) must end with END_STRUCT; \(found END_TYPE\)/,
    ],
    [
      'a missing END_VAR',
      'DATA_BLOCK "D"\nNON_RETAIN\n   VAR\n      x : Int;\nBEGIN\nEND_DATA_BLOCK',
      5,
      1,
      /END_VAR missing for VAR opened at 3:4, found BEGIN/,
    ],
    [
      'a member twice in two VAR sections',
      'DATA_BLOCK "D"\n   VAR\n      x : Int;\n   END_VAR\n   VAR RETAIN\n      X : Real;\n   END_VAR\nBEGIN\nEND_DATA_BLOCK',
      6,
      7,
      /X is declared twice in this block \(first at 3:7\)/,
    ],
    [
      'no member name in a VAR section',
      'DATA_BLOCK "D"\n   VAR\n      12 : Int;\n   END_VAR\nEND_DATA_BLOCK',
      3,
      7,
      /expected a member name or END_VAR \(for VAR opened at 2:4\), found 12/,
    ],
    [
      'a bad S7_Optimized_Access',
      'DATA_BLOCK "D"\n{ S7_Optimized_Access := \'yes\' }\nSTRUCT x : Int; END_STRUCT;\nEND_DATA_BLOCK',
      2,
      26,
      /S7_Optimized_Access is 'yes'/,
    ],
    ['a block number 0', 'DATA_BLOCK DB 0\nSTRUCT x : INT; END_STRUCT;\nEND_DATA_BLOCK', 1, 15, /DB number 0 is not a block number/],
    ['a missing end of a skipped FB', 'FUNCTION_BLOCK "F"\nBEGIN\n', 3, 1, /END_FUNCTION_BLOCK missing for FUNCTION_BLOCK opened at 1:1/],
  ];
  for (const [name, source, line, column, message] of cases) {
    it(`${name}: ${line}:${column}`, () => {
      const err = failure(source);
      expect(err.code).to.equal('INVALID_SOURCE');
      expect(err.message).to.match(message);
      expect({ line: err.line, column: err.column, file: err.file }).to.deep.equal({ line, column, file: 'bad.db' });
      expect(err.message.startsWith(`bad.db:${line}:${column}: `)).to.equal(true);
    });
  }
});

describe('symbols: broken sources throw SourceError and nothing else', () => {
  /** A small deterministic PRNG (mulberry32), so a failure can be replayed from its iteration number. */
  function rng(seed: number): () => number {
    let a = seed >>> 0;
    return () => {
      a = (a + 0x6d2b79f5) >>> 0;
      let t = a;
      t = Math.imul(t ^ (t >>> 15), t | 1);
      t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
      return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
    };
  }
  const PIECES = [
    '"',
    "'",
    '(*',
    '*)',
    '/*',
    '//',
    '\n',
    ';',
    ':',
    ':=',
    '[',
    ']',
    '..',
    ',',
    '#',
    'STRUCT',
    'END_STRUCT',
    'BEGIN',
    'END_DATA_BLOCK',
    'Array',
    'OF',
    '{',
    '}',
    '-',
    '1',
    'T#',
    '(',
    ')',
    '\uFEFF',
    '\u0000',
  ];

  it('20,000 random truncations and mutations of valid sources', () => {
    const sources = [fixture('tia-plant.db'), fixture('tia-mixed.scl'), fixture('step7-tank.awl')].map((b) => b.toString('latin1'));
    const random = rng(0x5eed);
    const pick = (n: number) => Math.floor(random() * n);
    let parsed = 0;
    let refused = 0;
    for (let iteration = 0; iteration < 20_000; iteration++) {
      let text = sources[iteration % sources.length]!;
      const edits = 1 + pick(3);
      for (let e = 0; e < edits; e++) {
        const at = pick(text.length + 1);
        switch (pick(4)) {
          case 0:
            text = text.slice(0, at);
            break;
          case 1:
            text = text.slice(0, at) + text.slice(at + 1 + pick(8));
            break;
          case 2:
            text = text.slice(0, at) + PIECES[pick(PIECES.length)]! + text.slice(at);
            break;
          default:
            text = text.slice(0, at) + String.fromCharCode(pick(0x80)) + text.slice(at + 1);
        }
      }
      try {
        parse(text, 'fuzz.db');
        parsed++;
      } catch (err) {
        if (!(err instanceof SourceError)) expect.fail(`iteration ${iteration}: ${String(err)}\n${text}`);
        expect(err.line).to.be.at.least(1);
        expect(err.column).to.be.at.least(1);
        refused++;
      }
    }
    expect(parsed + refused).to.equal(20_000);
    // Both outcomes occur: the mutations are neither all harmless nor all fatal.
    expect(parsed).to.be.greaterThan(500);
    expect(refused).to.be.greaterThan(5000);
  });
});
