import { expect } from 'chai';
import fc from 'fast-check';
import { AddressError, quoteTag } from '../lib/errors';
import { formatAddress, parseAddress } from '../lib/address';
import type { AreaName, DataTypeName, Tag } from '../lib/types';

/** Element sizes written out again here, so the parser's table is checked against an independent one. */
const BYTES: Record<DataTypeName, number> = {
  BOOL: 1,
  BYTE: 1,
  CHAR: 1,
  SINT: 1,
  USINT: 1,
  WORD: 2,
  INT: 2,
  UINT: 2,
  WCHAR: 2,
  S5TIME: 2,
  DATE: 2,
  COUNTER: 2,
  TIMER: 2,
  DWORD: 4,
  DINT: 4,
  UDINT: 4,
  REAL: 4,
  TIME: 4,
  TIME_OF_DAY: 4,
  LWORD: 8,
  LINT: 8,
  ULINT: 8,
  LREAL: 8,
  LTIME: 8,
  DATE_AND_TIME: 8,
  DTL: 12,
  STRING: 0,
  WSTRING: 0,
};
const TYPES = Object.keys(BYTES) as DataTypeName[];
const MEMORY_TYPES = TYPES.filter((t) => t !== 'COUNTER' && t !== 'TIMER');

function expectedBytes(t: Omit<Tag, 'address' | 'byteLength'>): number {
  if (t.type === 'BOOL') return Math.ceil((t.bitOffset + t.count) / 8);
  if (t.type === 'STRING') return (t.stringLength + 2) * t.count;
  if (t.type === 'WSTRING') return (2 * t.stringLength + 4) * t.count;
  return BYTES[t.type] * t.count;
}

/** Any tag the parser can produce, as a plain object without address/byteLength. */
const tagShape = fc
  .record({
    area: fc.constantFrom<AreaName>('DB', 'M', 'I', 'Q', 'PE', 'PA', 'C', 'T'),
    dbNumber: fc.integer({ min: 1, max: 65535 }),
    byteOffset: fc.oneof(fc.integer({ min: 0, max: 65535 }), fc.integer({ min: 0, max: 300 })),
    bitOffset: fc.integer({ min: 0, max: 7 }),
    type: fc.constantFrom(...MEMORY_TYPES),
    count: fc.oneof(fc.constant(1), fc.integer({ min: 1, max: 40 })),
    isArray: fc.boolean(),
    stringLength: fc.integer({ min: 1, max: 254 }),
  })
  .map((g) => {
    const timerCounter = g.area === 'C' || g.area === 'T';
    const type: DataTypeName = g.area === 'C' ? 'COUNTER' : g.area === 'T' ? 'TIMER' : g.type;
    const isString = type === 'STRING' || type === 'WSTRING';
    return {
      area: g.area,
      dbNumber: g.area === 'DB' ? g.dbNumber : 0,
      byteOffset: g.byteOffset,
      bitOffset: type === 'BOOL' ? g.bitOffset : 0,
      type,
      count: g.isArray ? g.count : 1,
      isArray: g.isArray,
      stringLength: isString ? g.stringLength : 0,
      timerCounter,
    };
  })
  .filter((t) => (t.timerCounter ? t.byteOffset + t.count - 1 : t.byteOffset + expectedBytes(t) - 1) <= 65535)
  .map(({ timerCounter: _, ...t }) => t);

function outcome(s: string): Tag | AddressError {
  try {
    return parseAddress(s);
  } catch (err) {
    if (err instanceof AddressError) return err;
    throw err;
  }
}

function checkInvariants(s: string, t: Tag): void {
  expect(t.address).to.equal(s);
  expect(t.count).to.be.at.least(1);
  expect(t.bitOffset).to.be.within(0, t.type === 'BOOL' ? 7 : 0);
  expect(t.byteLength).to.equal(t.area === 'C' || t.area === 'T' ? 2 * t.count : expectedBytes(t));
  if (!t.isArray) expect(t.count).to.equal(1);
  expect(t.dbNumber).to.be.within(t.area === 'DB' ? 1 : 0, t.area === 'DB' ? 65535 : 0);
  if (t.area !== 'C' && t.area !== 'T') expect(t.byteOffset + t.byteLength - 1).to.be.at.most(65535);
}

/** Strings built from the grammar's own pieces: mostly near-valid addresses. */
const grammarish = fc
  .array(
    fc.oneof(
      fc.constantFrom(
        'DB',
        'DB1',
        'DB0',
        ',',
        '.',
        ':',
        '%',
        '[',
        ']',
        'X',
        'B',
        'W',
        'D',
        'DBX',
        'DBW',
        'DBD',
        'DBB',
        'V',
        'T',
        'C',
        'Z',
        'M',
        'I',
        'Q',
        'E',
        'A',
        'PI',
        'PQ',
        'PE',
        'PA',
        ' ',
      ),
      fc.constantFrom(...TYPES, 'R', 'DI', 'S', 'TOD', 'DT', 'WS', 'x', 'real', 'int'),
      fc.nat({ max: 70000 }).map(String),
      fc.constantFrom('0', '1', '7', '8', '254', '255', '65535', '65536', '00', '99999999999999999999'),
    ),
    { maxLength: 9 },
  )
  .map((parts) => parts.join(''));

