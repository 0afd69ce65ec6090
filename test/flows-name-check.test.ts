/**
 * The editor's check of names on a connection that reads by name (lib/flows/name-check.ts, lib/flows/plc-tables.ts,
 * issue #31): a name the S7CommPlus parser leaves for the PLC is answered from the sources, else from the PLC's
 * table (browsed once per question and kept), never as the placeholder's BYTE.
 */
import { expect } from 'chai';
import { createClient } from '../lib/connect';
import { checkAddresses, nameInTable } from '../lib/flows/name-check';
import { PlcTables } from '../lib/flows/plc-tables';
import { compileSymbols, type SymbolTable } from '../lib/symbols';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';

describe('flows: names checked against the PLC table (s7plus://)', () => {
  const table = compileSymbols(SOURCES, { db: DB_NUMBERS });
  const client = createClient('s7plus://127.0.0.1:1');
  const parse = (a: string) => client.tag(a);
  after(() => client.close());

  it('a name of an optimized block answers its type and kind; a typo its closest names; no BYTE placeholder', () => {
    expect(nameInTable('"Recipe".Step', table)).to.include({ ok: true, type: 'INT', kind: 'elementary', address: null });
    const typo = nameInTable('"Recipe".Stepp', table);
    expect(typo).to.include({ ok: false, code: 'INVALID_ADDRESS' });
    expect((typo as { message: string }).message)
      .to.include('did you mean')
      .and.include('"Recipe".Step');
    expect(nameInTable('"Recipe"', table)).to.include({ ok: true, kind: 'struct' });
  });

  it('asks for the PLC table only when a name is not in the sources, once per question', async () => {
    let browses = 0;
    const browse = (): Promise<SymbolTable> => {
      browses++;
      return Promise.resolve(table);
    };
    const fromSources = await checkAddresses(['"Recipe".Step', 'DB1.DBW0:INT', 'DB1.DBX0.0'], { parse, table, browse });
    expect(browses).to.equal(0);
    expect(fromSources['"Recipe".Step']).to.include({ ok: true, type: 'INT' });
    expect(fromSources['DB1.DBW0:INT']).to.include({ ok: true, type: 'INT', count: 1 });
    const browsed = await checkAddresses(['"Recipe".Step', '"Tank".Nope', '"Recipe".Nope'], { parse, browse });
    expect(browses).to.equal(1);
    expect(browsed['"Recipe".Step']).to.include({ ok: true, type: 'INT' });
    expect(browsed['"Tank".Nope']).to.include({ ok: false, code: 'INVALID_ADDRESS' });
    // A broken address the S7CommPlus parser takes for a name: the table has no such name, and the S7 syntax says why.
    const broken = (await checkAddresses(['DB1.DBW'], { parse, browse }))['DB1.DBW'] as { ok: boolean; message: string };
    expect(broken.ok).to.equal(false);
    expect(broken.message).to.include('DB1.DBW');
  });

  it('a browse that fails leaves the names unchecked, saying why; an invalid address keeps the parser error', async () => {
    const browse = () => Promise.reject(new Error('connection refused'));
    const out = await checkAddresses(['"Tank".Level', '"Tank'], { parse, browse });
    expect(out['"Tank".Level']).to.deep.equal({
      ok: true,
      symbol: '"Tank".Level',
      address: null,
      type: '?',
      unchecked: 'the PLC could not be browsed: connection refused',
    });
    expect(out['"Tank']).to.include({ ok: false, code: 'INVALID_ADDRESS' });
  });

  it('PlcTables keeps a browse (or its failure) for a few seconds per PLC, and asks a connected live client instead', async () => {
    let now = 0;
    const tables = new PlcTables(10_000, () => now);
    const url = 's7plus://127.0.0.1:1?timeout=500';
    const first = tables.tableOf(url);
    expect(tables.tableOf(`${url}&maxItems=20`), 'the same PLC').to.equal(first);
    await first.then(
      () => expect.fail('nothing listens on port 1'),
      (err: { code: string }) => expect(err.code).to.be.a('string'),
    );
    now = 10_001;
    expect(tables.tableOf(url)).to.not.equal(first);
    await tables.tableOf(url).catch(() => undefined);
    let asked = 0;
    const live = { state: 'connected', browse: () => (asked++, Promise.resolve(table)) };
    expect(await tables.tableOf(url, { live })).to.equal(table);
    expect(asked).to.equal(1);
  });
});
