import { expect } from 'chai';
import fc from 'fast-check';
import { parseAddress } from '../lib/address';
import { S7Area, TransportSize, DataTransportSize } from '../lib/s7/constants';
import {
  maxReadItemData,
  maxReadItems,
  maxWriteItemData,
  planRead,
  planWrite,
  ReadPlanCache,
  tagData,
  type ReadPlan,
} from '../lib/s7/plan';
import { lowerBoundPdus } from '../lib/s7/plan/bound';
import type { Tag } from '../lib/types';

const tags = (addresses: string[]) => addresses.map(parseAddress);

/** Checks both PDU limits of every read PDU, recomputing the sizes from the items. */
function checkReadLimits(plan: ReadPlan, pduSize: number, maxItems = 255): void {
  for (const pdu of plan.pdus) {
    expect(pdu.items.length).to.be.within(1, maxItems);
    const request = 12 + 12 * pdu.items.length;
    let response = 14;
    pdu.items.forEach((it, i) => (response += 4 + it.length + (it.length % 2 === 1 && i < pdu.items.length - 1 ? 1 : 0)));
    expect(request, 'request size').to.be.at.most(pduSize);
    expect(response, 'response size').to.be.at.most(pduSize);
    expect(pdu.requestSize).to.equal(request);
    expect(pdu.responseSize).to.equal(response);
  }
}

/** Memory per area/DB filled with a pattern; answers items like a PLC would. */
function answer(plan: ReadPlan): Buffer[][] {
  return plan.pdus.map((pdu) =>
    pdu.items.map((it) => {
      const start = it.area === S7Area.C || it.area === S7Area.T ? it.address * 2 : it.address / 8;
      return patternBytes(it.area, it.dbNumber, start, it.length);
    }),
  );
}

function patternBytes(area: number, db: number, start: number, length: number): Buffer {
  const b = Buffer.alloc(length);
  for (let i = 0; i < length; i++) b[i] = (area * 31 + db * 7 + (start + i) * 13 + ((start + i) >> 8)) & 0xff;
  return b;
}

function expectedBytes(tag: Tag): Buffer {
  const area = { I: 0x81, Q: 0x82, M: 0x83, DB: 0x84, PE: 0x80, PA: 0x80, C: 0x1c, T: 0x1d }[tag.area];
  const ct = tag.area === 'C' || tag.area === 'T';
  return patternBytes(area, tag.dbNumber, ct ? tag.byteOffset * 2 : tag.byteOffset, ct ? tag.count * 2 : tag.byteLength);
}

function checkCoverage(list: readonly Tag[], plan: ReadPlan): void {
  const data = answer(plan);
  list.forEach((tag, i) => {
    const slices = plan.slices[i]!;
    expect(slices.length, `${tag.address} slices`).to.be.greaterThan(0);
    // The pieces tile the tag's bytes exactly once, in order.
    let at = 0;
    for (const s of slices) {
      expect(s.at).to.equal(at);
      expect(s.offset + s.length).to.be.at.most(plan.pdus[s.pdu]!.items[s.item]!.length);
      at += s.length;
    }
    expect(at).to.equal(plan.tagLengths[i]);
    const { data: buf, offset } = tagData(plan, i, data);
    expect(buf.subarray(offset, offset + at).equals(expectedBytes(tag)), `${tag.address} bytes`).to.equal(true);
  });
}