/** Addresses composed along the syntaxes, with small and edge numbers: about half of them parse. */
const num = fc.oneof(
  fc.integer({ min: 0, max: 12 }).map(String),
  fc.constantFrom('0', '7', '8', '30', '254', '255', '65534', '65535', '65536', '007'),
);
const typeName = fc.constantFrom(...TYPES, 'R', 'DI', 'I', 'C', 'S', 'TOD', 'DT', 'WS', 'B', 'W', 'DW', 'X', 'real', 'Int');
const dots = fc.array(num, { maxLength: 2 }).map((ns) => ns.map((n) => `.${n}`).join(''));
const override = fc.option(
  fc.tuple(typeName, fc.array(num, { maxLength: 2 })).map(([t, ns]) => `:${t}${ns.map((n) => `[${n}]`).join('')}`),
  { nil: '' },
);
const structured = fc.oneof(
  fc.tuple(num, typeName, num, dots).map(([db, t, off, d]) => `DB${db},${t}${off}${d}`),
  fc
    .tuple(fc.constantFrom('', '%'), num, fc.constantFrom('X', 'B', 'W', 'D'), num, dots, override)
    .map(([p, db, w, off, d, o]) => `${p}DB${db}.DB${w}${off}${d}${o}`),
  fc
    .tuple(
      fc.constantFrom('', '%'),
      fc.constantFrom('I', 'Q', 'E', 'A', 'M', 'PI', 'PE', 'PQ', 'PA', 'V'),
      fc.constantFrom('', 'X', 'B', 'W', 'D', 'R', 'I', 'DI', 'C'),
      num,
      dots,
      override,
    )
    .map(([p, area, w, off, d, o]) => `${p}${area}${w}${off}${d}${o}`),
  fc.tuple(fc.constantFrom('T', 'C', 'Z', 't', 'c'), num, override).map(([a, n, o]) => `${a}${n}${o}`),
);

describe('address parser properties', () => {
  it('any string gives a tag or an AddressError naming it, never anything else', () => {
    fc.assert(
      fc.property(fc.oneof(fc.string(), fc.string({ unit: 'binary', maxLength: 40 }), grammarish, structured), (s) => {
        const r = outcome(s);
        if (r instanceof AddressError) {
          expect(r.code).to.equal('INVALID_ADDRESS');
          // Named once, quoted once (a TIA name in its own quotes as written): quoteTag.
          expect(r.message.startsWith(`invalid address ${quoteTag(r.tag!)}: `), r.message).to.equal(true);
        } else {
          checkInvariants(s, r);
        }
      }),
      { numRuns: 20000 },
    );
  });

  it('every address that parses has a canonical form that parses to the same tag and formats to itself', () => {
    let parsed = 0;
    fc.assert(
      fc.property(structured, (s) => {
        const r = outcome(s);
        if (r instanceof AddressError) return;
        parsed += 1;
        const canonical = formatAddress(r);
        const back = parseAddress(canonical);
        expect({ ...back, address: s }, `${s} → ${canonical}`).to.deep.equal(r);
        expect(formatAddress(back)).to.equal(canonical);
      }),
      { numRuns: 20000 },
    );
    expect(parsed, 'enough generated addresses parse for the property to mean something').to.be.greaterThan(2500);
  });

  it('every tag shape the model allows survives format → parse, with the byte length of the type table', () => {
    fc.assert(
      fc.property(tagShape, (shape) => {
        const address = formatAddress(shape);
        const t = parseAddress(address);
        expect(t, address).to.deep.include(shape);
        checkInvariants(address, t);
      }),
      { numRuns: 10000 },
    );
  });

  it('case and surrounding whitespace never change the tag', () => {
    const spaces = fc.string({ unit: fc.constantFrom(' ', '\t', '\n', '\r'), maxLength: 3 });
    fc.assert(
      fc.property(tagShape, fc.array(fc.boolean(), { minLength: 64, maxLength: 64 }), spaces, spaces, (shape, upper, before, after) => {
        const canonical = formatAddress(shape);
        const mixed = [...canonical].map((ch, i) => (upper[i % 64] ? ch.toUpperCase() : ch.toLowerCase())).join('');
        const written = before + mixed + after;
        const t = parseAddress(written);
        expect(t.address).to.equal(written);
        expect({ ...t, address: '' }).to.deep.equal({ ...parseAddress(canonical), address: '' });
      }),
      { numRuns: 3000 },
    );
  });
});
