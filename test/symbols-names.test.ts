import { expect } from 'chai';
import { PlcError, SourceError } from '../lib/errors';
import type { SymbolEntry } from '../lib/symbols/model';
import { canonicalName, describeNameProblem, NameIndex, splitSymbol } from '../lib/symbols/names';

/** An entry as compileSymbols() makes them; only the name matters to the index. */
function entry(name: string, byte = 0, at?: SymbolEntry['at']): SymbolEntry {
  return {
    name,
    type: 'INT',
    kind: 'elementary',
    dataType: 'INT',
    stringLength: 0,
    area: 'DB',
    db: 1,
    byte,
    bit: null,
    size: 2,
    address: `DB1.DBW${byte}:INT`,
    comment: '',
    ...(at ? { at } : {}),
  };
}

const NAMES = [
  '"Tank".Level',
  '"Tank".Levels',
  '"Tank".Motor.Speed',
  '"Tank".Motor.Run',
  '"Tank"."Motor 1".Run',
  '"Tank"."Speed.Set"',
  '"Recipe".Step[3].Temp',
  '"Recipe".Step[-2]',
  '"Matrix".A[1,2]',
  '"DB10".Member',
  '"Anlage".Füllstand',
  '"Anlage".Maß',
  '"Start button"',
  '"Motor 1".Run',
];

function index(names = NAMES): NameIndex {
  return new NameIndex(names.map((n, i) => entry(n, i * 2)));
}