const addressArb = fc.oneof(
  fc
    .tuple(fc.integer({ min: 1, max: 3 }), fc.integer({ min: 0, max: 3000 }), fc.constantFrom('INT', 'REAL', 'B', 'LREAL', 'DINT'))
    .map(([db, off, t]) => `DB${db},${t}${off}`),
  fc
    .tuple(fc.integer({ min: 1, max: 3 }), fc.integer({ min: 0, max: 3000 }), fc.integer({ min: 0, max: 7 }))
    .map(([db, off, bit]) => `DB${db},X${off}.${bit}`),
  fc
    .tuple(fc.integer({ min: 1, max: 2 }), fc.integer({ min: 0, max: 3000 }), fc.constantFrom(1, 20, 40, 200, 254))
    .map(([db, off, n]) => `DB${db},S${off}.${n}`),
  fc.tuple(fc.integer({ min: 0, max: 500 }), fc.integer({ min: 1, max: 300 })).map(([off, n]) => `DB4,BYTE${off}.${n}`),
  fc.integer({ min: 0, max: 200 }).map((n) => `MW${n}`),
  fc.integer({ min: 0, max: 60 }).map((n) => `I${n}.${n % 8}`),
  fc.integer({ min: 0, max: 100 }).map((n) => `C${n}`),
  fc.tuple(fc.integer({ min: 0, max: 100 }), fc.integer({ min: 2, max: 150 })).map(([n, k]) => `T${n}:TIMER[${k}]`),
);

