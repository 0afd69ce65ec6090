import { expect } from 'chai';
import { ValueError } from '../lib/errors';
import { encodeReadRequest, encodeReadResponse, encodeWriteRequest, encodeWriteResponse, tpktFrame, type S7Item } from '../lib/s7/codec';
import { encodeSzl } from '../lib/s7/codec/szl';
import { encodeUserdata } from '../lib/s7/codec/userdata';

/** What an encoder throws when given something it cannot encode (docs/architecture.md: encoders throw ValueError). */
function thrown(f: () => unknown): unknown {
  try {
    f();
  } catch (err) {
    return err;
  }
  expect.fail('no error thrown');
}

function expectValueError(f: () => unknown, words: RegExp): void {
  const err = thrown(f);
  expect(err).to.be.instanceOf(ValueError);
  expect((err as ValueError).code).to.equal('INVALID_VALUE');
  expect((err as ValueError).message).to.match(words);
}

describe('S7 encoders refuse what they cannot encode with ValueError', () => {
  const item: S7Item = { area: 0x84, dbNumber: 1, transportSize: 0x02, count: 1, address: 0 };
  const many = Array.from({ length: 256 }, () => item);

  it('a job of more than 255 items', () => {
    expectValueError(() => encodeReadRequest(1, many), /"item count": an S7 job carries at most 255 items, got 256/);
    expectValueError(
      () =>
        encodeWriteRequest(
          1,
          many.map((i) => ({ ...i, dataTransportSize: 0x04, data: Buffer.alloc(1) })),
        ),
      /at most 255 items, got 256/,
    );
    expectValueError(() => encodeWriteResponse(1, new Array<number>(256).fill(0xff)), /at most 255 items, got 256/);
    expectValueError(
      () =>
        encodeReadResponse(
          1,
          many.map(() => ({ returnCode: 0xff, transportSize: 0x04, data: Buffer.alloc(1) })),
        ),
      /at most 255 items/,
    );
    // 255 is the limit, not past it.
    expect(encodeReadRequest(1, many.slice(0, 255))).to.be.instanceOf(Buffer);
  });

  it('a TPKT packet longer than 65535 bytes', () => {
    expectValueError(() => tpktFrame(0xffff), /"TPKT packet": 65539 bytes exceed 65535/);
    expect(tpktFrame(0xffff - 4).length).to.equal(0xffff);
  });

  it('userdata that does not fit an S7 PDU', () => {
    const params = { method: 0x11, type: 4, group: 4, subfunction: 1, sequence: 0 };
    expectValueError(() => encodeUserdata(1, params, Buffer.alloc(0xffff)), /"userdata": 65539 bytes do not fit an S7 PDU/);
  });

  it('an SZL record of another length than its list says', () => {
    const list = { id: 0x0011, index: 0, recordLength: 28, records: [Buffer.alloc(28), Buffer.alloc(27)] };
    expectValueError(() => encodeSzl(list), /"SZL record 1": it has 27 bytes, the list's records 28/);
  });
});