describe('symbol names (lib/symbols/names.ts)', () => {
  describe('lookup', () => {
    const idx = index();
    const found = (typed: string) => idx.lookup(typed)?.name;

    it('finds each name as TIA writes it', () => {
      for (const name of NAMES) expect(found(name), name).to.equal(name);
    });

    it('takes quotes as optional on plain identifiers', () => {
      expect(found('Tank.Level')).to.equal('"Tank".Level');
      expect(found('"Tank"."Level"')).to.equal('"Tank".Level');
      expect(found('Tank."Motor".Speed')).to.equal('"Tank".Motor.Speed');
      expect(found('Recipe.Step[3].Temp')).to.equal('"Recipe".Step[3].Temp');
    });

    it('requires quotes on names with spaces or dots', () => {
      expect(found('Tank.Motor 1.Run')).to.equal(undefined);
      expect(found('Start button')).to.equal(undefined);
      expect(found('"Start button"')).to.equal('"Start button"');
      // Unquoted, the dot separates members: "Speed.Set" is one member, Speed.Set two.
      expect(found('Tank.Speed.Set')).to.equal(undefined);
      expect(found('Tank."Speed.Set"')).to.equal('"Tank"."Speed.Set"');
    });

    it('matches regardless of case', () => {
      expect(found('TANK.LEVEL')).to.equal('"Tank".Level');
      expect(found('"tank".motor.SPEED')).to.equal('"Tank".Motor.Speed');
      expect(found('"start BUTTON"')).to.equal('"Start button"');
      expect(found('"TANK"."MOTOR 1".run')).to.equal('"Tank"."Motor 1".Run');
    });

    it('folds the case of umlauts and other non-ASCII letters without a locale, composed or not', () => {
      expect(found('Anlage.FÜLLSTAND')).to.equal('"Anlage".Füllstand');
      expect(found('ANLAGE.füllstand')).to.equal('"Anlage".Füllstand');
      // u + combining diaeresis (as some editors and file systems write it) is the same letter.
      expect(found('Anlage.Fu\u0308llstand')).to.equal('"Anlage".Füllstand');
      // The capital sharp s folds to ß; "SS" is another name (simple case folding, as TIA compares).
      expect(found('Anlage.MAẞ')).to.equal('"Anlage".Maß');
      expect(found('Anlage.MASS')).to.equal(undefined);
      // Dotted and dotless i are letters of their own, whatever the process locale.
      expect(found('Tank.Levei')).to.equal(undefined);
      expect(found('Tank.Levıl')).to.equal(undefined);
    });

    it('folds the Greek sigma the same wherever it stands', () => {
      const greek = index(['"Σύστημα".ΟΡΟΣ']);
      expect(greek.lookup('σύστημα.όροσ')).to.equal(undefined); // accents differ: another name
      expect(greek.lookup('σύστημα.ορος')?.name).to.equal('"Σύστημα".ΟΡΟΣ');
      expect(greek.lookup('σύστημα.οροσ')?.name).to.equal('"Σύστημα".ΟΡΟΣ');
    });

    it('ignores spaces inside index brackets, and reads the index as a number', () => {
      expect(found('Recipe.Step[ 3 ].Temp')).to.equal('"Recipe".Step[3].Temp');
      expect(found('Recipe.Step[03].Temp')).to.equal('"Recipe".Step[3].Temp');
      expect(found('Matrix.A[1, 2]')).to.equal('"Matrix".A[1,2]');
      expect(found('Matrix.A[ 1 ,2 ]')).to.equal('"Matrix".A[1,2]');
      expect(found('Recipe.Step[ -2 ]')).to.equal('"Recipe".Step[-2]');
      expect(found('Matrix.A[2,1]')).to.equal(undefined);
      expect(found('Recipe.Step[4].Temp')).to.equal(undefined);
    });

    it('finds a STEP 7 block without a symbol as DB10 or "DB10"', () => {
      expect(found('DB10.Member')).to.equal('"DB10".Member');
      expect(found('"DB10".Member')).to.equal('"DB10".Member');
      expect(found('db10.member')).to.equal('"DB10".Member');
      const step7 = index(['DB10.Member']);
      expect(step7.lookup('"DB10".Member')?.name).to.equal('DB10.Member');
    });

    it('trims the name, but refuses spaces around the dots', () => {
      expect(found('  Tank.Level \t')).to.equal('"Tank".Level');
      expect(found('Tank .Level')).to.equal(undefined);
      expect(found('Tank. Level')).to.equal(undefined);
    });

    it('does not find (and does not throw on) malformed names', () => {
      for (const bad of [
        '',
        '   ',
        '"Tank.Level',
        'Tank."Level',
        'Tank..Level',
        '.Tank',
        'Tank.',
        '""',
        'Tank.""',
        'Recipe.Step[].Temp',
        'Recipe.Step[a].Temp',
        'Recipe.Step[1.5].Temp',
        'Matrix.A[1,]',
        'Recipe.Step[3',
        'Recipe.Step[3]]',
        'Matrix.A[1][2]',
        '"Tank"Level',
        '%MW10',
        '%"Tank".Level',
        'Tank.Le\u0000vel',
        'x'.repeat(2000),
      ]) {
        expect(() => idx.lookup(bad), bad).not.to.throw();
        expect(idx.lookup(bad), bad).to.equal(undefined);
        expect(describeNameProblem(bad), bad).to.be.a('string');
      }
      expect(idx.lookup(42 as unknown as string)).to.equal(undefined);
    });
  });

  describe('describeNameProblem', () => {
    it('says nothing about a well-formed name, found or not', () => {
      expect(describeNameProblem('"Tank".Level')).to.equal(undefined);
      expect(describeNameProblem('Nowhere.Nothing[1, 2]')).to.equal(undefined);
      expect(describeNameProblem('"Anlage".Füllstand')).to.equal(undefined);
    });

    it('names what is malformed and where', () => {
      expect(describeNameProblem('"Tank.Level')).to.equal('unterminated quote at column 1');
      expect(describeNameProblem('Tank."Level')).to.equal('unterminated quote at column 6');
      expect(describeNameProblem('Tank..Level')).to.equal('empty part at column 6');
      expect(describeNameProblem('Tank.')).to.equal('a name cannot end with a dot');
      expect(describeNameProblem('.Tank')).to.equal('a name cannot start with a dot or a bracket');
      expect(describeNameProblem('Tank.""')).to.equal('empty quoted name at column 6');
      expect(describeNameProblem('Tank.Motor 1.Run')).to.equal('"Motor 1" has a space: write it in quotes, "Motor 1"');
      expect(describeNameProblem('Tank.Motor-1')).to.equal('"Motor-1" needs quotes (it is not a plain identifier): write "Motor-1"');
      expect(describeNameProblem('Tank.1st')).to.equal('"1st" needs quotes (it is not a plain identifier): write "1st"');
      expect(describeNameProblem('Step[a]')).to.equal('bad index "[a]": expected integers separated by commas, e.g. [3] or [1,2]');
      expect(describeNameProblem('Step[3')).to.equal('unclosed "[" at column 5');
      expect(describeNameProblem('A[1][2]')).to.equal('a second index group at column 5: write all indices in one, e.g. [1,2]');
      expect(describeNameProblem('"Tank"Level')).to.equal('unexpected "L" at column 7: expected ".", "[" or the end');
      expect(describeNameProblem('%MW10')).to.equal('"%" starts an absolute address (e.g. %MW10), not a symbol name');
      expect(describeNameProblem('')).to.equal('empty name');
    });
  });

  describe('splitSymbol and canonicalName', () => {
    it('splits a name into unquoted parts with their index groups', () => {
      expect(splitSymbol('"Recipe".Step[ 3 ]."Temp 1"')).to.deep.equal([
        { name: 'Recipe' },
        { name: 'Step', index: [3] },
        { name: 'Temp 1' },
      ]);
      expect(splitSymbol('Matrix.A[1, -2]')).to.deep.equal([{ name: 'Matrix' }, { name: 'A', index: [1, -2] }]);
      expect(splitSymbol('"Tank"."Speed.Set"')).to.deep.equal([{ name: 'Tank' }, { name: 'Speed.Set' }]);
      expect(splitSymbol('"Tank.Level')).to.equal(undefined);
    });

    it('writes a name as TIA does: the block always quoted, members only when they need it', () => {
      expect(canonicalName([{ name: 'Tank' }, { name: 'Motor' }])).to.equal('"Tank".Motor');
      expect(canonicalName([{ name: 'Motor 1' }, { name: 'Speed.Set' }])).to.equal('"Motor 1"."Speed.Set"');
      expect(canonicalName([{ name: 'Recipe' }, { name: 'Step', index: [3] }, { name: 'Temp' }])).to.equal('"Recipe".Step[3].Temp');
      expect(canonicalName([{ name: 'M' }, { name: 'A', index: [1, 2] }])).to.equal('"M".A[1,2]');
      expect(canonicalName([{ name: 'Anlage' }, { name: 'Füllstand' }, { name: '1st' }, { name: 'a-b' }])).to.equal(
        '"Anlage".Füllstand."1st"."a-b"',
      );
      expect(canonicalName([{ name: 'Start button' }])).to.equal('"Start button"');
    });

    it('reads back what it writes', () => {
      const parts = [{ name: 'A b' }, { name: 'c.d', index: [-1, 0] }, { name: 'Ölstand' }, { name: '_x9' }];
      expect(splitSymbol(canonicalName(parts))).to.deep.equal(parts);
    });
  });

  describe('names that differ only by case', () => {
    it('are refused when the index is built, at the second one, naming the first', () => {
      const at = (line: number) => ({ file: 'Tank.db', line, column: 5 });
      let err: unknown;
      try {
        new NameIndex([entry('"Tank".Level', 0, at(3)), entry('"Tank".LEVEL', 2, at(4))]);
      } catch (e) {
        err = e;
      }
      expect(err).to.be.instanceOf(SourceError);
      expect((err as SourceError).code).to.equal('INVALID_SOURCE');
      expect((err as SourceError).line).to.equal(4);
      expect((err as SourceError).message).to.equal(
        'Tank.db:4:5: "Tank".LEVEL and "Tank".Level (Tank.db:3:5) differ only by case or spelling; names are matched regardless of case, as in TIA',
      );
    });

    it('are refused also when spelt differently but the same name (quotes, index spaces, umlaut forms)', () => {
      expect(() => new NameIndex([entry('DB10.X'), entry('"DB10"."X"')])).to.throw(PlcError, /differ only by case or spelling/);
      expect(() => new NameIndex([entry('"A".S[1,2]'), entry('"A".S[1, 2]')])).to.throw(PlcError, /differ only/);
      expect(() => new NameIndex([entry('"A".Füll'), entry('"A".Fu\u0308ll')])).to.throw(PlcError, /differ only/);
      expect(() => new NameIndex([entry('"A".X'), entry('"A".X')])).to.throw(PlcError, /"A".X is declared twice/);
    });

    it('are not confused with names that only look alike', () => {
      // A quoted member with a dot and a path of two members are two names.
      const idx = index(['"T".a.b', '"T"."a.b"', '"T".S[1,2]', '"T".S[12]']);
      expect(idx.lookup('T.a.b')?.name).to.equal('"T".a.b');
      expect(idx.lookup('T."a.b"')?.name).to.equal('"T"."a.b"');
      expect(idx.lookup('T.S[12]')?.name).to.equal('"T".S[12]');
    });

    it('a malformed entry name is refused when the index is built', () => {
      expect(() => new NameIndex([entry('"Tank.Level', 0, { file: 'a.db', line: 1, column: 1 })])).to.throw(
        SourceError,
        'a.db:1:1: symbol name "\\"Tank.Level" is malformed: unterminated quote at column 1',
      );
    });
  });

  describe('suggest', () => {
    const idx = index();

    it('proposes the closest names of the same block, the fewest edits away', () => {
      expect(idx.suggest('"Tank".Levle')).to.deep.equal(['"Tank".Level']);
      expect(idx.suggest('"Tank".Lvel')).to.deep.equal(['"Tank".Level']);
      expect(idx.suggest('"Tank".Levelz')).to.deep.equal(['"Tank".Level', '"Tank".Levels']);
      expect(idx.suggest('Tank.Motor.Sped')).to.deep.equal(['"Tank".Motor.Speed']);
      expect(idx.suggest('Tank.Levle', 1)).to.deep.equal(['"Tank".Level']);
    });

    it('prefers siblings over an equally close name elsewhere in the block, and looks there when no sibling is close', () => {
      const near = index(['"B".X.Aa', '"B".Y.Ac', '"B".Y.Ad', '"B".Y.Ae', '"B".Y.Af']);
      expect(near.suggest('B.Y.Aa')).to.deep.equal(['"B".Y.Ac', '"B".Y.Ad', '"B".Y.Ae']);
      expect(near.suggest('B.Y.Aa', 5)).to.deep.equal(['"B".Y.Ac', '"B".Y.Ad', '"B".Y.Ae', '"B".Y.Af']);
      expect(near.suggest('B.Z.Aa')).to.deep.equal(['"B".X.Aa']);
      expect(index(['"B".X.Speed', '"B".Y.Run']).suggest('B.Y.Speed')).to.deep.equal(['"B".X.Speed']);
    });

    it('finds the block when the block is misspelt', () => {
      expect(idx.suggest('"Tnak".Level')).to.deep.equal(['"Tank".Level']);
      expect(idx.suggest('"Start buton"')).to.deep.equal(['"Start button"']);
    });

    it('helps with a malformed name: missing quotes, an unterminated quote', () => {
      expect(idx.suggest('Tank.Motor 1.Run')).to.deep.equal(['"Tank"."Motor 1".Run']);
      expect(idx.suggest('"Tank.Level')[0]).to.equal('"Tank".Level');
      expect(idx.suggest('Start button')).to.deep.equal(['"Start button"']);
    });

    it('proposes nothing when nothing is close, and respects max', () => {
      expect(idx.suggest('"Tank".Completely.Different')).to.deep.equal([]);
      expect(idx.suggest('Nowhere.Level')).to.deep.equal([]);
      expect(idx.suggest('Tank.Levle', 0)).to.deep.equal([]);
      expect(idx.suggest('')).to.deep.equal([]);
      expect(idx.suggest('%MW10')).to.deep.equal([]);
    });
  });

  describe('size', () => {
    it('builds an index of 100,000 entries and answers lookups and suggestions over it', () => {
      // Speed is measured in bench/; this checks that a large table works at all and stays exact.
      const names: string[] = [];
      for (let b = 0; b < 100; b++) for (let m = 0; m < 1000; m++) names.push(`"Block ${b}".Member_${m}.Value`);
      const big = index(names);
      expect(big.lookup('"BLOCK 42".member_999.value')?.name).to.equal('"Block 42".Member_999.Value');
      expect(big.suggest('"Block 42".Member_999.Valeu')).to.deep.equal(['"Block 42".Member_999.Value']);
    });
  });
});
