/**
 * Blocks with optimized access in the symbol model (issue #25): a TIA
 * source of an optimized DB compiles to its members with their types and
 * structure and no byte, bit or address (golden:
 * test/fixtures/symbols/optimized/), and a name in such a block asked of a
 * protocol that reads by address (s7://, fetchwrite://) fails with
 * OPTIMIZED_BLOCK before anything is sent; the layout check leaves such a
 * block out.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { S7_TAG_SYNTAX } from '../lib/address';
import { OptimizedBlockError, PlcError } from '../lib/errors';
import { FetchWriteClient } from '../lib/fetchwrite/client';
import { FetchWriteServer, type FetchWriteRequestEvent } from '../lib/fetchwrite/server';
import { describe as describeSymbols, resolveAddress } from '../lib/flows/symbol-config';
import { S7Client } from '../lib/s7/client';
import { diagnose } from '../lib/doctor';
import { S7Server, type S7RequestEvent } from '../lib/s7/server';
import { compileSymbols } from '../lib/symbols';
import type { SymbolEntry, SymbolTable } from '../lib/symbols/model';
import { resolveSymbol } from '../lib/symbols/resolve';
import type { LayoutOkEvent } from '../lib/types';
import { parseUrl, type FetchWriteEndpoint, type S7Endpoint } from '../lib/url';

const FIXTURES = path.resolve(__dirname, '../../test/fixtures/symbols/optimized');
const SOURCE = 'tia-optimized.db';
/** The numbers a TIA source does not carry. */
const NUMBERS = { Tank: 1, Recipe: 2, Line: 3 };
const FAST = { backoff: { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 } };

function table(): SymbolTable {
  return compileSymbols([{ name: SOURCE, content: fs.readFileSync(path.join(FIXTURES, SOURCE)) }], { db: NUMBERS });
}

/** One line per block, then one per entry; null written as null. */
function goldenText(t: SymbolTable): string {
  const lines = t.blocks.map((b) => `# DB ${b.db} "${b.name}" length ${String(b.length)}${b.optimized ? ' optimized' : ''}`);
  for (const e of t.entries)
    lines.push(
      [e.name, e.type, e.kind, String(e.address), String(e.byte), String(e.bit), e.size, JSON.stringify(e.initial) ?? '-'].join(' | '),
    );
  return `${lines.join('\n')}\n`;
}

function thrown(f: () => unknown): PlcError {
  try {
    f();
  } catch (err) {
    if (err instanceof PlcError) return err;
    throw err;
  }
  throw new Error('expected a PlcError, nothing was thrown');
}

