/**
 * The editor's questions answered by the library (lib/flows/editor-answers.ts): the connection node serves them,
 * these tests ask them without Node-RED. The endpoints themselves are tested in test/nodes/editor.test.ts,
 * test/nodered-symbols.test.ts and test/nodes/connection-s7plus.test.ts.
 */
import { expect } from 'chai';
import { csvExportAnswer, csvImportAnswer, duplicatesAnswer, symbolConfig, urlAnswer, validateAnswer } from '../lib/flows/editor-answers';

describe('flows: the editor answers', () => {
  it("urlAnswer formats fields with each scheme's own defaults and parses a URL into them, with the PLC key", () => {
    const parsed = urlAnswer({ url: 's7://10.0.0.5' });
    expect(parsed).to.include({ ok: true });
    const again = urlAnswer({ endpoint: (parsed as { endpoint: object }).endpoint });
    expect(again).to.deep.equal(parsed);
    const bad = urlAnswer({ url: 'mqtt://x' });
    expect(bad).to.include({ ok: false, code: 'INVALID_URL' });
  });

  it('validateAnswer: an invalid URL answers no addresses; an s7:// URL answers each address with its parser', async () => {
    expect(await validateAnswer({ url: 'nope://', addresses: ['DB1.DBW0'] })).to.deep.include({ results: {} });
    const answer = await validateAnswer({ url: 's7://127.0.0.1', addresses: ['DB1.DBW0:INT', 'DB1.DBW'] });
    expect(answer.url).to.deep.equal({ ok: true });
    expect(answer.results['DB1.DBW0:INT']).to.include({ ok: true, type: 'INT' });
    expect(answer.results['DB1.DBW']).to.include({ ok: false, code: 'INVALID_ADDRESS' });
  });

  it('CSV export is read back by the import, a bad URL falling back to the S7 parser', () => {
    const { csv } = csvExportAnswer({ tags: [{ name: 'level', address: 'DB1.DBD0:REAL' }, null, { name: 7 }] });
    const back = csvImportAnswer({ url: 'nope://', text: csv });
    expect(back.url).to.include({ ok: false });
    expect(back.tags[0]).to.deep.equal({ name: 'level', address: 'DB1.DBD0:REAL' });
  });

  it('duplicatesAnswer: the names given to more than one row, with their indexes; rows that are no objects count as empty', () => {
    const rows = [{ name: 'a', address: 'MW0' }, null, { address: 'MW0' }, { name: 'MW0', address: 'MW2' }, { name: 'a', address: 'MW4' }];
    expect(duplicatesAnswer({ tags: rows })).to.deep.equal({
      duplicates: [
        { name: 'a', rows: [0, 4] },
        { name: 'MW0', rows: [2, 3] },
      ],
    });
    expect(duplicatesAnswer({})).to.deep.equal({ duplicates: [] });
  });

  it("symbolConfig reads a request's sources as a connection's config, never strict (the editor checks, it does not refuse)", () => {
    const sources = [{ name: 'Tank.db', content: 'x' }];
    expect(symbolConfig({ symbolSources: sources, dbNumbers: [{ block: 'Tank', db: 1 }], strictSymbols: true })).to.deep.equal({
      symbolSources: sources,
      dbNumbers: [{ block: 'Tank', db: 1 }],
      strictSymbols: false,
    });
  });
});