describe('S7 planner: reads', () => {
  it('merges neighbours into one item and keeps distant tags apart', () => {
    const plan = planRead(tags(['DB1,INT0', 'DB1,INT2', 'DB1,REAL10', 'DB1,INT200', 'M0.1', 'M0.2']), 240);
    expect(plan.pdus).to.have.length(1);
    const items = plan.pdus[0]!.items.map((it) => [it.area, it.address, it.length]);
    expect(items).to.have.deep.members([
      [0x83, 0, 1],
      [0x84, 0, 14],
      [0x84, 200 * 8, 2],
    ]);
    // DB1,REAL10 lies 10 bytes into the merged DB1 item.
    const s = plan.slices[2]!;
    expect(s).to.have.length(1);
    expect(plan.pdus[0]!.items[s[0]!.item]!.address).to.equal(0);
    expect(s[0]!.offset).to.equal(10);
  });

  it('read items are shaped for the codec: BYTE transport, bit address, count in bytes', () => {
    const plan = planRead(tags(['DB200,B2']), 240);
    expect(plan.pdus[0]!.items[0]).to.deep.equal({
      area: 0x84,
      dbNumber: 200,
      transportSize: TransportSize.BYTE,
      count: 1,
      address: 16,
      length: 1,
    });
  });

  it('counters and timers are read as COUNTER/TIMER items addressed by number, 2 bytes each', () => {
    const plan = planRead(tags(['C5', 'C6', 'T3']), 240);
    const items = plan.pdus.flatMap((p) => p.items);
    expect(items).to.have.deep.members([
      { area: S7Area.C, dbNumber: 0, transportSize: TransportSize.COUNTER, count: 2, address: 5, length: 4 },
      { area: S7Area.T, dbNumber: 0, transportSize: TransportSize.TIMER, count: 1, address: 3, length: 2 },
    ]);
    checkCoverage(tags(['C5', 'C6', 'T3']), plan);
  });

  it('splits STRING[254] (256 bytes) at PDU 240 into chunks of at most 222 bytes in 2 PDUs and reassembles it', () => {
    const list = tags(['DB1,S0.254']);
    const plan = planRead(list, 240);
    expect(plan.pdus).to.have.length(2);
    const lengths = plan.pdus.flatMap((p) => p.items.map((i) => i.length));
    expect(lengths.reduce((a, b) => a + b)).to.equal(256);
    expect(Math.max(...lengths)).to.equal(maxReadItemData(240));
    expect(plan.slices[0]).to.have.length(2);
    checkCoverage(list, plan);
  });

  it('never cuts a value that fits one item: neighbours go whole into the next PDU', () => {
    // 12 REAL[5] of 20 bytes back to back: 240 bytes, more than one PDU's 222.
    const list = Array.from({ length: 12 }, (_, i) => parseAddress(`DB1,REAL${i * 20}.5`));
    const plan = planRead(list, 240);
    expect(plan.pdus).to.have.length(2);
    plan.slices.forEach((s) => expect(s).to.have.length(1));
    checkCoverage(list, plan);
  });

  it('merge: false reads every tag as its own item', () => {
    const plan = planRead(tags(['DB1,INT0', 'DB1,INT2', 'DB1,INT4']), 240, { merge: false });
    expect(plan.pdus.flatMap((p) => p.items)).to.have.length(3);
  });

  it('respects the item limit of the request: 12 + 12·items ≤ PDU (19 at 240), or a smaller maxItems', () => {
    const list = Array.from({ length: 40 }, (_, i) => parseAddress(`DB${i + 1},INT0`));
    expect(maxReadItems(240)).to.equal(19);
    const plan = planRead(list, 240);
    expect(plan.pdus.map((p) => p.items.length)).to.deep.equal([19, 19, 2]);
    const capped = planRead(list, 960, { maxItems: 20 });
    expect(capped.pdus.map((p) => p.items.length)).to.deep.equal([20, 20]);
    checkReadLimits(capped, 960, 20);
  });

  it('bridges larger gaps once a PDU runs out of items before bytes', () => {
    // 40 INTs 20 bytes apart in one DB: 40 items would need 3 PDUs; bridged they fit 226 bytes × 4.
    const list = Array.from({ length: 40 }, (_, i) => parseAddress(`DB1,INT${i * 20}`));
    const plan = planRead(list, 240);
    expect(plan.pdus.length).to.equal(lowerBoundPdus(list, 240));
    checkReadLimits(plan, 240);
    checkCoverage(list, plan);
  });

  it('property: every plan respects both limits and the item limit, covers each tag exactly once, reassembles its bytes, and needs no fewer PDUs than the lower bound', () => {
    const limits = fc.constantFrom(undefined, 20, 7, 1);
    fc.assert(
      fc.property(
        fc.array(addressArb, { minLength: 1, maxLength: 150 }),
        fc.constantFrom(240, 480, 960),
        fc.boolean(),
        limits,
        (addresses, pdu, merge, maxItems) => {
          const list = addresses.map(parseAddress);
          const options = maxItems === undefined ? {} : { maxItems };
          const plan = planRead(list, pdu, { merge, ...options });
          checkReadLimits(plan, pdu, maxItems);
          checkCoverage(list, plan);
          expect(plan.pdus.length).to.be.at.least(lowerBoundPdus(list, pdu, options));
        },
      ),
      { numRuns: 300 },
    );
  });

  it("at 20 items per job the benchmark's 1000 scattered tags take 11 PDUs at PDU 960 (9 when the PDU decides), the lower bound both times", () => {
    const { table } = require('../../bench/lib/tables') as { table: (name: string) => { address: string }[] };
    const list = table('1000 scattered').map((t) => parseAddress(t.address));
    for (const [maxItems, pdus] of [
      [20, 11],
      [255, 9],
    ] as const) {
      const plan = planRead(list, 960, { maxItems });
      expect(plan.pdus, `maxItems ${maxItems}`).to.have.length(pdus);
      expect(lowerBoundPdus(list, 960, { maxItems })).to.equal(pdus);
      checkReadLimits(plan, 960, maxItems);
      checkCoverage(list, plan);
    }
  });

  it('reaches the lower bound on contiguous and small tables, and on 1000 tightly scattered tags but at PDU 240 (49 vs 48)', () => {
    const contiguous = Array.from({ length: 1000 }, (_, i) => parseAddress(`DB1,INT${i * 2}`));
    const kinds = ['INT', 'REAL', 'X', 'S'];
    let offset = 0;
    const scattered = Array.from({ length: 1000 }, (_, i) => {
      const kind = kinds[i % 4]!;
      const tag =
        kind === 'X'
          ? parseAddress(`DB1,X${offset}.${i % 8}`)
          : kind === 'S'
            ? parseAddress(`DB1,S${offset}.20`)
            : parseAddress(`DB1,${kind}${offset}`);
      offset += tag.byteLength + (i % 3) * 2 + 2;
      return tag;
    });
    // With the protocol's 255 items per job, and with the 20 the client sends by default.
    for (const options of [{}, { maxItems: 20 }]) {
      for (const pdu of [240, 480, 960]) {
        for (const list of [contiguous, scattered, scattered.slice(0, 100), scattered.slice(0, 10)]) {
          const plan = planRead(list, pdu, options);
          const bound = lowerBoundPdus(list, pdu, options);
          checkReadLimits(plan, pdu, options.maxItems);
          // The bound may cut a tag across PDUs; the planner never does (its halves could come from two PLC cycles).
          const slack = list === scattered && pdu === 240 ? 1 : 0;
          expect(plan.pdus.length, `${list.length} tags at PDU ${pdu}, ${options.maxItems ?? 255} items`).to.be.within(
            bound,
            bound + slack,
          );
        }
      }
    }
  });
});

