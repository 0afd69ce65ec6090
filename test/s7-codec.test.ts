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
} from '../lib/s7/codec';
import { describeReturnCode, headerError, remoteTsapFor } from '../lib/s7/constants';

const hex = (s: string) => Buffer.from(s.replace(/[\s|]+/g, ''), 'hex');
const show = (b: Buffer) => b.toString('hex').toUpperCase();

/** Frames verbatim from the S7 source document (seeds/000, PROTOCOLS.md §1). */
const DOC = {
  connectionRequest: hex('03 00 00 16 11 E0 00 00 00 01 00 C1 02 10 00 C2 02 03 01 C0 01 0A'),
  connectionConfirm: hex('03 00 00 16 11 D0 00 01 00 11 00 C0 01 0A C1 02 10 00 C2 02 03 01'),
  setup: hex('03 00 00 19 02 F0 80 32 01 00 00 CC C1 00 08 00 00 F0 00 00 01 00 01 03 C0'),
  setupAck: hex('03 00 00 1B 02 F0 80 32 03 00 00 CC C1 00 08 00 00 00 00 F0 00 00 01 00 01 00 F0'),
  // Four BYTE items of DB200 at bit addresses 0, 17, 81, 89 (the document's erratum: 17/81/89 are not byte aligned).
  read: hex(
    '03 00 00 43 02 F0 80 32 01 00 00 00 01 00 32 00 00 04 04' +
      '12 0A 10 02 00 01 00 C8 84 00 00 00' +
      '12 0A 10 02 00 01 00 C8 84 00 00 11' +
      '12 0A 10 02 00 01 00 C8 84 00 00 51' +
      '12 0A 10 02 00 01 00 C8 84 00 00 59',
  ),
  // One BYTE of DB200, value 9 (at bit address 9, as printed).
  write: hex('03 00 00 24 02 F0 80 32 01 00 00 00 09 00 0E 00 05 05 01 12 0A 10 02 00 01 00 C8 84 00 00 09 00 04 00 08 09'),
};

describe('S7 codec', () => {
  describe('the source document frames', () => {
    it('encodes the connection request byte for byte (calling TSAP 0x1000, called 0x0301 = basic, rack 0 slot 1)', () => {
      const frame = encodeConnectionRequest({ sourceRef: 1, callingTsap: 0x1000, calledTsap: remoteTsapFor('basic', 0, 1), tpduSize: 0x0a });
      expect(show(frame)).to.equal(show(DOC.connectionRequest));
      expect(decodeCotp(DOC.connectionRequest)).to.deep.equal({ type: 'CR', sourceRef: 1, destinationRef: 0, callingTsap: 0x1000, calledTsap: 0x0301, tpduSize: 0x0a });
    });

    it('decodes the PLC connection confirm (byte 5 = 0xD0) and encodes it the same way', () => {
      const cc = decodeCotp(DOC.connectionConfirm);
      expect(cc).to.deep.equal({ type: 'CC', destinationRef: 1, sourceRef: 0x11, callingTsap: 0x1000, calledTsap: 0x0301, tpduSize: 0x0a });
      expect(show(encodeConnectionConfirm({ destinationRef: 1, sourceRef: 0x11, callingTsap: 0x1000, calledTsap: 0x0301, tpduSize: 0x0a }))).to.equal(show(DOC.connectionConfirm));
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
        expect(ack.items.map((i) => [i.returnCode, show(i.data)])).to.deep.equal([[0xff, 'AA'], [0x0a, ''], [0xff, '01'], [0xff, 'BBCCDD']]);
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

    it('property: any bytes decode to a message or a ProtocolError, never anything else', () => {
      const seeds = [DOC.setupAck, DOC.read, DOC.write, encodeWriteResponse(1, [0xff]), encodeErrorAck(2, 0x85, 0)];
      const mutated = fc.tuple(fc.constantFrom(...seeds), fc.array(fc.tuple(fc.nat(80), fc.nat(255)), { maxLength: 6 }), fc.nat(90)).map(([seed, edits, cut]) => {
        const b = Buffer.from(seed);
        for (const [i, v] of edits) if (i < b.length) b[i] = v;
        return b.subarray(0, Math.min(b.length, cut + 7));
      });
      fc.assert(
        fc.property(fc.oneof(mutated, fc.uint8Array({ maxLength: 80 }).map((a) => Buffer.from(a))), (frame) => {
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
        }),
        { numRuns: 20000 },
      );
    });
  });
});
