/**
 * The cyclic-data codec (userdata group 2, issue #33) against hand-built
 * frames laid out as Wireshark's s7comm dissector reads them
 * (s7comm_decode_ud_cyclic_subfunc: item count, time base, factor, S7ANY
 * items; answers and pushes as read-response items) and PLC4X's s7.mspec
 * (S7PayloadUserDataItemCyclicServices*), one field per line.
 */
import { expect } from 'chai';
import { ProtocolError, ValueError } from '../lib/errors';
import {
  CyclicSubfunction,
  decodeCyclicSubscribe,
  decodeCyclicUnsubscribe,
  decodeCyclicValues,
  encodeCyclicAnswer,
  encodeCyclicPush,
  encodeCyclicSubscribe,
  encodeCyclicUnsubscribe,
  encodeCyclicValues,
  isCyclicRequest,
} from '../lib/s7/codec/cyclic';
import { decodeUserdata, isUserdataPush } from '../lib/s7/codec/userdata';

const hex = (...parts: string[]) => Buffer.from(parts.join('').replace(/\s+/g, ''), 'hex');

/** Registration of DB1.DBB0 BYTE[3] every 2 × 100 ms. */
const REGISTER = hex(
  '0300002d', // TPKT, 45 bytes
  '02f080', // COTP DT, EOT
  '32 07 0000 0000 0008 0014', // S7 userdata, PDU ref 0, parameters 8, data 20
  '000112 04 11 42 01 00', // userdata head, length 4, request, type 4 (request) group 2 (cyclic), subfunction 01, sequence 0
  'ff 09 0010', // item: return code FF, octet string, 16 bytes
  '0001', // item count
  '00', // time base 100 ms
  '02', // factor 2
  '12 0a 10 02 0003 0001 84 000000', // S7ANY: BYTE, 3, DB1, area DB, address 0.0
);

/** The CPU's answer: job id 1 (sequence), the first values: 3 bytes counted in bits. */
const ANSWER = hex(
  '0300002a',
  '02f080',
  '32 07 0000 0007 000c 000d', // PDU ref 7, parameters 12, data 13
  '000112 08 12 82 01 01 00 00 0000', // response, type 8 group 2, subfunction 01, sequence (job id) 1, dur 0, last unit, no error
  'ff 09 0009',
  '0001', // item count
  'ff 04 0018 123456', // return code FF, BYTE/WORD/DWORD, 24 bits, data
);

/** The same values pushed by the CPU (type 0). */
const PUSH = hex(
  '0300002a',
  '02f080',
  '32 07 0000 0000 000c 000d',
  '000112 08 12 02 01 01 00 00 0000',
  'ff 09 0009',
  '0001',
  'ff 04 0018 123456',
);

/** Unsubscribe (subfunction 04) job 1: function 05 (end one job), job id. */
const UNSUBSCRIBE = hex('0300001f', '02f080', '32 07 0000 0000 0008 0006', '000112 04 11 42 04 00', 'ff 09 0002', '05 01');

/** A refusal: 0xD805, no more cyclic read jobs; the empty item. */
const REFUSAL = hex('03000021', '02f080', '32 07 0000 0009 000c 0004', '000112 08 12 82 01 00 00 00 d805', '0a 00 0000');

const ITEM = { area: 0x84, dbNumber: 1, transportSize: 2, count: 3, address: 0 };

