import { expect } from 'chai';
import fc from 'fast-check';
import { PlcError, ProtocolError } from '../lib/errors';
import { FrameReader } from '../lib/link/framer';
import {
  OpCode,
  checkRequest,
  checkResponse,
  decodeRequest,
  decodeResponse,
  encodeRequest,
  encodeResponse,
  errorFor,
  type ResponseExpectation,
} from '../lib/fetchwrite/codec';

const hex = (s: string) => Buffer.from(s.replace(/\s+/g, ''), 'hex');
const show = (b: Buffer) => b.toString('hex').toUpperCase();
const FETCH2: ResponseExpectation = { op: OpCode.FetchRequest, dataBytes: 2 };
const WRITE: ResponseExpectation = { op: OpCode.WriteRequest, dataBytes: 0 };

describe('FETCH/WRITE codec', () => {
  describe('the FETCH/WRITE frames of docs/protocols.md', () => {
    it('encodes the fetch of MB0..MB1 byte for byte', () => {
      const frame = encodeRequest({ op: OpCode.FetchRequest, org: 2, dbNumber: 0, start: 0, length: 2 });
      expect(show(frame)).to.equal(show(hex('53 35 10 01 03 05 03 08 02 00 00 00 00 02 FF 02')));
      expect(decodeRequest(frame)).to.deep.equal({ op: 5, org: 2, dbNumber: 0, start: 0, length: 2 });
    });

    it('encodes a DB write (REAL 22.0 to DB62, data word 1008) and decodes its acknowledgement', () => {
      const data = Buffer.alloc(4);
      data.writeFloatBE(22.0);
      const frame = encodeRequest({ op: OpCode.WriteRequest, org: 1, dbNumber: 62, start: 1008, length: 2, data });
      expect(show(frame)).to.equal(show(hex('53 35 10 01 03 03 03 08 01 3E 03 F0 00 02 FF 02 41 B0 00 00')));
      expect(decodeRequest(frame)).to.deep.equal({ op: 3, org: 1, dbNumber: 62, start: 1008, length: 2, data: hex('41B00000') });
      const ack = hex('53 35 10 01 03 04 0F 03 00 FF 07 00 00 00 00 00');
      expect(decodeResponse(ack)).to.deep.equal({ op: 4, error: 0, data: Buffer.alloc(0) });
      expect(show(encodeResponse(OpCode.WriteAck, 0))).to.equal(show(ack));
    });

    it('a fetch response carries its data after the 16-byte header', () => {
      const r = encodeResponse(OpCode.FetchResponse, 0, hex('12 34'));
      expect(show(r)).to.equal(show(hex('53 35 10 01 03 06 0F 03 00 FF 07 00 00 00 00 00 12 34')));
      expect(decodeResponse(r)).to.deep.equal({ op: 6, error: 0, data: hex('1234') });
    });

    it('error responses carry no data (fetch 06 and write ack 04)', () => {
      const fetchErr = encodeResponse(OpCode.FetchResponse, 0x02, Buffer.from('ignored'));
      expect(show(fetchErr)).to.equal(show(hex('53 35 10 01 03 06 0F 03 02 FF 07 00 00 00 00 00')));
      expect(decodeResponse(fetchErr)).to.deep.equal({ op: 6, error: 2, data: Buffer.alloc(0) });
      const writeErr = hex('53 35 10 01 03 04 0F 03 03 FF 07 00 00 00 00 00');
      expect(show(encodeResponse(OpCode.WriteAck, 3))).to.equal(show(writeErr));
      expect(decodeResponse(writeErr).error).to.equal(3);
    });
  });

  describe('the error byte', () => {
    it('translates the S5 CP codes into typed errors naming the job', () => {
      const e2 = errorFor(0x02, 'fetch of DB5 0+2');
      expect(e2).to.be.instanceOf(PlcError);
      expect(e2.code).to.equal('OBJECT_DOES_NOT_EXIST');
      expect(e2.plcCode).to.equal(2);
      expect(e2.message).to.match(/^fetch of DB5 0\+2: .*area does not exist/);
      expect(errorFor(0x03, 'x').code).to.equal('ADDRESS_OUT_OF_RANGE');
      expect(errorFor(0x06, 'x').code).to.equal('TYPE_NOT_SUPPORTED');
      expect(errorFor(0x06, 'x').message).to.match(/invalid ORG format/);
      expect(errorFor(0x04, 'x').message).to.match(/QVZ/);
    });

    it('keeps the number of an unknown code', () => {
      const e = errorFor(0x42, 'write of M 0+1');
      expect(e.code).to.equal('PLC_ERROR');
      expect(e.plcCode).to.equal(0x42);
      expect(e.message).to.match(/error 42 \(unknown code\)/);
    });
  });

  describe('encoder guards', () => {
    it('refuses values the header cannot carry instead of wrapping them', () => {
      for (const bad of [{ start: 0x10000 }, { length: -1 }, { dbNumber: 256 }, { start: 1.5 }]) {
        const err = (() => {
          try {
            encodeRequest({ op: OpCode.FetchRequest, org: 1, dbNumber: 1, start: 0, length: 1, ...bad });
          } catch (e) {
            return e;
          }
          return undefined;
        })();
        expect(err, JSON.stringify(bad)).to.be.instanceOf(PlcError);
      }
    });
  });

  describe('framing (the reader is told what the pending job expects)', () => {
    const answer = encodeResponse(OpCode.FetchResponse, 0, hex('ABCD'));

    it('waits for the header and the expected data, then cuts exactly that', () => {
      expect(checkResponse(answer.subarray(0, 5), FETCH2)).to.deep.equal({ kind: 'need' });
      expect(checkResponse(answer.subarray(0, 17), FETCH2)).to.deep.equal({ kind: 'need' });
      expect(checkResponse(answer, FETCH2)).to.deep.equal({ kind: 'frame', length: 18 });
      expect(checkResponse(Buffer.concat([answer, hex('99')]), FETCH2)).to.deep.equal({ kind: 'frame', length: 18 });
    });

    it('an error answer is 16 bytes even for a fetch', () => {
      expect(checkResponse(encodeResponse(OpCode.FetchResponse, 3), FETCH2)).to.deep.equal({ kind: 'frame', length: 16 });
      expect(checkResponse(encodeResponse(OpCode.WriteAck, 0), WRITE)).to.deep.equal({ kind: 'frame', length: 16 });
    });

    it('is bad on bytes with no job pending, a wrong answer type, or a wrong start', () => {
      const bad = (v: ReturnType<typeof checkResponse>) => v.kind === 'bad' && v.error instanceof ProtocolError;
      expect(bad(checkResponse(answer, undefined))).to.equal(true);
      expect(bad(checkResponse(encodeResponse(OpCode.WriteAck, 0), FETCH2))).to.equal(true);
      expect(bad(checkResponse(answer, WRITE))).to.equal(true);
      // Garbage is refused from its first bytes, without waiting for 16.
      expect(bad(checkResponse(Buffer.from('HTTP'), FETCH2))).to.equal(true);
      const wrongLength = Buffer.from(answer);
      wrongLength[2] = 0x11;
      expect(bad(checkResponse(wrongLength, FETCH2))).to.equal(true);
    });

    it('cuts a request stream: fetches are 16 bytes, writes carry their data in the header’s units', () => {
      const fetch = encodeRequest({ op: OpCode.FetchRequest, org: 1, dbNumber: 1, start: 0, length: 4 });
      const write = encodeRequest({ op: OpCode.WriteRequest, org: 1, dbNumber: 1, start: 0, length: 2, data: hex('01020304') });
      const reader = new FrameReader((b) => checkRequest(b, 'word'));
      const stream = Buffer.concat([fetch, write, fetch]);
      const frames: Buffer[] = [];
      for (const byte of stream) frames.push(...reader.push(Buffer.of(byte)));
      expect(frames.map(show)).to.deep.equal([fetch, write, fetch].map(show));
      expect(reader.push(stream).map(show)).to.deep.equal([fetch, write, fetch].map(show));
      // With byte units the same header announces 2 data bytes, not 4.
      expect(checkRequest(write, 'byte')).to.deep.equal({ kind: 'frame', length: 18 });
    });
  });

  describe('properties', () => {
    it('decoders and frame checks throw nothing (decoders: only ProtocolError) on arbitrary bytes', () => {
      fc.assert(
        fc.property(fc.uint8Array({ maxLength: 48 }), fc.nat(70000), fc.boolean(), (a, n, isFetch) => {
          const buf = Buffer.from(a);
          for (const decode of [decodeResponse, decodeRequest]) {
            try {
              decode(buf);
            } catch (err) {
              if (!(err instanceof ProtocolError)) throw err;
            }
          }
          const expectation: ResponseExpectation = { op: isFetch ? OpCode.FetchRequest : OpCode.WriteRequest, dataBytes: n };
          for (const verdict of [checkResponse(buf, expectation), checkRequest(buf, 'word'), checkRequest(buf, 'byte')]) {
            // The types say this cannot happen; the fuzz loop checks that they hold.
            // eslint-disable-next-line @typescript-eslint/only-throw-error
            if (verdict.kind === 'bad' && !(verdict.error instanceof ProtocolError)) throw verdict.error;
            if (verdict.kind === 'frame' && (verdict.length < 16 || verdict.length > buf.length)) throw new Error('bad cut');
          }
        }),
        { numRuns: 20000 },
      );
    });

    it('the same arbitrary bytes with a valid header start', () => {
      const start = hex('53 35 10 01 03');
      fc.assert(
        fc.property(fc.uint8Array({ maxLength: 40 }), (a) => {
          const buf = Buffer.concat([start, Buffer.from(a)]);
          for (const decode of [decodeResponse, decodeRequest]) {
            try {
              decode(buf);
            } catch (err) {
              if (!(err instanceof ProtocolError)) throw err;
            }
          }
        }),
        { numRuns: 20000 },
      );
    });

    it('encodeRequest ∘ decodeRequest is the identity', () => {
      fc.assert(
        fc.property(
          fc.boolean(),
          fc.integer({ min: 1, max: 7 }),
          fc.integer({ min: 0, max: 255 }),
          fc.integer({ min: 0, max: 0xffff }),
          fc.uint8Array({ minLength: 1, maxLength: 64 }),
          (isFetch, org, dbNumber, start, data) => {
            const r = isFetch
              ? { op: OpCode.FetchRequest as const, org, dbNumber, start, length: data.length }
              : { op: OpCode.WriteRequest as const, org, dbNumber, start, length: data.length, data: Buffer.from(data) };
            expect(decodeRequest(encodeRequest(r))).to.deep.equal(r);
          },
        ),
        { numRuns: 2000 },
      );
    });
  });
});