describe('S7 planner: packing out of address order', () => {
  // The benchmark's tables (bench/lib/tables.js, deterministic).
  const { table } = require('../../bench/lib/tables') as { table: (name: string) => { address: string }[] };
  /** True when some PDU's items are not in address order, or PDUs' address ranges interleave: the cover draft won. */
  const outOfOrder = (plan: ReadPlan) => {
    const keys = plan.pdus.map((pdu) => pdu.items.map((it) => (it.area * 0x10000 + it.dbNumber) * 0x1000000 + it.address));
    return keys.some((k, p) => k.some((v, i) => i > 0 && v < k[i - 1]!) || (p > 0 && Math.min(...k) < Math.max(...keys[p - 1]!)));
  };

  it("reads the benchmark's 1000 scattered tags at PDU 240 / 19 items in 34 PDUs, the lower bound (address order needs 35)", () => {
    const list = table('1000 scattered').map((t) => parseAddress(t.address));
    const plan = planRead(list, 240, { maxItems: 19 });
    expect(lowerBoundPdus(list, 240, { maxItems: 19 })).to.equal(34);
    expect(plan.pdus).to.have.length(34);
    expect(outOfOrder(plan)).to.equal(true);
    checkReadLimits(plan, 240, 19);
    checkCoverage(list, plan);
  });

  it('property: on dense scattered tables every plan respects both limits and covers each tag exactly once, in or out of order', () => {
    let reordered = 0;
    const dense = fc.array(
      fc.tuple(fc.constantFrom('INT', 'REAL', 'X', 'S', 'B', 'MW', 'C'), fc.integer({ min: 0, max: 14 }), fc.integer({ min: 1, max: 3 })),
      {
        minLength: 150,
        maxLength: 400,
      },
    );
    fc.assert(
      fc.property(dense, fc.constantFrom(19, 12), (parts, maxItems) => {
        const at = new Map<string, number>();
        const list = parts.map(([kind, gap, db], i) => {
          // Each area (three DBs, M, counters) is filled in address order with its own gaps.
          const area = kind === 'MW' ? 'M' : kind === 'C' ? 'C' : `DB${db}`;
          const offset = (at.get(area) ?? 0) + (kind === 'C' ? gap % 3 : gap);
          const address =
            kind === 'MW'
              ? `MW${offset}`
              : kind === 'C'
                ? `C${offset}`
                : kind === 'X'
                  ? `DB${db},X${offset}.${i % 8}`
                  : kind === 'S'
                    ? `DB${db},S${offset}.${(gap % 4) * 5 + 1}`
                    : kind === 'B'
                      ? `DB${db},BYTE${offset}`
                      : `DB${db},${kind}${offset}`;
          const tag = parseAddress(address);
          at.set(area, offset + (kind === 'C' ? tag.count : tag.byteLength));
          return tag;
        });
        const plan = planRead(list, 240, { maxItems });
        checkReadLimits(plan, 240, maxItems);
        checkCoverage(list, plan);
        expect(plan.pdus.length).to.be.at.least(lowerBoundPdus(list, 240, { maxItems }));
        if (outOfOrder(plan)) reordered++;
      }),
      { numRuns: 60 },
    );
    expect(reordered, 'plans packed out of address order').to.be.greaterThan(0);
  });
});