describe('S7 cyclic data codec (userdata group 2)', () => {
  it('encodes a registration byte for byte and decodes it back', () => {
    const frame = encodeCyclicSubscribe({ subfunction: CyclicSubfunction.Memory, timeBase: 0, factor: 2, items: [ITEM] });
    expect(frame.toString('hex')).to.equal(REGISTER.toString('hex'));
    expect(isCyclicRequest(frame)).to.equal(true);
    const u = decodeUserdata(REGISTER);
    expect(u.params).to.include({ type: 4, group: 2, subfunction: 1 });
    expect(decodeCyclicSubscribe(1, u.data)).to.deep.equal({ subfunction: 1, timeBase: 0, factor: 2, items: [ITEM] });
  });

  it("encodes the CPU's answer and push, and decodes their items as a read answer's", () => {
    const values = encodeCyclicValues([{ returnCode: 0xff, transportSize: 4, data: hex('123456') }]);
    expect(encodeCyclicAnswer(7, 1, 1, values).toString('hex')).to.equal(ANSWER.toString('hex'));
    expect(encodeCyclicPush(1, 1, values).toString('hex')).to.equal(PUSH.toString('hex'));
    expect(isUserdataPush(PUSH)).to.equal(true);
    expect(isUserdataPush(ANSWER)).to.equal(false);
    const u = decodeUserdata(PUSH);
    expect(u.params).to.include({ type: 0, group: 2, sequence: 1 });
    const items = decodeCyclicValues(u.data);
    expect(items.map((i) => [i.returnCode, i.transportSize, i.data.toString('hex')])).to.deep.equal([[0xff, 4, '123456']]);
  });

  it('encodes an unsubscribe and a refusal byte for byte', () => {
    expect(encodeCyclicUnsubscribe(1).toString('hex')).to.equal(UNSUBSCRIBE.toString('hex'));
    expect(decodeCyclicUnsubscribe(decodeUserdata(UNSUBSCRIBE).data)).to.deep.equal({ func: 5, jobId: 1 });
    expect(encodeCyclicAnswer(9, 1, 0, undefined, 0xd805).toString('hex')).to.equal(REFUSAL.toString('hex'));
    expect(decodeUserdata(REFUSAL).params.errorCode).to.equal(0xd805);
  });

  it('items: a fill byte after odd-length data except the last; a failed item carries no data; BIT counts one bit', () => {
    const items = [
      { returnCode: 0xff, transportSize: 4, data: hex('01') },
      { returnCode: 0x0a, transportSize: 0, data: Buffer.alloc(0) },
      { returnCode: 0xff, transportSize: 3, data: hex('01') },
      { returnCode: 0xff, transportSize: 9, data: hex('abcdef') },
    ];
    const data = encodeCyclicValues(items);
    expect(data.toString('hex')).to.equal(['0004', 'ff04000801', '00', '0a000000', 'ff03000101', '00', 'ff090003abcdef'].join(''));
    expect(decodeCyclicValues(data).map((i) => [i.returnCode, i.data.toString('hex')])).to.deep.equal([
      [0xff, '01'],
      [0x0a, ''],
      [0xff, '01'],
      [0xff, 'abcdef'],
    ]);
  });

  it('malformed data is a ProtocolError naming what is wrong; bad jobs are a ValueError', () => {
    const bad = (f: () => unknown, m: RegExp) => expect(f).to.throw(ProtocolError, m);
    bad(() => decodeCyclicValues(hex('00')), /at least 2/);
    bad(() => decodeCyclicValues(hex('0002', 'ff040008ff')), /item 2 of 2 is missing/);
    bad(() => decodeCyclicValues(hex('0001', 'ff040018ff')), /announces 3 bytes, 1 present/);
    bad(() => decodeCyclicValues(hex('0001', 'ff040008ff', '0000')), /2 bytes after 1 items/);
    bad(() => decodeCyclicSubscribe(1, hex('0002 00 01', '120a10020003000184000000')), /needs 28 bytes/);
    bad(() => decodeCyclicSubscribe(1, hex('0001 00 01', '120b1002000300018400000000')), /needs 16 bytes/);
    bad(() => decodeCyclicSubscribe(1, hex('0001 00 01', '120a11020003000184000000')), /item 1: not an S7ANY/);
    bad(() => decodeCyclicSubscribe(4, hex('0000 00 01')), /not a registration/);
    bad(() => decodeCyclicUnsubscribe(hex('05')), /expected 2/);
    const job = { subfunction: CyclicSubfunction.Memory as const, timeBase: 0, factor: 1, items: [ITEM] };
    expect(() => encodeCyclicSubscribe({ ...job, factor: 0 })).to.throw(ValueError, /factor 0/);
    expect(() => encodeCyclicSubscribe({ ...job, timeBase: 3 })).to.throw(ValueError, /time base 3/);
    expect(() => encodeCyclicSubscribe({ ...job, items: [] })).to.throw(ValueError, /0 items/);
  });
});
