/**
 * The protocol registry (lib/drivers.ts): every protocol one entry, every
 * URL scheme parsed through its entry, capabilities that say what the
 * client does, and no protocol named anywhere the registry is read.
 */
import { MockBinding } from '@serialport/binding-mock';
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { createClient } from '../lib/connect';
import { DRIVERS, URL_SCHEMES } from '../lib/drivers';
import { PlcError } from '../lib/errors';
import { compileSymbols } from '../lib/symbols';
import type { Protocol } from '../lib/types';
import { DEFAULTS, parseUrl } from '../lib/url';

const ROOT = path.resolve(__dirname, '../..');

/** A URL of each scheme, as a user writes it. */
const SAMPLES: Readonly<Record<string, string>> = {
  s7: 's7://127.0.0.1:1?rack=0&slot=1',
  fetchwrite: 'fetchwrite://127.0.0.1?port=1',
  freeport: 'freeport:///dev/ttyFAKE0?baud=9600',
  'freeport+tcp': 'freeport+tcp://127.0.0.1:1',
  s7plus: 's7plus://127.0.0.1:1?tls=false',
};

const PROTOCOLS: readonly Protocol[] = ['s7', 'fetchwrite', 'freeport', 's7plus'];

const TABLE = compileSymbols(
  [
    {
      name: 'Tank.db',
      content: 'DATA_BLOCK "Tank"\n{ S7_Optimized_Access := \'FALSE\' }\nSTRUCT\n  Level : INT;\nEND_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n',
    },
  ],
  {
    db: { Tank: 1 },
  },
);

const schemes = () => Object.values(DRIVERS).flatMap((d) => Object.keys(d.urls.schemes));