describe('S7 planner: lower bound', () => {
  it('counts response bytes per PDU and items per request', () => {
    expect(lowerBoundPdus([], 240)).to.equal(0);
    // 1000 contiguous INTs: 2000 bytes need 10 items of ≤ 222 → 2040 bytes over 226 per PDU → 10.
    expect(
      lowerBoundPdus(
        Array.from({ length: 1000 }, (_, i) => parseAddress(`DB1,INT${i * 2}`)),
        240,
      ),
    ).to.equal(10);
    // 40 INTs in 40 DBs: 40 items, 19 per request → 3.
    expect(
      lowerBoundPdus(
        Array.from({ length: 40 }, (_, i) => parseAddress(`DB${i + 1},INT0`)),
        240,
      ),
    ).to.equal(3);
    // STRING[254]: 256 bytes need 2 items → 264 bytes > 226.
    expect(lowerBoundPdus(tags(['DB1,S0.254']), 240)).to.equal(2);
    // 100 INTs 10 bytes apart: 3 PDUs hold 57 items, so 43 gaps of 8 bytes are bridged: 200 + 344 + 228 > 3 × 226 → 4.
    const spaced = Array.from({ length: 100 }, (_, i) => parseAddress(`DB1,INT${i * 10}`));
    expect(lowerBoundPdus(spaced, 240)).to.equal(4);
    expect(planRead(spaced, 240).pdus).to.have.length(4);
  });

  it('counts the fill byte after every odd-length item but the last of its PDU', () => {
    // 33 STRING[7] (9 bytes) 20 bytes apart, 19 items per request: 33 × 13 bytes fit 2 × 226 without fills,
    // but each item but a PDU's last takes 14: 33 × 14 − n > 226 n for n = 2 → 3, which the planner reaches.
    const strings = Array.from({ length: 33 }, (_, i) => parseAddress(`DB1,S${i * 29}.7`));
    expect(strings[0]!.byteLength).to.equal(9);
    expect(lowerBoundPdus(strings, 240, { maxItems: 19 })).to.equal(3);
    const plan = planRead(strings, 240, { maxItems: 19 });
    expect(plan.pdus).to.have.length(3);
    checkReadLimits(plan, 240);
    // Even-length tags (STRING[8], 10 bytes) need no fill: at PDU 480, 33 items fit 2 requests of 19 and 2 × 466 bytes.
    const even = Array.from({ length: 33 }, (_, i) => parseAddress(`DB1,S${i * 30}.8`));
    expect(lowerBoundPdus(even, 480, { maxItems: 19 })).to.equal(2);
    expect(planRead(even, 480, { maxItems: 19 }).pdus).to.have.length(2);
  });

  it('property: the fill-byte bound never exceeds what the planner achieves on odd-length tags', () => {
    const odd = fc.array(fc.tuple(fc.constantFrom('X', 'B', 'S'), fc.integer({ min: 0, max: 40 })), { minLength: 1, maxLength: 120 });
    fc.assert(
      fc.property(odd, fc.constantFrom(120, 240, 480), fc.constantFrom(undefined, 19), (parts, pdu, maxItems) => {
        let at = 0;
        const list = parts.map(([kind, gap]) => {
          at += gap;
          const tag = parseAddress(
            kind === 'X' ? `DB1,X${at}.${gap % 8}` : kind === 'B' ? `DB1,BYTE${at}` : `DB1,S${at}.${(gap % 5) * 2 + 1}`,
          );
          at += tag.byteLength;
          return tag;
        });
        const options = maxItems ? { maxItems } : {};
        expect(planRead(list, pdu, options).pdus.length).to.be.at.least(lowerBoundPdus(list, pdu, options));
      }),
      { numRuns: 300 },
    );
  });
});

