import { expect } from 'chai';
import { S7_TAG_SYNTAX } from '../lib/address';
import { AddressError } from '../lib/errors';
import { Org } from '../lib/fetchwrite/codec';
import {
  MERGE_GAP,
  checkReach,
  enclosingUnits,
  maxJobBytes,
  planRead,
  planWrite,
  splitJobs,
  wireUnits,
  type DbUnit,
} from '../lib/fetchwrite/plan';
import type { Tag } from '../lib/types';

const tag = (address: string): Tag => S7_TAG_SYNTAX.parse(address);
const tags = (...addresses: string[]): Tag[] => addresses.map(tag);
/** A plan's ranges without their tag lists, for comparing. */
const spans = (addresses: string[], dbUnit: DbUnit = 'word') =>
  planRead(tags(...addresses), dbUnit).ranges.map(({ org, dbNumber, start, length }) => ({ org, dbNumber, start, length }));

describe('FETCH/WRITE planner (lib/fetchwrite/plan.ts)', () => {
  describe('read ranges', () => {
    it('merges tags of one DB into one range and keeps each tag index', () => {
      const plan = planRead(tags('DB1.DBW10', 'DB1.DBW0', 'DB1.DBD4'), 'word');
      expect(plan.unreadable).to.deep.equal([]);
      expect(plan.ranges).to.deep.equal([{ org: Org.DB, dbNumber: 1, start: 0, length: 12, tags: [1, 2, 0] }]);
    });

    it(`merges across a gap of ${MERGE_GAP} bytes, not one byte more`, () => {
      // DBB0 ends at byte 1: a tag starting at 1 + gap is merged, at 2 + gap it is not.
      const far = spans(['DB1.DBB0', `DB1.DBB${1 + MERGE_GAP}`], 'byte');
      expect(far).to.deep.equal([{ org: Org.DB, dbNumber: 1, start: 0, length: 2 + MERGE_GAP }]);
      const farther = spans(['DB1.DBB0', `DB1.DBB${2 + MERGE_GAP}`], 'byte');
      expect(farther).to.deep.equal([
        { org: Org.DB, dbNumber: 1, start: 0, length: 1 },
        { org: Org.DB, dbNumber: 1, start: 2 + MERGE_GAP, length: 1 },
      ]);
    });

    it('keeps areas and DBs apart, in ORG order then DB number', () => {
      expect(spans(['MB0', 'DB2.DBW0', 'DB1.DBW0'])).to.deep.equal([
        { org: Org.DB, dbNumber: 1, start: 0, length: 2 },
        { org: Org.DB, dbNumber: 2, start: 0, length: 2 },
        { org: Org.M, dbNumber: 0, start: 0, length: 1 },
      ]);
    });

    it('aligns a DB counted in words to whole words, and not with dbUnit=byte', () => {
      expect(spans(['DB1.DBB3'])).to.deep.equal([{ org: Org.DB, dbNumber: 1, start: 2, length: 2 }]);
      expect(spans(['DB1.DBB3'], 'byte')).to.deep.equal([{ org: Org.DB, dbNumber: 1, start: 3, length: 1 }]);
    });

    it('counts counters and timers two bytes a number, one number a job (the ORG range takes length 1)', () => {
      expect(spans(['C5', 'C6', 'T2'])).to.deep.equal([
        { org: Org.C, dbNumber: 0, start: 10, length: 2 },
        { org: Org.C, dbNumber: 0, start: 12, length: 2 },
        { org: Org.T, dbNumber: 0, start: 4, length: 2 },
      ]);
    });

    it('does not merge past what one job may carry, unless one tag alone is longer', () => {
      const max = maxJobBytes(Org.DB, 'word');
      expect(max).to.equal(4096);
      expect(spans(['DB1,B0.4000', `DB1.DBW${max - 2}`])).to.deep.equal([{ org: Org.DB, dbNumber: 1, start: 0, length: max }]);
      expect(spans(['DB1,B0.4000', `DB1.DBW${max}`])).to.have.length(2);
      expect(spans(['DB1,B0.5000', 'DB1.DBW4'])).to.deep.equal([{ org: Org.DB, dbNumber: 1, start: 0, length: 5000 }]);
    });

    it('leaves the output modules (PA) unreadable and plans the rest', () => {
      const plan = planRead(tags('PAW256', 'PEW256'), 'word');
      expect(plan.unreadable).to.deep.equal([0]);
      expect(plan.ranges).to.deep.equal([{ org: Org.PEPA, dbNumber: 0, start: 256, length: 2, tags: [1] }]);
    });
  });

  describe('jobs', () => {
    it('splits a range into jobs of at most maxJobBytes, in order, covering it once', () => {
      const jobs = splitJobs({ org: Org.DB, dbNumber: 1, start: 100, length: 5000 }, 'word');
      expect(jobs).to.deep.equal([
        { org: Org.DB, dbNumber: 1, start: 100, length: 4096 },
        { org: Org.DB, dbNumber: 1, start: 4196, length: 904 },
      ]);
      expect(splitJobs({ org: Org.DB, dbNumber: 1, start: 0, length: 5000 }, 'byte').map((j) => j.length)).to.deep.equal([2048, 2048, 904]);
      expect(splitJobs({ org: Org.M, dbNumber: 0, start: 0, length: 256 }, 'word')).to.have.length(1);
    });

    it('gives start and length in the area unit of the request header', () => {
      expect(wireUnits({ org: Org.DB, dbNumber: 1, start: 10, length: 4 }, 'word')).to.deep.equal({ start: 5, length: 2 });
      expect(wireUnits({ org: Org.DB, dbNumber: 1, start: 10, length: 4 }, 'byte')).to.deep.equal({ start: 10, length: 4 });
      expect(wireUnits({ org: Org.T, dbNumber: 0, start: 4, length: 2 }, 'byte')).to.deep.equal({ start: 2, length: 1 });
      expect(wireUnits({ org: Org.M, dbNumber: 0, start: 7, length: 3 }, 'word')).to.deep.equal({ start: 7, length: 3 });
    });

    it('widens a changed byte range to whole units for a read-modify-write', () => {
      expect(enclosingUnits({ org: Org.DB, dbNumber: 1, start: 3, length: 2 }, 'word')).to.deep.equal({
        org: Org.DB,
        dbNumber: 1,
        start: 2,
        length: 4,
      });
      expect(enclosingUnits({ org: Org.DB, dbNumber: 1, start: 3, length: 2 }, 'byte')).to.deep.equal({
        org: Org.DB,
        dbNumber: 1,
        start: 3,
        length: 2,
      });
    });
  });

  describe('writes', () => {
    it('writes a word on a word boundary as it is', () => {
      const plan = planWrite(tag('DB1.DBW4'), 0x1234, 'word');
      expect(plan.kind).to.equal('direct');
      if (plan.kind !== 'direct') return;
      expect(plan.at).to.deep.equal({ org: Org.DB, dbNumber: 1, start: 4 });
      expect([...plan.data]).to.deep.equal([0x12, 0x34]);
    });

    it('writes a bit by read-modify-write of its byte, changing only that bit', () => {
      const plan = planWrite(tag('DB1.DBX3.1'), true, 'word');
      expect(plan.kind).to.equal('modify');
      if (plan.kind !== 'modify') return;
      expect(plan.range).to.deep.equal({ org: Org.DB, dbNumber: 1, start: 3, length: 1 });
      const word = Buffer.from([0xf0, 0x0c]);
      plan.change(word, 1);
      expect([...word]).to.deep.equal([0xf0, 0x0e]);
    });

    it('writes an odd byte of a DB counted in words by read-modify-write, directly with dbUnit=byte', () => {
      const odd = planWrite(tag('DB1.DBB3'), 0x7f, 'word');
      expect(odd.kind).to.equal('modify');
      if (odd.kind === 'modify') {
        expect(odd.range).to.deep.equal({ org: Org.DB, dbNumber: 1, start: 3, length: 1 });
        const word = Buffer.from([0xaa, 0xbb]);
        odd.change(word, 1);
        expect([...word]).to.deep.equal([0xaa, 0x7f]);
      }
      expect(planWrite(tag('DB1.DBB3'), 0x7f, 'byte').kind).to.equal('direct');
    });

    it('writes a counter at two bytes a number', () => {
      const plan = planWrite(tag('C5'), 42, 'word');
      expect(plan.kind).to.equal('direct');
      if (plan.kind === 'direct') expect(plan.at).to.deep.equal({ org: Org.C, dbNumber: 0, start: 10 });
    });
  });

  describe('reach', () => {
    it('refuses a DB beyond 255 and an address beyond the ORG range with an AddressError naming the address', () => {
      expect(() => checkReach(tag('DB300.DBW0'), 'word'))
        .to.throw(AddressError, /DB300 cannot be reached by FETCH\/WRITE \(ORG 1 takes DB 1..255\)/)
        .with.property('message')
        .that.contains('DB300.DBW0');
      expect(() => checkReach(tag('MB256'), 'word')).to.throw(AddressError, /starts beyond what FETCH\/WRITE reaches \(M bytes 0..255\)/);
      expect(() => checkReach(tag('DB1.DBW4095'), 'word')).to.throw(
        AddressError,
        /ends beyond what FETCH\/WRITE reaches \(DB bytes 0..4095\)/,
      );
      expect(() => checkReach(tag('DB1.DBW4094'), 'word')).not.to.throw();
      expect(() => checkReach(tag('DB1.DBW4094'), 'byte')).not.to.throw();
      expect(() => checkReach(tag('C256'), 'word')).to.throw(AddressError, /\(C 0..255\)/);
    });
  });
});
