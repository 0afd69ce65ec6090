/**
 * The classic alarm codec (lib/s7/codec/alarms.ts, alarm-query.ts) against hex fixtures laid out byte by byte from
 * PLC4X's s7.mspec and the fields Wireshark's s7comm dissector names (the same bytes tshark reads clean in
 * test/s7-alarms-tshark.test.ts): each encodes to its fixture and decodes back to its fields.
 */
import { expect } from 'chai';
import { decodeQueryAnswer, decodeQueryRequest, encodeQueryAnswer, encodeQueryRequest } from '../lib/s7/codec/alarm-query';
import {
  decodeAckAnswer,
  decodeAckIndication,
  decodeAckRequest,
  decodeAlarmIndication,
  decodeMessageServiceAnswer,
  decodeMessageServiceRequest,
  encodeAckRequest,
  encodeAlarmIndication,
  encodeMessageServiceRequest,
} from '../lib/s7/codec/alarms';
import { ProtocolError } from '../lib/errors';

const hex = (s: string) => Buffer.from(s.replace(/\s+/g, ''), 'hex');
const T = new Date(Date.UTC(2024, 4, 3, 10, 11, 12, 345));
const STAMP = '24 05 03 10 11 12 34 56'; // 2024-05-03 10:11:12.345, a Friday (6)

describe('S7 classic alarm codec: hex fixtures (issue #33)', () => {
  it('message service: MODE+SYS+ALM with ALARM_S_INITIATE, and its answers', () => {
    const req = hex('83 00 706c63776972652020 09 00'.replace('706c63776972652020', '706c637769726520'));
    expect(encodeMessageServiceRequest({ events: 0x83, username: 'plcwire', alarms: 9 })).to.deep.equal(req);
    expect(decodeMessageServiceRequest(req)).to.deep.equal({ events: 0x83, username: 'plcwire ', alarms: 9 });
    expect(decodeMessageServiceAnswer(hex('02 00 09 00 00'))).to.deep.equal({ result: 2, alarmType: 9 });
    expect(decodeMessageServiceAnswer(hex('02 00'))).to.deep.equal({ result: 2 });
    expect(() => decodeMessageServiceAnswer(hex('02 00 09'))).to.throw(ProtocolError);
  });

  it('ALARM_S indication with three associated values (lengths in bits for sizes 4 and 5, bytes for REAL)', () => {
    const data = hex(`${STAMP} 00 01  12 1e 16 03 60000001 01 00 ff fe  ff 04 0010 0102  ff 07 0004 41200000  ff 05 0010 fffe`);
    const ind = {
      time: T,
      objects: [
        {
          syntaxId: 0x16,
          eventId: 0x60000001,
          eventState: 1,
          localState: 0,
          ackGoing: 0xff,
          ackComing: 0xfe,
          values: [
            { returnCode: 0xff, transportSize: 4, data: hex('0102') },
            { returnCode: 0xff, transportSize: 7, data: hex('41200000') },
            { returnCode: 0xff, transportSize: 5, data: hex('fffe') },
          ],
        },
      ],
    };
    expect(encodeAlarmIndication(ind)).to.deep.equal(data);
    expect(decodeAlarmIndication(data)).to.deep.equal(ind);
    expect(() => decodeAlarmIndication(data.subarray(0, data.length - 1))).to.throw(ProtocolError);
  });

  it('NOTIFY indication: its object has the 4 event bytes (going, coming, last changed, reserved)', () => {
    const data = hex(`${STAMP} 00 01  12 0e 1c 00 00002003 01 00 ff ff 00 01 01 00`);
    const ind = decodeAlarmIndication(data);
    expect(ind.objects[0]).to.deep.include({
      syntaxId: 0x1c,
      eventId: 0x2003,
      eventState: 1,
      notify: { going: 0, coming: 1, lastChanged: 1 },
    });
    expect(encodeAlarmIndication(ind)).to.deep.equal(data);
  });

  it('acknowledgement: request, answer, indication', () => {
    const req = hex('09 01  12 08 19 01 60000001 00 01');
    expect(encodeAckRequest([{ eventId: 0x60000001, ackGoing: 0, ackComing: 1 }])).to.deep.equal(req);
    expect(decodeAckRequest(req)).to.deep.equal([{ eventId: 0x60000001, ackGoing: 0, ackComing: 1 }]);
    expect(decodeAckAnswer(hex('09 02 ff 0a'))).to.deep.equal([0xff, 0x0a]);
    const ind = decodeAckIndication(hex(`${STAMP} 00 01 12 08 19 01 60000001 ff ff`));
    expect(ind).to.deep.equal({ time: T, objects: [{ eventId: 0x60000001, ackGoing: 0xff, ackComing: 0xff }] });
  });

  it('alarm query: the request by alarm type, an answer with one dataset, and the empty answer (0x0A)', () => {
    expect(encodeQueryRequest(4)).to.deep.equal(hex('00 01 12 08 1a 00 01 34 00000004'));
    expect(decodeQueryRequest(hex('00 01 12 08 1a 00 01 34 00000004'))).to.deep.equal({ queryType: 1, alarmType: 4 });
    expect(decodeQueryRequest(hex('00 01 12 08 1a 00 01 34 04'))).to.deep.equal({ queryType: 1, alarmType: 4 }); // PLC4X's one-byte form
    const answer = hex(`00 01 ff 09 0026  25 0000 04 00000101 00 01 ff fe  ${STAMP} ff 05 0010 0102  0000000000000000 0a 00 0000`);
    const entry = {
      alarmType: 4,
      eventId: 0x101,
      eventState: 1,
      ackGoing: 0xff,
      ackComing: 0xfe,
      coming: { time: T, value: { returnCode: 0xff, transportSize: 5, data: hex('0102') } },
    };
    expect(encodeQueryAnswer([entry])).to.deep.equal(answer);
    expect(decodeQueryAnswer(answer)).to.deep.equal([entry]);
    expect(encodeQueryAnswer([])).to.deep.equal(hex('00 00 0a 00 0000'));
    expect(decodeQueryAnswer(hex('00 00 0a 00 0000'))).to.deep.equal([]);
  });
});
