import { expect } from 'chai';
import fc from 'fast-check';
import { PlcError, ProtocolError } from '../lib/errors';
import { FrameReader } from '../lib/link/framer';
import {
  checkTpkt,
  decodeCotp,
  decodeS7,
  encodeConnectionConfirm,
  encodeConnectionRequest,
  encodeErrorAck,
  encodeReadRequest,
  encodeReadResponse,
  encodeSetupAck,
  encodeSetupCommunication,
  encodeWriteRequest,
  encodeWriteResponse,
  encodeDisconnectRequest,
  encodeCotpError,
  dataPartLength,
  s7AnswerRef,
  scanReadAck,
  type ReadItemTable,
  type S7Item,
  type S7WriteItem,
} from '../lib/s7/codec';
import { describeReturnCode, headerError, remoteTsapFor, returnCodeError } from '../lib/s7/constants';
import { CAPTURE, DOC, HAND, hex, show } from './fixtures/s7';

describe('S7 codec', () => {
  describe('the frames of docs/protocols.md', () => {
    it('encodes the connection request byte for byte (calling TSAP 0x1000, called 0x0301 = basic, rack 0 slot 1)', () => {
      const frame = encodeConnectionRequest({
        sourceRef: 1,
        callingTsap: 0x1000,
        calledTsap: remoteTsapFor('basic', 0, 1),
        tpduSize: 0x0a,
      });
      expect(show(frame)).to.equal(show(DOC.connectionRequest));
      expect(decodeCotp(DOC.connectionRequest)).to.deep.equal({
        type: 'CR',
        sourceRef: 1,
        destinationRef: 0,
        callingTsap: 0x1000,
        calledTsap: 0x0301,
        tpduSize: 0x0a,
      });
    });

    it('decodes the PLC connection confirm (byte 5 = 0xD0) and encodes it the same way', () => {
      const cc = decodeCotp(DOC.connectionConfirm);
      expect(cc).to.deep.equal({ type: 'CC', destinationRef: 1, sourceRef: 0x11, callingTsap: 0x1000, calledTsap: 0x0301, tpduSize: 0x0a });
      expect(
        show(encodeConnectionConfirm({ destinationRef: 1, sourceRef: 0x11, callingTsap: 0x1000, calledTsap: 0x0301, tpduSize: 0x0a })),
      ).to.equal(show(DOC.connectionConfirm));
    });

    it('encodes setup communication byte for byte and decodes the negotiated PDU 240 from the answer', () => {
      expect(show(encodeSetupCommunication(0xccc1, { maxAmqCalling: 1, maxAmqCalled: 1, pduSize: 960 }))).to.equal(show(DOC.setup));
      const ack = decodeS7(DOC.setupAck);
      expect(ack).to.deep.equal({ kind: 'setup-ack', pduRef: 0xccc1, params: { maxAmqCalling: 1, maxAmqCalled: 1, pduSize: 240 } });
      expect(show(encodeSetupAck(0xccc1, { maxAmqCalling: 1, maxAmqCalled: 1, pduSize: 240 }))).to.equal(show(DOC.setupAck));
    });

    it('encodes the 67-byte four-item read byte for byte and decodes its bit addresses', () => {
      const items = [0, 17, 81, 89].map((address) => ({ area: 0x84, dbNumber: 200, transportSize: 0x02, count: 1, address }));
      expect(show(encodeReadRequest(1, items))).to.equal(show(DOC.read));
      const job = decodeS7(DOC.read);
      expect(job).to.deep.equal({ kind: 'read-request', pduRef: 1, items });
    });

    it('encodes the 36-byte write byte for byte (data length 8 bits for transport size 04)', () => {
      const item = { area: 0x84, dbNumber: 200, transportSize: 0x02, count: 1, address: 9, dataTransportSize: 0x04, data: Buffer.of(9) };
      expect(show(encodeWriteRequest(9, [item]))).to.equal(show(DOC.write));
      const job = decodeS7(DOC.write);
      expect(job.kind).to.equal('write-request');
      if (job.kind === 'write-request') {
        expect(job.items[0]!.data).to.deep.equal(Buffer.of(9));
        expect(job.items[0]!.dataTransportSize).to.equal(0x04);
      }
    });
  });

  describe('frames of real peers', () => {
    it('encodes the S7-300 connection request (TPDU size first, called TSAP 0x0102 = PG rack 0 slot 2)', () => {
      const frame = encodeConnectionRequest(
        { sourceRef: 1, callingTsap: 0x0100, calledTsap: remoteTsapFor('pg', 0, 2), tpduSize: 0x0a },
        'size-first',
      );
      expect(show(frame)).to.equal(show(CAPTURE.connectionRequestSlot2));
      expect(decodeCotp(CAPTURE.connectionRequestSlot2)).to.deep.include({
        type: 'CR',
        callingTsap: 0x0100,
        calledTsap: 0x0102,
        tpduSize: 0x0a,
      });
    });

    it('encodes setup communication asking for 480 and decodes an S7-1200 answering 240', () => {
      expect(show(encodeSetupCommunication(0, { maxAmqCalling: 1, maxAmqCalled: 1, pduSize: 480 }))).to.equal(show(CAPTURE.setup480));
      expect(show(encodeSetupCommunication(0x0400, { maxAmqCalling: 1, maxAmqCalled: 1, pduSize: 480 }))).to.equal(
        show(CAPTURE.setup1200Request),
      );
      expect(decodeS7(CAPTURE.setup1200Ack)).to.deep.equal({
        kind: 'setup-ack',
        pduRef: 0x0400,
        params: { maxAmqCalling: 1, maxAmqCalled: 1, pduSize: 240 },
      });
    });

    it('decodes the PUT/GET refusal of an S7-1200 and words it', () => {
      const msg = decodeS7(CAPTURE.putGetRefused);
      expect(msg).to.deep.equal({ kind: 'error', pduRef: 0, errorClass: 0x81, errorCode: 0x04, rosctr: 2 });
      expect(show(encodeErrorAck(0, 0x81, 0x04))).to.equal(show(CAPTURE.putGetRefused));
      const err = headerError(0x81, 0x04, 'read DB1,INT0');
      expect(err).to.be.instanceOf(PlcError);
      expect(err.code).to.equal('ACCESS_DENIED');
      expect(err.message).to.equal(
        'read DB1,INT0: the PLC answered 0x8104: function not supported or access denied: PUT/GET access is not enabled on this S7-1200/1500 (or the block is optimized)',
      );
    });

    it('encodes an ack-data refusal that echoes the function with zero items', () => {
      expect(show(encodeErrorAck(5, 0x85, 0x00, 0x04))).to.equal('0300001502F08032030000000500020000850004' + '00');
      expect(decodeS7(encodeErrorAck(5, 0x85, 0x00, 0x04))).to.deep.equal({
        kind: 'error',
        pduRef: 5,
        errorClass: 0x85,
        errorCode: 0,
        rosctr: 3,
        func: 4,
      });
    });
  });

  describe("snap7's server (an independent peer)", () => {
    it('decodes failed items sent as 05 00 00 04 with no data bytes, as snap7 does', () => {
      // Read ack of 3 items: ok INT (2 bytes), DB missing (0A 00 00 04, no data), ok BYTE. Data length 6 + 4 + 5 = 15.
      const frame = hex(
        '03 00 00 24 02 F0 80 32 03 00 00 00 07 00 02 00 0F 00 00 04 03' + 'FF 04 00 10 04 D2' + '0A 00 00 04' + 'FF 04 00 08 7E',
      );
      const ack = decodeS7(frame);
      expect(ack.kind).to.equal('read-ack');
      if (ack.kind !== 'read-ack') return;
      expect(ack.items.map((i) => [i.returnCode, show(i.data)])).to.deep.equal([
        [0xff, '04D2'],
        [0x0a, ''],
        [0xff, '7E'],
      ]);
    });
  });

  describe("in place: the client's read path (s7AnswerRef, scanReadAck)", () => {
    const table = (n: number): ReadItemTable => ({ code: new Uint8Array(n), start: new Int32Array(n), length: new Int32Array(n) });
    const snap7Ack = () =>
      hex('03 00 00 24 02 F0 80 32 03 00 00 00 07 00 02 00 0F 00 00 04 03' + 'FF 04 00 10 04 D2' + '0A 00 00 04' + 'FF 04 00 08 7E');

    it("locates snap7's items (a failed one without data) where decodeS7 finds them, at an offset in the table", () => {
      const frame = snap7Ack();
      const t = table(5);
      expect(s7AnswerRef(frame)).to.equal(7);
      expect(scanReadAck(frame, 3, t, 2)).to.equal(true);
      expect([...t.code.subarray(2)]).to.deep.equal([0xff, 0x0a, 0xff]);
      expect([...t.length.subarray(2)]).to.deep.equal([2, 0, 1]);
      expect(show(frame.subarray(t.start[2]!, t.start[2]! + 2))).to.equal('04D2');
      expect(frame[t.start[4]!]).to.equal(0x7e);
    });

    it('steps over the fill byte after an odd item', () => {
      const t = table(2);
      expect(scanReadAck(HAND.readAckWithFill, 2, t, 0)).to.equal(true);
      expect([...t.code]).to.deep.equal([0xff, 0x0a]);
      expect(HAND.readAckWithFill[t.start[0]!]).to.equal(0xaa);
    });

    it('declines what is not a plain read ack of that many items, leaving it to decodeS7', () => {
      const t = table(4);
      expect(scanReadAck(snap7Ack(), 2, t, 0), 'item count').to.equal(false);
      expect(scanReadAck(CAPTURE.putGetRefused, 0, t, 0), 'header error').to.equal(false);
      expect(scanReadAck(HAND.writeAck, 3, t, 0), 'write ack').to.equal(false);
      expect(scanReadAck(DOC.setupAck, 0, t, 0), 'setup ack').to.equal(false);
      const truncated = snap7Ack().subarray(0, 0x23);
      expect(scanReadAck(truncated, 3, t, 0), 'truncated').to.equal(false);
      expect(s7AnswerRef(truncated)).to.equal(-1);
      expect(s7AnswerRef(CAPTURE.putGetRefused)).to.equal(0);
      expect(s7AnswerRef(HAND.disconnect)).to.equal(-1);
    });

    it('property: on any bytes they agree with decodeS7 (same reference, same items), and take every plain read ack it takes', () => {
      const readAcks = [
        snap7Ack(),
        HAND.readAckWithFill,
        encodeReadResponse(0x1234, [
          { returnCode: 0xff, transportSize: 4, data: hex('01 02 03') },
          { returnCode: 0xff, transportSize: 3, data: hex('01') },
          { returnCode: 0x05, transportSize: 0, data: Buffer.alloc(0) },
          { returnCode: 0xff, transportSize: 9, data: hex('0A 0B 0C 0D 0E') },
        ]),
      ];
      const seeds = [...readAcks, DOC.setupAck, HAND.writeAck, CAPTURE.putGetRefused];
      const mutated = fc
        .tuple(fc.constantFrom(...seeds), fc.array(fc.tuple(fc.nat(60), fc.nat(255)), { maxLength: 4 }), fc.nat(60))
        .map(([seed, edits, cut]) => {
          const b = Buffer.from(seed);
          for (const [i, v] of edits) if (i < b.length) b[i] = v;
          return b.subarray(0, Math.min(b.length, cut + 7));
        });
      let taken = 0;
      fc.assert(
        fc.property(fc.oneof(mutated, fc.constantFrom(...readAcks)), fc.nat(6), (frame, count) => {
          let message;
          try {
            message = decodeS7(frame);
          } catch {
            message = undefined;
          }
          const ref = s7AnswerRef(frame);
          if (ref >= 0 && message) expect(ref).to.equal(message.pduRef);
          if (message && frame[4] === 2) expect(ref).to.equal(message.pduRef);
          const t = table(count);
          const ok = scanReadAck(frame, count, t, 0);
          const plain = message?.kind === 'read-ack' && message.items.length === count && frame[4] === 2;
          expect(ok).to.equal(plain);
          if (!ok || message?.kind !== 'read-ack') return;
          taken++;
          message.items.forEach((item, i) => {
            expect(t.code[i]).to.equal(item.returnCode);
            expect(t.length[i]).to.equal(item.data.length);
            expect(t.start[i]).to.equal(item.data.byteOffset - frame.byteOffset);
          });
        }),
        { numRuns: 20000 },
      );
      expect(taken).to.be.greaterThan(100);
    });
  });

  describe('hand-built frames', () => {
    it('decodes a read ack with a fill byte after an odd item and a failed item', () => {
      const ack = decodeS7(HAND.readAckWithFill);
      if (ack.kind !== 'read-ack') throw new Error(ack.kind);
      expect(ack.items.map((i) => [i.returnCode, i.transportSize, show(i.data)])).to.deep.equal([
        [0xff, 4, 'AA'],
        [0x0a, 0, ''],
      ]);
      expect(
        show(
          encodeReadResponse(1, [
            { returnCode: 0xff, transportSize: 4, data: hex('AA') },
            { returnCode: 0x0a, transportSize: 0, data: Buffer.alloc(0) },
          ]),
        ),
      ).to.equal(show(HAND.readAckWithFill));
    });

    it('encodes and decodes a write ack with per-item return codes', () => {
      expect(show(encodeWriteResponse(2, [0xff, 0x05, 0x0a]))).to.equal(show(HAND.writeAck));
      expect(decodeS7(HAND.writeAck)).to.deep.equal({ kind: 'write-ack', pduRef: 2, returnCodes: [0xff, 0x05, 0x0a] });
    });

    it('encodes and decodes COTP DR and ER', () => {
      expect(show(encodeDisconnectRequest(1, 1, 3))).to.equal(show(HAND.disconnect));
      expect(decodeCotp(HAND.disconnect)).to.deep.equal({ type: 'DR', destinationRef: 1, sourceRef: 1, reason: 3 });
      expect(show(encodeCotpError(1, 2))).to.equal(show(HAND.cotpError));
      expect(decodeCotp(HAND.cotpError)).to.deep.equal({ type: 'ER', destinationRef: 1, cause: 2 });
    });

    it('puts a fill byte between write items after odd data, never after the last', () => {
      const items: S7WriteItem[] = [
        { area: 0x84, dbNumber: 1, transportSize: 0x02, count: 3, address: 0, dataTransportSize: 0x04, data: hex('010203') },
        { area: 0x84, dbNumber: 1, transportSize: 0x02, count: 1, address: 80, dataTransportSize: 0x04, data: hex('04') },
      ];
      const frame = encodeWriteRequest(1, items);
      expect(show(frame.subarray(7 + 10 + 2 + 24))).to.equal('0004001801020300' + '0004000804');
      expect(frame.readUInt16BE(15)).to.equal(dataPartLength(items)).and.to.equal(13);
    });
  });

  describe('read and write answers', () => {
    it('puts a fill byte after odd-length items except the last, and decodes them back', () => {
      const frame = encodeReadResponse(7, [
        { returnCode: 0xff, transportSize: 0x04, data: hex('AA') },
        { returnCode: 0x0a, transportSize: 0x00, data: Buffer.alloc(0) },
        { returnCode: 0xff, transportSize: 0x03, data: hex('01') },
        { returnCode: 0xff, transportSize: 0x04, data: hex('BBCC DD') },
      ]);
      // header 12 + params 2 + items: (4+1+fill) (4) (4+1+fill) (4+3)
      expect(show(frame.subarray(7 + 12 + 2))).to.equal(['FF040008AA00', '0A000000', 'FF030001' + '0100', 'FF040018BBCCDD'].join(''));
      const ack = decodeS7(frame);
      expect(ack.kind).to.equal('read-ack');
      if (ack.kind === 'read-ack') {
        expect(ack.items.map((i) => [i.returnCode, show(i.data)])).to.deep.equal([
          [0xff, 'AA'],
          [0x0a, ''],
          [0xff, '01'],
          [0xff, 'BBCCDD'],
        ]);
      }
    });

    it('decodes write acknowledgements and header errors', () => {
      expect(decodeS7(encodeWriteResponse(3, [0xff, 0x05]))).to.deep.equal({ kind: 'write-ack', pduRef: 3, returnCodes: [0xff, 0x05] });
      expect(decodeS7(encodeErrorAck(4, 0x81, 0x04))).to.deep.include({ kind: 'error', pduRef: 4, errorClass: 0x81, errorCode: 0x04 });
    });

    it('writes a bit item with data length 1 (bit), and multi-item writes with fill bytes', () => {
      const frame = encodeWriteRequest(2, [
        { area: 0x84, dbNumber: 1, transportSize: 0x01, count: 1, address: 12 * 8 + 2, dataTransportSize: 0x03, data: hex('01') },
        { area: 0x83, dbNumber: 0, transportSize: 0x02, count: 2, address: 80, dataTransportSize: 0x04, data: hex('1234') },
      ]);
      const data = frame.subarray(frame.length - 12);
      expect(show(data)).to.equal('000300010100' + '000400101234');
      const job = decodeS7(frame);
      if (job.kind !== 'write-request') throw new Error(job.kind);
      expect(job.items.map((i) => show(i.data))).to.deep.equal(['01', '1234']);
    });
  });

  describe('errors in words', () => {
    it('maps item return codes to typed errors', () => {
      expect(describeReturnCode(0x0a)).to.deep.equal({ code: 'OBJECT_DOES_NOT_EXIST', text: 'object does not exist (missing DB?)' });
      expect(describeReturnCode(0x05).code).to.equal('ADDRESS_OUT_OF_RANGE');
      expect(describeReturnCode(0x03).code).to.equal('ACCESS_DENIED');
      expect(describeReturnCode(0x42).text).to.match(/0x42/);
    });

    it('words item return codes as typed errors naming the context and tag', () => {
      const missing = returnCodeError(0x0a, 'read DB7,INT0', 'DB7,INT0');
      expect(missing.code).to.equal('OBJECT_DOES_NOT_EXIST');
      expect(missing.tag).to.equal('DB7,INT0');
      expect(missing.message).to.equal('read DB7,INT0: the PLC answered 0x0A: object does not exist (missing DB?)');
      expect(returnCodeError(0x05, 'x').code).to.equal('ADDRESS_OUT_OF_RANGE');
      expect(returnCodeError(0x03, 'x').code).to.equal('ACCESS_DENIED');
      expect(returnCodeError(0x06, 'x').code).to.equal('TYPE_NOT_SUPPORTED');
      expect(returnCodeError(0x07, 'x').code).to.equal('TYPE_NOT_SUPPORTED');
      expect(headerError(0x83, 0x04, 'write').code).to.equal('ACCESS_DENIED');
    });

    it('maps header errors: PUT/GET access and PDU too large', () => {
      const putget = headerError(0x81, 0x04, 'read');
      expect(putget.code).to.equal('ACCESS_DENIED');
      expect(putget.message).to.include('PUT/GET access is not enabled on this S7-1200/1500');
      expect(headerError(0x85, 0x00, 'read').code).to.equal('PDU_TOO_LARGE');
      expect(headerError(0x99, 0x01, 'read').message).to.match(/0x9901/);
    });
  });

  describe('hostile input', () => {
    it('rejects bad TPKT headers: version, length 0, length under a COTP header', () => {
      expect(checkTpkt(hex('04000010'))).to.have.property('kind', 'bad');
      expect(checkTpkt(hex('03000000'))).to.have.property('kind', 'bad');
      expect(checkTpkt(hex('03000006'))).to.have.property('kind', 'bad');
      expect(checkTpkt(hex('0300FFFF0000'))).to.deep.equal({ kind: 'need' });
      expect(checkTpkt(hex('0300'))).to.deep.equal({ kind: 'need' });
    });

    it('cuts frames split at every byte and several frames in one chunk', () => {
      const stream = Buffer.concat([DOC.setupAck, DOC.read, DOC.write]);
      for (let split = 1; split < stream.length; split++) {
        const reader = new FrameReader(checkTpkt);
        const frames = [...reader.push(stream.subarray(0, split)), ...reader.push(stream.subarray(split))];
        expect(frames.map(show)).to.deep.equal([DOC.setupAck, DOC.read, DOC.write].map(show));
      }
    });

    it('throws ProtocolError on lengths that do not add up and on truncated items', () => {
      const wrong = Buffer.from(DOC.read);
      wrong.writeUInt16BE(0x30, 13); // parameter length
      expect(() => decodeS7(wrong)).to.throw(ProtocolError, /lengths/);
      const ack = encodeReadResponse(1, [{ returnCode: 0xff, transportSize: 0x04, data: hex('AABB') }]);
      ack.writeUInt16BE(0x0100, ack.length - 4); // announce 32 bytes
      expect(() => decodeS7(ack)).to.throw(ProtocolError, /announced/);
      expect(() => decodeS7(DOC.connectionRequest)).to.throw(ProtocolError, /expected COTP data/);
    });

    it('rejects fragmented COTP data, trailing garbage and a TPKT length that is not the frame', () => {
      const frag = Buffer.from(DOC.read);
      frag[6] = 0x00;
      expect(() => decodeS7(frag)).to.throw(ProtocolError, /fragmented/);
      expect(() => decodeS7(Buffer.concat([DOC.read, hex('00')]))).to.throw(ProtocolError, /TPKT length/);
      const longer = Buffer.concat([HAND.writeAck, hex('FF FF')]);
      longer.writeUInt16BE(longer.length, 2);
      longer.writeUInt16BE(5, 15); // data length
      expect(() => decodeS7(longer)).to.throw(ProtocolError, /3 items but 5 return codes/);
      const padded = Buffer.concat([HAND.readAckWithFill, hex('00 00')]);
      padded.writeUInt16BE(padded.length, 2);
      padded.writeUInt16BE(12, 15);
      expect(() => decodeS7(padded)).to.throw(ProtocolError, /2 stray bytes/);
    });

    it('property: read and write jobs round-trip through encode and decode', () => {
      const item = fc.record({
        area: fc.constantFrom(0x81, 0x82, 0x83, 0x84, 0x80, 0x1c, 0x1d),
        dbNumber: fc.nat(0xffff),
        transportSize: fc.constantFrom(0x01, 0x02, 0x04, 0x06, 0x08),
        count: fc.nat(0xffff),
        address: fc.nat(0xffffff),
      });
      fc.assert(
        fc.property(fc.nat(0xffff), fc.array(item, { maxLength: 20 }), (ref, items: S7Item[]) => {
          expect(decodeS7(encodeReadRequest(ref, items))).to.deep.equal({ kind: 'read-request', pduRef: ref, items });
        }),
        { numRuns: 500 },
      );
      const writeItem = fc
        .tuple(item, fc.constantFrom(0x04, 0x09, 0x07), fc.uint8Array({ maxLength: 40 }))
        .map(([i, ts, d]) => ({ ...i, dataTransportSize: ts, data: Buffer.from(d) }));
      fc.assert(
        fc.property(fc.array(writeItem, { maxLength: 10 }), (items: S7WriteItem[]) => {
          const msg = decodeS7(encodeWriteRequest(7, items));
          if (msg.kind !== 'write-request') throw new Error(msg.kind);
          expect(msg.items.map((i) => ({ ...i, data: show(i.data) }))).to.deep.equal(items.map((i) => ({ ...i, data: show(i.data) })));
        }),
        { numRuns: 500 },
      );
      const responseItem = fc.oneof(
        fc
          .tuple(fc.constantFrom(0x04, 0x05, 0x07, 0x09), fc.uint8Array({ maxLength: 40 }))
          .map(([ts, d]) => ({ returnCode: 0xff, transportSize: ts, data: Buffer.from(d) })),
        fc.constantFrom(0x01, 0x03, 0x05, 0x06, 0x07, 0x0a).map((rc) => ({ returnCode: rc, transportSize: 0, data: Buffer.alloc(0) })),
      );
      fc.assert(
        fc.property(fc.array(responseItem, { maxLength: 20 }), (items) => {
          const msg = decodeS7(encodeReadResponse(3, items));
          if (msg.kind !== 'read-ack') throw new Error(msg.kind);
          expect(msg.items.map((i) => [i.returnCode, show(i.data)])).to.deep.equal(items.map((i) => [i.returnCode, show(i.data)]));
        }),
        { numRuns: 500 },
      );
    });

    it('property: any bytes decode to a message or a ProtocolError, never anything else', () => {
      const seeds = [DOC.setupAck, DOC.read, DOC.write, encodeWriteResponse(1, [0xff]), encodeErrorAck(2, 0x85, 0)];
      const mutated = fc
        .tuple(fc.constantFrom(...seeds), fc.array(fc.tuple(fc.nat(80), fc.nat(255)), { maxLength: 6 }), fc.nat(90))
        .map(([seed, edits, cut]) => {
          const b = Buffer.from(seed);
          for (const [i, v] of edits) if (i < b.length) b[i] = v;
          return b.subarray(0, Math.min(b.length, cut + 7));
        });
      fc.assert(
        fc.property(
          fc.oneof(
            mutated,
            fc.uint8Array({ maxLength: 80 }).map((a) => Buffer.from(a)),
          ),
          (frame) => {
            try {
              decodeS7(frame);
            } catch (err) {
              if (!(err instanceof PlcError)) throw err;
            }
            try {
              decodeCotp(frame);
            } catch (err) {
              if (!(err instanceof PlcError)) throw err;
            }
            checkTpkt(frame);
          },
        ),
        { numRuns: 20000 },
      );
    });
  });
});
