/**
 * The golden TIA Portal ↔ PLCSIM frames of gijzelaerr/s7commplus (MIT;
 * test/fixtures/s7plus/golden-tia.json says where from): our codec decodes
 * each and re-encodes it byte for byte (the explores are in
 * s7plus-messages.test.ts). Also the subscription create that the s7commplus
 * package builds (test/fixtures/s7plus/s7commplus-frames.json).
 */
import { expect } from 'chai';
import fs from 'node:fs';
import path from 'node:path';
import { ProtocolError } from '../lib/errors';
import { DataType, FunctionCode, Ids, PValueFlag, dbAccessArea } from '../lib/s7plus/constants';
import { encodeObject } from '../lib/s7plus/codec/object';
import { decodeCreateObjectRequest, encodeCreateObjectRequest } from '../lib/s7plus/codec/session';
import {
  decodeSubStreamedRequest,
  decodeSubStreamedResponse,
  encodeSubStreamedRequest,
  encodeSubStreamedResponse,
} from '../lib/s7plus/codec/substreamed';
import {
  decodeNotification,
  encodeNotification,
  parseReferenceList,
  readSubscription,
  referenceList,
  subscriptionCreateRequest,
  subscriptionObject,
  type NotificationItem,
} from '../lib/s7plus/codec/subscription';

const FIXTURES = path.join(__dirname, '..', '..', 'test', 'fixtures', 's7plus');
const load = (name: string): Record<string, Buffer> =>
  Object.fromEntries(
    Object.entries((JSON.parse(fs.readFileSync(path.join(FIXTURES, name), 'utf8')) as { frames: Record<string, string> }).frames).map(
      ([k, v]) => [k, Buffer.from(v, 'hex')],
    ),
  );
const GOLDEN = load('golden-tia.json');
const PY = load('s7commplus-frames.json');
const dataOf = (frame: Buffer): Buffer => frame.subarray(4, 4 + frame.readUInt16BE(2));
const V2 = { integrity: true };