describe('S7 planner: plan cache', () => {
  it('reuses the plan for the same array or the same addresses, and plans anew otherwise', () => {
    const cache = new ReadPlanCache(4);
    const a = tags(['DB1,INT0', 'DB1,REAL4']);
    const p1 = cache.get(a, 240);
    expect(cache.get(a, 240)).to.equal(p1);
    expect(cache.get(tags(['DB1,INT0', 'DB1,REAL4']), 240)).to.equal(p1);
    expect(cache.get(a, 480)).to.not.equal(p1);
    expect(cache.get(tags(['DB1,INT0', 'DB1,REAL8']), 240)).to.not.equal(p1);
    expect(cache.hits).to.equal(2);
    expect(cache.misses).to.equal(3);
  });

  it('tells plans of the same array apart by item limit and merge', () => {
    const cache = new ReadPlanCache(8);
    const list = Array.from({ length: 30 }, (_, i) => parseAddress(`DB${i + 1},INT0`));
    const wide = cache.get(list, 960);
    const narrow = cache.get(list, 960, { maxItems: 20 });
    expect(narrow).to.not.equal(wide);
    expect([wide.maxItems, narrow.maxItems]).to.deep.equal([79, 20]);
    expect(wide.pdus.map((p) => p.items.length)).to.deep.equal([30]);
    expect(narrow.pdus.map((p) => p.items.length)).to.deep.equal([20, 10]);
    expect(cache.get(list, 960, { maxItems: 20 })).to.equal(narrow);
    expect(cache.get(list, 960)).to.equal(wide);
    const neighbours = tags(['DB1,INT0', 'DB1,INT2']);
    expect(cache.get(neighbours, 960).pdus[0]!.items).to.have.length(1);
    const alone = cache.get(neighbours, 960, { merge: false });
    expect([alone.merged, alone.pdus[0]!.items.length]).to.deep.equal([false, 2]);
  });

  it('stays bounded', () => {
    const cache = new ReadPlanCache(3);
    for (let i = 0; i < 10; i++) cache.get(tags([`DB1,INT${i * 2}`]), 240);
    const first = tags(['DB1,INT0']);
    cache.get(first, 240);
    expect(cache.misses).to.equal(11);
  });
});

