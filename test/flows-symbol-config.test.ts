/** The connection node's symbol configuration, without Node-RED: sources from the flow, the key, compile, describe, resolve. */
import { expect } from 'chai';
import { createClient, parseAddress } from '../lib';
import { compile, compileCached, describe as describeSymbols, resolveAddress, symbolsKey } from '../lib/flows/symbol-config';

const TANK_DB = `DATA_BLOCK "Tank"
{ S7_Optimized_Access := 'FALSE' }
VERSION : 0.1
NON_RETAIN
   STRUCT
      Level : Real;
      Count : Int;
   END_STRUCT;
BEGIN
END_DATA_BLOCK
`;

const config = (extra: Record<string, unknown> = {}) => ({
  symbolSources: [{ name: 'Tank.db', content: TANK_DB }],
  dbNumbers: [{ block: 'Tank', db: 3 }],
  strictSymbols: false,
  ...extra,
});

describe('flows: symbol configuration', () => {
  it('no sources: no key, no table, no problems', () => {
    expect(symbolsKey(undefined)).to.equal('');
    expect(symbolsKey({ symbolSources: [{ name: '  ', content: TANK_DB }] })).to.equal('');
    expect(compile({ symbolSources: 'Tank.db' })).to.deep.equal({});
    expect(compileCached({})).to.deep.equal({});
  });

  it('the key changes with the content, the block numbers and strictness, not with the order of the numbers', () => {
    const key = symbolsKey(config());
    expect(key).to.match(/^[0-9a-f]{64}$/);
    expect(symbolsKey(config({ strictSymbols: true }))).to.not.equal(key);
    expect(symbolsKey(config({ dbNumbers: [{ block: 'Tank', db: 4 }] }))).to.not.equal(key);
    expect(symbolsKey(config({ symbolSources: [{ name: 'Tank.db', content: TANK_DB + ' ' }] }))).to.not.equal(key);
    const two = [
      { block: 'A', db: 1 },
      { block: 'Tank', db: 3 },
    ];
    expect(symbolsKey(config({ dbNumbers: two }))).to.equal(symbolsKey(config({ dbNumbers: [...two].reverse() })));
  });

  it('base64 sources are decoded; block numbers outside 1..65535 are dropped', () => {
    const b64 = config({ symbolSources: [{ name: 'Tank.db', content: Buffer.from(TANK_DB).toString('base64'), encoding: 'base64' }] });
    expect(compile(b64).table!.lookup('"Tank".Count')!.address).to.equal('DB3.DBW4:INT');
    const { table, problems } = compile(config({ dbNumbers: [{ block: 'Tank', db: 0 }] }));
    // Without its number a TIA source's DB cannot be placed: the compile says so.
    expect(table).to.equal(undefined);
    expect(problems![0]!.message).to.match(/Tank/);
  });

  it('a compile error names the file and line', () => {
    const { problems } = compile(config({ symbolSources: [{ name: 'Tank.db', content: TANK_DB.replace('Int;', 'Integr;') }] }));
    expect(problems).to.have.length.greaterThan(0);
    expect(problems![0]).to.include({ code: 'INVALID_SOURCE', file: 'Tank.db', line: 7 });
  });

  it('the cache answers the same sources with the same result; describe lists entries and blocks', () => {
    const first = compileCached(config());
    expect(compileCached(config())).to.equal(first);
    const d = describeSymbols(first);
    expect(d.errors).to.deep.equal([]);
    expect(d.blocks.map((b) => [b.name, b.db, b.length])).to.deep.equal([['Tank', 3, 6]]);
    expect(d.entries.find((e) => e.name === '"Tank".Level')).to.deep.equal({
      name: '"Tank".Level',
      address: 'DB3.DBD0:REAL',
      type: 'REAL',
      kind: 'elementary',
    });
    expect(describeSymbols({ problems: [{ code: 'X', message: 'm' }] })).to.deep.equal({
      blocks: [],
      entries: [],
      types: [],
      errors: [{ code: 'X', message: 'm' }],
    });
  });

  it('resolves an address first, then a name, with a hint for a near miss', () => {
    const { table } = compile(config());
    expect(resolveAddress('DB3.DBW4', parseAddress, table)).to.deep.equal({ ok: true, type: 'WORD', count: 1 });
    expect(resolveAddress('"Tank".Count', parseAddress, table)).to.deep.equal({
      ok: true,
      symbol: '"Tank".Count',
      address: 'DB3.DBW4:INT',
      type: 'INT',
      kind: 'elementary',
    });
    const miss = resolveAddress('"Tank".Levl', parseAddress, table);
    expect(miss.ok).to.equal(false);
    expect(miss)
      .to.have.property('message')
      .that.matches(/^unknown symbol "Tank"\.Levl; did you mean "Tank"\.Level\?/);
    const none = resolveAddress('Tank.Level', parseAddress, undefined);
    expect(none).to.include({ ok: false, code: 'INVALID_ADDRESS' });
    // A whole DB by its name, as a client reads it (the editor called it unknown).
    expect(resolveAddress('"Tank"', parseAddress, table)).to.deep.include({ ok: true, symbol: '"Tank"', kind: 'struct' });
    // The client's words for an unknown name: what is wrong with the text as an address too.
    const client = createClient('s7://127.0.0.1', { symbols: table! });
    const said = (() => {
      try {
        client.tag('Tank.Nope');
      } catch (err) {
        return (err as Error).message;
      }
    })();
    expect(resolveAddress('Tank.Nope', parseAddress, table)).to.deep.equal({ ok: false, code: 'INVALID_ADDRESS', message: said });
    expect(said).to.match(/^unknown symbol Tank\.Nope; "Tank" has no such member/);
  });
});