describe('symbols: blocks with optimized access', () => {
  describe('compiling a TIA source', () => {
    it('the fixture is in the form TIA Portal exports: UTF-8 with a BOM, CRLF line ends, the attribute written', () => {
      const bytes = fs.readFileSync(path.join(FIXTURES, SOURCE));
      expect([...bytes.subarray(0, 3)]).to.deep.equal([0xef, 0xbb, 0xbf]);
      const text = bytes.toString('utf8', 3);
      expect(text.split('\r\n').length).to.be.greaterThan(40);
      expect(text.replace(/\r\n/g, '')).to.not.contain('\n');
      expect(text).to.contain('DATA_BLOCK "Recipe"\r\n{ S7_Optimized_Access := \'TRUE\' }\r\nVERSION : 0.1\r\nNON_RETAIN\r\n');
    });

    it(`lists every member of ${SOURCE} with its type and structure, byte, bit and address null (golden)`, () => {
      const expected = path.join(FIXTURES, `${SOURCE}.expected`);
      const t = table();
      if (process.env.UPDATE_GOLDEN === '1') fs.writeFileSync(expected, goldenText(t));
      expect(goldenText(t)).to.equal(fs.readFileSync(expected, 'utf8'));
    });

    it('says which blocks are optimized: optimized true and length null; a standard block keeps its summary as before', () => {
      expect(table().blocks).to.deep.equal([
        { name: 'Recipe', db: 2, optimized: true, length: null, file: SOURCE },
        { name: 'Line', db: 3, optimized: true, length: null, file: SOURCE },
        { name: 'Tank', db: 1, length: 10, file: SOURCE },
      ]);
    });

    it('finds the members by name as users type them, with children, start values and comments; no entry has an address', () => {
      const t = table();
      const optimized = t.entries.filter((e) => e.db === 2 || e.db === 3);
      expect(optimized).to.have.length(t.entries.length - 5);
      for (const e of optimized) expect([e.byte, e.bit, e.address, e.access], e.name).to.deep.equal([null, null, null, undefined]);
      expect(t.lookup('recipe.heater.power')).to.include({ name: '"Recipe".Heater.Power', type: 'LREAL', dataType: 'LREAL', db: 2 });
      expect(t.lookup('"Recipe".Heater')?.children).to.deep.equal(['"Recipe".Heater.On', '"Recipe".Heater.Power']);
      expect(t.lookup('"Recipe".Pumps')).to.include({ kind: 'array', type: 'ARRAY[0..1] OF "Pump"' });
      expect(t.lookup('"Recipe".Pumps[1].Speed')?.initial).to.equal(1500);
      expect(t.lookup('"Recipe".Temperature')).to.include({ initial: 20.5, comment: 'set point in degrees' });
      expect(t.lookup('"Recipe".Name')).to.include({ type: 'STRING[20]', stringLength: 20 });
      expect(t.lookup('"Recipe".Title')).to.include({ type: 'WSTRING[10]', stringLength: 10 });
      expect(t.lookup('"Recipe".Batch')).to.include({ type: 'DINT' });
      expect(t.suggest('"Recipe".Temprature')).to.deep.equal(['"Recipe".Temperature']);
    });

    it('a standard block beside optimized ones is laid out exactly as when it is compiled alone', () => {
      const text = fs.readFileSync(path.join(FIXTURES, SOURCE), 'utf8');
      const alone = text.replace(/DATA_BLOCK "Recipe"[\s\S]*?END_DATA_BLOCK\r\n\r\nDATA_BLOCK "Line"[\s\S]*?END_DATA_BLOCK\r\n\r\n/, '');
      expect(alone).to.not.contain('"Recipe"');
      const standard = compileSymbols([{ name: SOURCE, content: alone }], { db: { Tank: 1 } });
      const strip = (e: SymbolEntry) => ({ ...e, at: undefined });
      expect(
        table()
          .entries.filter((e) => e.db === 1)
          .map(strip),
      ).to.deep.equal(standard.entries.map(strip));
      expect(table().lookup('"Tank".Pump.Speed')).to.include({ byte: 6, bit: null, address: 'DB1.DBD6:REAL' });
    });

    it('refuses what cannot be laid out as in a standard block, the 64 KB limit in words about optimized access', () => {
      const source = (body: string) =>
        `DATA_BLOCK "Big"\r\n{ S7_Optimized_Access := 'TRUE' }\r\nVERSION : 0.1\r\n   VAR \r\n${body}\r\n   END_VAR\r\n\r\nBEGIN\r\n\r\nEND_DATA_BLOCK\r\n`;
      const compile = (body: string) => () => compileSymbols([{ name: 'Big.db', content: source(body) }], { db: { Big: 4 } });
      expect(thrown(compile('      Values : Array[1..9000] of LReal;')).message).to.equal(
        'Big.db:5:16: "Big".Values ends beyond byte 65535: plcwire compiles a block with optimized access up to 65536 bytes (64 KB) ' +
          'counted as if it had standard access',
      );
      expect(thrown(compile('      Pump : "Nope";')).message).to.match(/^Big\.db:5:14: unknown type "Nope"/);
      expect(compile('      Values : Array[1..8000] of LReal;')().blocks).to.deep.equal([
        { name: 'Big', db: 4, optimized: true, length: null, file: 'Big.db' },
      ]);
    });

    it('tells the editor the same: no address for those entries, the block marked optimized', () => {
      const t = table();
      const d = describeSymbols({ table: t });
      expect(d.entries.find((e) => e.name === '"Recipe".Start')).to.deep.equal({
        name: '"Recipe".Start',
        address: null,
        type: 'BOOL',
        kind: 'elementary',
      });
      expect(d.blocks.filter((b) => b.optimized).map((b) => b.name)).to.deep.equal(['Recipe', 'Line']);
    });
  });

  describe('names over a protocol that reads by address', () => {
    const parse = (a: string) => S7_TAG_SYNTAX.parse(a);

    it('refuses a member, a struct, an array and the whole block with OPTIMIZED_BLOCK naming the tag and the block', () => {
      const t = table();
      for (const name of ['"Recipe".Temperature', 'Recipe.Heater', '"Recipe".Steps', '"Recipe".Pumps[0]', '"Recipe"', 'line.pump.run']) {
        const err = thrown(() => resolveSymbol(t, name, parse));
        expect(err, name).to.be.instanceOf(OptimizedBlockError);
        expect(err.code, name).to.equal('OPTIMIZED_BLOCK');
        expect(err.tag, name).to.equal(name);
        expect(err.message, name)
          .to.contain(' is in DB')
          .and.contain('a block with optimized access')
          .and.contain('over s7plus:// (S7CommPlus)');
        expect(err.message, name).to.contain('untick "Optimized block access"').and.contain('PUT/GET');
      }
      const err = thrown(() => resolveSymbol(t, '"Recipe".Temperature', parse)) as OptimizedBlockError;
      expect(err.message).to.match(/^"Recipe"\.Temperature is in DB2 "Recipe", a block with optimized access/);
      expect([err.block, err.db]).to.deep.equal(['Recipe', 2]);
      // A standard block's names resolve as before.
      expect(resolveSymbol(t, '"Tank".Pump', parse)?.tag).to.include({ address: '"Tank".Pump', dbNumber: 1, byteOffset: 4 });
    });

    it("the editor's row answer for such a name is the refusal, in the client's words", () => {
      const answer = resolveAddress('"Recipe".Start', parse, table());
      expect(answer).to.deep.include({ ok: false, code: 'OPTIMIZED_BLOCK' });
      expect(!answer.ok && answer.message).to.contain('s7plus://');
    });
  });

  describe('an S7 client (s7://) with the table', function () {
    this.timeout(10000);
    let server: S7Server;
    let client: S7Client;
    let requests: S7RequestEvent[];

    beforeEach(async () => {
      const symbols = table();
      server = new S7Server({ port: 0, profile: 's7-300', symbols });
      await server.listen();
      server.memory.area('DB', 1)!.writeFloatBE(42.5, 0);
      client = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?rack=0&slot=2&timeout=1500`) as S7Endpoint, {
        ...FAST,
        symbols,
        strictSymbols: true,
      });
      const ok = new Promise<LayoutOkEvent>((resolve) => client.once('layoutOk', resolve));
      await client.connect();
      // The check on connect compares the standard block only, and finds it as the sources declare it.
      expect((await ok).checks.map((c) => [c.db, c.status])).to.deep.equal([[1, 'ok']]);
      requests = [];
      server.on('request', (r: S7RequestEvent) => requests.push(r));
    });

    afterEach(async () => {
      await client.close();
      await server.close();
    });

    it('reads a standard name and refuses an optimized one in the same call, sending only the standard one', async () => {
      const r = await client.readDetailed(['"Recipe".Temperature', '"Tank".Level', '"Line".Pump']);
      expect(r['"Tank".Level']).to.deep.equal({ ok: true, value: 42.5 });
      for (const name of ['"Recipe".Temperature', '"Line".Pump']) {
        const one = r[name]!;
        expect(one.ok, name).to.equal(false);
        if (!one.ok) expect([one.error.code, one.error.tag], name).to.deep.equal(['OPTIMIZED_BLOCK', name]);
      }
      expect(requests.map((q) => [q.kind, q.items])).to.deep.equal([['read', 1]]);
    });

    it('refuses a write to an optimized member before anything is sent', async () => {
      const err = await client.write({ '"Recipe".Start': true }).then(
        () => undefined,
        (e: unknown) => e as PlcError,
      );
      expect(err?.message).to.contain('"Recipe".Start is in DB2 "Recipe", a block with optimized access');
      expect(requests).to.deep.equal([]);
    });

    it('checkLayout() leaves the optimized blocks out: they have no length to compare', async () => {
      const checks = await client.checkLayout();
      expect(checks.map((c) => ({ db: c.db, status: c.status, declared: c.declared }))).to.deep.equal([
        { db: 1, status: 'ok', declared: 10 },
      ]);
    });
  });

  describe('a FETCH/WRITE client (fetchwrite://) with the table', function () {
    this.timeout(10000);

    it('refuses an optimized member before anything is sent and reads a standard one', async () => {
      const symbols = table();
      const server = new FetchWriteServer({ port: 0, symbols });
      const { fetchPort } = await server.listen();
      const jobs: FetchWriteRequestEvent[] = [];
      const client = new FetchWriteClient(parseUrl(`fetchwrite://127.0.0.1?port=${fetchPort}&timeout=1500`) as FetchWriteEndpoint, {
        ...FAST,
        symbols,
      });
      try {
        await client.connect();
        server.on('request', (r: FetchWriteRequestEvent) => jobs.push(r));
        const r = await client.readDetailed(['"Line".Count', '"Tank".Level']);
        expect(r['"Tank".Level']).to.deep.equal({ ok: true, value: 0 });
        expect(!r['"Line".Count']!.ok && r['"Line".Count']!.error.code).to.equal('OPTIMIZED_BLOCK');
        expect(jobs.map((j) => j.kind)).to.deep.equal(['fetch']);
      } finally {
        await client.close();
        await server.close();
      }
    });
  });

  describe('the doctor on an s7:// URL', function () {
    this.timeout(15000);

    it('a name in an optimized block is a failed step that names the block and says to use s7plus://; a standard name passes', async () => {
      const symbols = table();
      const server = new S7Server({ port: 0, profile: 's7-1500', symbols });
      await server.listen();
      try {
        const url = `s7://127.0.0.1:${server.port}?slot=1&timeout=2000`;
        const r = await diagnose(url, ['"Tank".Level', '"Recipe".Heater.Power', 'DB1,INT0'], { symbols });
        expect(r.ok).to.equal(false);
        // The walk stops at the failed step: DB1,INT0 is not read.
        expect(r.steps.map((x) => x.step).slice(-3)).to.deep.equal(['putget', 'symbol "Tank".Level', 'symbol "Recipe".Heater.Power']);
        const [standard, optimized] = r.steps.slice(-2);
        expect(standard).to.include({ step: 'symbol "Tank".Level', ok: true });
        expect(optimized).to.deep.equal({
          step: 'symbol "Recipe".Heater.Power',
          ok: false,
          detail:
            '"Recipe".Heater.Power is in DB2 "Recipe", a block with optimized access: it has no absolute address to read or write by. ' +
            'Read it by name over s7plus:// (S7CommPlus), or untick "Optimized block access" in the block\'s properties in TIA Portal, download it and use PUT/GET',
          hint:
            `Read this name over S7CommPlus (the PLC finds the member by name, which PUT/GET cannot), with the same sources: try plcwire doctor s7plus://127.0.0.1:${server.port} "<name>" ` +
            "(it shows the PLC's certificate and the fingerprint= that pins it). " +
            'Or switch the DB to standard access: TIA Portal → the DB\'s Properties → Attributes → untick "Optimized block access", compile and download, ' +
            'then export its source again (Generate source from blocks) and read it over s7:// with PUT/GET.',
        });
      } finally {
        await server.close();
      }
    });
  });
});