describe('S7 planner: writes', () => {
  it('writes each bit as its own BIT item, never a byte', () => {
    const plan = planWrite(
      [
        { tag: parseAddress('DB1,X12.2'), value: true },
        { tag: parseAddress('DB1.DBX0.6:BOOL[3]'), value: [true, false, true] },
      ],
      240,
    );
    const items = plan.pdus.flatMap((p) => p.items);
    expect(items).to.have.length(4);
    for (const it of items) {
      expect(it.transportSize).to.equal(TransportSize.BIT);
      expect(it.dataTransportSize).to.equal(DataTransportSize.BIT);
      expect(it.count).to.equal(1);
      expect(it.data.length).to.equal(1);
    }
    expect(items.map((i) => [i.address, i.data[0]])).to.have.deep.members([
      [12 * 8 + 2, 1],
      [6, 1],
      [7, 0],
      [8, 1],
    ]);
  });

  it('writes a STRING from its length byte on, keeping the max-length byte', () => {
    const plan = planWrite([{ tag: parseAddress('DB1,S10.20'), value: 'abc' }], 240);
    const [item] = plan.pdus[0]!.items;
    expect(item!.address).to.equal(11 * 8);
    expect(item!.data.toString('hex')).to.equal('03616263');
  });

  it("reports a value that does not fit as that tag's error and sends the others", () => {
    const plan = planWrite(
      [
        { tag: parseAddress('DB1,INT0'), value: 70000 },
        { tag: parseAddress('DB1,INT2'), value: 5 },
      ],
      240,
    );
    expect(plan.errors[0]?.code).to.equal('INVALID_VALUE');
    expect(plan.errors[0]?.message).to.contain('DB1,INT0');
    expect(plan.errors[1]).to.equal(undefined);
    expect(plan.pdus.flatMap((p) => p.tags)).to.deep.equal([1]);
  });

  it('splits a write larger than one PDU into chunks that rebuild the data', () => {
    const value = Array.from({ length: 300 }, (_, i) => i & 0xff);
    const plan = planWrite([{ tag: parseAddress('DB1,BYTE100.300'), value }], 240);
    const items = plan.pdus.flatMap((p) => p.items);
    expect(items.length).to.equal(Math.ceil(300 / maxWriteItemData(240)));
    const rebuilt = Buffer.alloc(300);
    for (const it of items) it.data.copy(rebuilt, it.address / 8 - 100);
    expect([...rebuilt]).to.deep.equal(value);
  });

  it('property: write PDUs respect 12 + 12·items + Σ(4 + data + fill) ≤ PDU, 14 + items ≤ PDU and the item limit', () => {
    const writeArb = fc.array(
      fc.oneof(
        fc
          .tuple(fc.integer({ min: 0, max: 500 }), fc.integer({ min: -32768, max: 32767 }))
          .map(([o, v]) => ({ a: `DB1,INT${o}`, v: v as unknown })),
        fc.tuple(fc.integer({ min: 0, max: 500 }), fc.boolean()).map(([o, v]) => ({ a: `DB1,X${o}.3`, v: v as unknown })),
        fc
          .tuple(fc.integer({ min: 0, max: 500 }), fc.string({ maxLength: 254 }))
          .map(([o, v]) => ({ a: `DB2,S${o}.254`, v: v.replace(/[^\x20-\x7e]/g, 'x') as unknown })),
        fc
          .tuple(fc.integer({ min: 0, max: 500 }), fc.integer({ min: 1, max: 600 }))
          .map(([o, n]) => ({ a: `DB3,BYTE${o}.${n}`, v: new Array(n).fill(7) as unknown })),
      ),
      { minLength: 1, maxLength: 80 },
    );
    fc.assert(
      fc.property(writeArb, fc.constantFrom(240, 480, 960), fc.constantFrom(undefined, 20, 3), (writes, pdu, maxItems) => {
        const plan = planWrite(
          writes.map((w) => ({ tag: parseAddress(w.a), value: w.v })),
          pdu,
          maxItems === undefined ? {} : { maxItems },
        );
        expect(plan.errors.every((e) => e === undefined)).to.equal(true);
        const perTag = new Map<number, number>();
        for (const p of plan.pdus) {
          let request = 12;
          p.items.forEach((it, i) => (request += 12 + 4 + it.data.length + (it.data.length % 2 === 1 && i < p.items.length - 1 ? 1 : 0)));
          expect(request).to.be.at.most(pdu);
          expect(14 + p.items.length).to.be.at.most(pdu);
          expect(p.items.length).to.be.within(1, maxItems ?? 255);
          expect(p.requestSize).to.equal(request);
          p.items.forEach((it, i) =>
            perTag.set(p.tags[i]!, (perTag.get(p.tags[i]!) ?? 0) + (it.dataTransportSize === DataTransportSize.BIT ? 1 : it.data.length)),
          );
        }
        writes.forEach((w, i) => {
          const tag = parseAddress(w.a);
          const expected = tag.type === 'BOOL' ? 1 : tag.type === 'STRING' ? 1 + (w.v as string).length : tag.byteLength;
          expect(perTag.get(i)).to.equal(expected);
        });
      }),
      { numRuns: 200 },
    );
  });
});