describe('S7CommPlus golden TIA frames', () => {
  it('has the frames it names, each as long as its header says', () => {
    expect(Object.keys(GOLDEN)).to.have.length(8);
    for (const [name, f] of Object.entries(GOLDEN)) expect(f.length, name).to.equal(4 + f.readUInt16BE(2));
  });

  describe('subscription create', () => {
    it("decodes TIA's subscription create: container, integrity id 0x12, the Subscription object", () => {
      const req = decodeCreateObjectRequest(dataOf(GOLDEN.sub_create_req!), V2);
      expect(req.header).to.deep.equal({
        functionCode: FunctionCode.CreateObject,
        sequence: 0x8f,
        sessionId: 0x7000103d,
        transportFlags: 0x34,
      });
      expect(req.body.requestId).to.equal(0x7000103e);
      expect(req.integrityId).to.equal(0x12);
      expect(readSubscription(req.body.object)).to.deep.equal({
        relationId: 0x7fffc056,
        cycleMs: 900,
        creditLimit: -1,
        changeCounter: 1,
        items: [],
      });
      expect(encodeCreateObjectRequest(req).equals(dataOf(GOLDEN.sub_create_req!))).to.equal(true);
    });

    it("builds TIA's Subscription object byte for byte from its settings", () => {
      const req = decodeCreateObjectRequest(dataOf(GOLDEN.sub_create_req!), V2);
      const ours = subscriptionObject({
        relationId: 0x7fffc056,
        cycleMs: 900,
        creditLimit: -1,
        changeCounter: 1,
        items: [],
        routeMode: 1,
        functionClassId: 3,
      });
      expect(encodeObject(ours).toString('hex')).to.equal(encodeObject(req.body.object).toString('hex'));
    });

    it("builds s7commplus's subscription create byte for byte (subscription.py build_subscription_request)", () => {
      const item = { referenceId: 1, accessArea: dbAccessArea(1), symbolCrc: 0x1234, accessSubArea: Ids.DBValueActual, lids: [0xa] };
      const object = subscriptionObject({ relationId: 0x7fffc001, cycleMs: 250, creditLimit: 10, changeCounter: 1, items: [item] });
      const req = { ...subscriptionCreateRequest(9, 0x3a1, 0x7000103e, object), integrityId: 0x12 };
      expect(encodeCreateObjectRequest(req).toString('hex')).to.equal(PY.subscription_create_request!.toString('hex'));
      expect(readSubscription(decodeCreateObjectRequest(PY.subscription_create_request!, V2).body.object).items).to.deep.equal([item]);
    });

    it('refuses a reference list that does not follow the layout, and a CreateObject that is no subscription', () => {
      const good = referenceList(1, [{ referenceId: 1, accessArea: 1, symbolCrc: 0, accessSubArea: 2, lids: [3, 4] }]);
      expect(parseReferenceList(good).items[0]!.lids).to.deep.equal([3, 4]);
      expect(() => parseReferenceList(good.slice(0, -1))).to.throw(ProtocolError, /item 1 is cut short/);
      expect(() => parseReferenceList([...good, 9])).to.throw(ProtocolError, /1 values after the last item/);
      expect(() => parseReferenceList([5, 0, 0])).to.throw(ProtocolError, /no list head/);
      const session = decodeCreateObjectRequest(dataOf(PY.session_create_frame!), V2).body.object;
      expect(() => readSubscription(session)).to.throw(ProtocolError, /class 287, not a subscription/);
    });
  });

  describe('notifications', () => {
    it('decodes the CPU-state notification: subscription, sequence, timestamp, a struct of four DInt', () => {
      const data = dataOf(GOLDEN.notification_cpu_state!);
      const n = decodeNotification(data);
      expect(n.subscriptionId).to.equal(0x7000103f);
      expect(n.reserved).to.deep.equal([0x0400, 0, 0]);
      expect(n.sequence).to.equal(2);
      expect(n.creditTick).to.equal(0);
      // s7commplus's tests/test_golden_tia_captures.py reads the same: 1789505130017193 µs.
      expect(n.timestamp).to.equal(1789505130017193n);
      expect(new Date(Number(n.timestamp! / 1000n)).toISOString()).to.match(/^2026-09-15T/); // the capture's date
      expect(n.changeCounter).to.equal(2);
      expect(n.items).to.have.length(1);
      const item = n.items[0]!;
      expect(item.kind === 'value' && item.ref).to.equal(1);
      const struct =
        item.kind === 'value' ? (item.value.value as { id: number; members: { key: number; value: { value: unknown } }[] }) : undefined;
      expect(struct?.id).to.equal(0xe79);
      expect(struct?.members.map((m) => [m.key, m.value.value])).to.deep.equal([
        [3700, 3],
        [3696, 1],
        [3697, 2],
        [3698, 0],
      ]);
      expect(encodeNotification(n).equals(data)).to.equal(true);
    });

    it('decodes the event notification: sequence 531 and 15 records, and re-encodes it', () => {
      const data = dataOf(GOLDEN.notification_sub_events!);
      const n = decodeNotification(data);
      expect(n.subscriptionId).to.equal(0x70001040);
      expect(n.sequence).to.equal(531);
      expect(n.items.map((i) => i.ref)).to.deep.equal([13, 14, 15, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 16]);
      const udint = n.items.find((i) => i.ref === 3);
      expect(udint?.kind === 'value' && udint.value).to.deep.equal({ flags: 0, type: DataType.UDInt, value: 0x04500000 });
      expect(encodeNotification(n).equals(data)).to.equal(true);
    });

    it('round-trips error records and values by VLQ reference; refuses an unknown record with ProtocolError', () => {
      const n = {
        subscriptionId: 5,
        reserved: [0, 0, 0] as [number, number, number],
        creditTick: 1,
        sequence: 300,
        changeCounter: 4,
        items: [
          { kind: 'error', ref: 7, status: 0x13 },
          { kind: 'value', ref: 200, vlqRef: true, value: { flags: 0, type: DataType.Int, value: -5 } },
        ] as NotificationItem[],
      };
      expect(decodeNotification(encodeNotification(n))).to.deep.equal(n);
      const bad = Buffer.from(encodeNotification(n));
      bad[15] = 0x77; // the first record's tag
      expect(() => decodeNotification(bad)).to.throw(ProtocolError, /record 0x77 at offset 15/);
      expect(() => decodeNotification(dataOf(GOLDEN.symbolic_write_resp!))).to.throw(ProtocolError, /expected a notification/);
    });
  });

  describe('symbolic write (SetVarSubStreamed)', () => {
    it("decodes TIA's write of 'test' and re-encodes it byte for byte", () => {
      const data = dataOf(GOLDEN.symbolic_write_req!);
      const req = decodeSubStreamedRequest(data, V2);
      expect(req.header.functionCode).to.equal(FunctionCode.SetVarSubStreamed);
      expect(req.body.inObjectId).to.equal(0xc9);
      expect(req.body.address).to.deep.equal({ flags: PValueFlag.AddressArray, type: DataType.UDInt, value: [415] });
      expect(req.body.qualifier).to.deep.equal({ parentRid: 0, compositionAid: 0, keyQualifier: 0 });
      expect(req.body.sequenceField).to.equal(1);
      expect(req.body.value).to.deep.equal({ flags: 0, type: DataType.Blob, value: { rootId: 0, data: Buffer.from('test') } });
      expect(req.integrityId).to.equal(6);
      expect(encodeSubStreamedRequest(req).equals(data)).to.equal(true);
    });

    it('decodes its answer (return value 0, the byte 0x0D after it) and re-encodes it', () => {
      const data = dataOf(GOLDEN.symbolic_write_resp!);
      const res = decodeSubStreamedResponse(data, FunctionCode.SetVarSubStreamed, { integrity: false });
      expect(res.body).to.deep.equal({ returnValue: 0n, marker: 0x0d });
      expect(encodeSubStreamedResponse(res).equals(data)).to.equal(true);
    });

    it('carries a value in a GetVarSubStreamed answer (the protection level, a UDInt)', () => {
      const header = { functionCode: FunctionCode.GetVarSubStreamed, sequence: 3, transportFlags: 0x34 };
      const body = { returnValue: 0n, marker: 0, value: { flags: 0, type: DataType.UDInt, value: 3 } };
      const back = decodeSubStreamedResponse(
        encodeSubStreamedResponse({ header, body, integrityId: 9 }),
        FunctionCode.GetVarSubStreamed,
        V2,
      );
      expect(back).to.deep.equal({ header, body, integrityId: 9 });
    });
  });
});