describe('drivers: the protocol registry', () => {
  before(() => MockBinding.createPort('/dev/ttyFAKE0', { echo: false, record: false }));
  after(() => MockBinding.reset());

  it('has one entry per protocol, each under the name its URLs parse to', () => {
    expect(Object.keys(DRIVERS).sort()).to.deep.equal([...PROTOCOLS].sort());
    for (const [name, driver] of Object.entries(DRIVERS)) expect(driver.urls.protocol, name).to.equal(name);
  });

  it('parses every scheme an entry lists, to that entry, and creates the client of that protocol', async () => {
    expect(schemes().sort()).to.deep.equal(Object.keys(SAMPLES).sort());
    for (const [name, driver] of Object.entries(DRIVERS)) {
      for (const scheme of Object.keys(driver.urls.schemes)) {
        const endpoint = parseUrl(SAMPLES[scheme]!);
        expect(endpoint.protocol, scheme).to.equal(name);
        const client = createClient(endpoint, { binding: MockBinding });
        expect(client.protocol, scheme).to.equal(name);
        await client.close();
      }
    }
  });

  it("the schemes the types know (URL_SCHEMES, for connect() typed by scheme) are each entry's URL schemes", () => {
    for (const [protocol, entry] of Object.entries(DRIVERS)) {
      expect([...URL_SCHEMES[protocol as Protocol]].sort(), protocol).to.deep.equal(Object.keys(entry.urls.schemes).sort());
    }
  });

  it('an unknown scheme is refused naming every scheme of the registry', () => {
    let err: unknown;
    try {
      parseUrl('modbus://127.0.0.1');
    } catch (e) {
      err = e;
    }
    expect(err).to.be.instanceOf(PlcError);
    expect((err as PlcError).code).to.equal('INVALID_URL');
    for (const scheme of schemes()) expect((err as PlcError).message).to.contain(`${scheme}:`);
  });

  it('DEFAULTS hold every entry’s defaults', () => {
    for (const driver of Object.values(DRIVERS)) expect(DEFAULTS).to.include(driver.urls.defaults);
  });

  it('capabilities say what the client does: symbols refused (NOT_SUPPORTED) exactly where the entry has none; blockLength where the client asks a block length', async () => {
    for (const [name, driver] of Object.entries(DRIVERS)) {
      const url = SAMPLES[name]!;
      let client: ReturnType<typeof createClient> | undefined;
      let err: unknown;
      try {
        client = createClient(url, { symbols: TABLE, binding: MockBinding });
      } catch (e) {
        err = e;
      }
      if (driver.symbols) {
        expect(err, name).to.equal(undefined);
        expect(client!.tag('"Tank".Level').address, name).to.equal('"Tank".Level');
      } else {
        expect(err, name).to.be.instanceOf(PlcError);
        expect((err as PlcError).code, name).to.equal('NOT_SUPPORTED');
        expect((err as PlcError).message, name).to.contain(driver.noSymbols);
      }
      const plain = client ?? createClient(url, { binding: MockBinding });
      const contract = (plain as unknown as { driver: { blockLength?: unknown } }).driver;
      expect(typeof contract.blockLength === 'function', name).to.equal(driver.blockLength);
      await plain.close();
    }
  });

  it('no file outside lib/drivers.ts and the protocol folders tests a scheme: the doctor, the CLI, lib/flows and the nodes ask the registry', () => {
    // The protocol folders may name their own scheme (lib/s7/url.ts isS7Endpoint); nodes/*.html are the edit dialogs, which show each protocol's fields.
    const own = /^lib\/(?:s7|s7plus|fetchwrite|freeport|iso)\/|^lib\/drivers\.ts$/;
    const files = [...sourceFiles('lib', '.ts'), ...sourceFiles('nodes', '.js')].filter((f) => !own.test(f));
    expect(files).to.include.members(['lib/doctor/index.ts', 'lib/cli/system.ts', 'lib/cli/s7plus.ts', 'nodes/connection.js']);
    const found = files.flatMap((f) => schemeTests(fs.readFileSync(path.join(ROOT, f), 'utf8')).map((t) => `${f}: ${t}`));
    expect(found).to.deep.equal([]);
  });

  it('the scheme-test finder finds what it is meant to find', () => {
    const samples = [
      'if (/^\\s*s7plus:/i.test(url)) return 1;',
      "if (endpoint.protocol !== 's7plus') throw e;",
      'if ("s7" === p) x();',
      "switch (p) { case 'fetchwrite': break; }",
      "if (url.startsWith('freeport+tcp:')) x();",
    ];
    for (const code of samples) expect(schemeTests(code), code).to.have.length(1);
    // Words and keys are not tests: messages, comments, a lookup by protocol.
    expect(schemeTests("// protocol === 's7'\nthrow new Error('give an s7plus:// URL'); DRIVERS['s7'];")).to.deep.equal([]);
  });

  it('connect.ts, url.ts and the serve command name no protocol: they read the registry', () => {
    for (const file of ['lib/connect.ts', 'lib/url.ts', 'lib/cli/serve.ts']) {
      const code = fs
        .readFileSync(path.join(ROOT, file), 'utf8')
        .replace(/\/\*[\s\S]*?\*\//g, '')
        .replace(/\/\/.*$/gm, '');
      for (const protocol of PROTOCOLS) expect(code, file).to.not.match(new RegExp(`['"\`]${protocol}['"\`]`));
      expect(code, file).to.not.match(/\bswitch\s*\(/);
    }
  });
});

/** Files under `dir` (relative to the repository root) ending in `ext`, node_modules left out. */
function sourceFiles(dir: string, ext: string): string[] {
  return fs.readdirSync(path.join(ROOT, dir), { withFileTypes: true }).flatMap((e) => {
    const rel = `${dir}/${e.name}`;
    if (e.isDirectory()) return e.name === 'node_modules' ? [] : sourceFiles(rel, ext);
    return e.name.endsWith(ext) ? [rel] : [];
  });
}

const SCHEME = String.raw`(?:s7plus|s7|fetchwrite|freeport(?:\+tcp)?)`;

/** Where code (comments left out) tests a URL scheme or protocol name: a comparison, a case, a regex or a string prefix. */
const SCHEME_TESTS = [
  new RegExp(String.raw`[=!]==?\s*['"\`]${SCHEME}['"\`]`, 'g'),
  new RegExp(String.raw`['"\`]${SCHEME}['"\`]\s*[=!]==?`, 'g'),
  new RegExp(String.raw`\bcase\s+['"\`]${SCHEME}['"\`]`, 'g'),
  new RegExp(String.raw`\/\^[^/\n]*${SCHEME}\\?:`, 'g'),
  new RegExp(String.raw`\.(?:startsWith|includes|match|test)\(\s*['"\`]${SCHEME}`, 'g'),
];

function schemeTests(code: string): string[] {
  const bare = code.replace(/\/\*[\s\S]*?\*\//g, '').replace(/(^|[^:])\/\/.*$/gm, '$1');
  return SCHEME_TESTS.flatMap((re) => [...bare.matchAll(re)].map((m) => m[0]));
}
