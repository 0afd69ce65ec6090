/**
 * S7CommPlus messages against bytes we did not write:
 * - test/fixtures/s7plus/s7commplus-frames.json: requests and answers the
 *   s7commplus package 0.3.0 (PyPI, MIT) builds (its client's and its
 *   server's own functions, run once; the file says which);
 * - test/fixtures/s7plus/golden-tia.json: TIA Portal ↔ PLCSIM frames from
 *   gijzelaerr/s7commplus (MIT).
 * Requests must re-encode byte for byte; answers must decode to what the peer meant.
 */
import { expect } from 'chai';
import fs from 'node:fs';
import path from 'node:path';
import { ProtocolError } from '../lib/errors';
import { DataType, FunctionCode, Ids, serviceResultCode } from '../lib/s7plus/constants';
import {
  decodeExploreRequest,
  decodeExploreResponse,
  encodeExploreRequest,
  encodeExploreResponse,
  cpuExecUnitObject,
  cpuStateOf,
  exploreRequest,
} from '../lib/s7plus/codec/explore';
import { encodeFrames, S7pFrameReader } from '../lib/s7plus/codec/frame';
import { peekMessage } from '../lib/s7plus/codec/header';
import { attributeOf, childrenOf, decodeObject, encodeObject } from '../lib/s7plus/codec/object';
import {
  decodeCreateObjectRequest,
  decodeCreateObjectResponse,
  decodeDeleteObjectRequest,
  decodeDeleteObjectResponse,
  decodeInitSslRequest,
  decodeInitSslResponse,
  encodeCreateObjectRequest,
  encodeCreateObjectResponse,
  encodeDeleteObjectRequest,
  encodeDeleteObjectResponse,
  encodeInitSslRequest,
  encodeInitSslResponse,
  sessionCreateRequest,
  sessionInfo,
} from '../lib/s7plus/codec/session';
import {
  blobValue,
  classicBlobAddress,
  decodeGetMultiVariablesRequest,
  decodeGetMultiVariablesResponse,
  decodeSetMultiVariablesRequest,
  decodeSetMultiVariablesResponse,
  encodeGetMultiVariablesRequest,
  encodeGetMultiVariablesResponse,
  encodeSetMultiVariablesRequest,
  encodeSetMultiVariablesResponse,
  isSessionSetup,
  readRequest,
  resolveClassicBlob,
  sessionSetupRequest,
  writeRequest,
} from '../lib/s7plus/codec/variables';

const FIXTURES = path.join(__dirname, '..', '..', 'test', 'fixtures', 's7plus');
const load = (name: string): Record<string, Buffer> =>
  Object.fromEntries(
    Object.entries((JSON.parse(fs.readFileSync(path.join(FIXTURES, name), 'utf8')) as { frames: Record<string, string> }).frames).map(
      ([k, v]) => [k, Buffer.from(v, 'hex')],
    ),
  );
const PY = load('s7commplus-frames.json');
const GOLDEN = load('golden-tia.json');
const hex = (s: string) => Buffer.from(s.replace(/\s+/g, ''), 'hex');
/** The data of a frame (header and trailer off). */
const dataOf = (frame: Buffer): Buffer => frame.subarray(4, 4 + frame.readUInt16BE(2));
const V2 = { integrity: true };
const V1 = { integrity: false };

function throwsProtocol(f: () => unknown, pattern: RegExp): void {
  expect(f).to.throw(ProtocolError, pattern);
}

describe('S7CommPlus messages', () => {
  describe('InitSSL, CreateObject, DeleteObject (the session)', () => {
    it('encodes InitSSL as s7commplus does (flags 0x30, session 0, 4 zero bytes) and decodes its answer', () => {
      const req = encodeInitSslRequest(1);
      expect(req.toString('hex')).to.equal('31000005b3000000010000000030' + '00000000');
      expect(decodeInitSslRequest(req).header).to.deep.equal({
        functionCode: FunctionCode.InitSsl,
        sequence: 1,
        sessionId: 0,
        transportFlags: 0x30,
      });
      const res = decodeInitSslResponse(PY.init_ssl_response!);
      expect(res.body.returnValue).to.equal(0n);
      expect(encodeInitSslResponse(res).equals(PY.init_ssl_response!)).to.equal(true);
    });

    it("builds the session's CreateObject byte for byte as s7commplus's client (connection.py _create_session)", () => {
      const frame = PY.session_create_frame!;
      const ours = encodeCreateObjectRequest(sessionCreateRequest(1, { name: 's7commplus' }));
      expect(encodeFrames(1, ours).toString('hex')).to.equal(frame.toString('hex'));
      const back = decodeCreateObjectRequest(dataOf(frame), V2); // no integrity id before the session exists
      expect(back.body.requestId).to.equal(Ids.ObjectServerSessionContainer);
      expect(back.integrityId).to.equal(undefined);
      expect(attributeOf(back.body.object, Ids.ObjectVariableTypeName)?.value).to.equal('s7commplus');
      expect(childrenOf(back.body.object).map((o) => o.classId)).to.deep.equal([Ids.ClassSubscriptions]);
    });

    it("decodes s7commplus's server's CreateObject answer: session id, ServerSessionVersion, and re-encodes it", () => {
      const res = decodeCreateObjectResponse(PY.create_object_response!);
      expect(res.body.objectIds).to.deep.equal([1]);
      const info = sessionInfo(res.body);
      expect(info).to.deep.equal({
        sessionId: 1,
        subscriptionContainerId: 0,
        serverSessionVersion: { flags: 0, type: DataType.UDInt, value: 1 },
      });
      expect(encodeCreateObjectResponse(res).equals(PY.create_object_response!)).to.equal(true);
    });

    it('says in a ProtocolError that the PLC refused the session, with its code', () => {
      const refused = encodeCreateObjectResponse({
        header: { functionCode: FunctionCode.CreateObject, sequence: 2, transportFlags: 0 },
        body: { returnValue: 0x8318890001b3fffen, objectIds: [] },
      });
      const body = decodeCreateObjectResponse(refused).body;
      expect(() => sessionInfo(body)).to.throw(ProtocolError, /refused the session \(CreateObject returned 0x8318890001b3fffe\)/);
      expect(serviceResultCode(body.returnValue)).to.equal(-2);
    });

    it('encodes DeleteObject with and without integrity id; takes the 4-byte close of s7commplus; decodes the answer', () => {
      const header = { functionCode: FunctionCode.DeleteObject, sequence: 9, sessionId: 0x3a1, transportFlags: 0x34 };
      const withId = encodeDeleteObjectRequest({ header, body: { objectId: 0x3a1 }, integrityId: 130 });
      expect(withId.subarray(14).toString('hex')).to.equal('000003a1' + '8102' + '00000000');
      expect(decodeDeleteObjectRequest(withId, V2)).to.deep.equal({ header, body: { objectId: 0x3a1 }, integrityId: 130 });
      const python = hex('31000004d4 0000 0009 000003a1 34 00000000');
      expect(decodeDeleteObjectRequest(python, V2).body.objectId).to.equal(0);
      const res = decodeDeleteObjectResponse(PY.delete_object_response!, V1);
      expect(res.body.returnValue).to.equal(0n);
      expect(encodeDeleteObjectResponse(res).equals(PY.delete_object_response!)).to.equal(true);
    });
  });

  describe('session setup (SetMultiVariables of ServerSessionVersion)', () => {
    it('writes ServerSessionVersion back byte for byte as s7commplus (connection.py _build_session_setup_frame)', () => {
      const frame = PY.session_setup_frame!;
      const req = sessionSetupRequest(3, 0x3a1, { flags: 0, type: DataType.UDInt, value: 2 });
      expect(encodeFrames(2, encodeSetMultiVariablesRequest(req)).toString('hex')).to.equal(frame.toString('hex'));
      const back = decodeSetMultiVariablesRequest(dataOf(frame), V1);
      expect(isSessionSetup(back.body)).to.equal(true);
      expect(back.body.targets).to.deep.equal({ kind: 'attributes', inObjectId: 0x3a1, ids: [306] });
    });
  });

  describe('Explore', () => {
    for (const name of ['explore_device_tree_req', 'explore_asroot_req', 'explore_pair_req']) {
      it(`decodes the golden ${name} and re-encodes it byte for byte`, () => {
        const data = dataOf(GOLDEN[name]!);
        const req = decodeExploreRequest(data, V2);
        expect(req.header.sessionId).to.equal(0x7000103d);
        expect(encodeExploreRequest(req).equals(data)).to.equal(true);
      });
    }

    it('reads the golden explores field by field (ids, flags, the 58 attributes, the integrity ids 4, 33, 34)', () => {
      const tree = decodeExploreRequest(dataOf(GOLDEN.explore_device_tree_req!), V2);
      expect(tree.body).to.deep.equal({ exploreId: 0x22, requestId: 0, childsRecursive: 1, flag: 1, parents: 0, attributes: [] });
      expect(tree.integrityId).to.equal(4);
      const root = decodeExploreRequest(dataOf(GOLDEN.explore_asroot_req!), V2);
      expect(root.body.exploreId).to.equal(Ids.NativeThePlcProgramRID);
      expect(root.body.attributes).to.have.length(58);
      expect(root.body.attributes).to.include(Ids.ObjectVariableTypeName);
      expect(root.integrityId).to.equal(33);
      const pair = decodeExploreRequest(dataOf(GOLDEN.explore_pair_req!), V2);
      expect(pair.body.exploreId).to.equal(Ids.DBWildcardRID);
      expect(pair.integrityId).to.equal(34);
    });

    it("encodes the CPU-state Explore byte for byte as s7commplus's client (theCPUexecUnit, RID 52)", () => {
      const req = { ...exploreRequest(7, 0x3a1, Ids.NativeTheCpuExecUnitRID), integrityId: 4 };
      expect(encodeExploreRequest(req).toString('hex')).to.equal(PY.cpu_state_request!.toString('hex'));
      const attrs = { ...exploreRequest(8, 0x3a1, Ids.NativeThePlcProgramRID, [233, 2521]), integrityId: 200 };
      expect(encodeExploreRequest(attrs).toString('hex')).to.equal(PY.explore_request!.toString('hex'));
    });

    it("reads RUN from s7commplus's server's theCPUexecUnit, and our simulator's object is the same bytes", () => {
      const res = decodeExploreResponse(PY.cpu_state_response!, V1);
      expect(cpuStateOf(res.body.objects)).to.equal('RUN');
      const ours = encodeExploreResponse({ header: res.header, body: { returnValue: 0n, objects: [cpuExecUnitObject('RUN')] } });
      expect(ours.toString('hex')).to.equal(PY.cpu_state_response!.toString('hex'));
      expect(cpuStateOf([cpuExecUnitObject('STOP')])).to.equal('STOP');
      expect(cpuStateOf([])).to.equal('UNKNOWN');
    });

    it('reads the CPU state from the cycle attributes 0x1F80/0x1F81 when the struct is absent (1/7 RUN, 0/0 STOP)', () => {
      const obj = (a: number, b: number) =>
        decodeObject(
          hex(`a1 00000034 9103 00 00 a3 bf00 0003 ${a.toString(16).padStart(4, '0')} a3 bf01 0003 ${b.toString(16).padStart(4, '0')} a2`),
        ).value;
      expect(cpuStateOf([obj(1, 7)])).to.equal('RUN');
      expect(cpuStateOf([obj(0, 0)])).to.equal('STOP');
      expect(cpuStateOf([obj(0, 8)])).to.equal('UNKNOWN');
    });

    it('returns the return value of an Explore of a missing object (s7commplus server: -12) and no objects', () => {
      const res = decodeExploreResponse(PY.explore_missing_response!, V1);
      expect(res.body.returnValue).to.equal(0x8020ab001992fff4n);
      expect(serviceResultCode(res.body.returnValue)).to.equal(-12);
      expect(res.body.objects).to.deep.equal([]);
    });

    it('keeps bytes between the return value and the first object, and the integrity id after the body', () => {
      const header = { functionCode: FunctionCode.Explore, sequence: 1, transportFlags: 0x34 };
      const body = { returnValue: 0n, preamble: hex('0000000305'), objects: [cpuExecUnitObject('STOP')] };
      const back = decodeExploreResponse(encodeExploreResponse({ header, body, integrityId: 300 }), V2);
      expect(back).to.deep.equal({ header, body, integrityId: 300 });
    });

    it('refuses filter objects and truncated requests with ProtocolError', () => {
      const data = Buffer.from(dataOf(GOLDEN.explore_device_tree_req!));
      data[14 + 8] = 1; // filter count
      throwsProtocol(() => decodeExploreRequest(data, V2), /1 filter objects is not supported/);
      throwsProtocol(() => decodeExploreRequest(dataOf(GOLDEN.explore_device_tree_req!).subarray(0, 25), V2), /truncated/);
      throwsProtocol(
        () => decodeExploreRequest(dataOf(GOLDEN.explore_device_tree_req!), V1),
        /1 unexpected bytes after the Explore request/,
      );
    });
  });

  describe('objects', () => {
    it('keeps relations and type-info lists as they came, and re-encodes them', () => {
      const bytes = hex('a1 51010001 8a0c 00 00 a4 941c 00000008 ab 0004 01020304 0002 0506 0000 ac 0000 a1 00000000 00 00 00 a2 a2');
      const { value, length } = decodeObject(Buffer.concat([bytes, hex('ff')]));
      expect(length).to.equal(bytes.length);
      expect(value.members.map((m) => m.kind)).to.deep.equal(['relation', 'list', 'list', 'object']);
      expect(value.members[0]).to.deep.equal({ kind: 'relation', id: 2588, target: 8 });
      expect(encodeObject(value).equals(bytes)).to.equal(true);
    });

    it('throws ProtocolError on an object without terminator, an unknown element, and nesting too deep', () => {
      throwsProtocol(() => decodeObject(hex('a1 00000001 00 00 00 a3 8169 0001 01')), /no terminator/);
      throwsProtocol(() => decodeObject(hex('a1 00000001 00 00 00 a7 a2')), /element 0xa7 .* not supported/);
      throwsProtocol(() => decodeObject(hex('a1 00000001 00 00 00'.repeat(70))), /nested deeper than 64/);
      throwsProtocol(() => decodeObject(hex('a2')), /expected an object \(0xa1\) at offset 0/);
    });
  });

  describe('GetMultiVariables, SetMultiVariables', () => {
    it("encodes a DB read by address byte for byte as s7commplus's client (classic blob, two items)", () => {
      const req = { ...readRequest(5, 0x3a1, [classicBlobAddress(1, 0, 4), classicBlobAddress(7, 10, 2)]), integrityId: 3 };
      expect(encodeGetMultiVariablesRequest(req).toString('hex')).to.equal(PY.read_request!.toString('hex'));
      const back = decodeGetMultiVariablesRequest(PY.read_request!, V2);
      expect(back.body.addresses.map(resolveClassicBlob)).to.deep.equal([
        { db: 1, offset: 0, length: 4 },
        { db: 7, offset: 10, length: 2 },
      ]);
      expect(back.integrityId).to.equal(3);
    });

    it("decodes s7commplus's server's read answer: item 1 a blob, item 2 error 0x8104", () => {
      const res = decodeGetMultiVariablesResponse(PY.read_response!, V1);
      expect([...res.body.values]).to.deep.equal([[1, blobValue(hex('01020304'))]]);
      expect([...res.body.errors]).to.deep.equal([[2, 0x8104n]]);
      const ours = encodeGetMultiVariablesResponse(res);
      // s7commplus's V1 server adds a zero legacy integrity id; ours sends one only where the session has them.
      expect(Buffer.concat([ours, hex('00')]).equals(PY.read_response!)).to.equal(true);
      expect(decodeGetMultiVariablesResponse(encodeGetMultiVariablesResponse({ ...res, integrityId: 7 }), V2).integrityId).to.equal(7);
    });

    it("encodes a DB write byte for byte as s7commplus's client, and decodes its server's answer", () => {
      const req = { ...writeRequest(6, 0x3a1, [classicBlobAddress(1, 2, 2)], [blobValue(hex('1234'))]), integrityId: 1 };
      expect(encodeSetMultiVariablesRequest(req).toString('hex')).to.equal(PY.write_request!.toString('hex'));
      const back = decodeSetMultiVariablesRequest(PY.write_request!, V2);
      expect(back.body.values).to.deep.equal([blobValue(hex('1234'))]);
      expect(isSessionSetup(back.body)).to.equal(false);
      const res = decodeSetMultiVariablesResponse(PY.write_response!, V1);
      expect(res.body).to.deep.equal({ returnValue: 0n, errors: new Map() });
      const failed = encodeSetMultiVariablesResponse({
        header: res.header,
        body: { returnValue: 0n, errors: new Map([[1, 0x8104n]]) },
        integrityId: 2,
      });
      expect(decodeSetMultiVariablesResponse(failed, V2).body.errors.get(1)).to.equal(0x8104n);
    });

    it('refuses inconsistent requests and answers with ProtocolError', () => {
      const bad = Buffer.from(PY.read_request!);
      bad[14 + 5] = 0x0d; // field count 13 for 14 fields
      throwsProtocol(() => decodeGetMultiVariablesRequest(bad, V2), /counts 13 address fields, its addresses have 14/);
      const w = Buffer.from(PY.write_request!);
      throwsProtocol(() => decodeSetMultiVariablesRequest(Buffer.concat([w.subarray(0, 32), hex('02')]), V2), /item 2 where item 1 of 1/);
      throwsProtocol(
        () => decodeGetMultiVariablesResponse(hex('320000054c0000000500 00 01 0002 05 01 0002 06 00 00'), V1),
        /item 1 answered twice/,
      );
      throwsProtocol(
        () => decodeGetMultiVariablesResponse(hex('320000054200000005 00 00'), V1),
        /answer to function 0x054c is function 0x0542/,
      );
      throwsProtocol(() => decodeGetMultiVariablesRequest(PY.read_response!, V1), /expected a request \(0x31\), found opcode 0x32/);
    });

    it('peeks opcode, function and sequence to route an answer', () => {
      expect(peekMessage(PY.read_response!)).to.deep.equal({ opcode: 0x32, functionCode: FunctionCode.GetMultiVariables, sequence: 5 });
      expect(peekMessage(dataOf(GOLDEN.notification_cpu_state!))).to.deep.equal({ opcode: 0x33 });
    });
  });

  it('the frame reader hands every golden frame (with a trailer added) back whole', () => {
    const reader = new S7pFrameReader();
    const frames = Object.values(GOLDEN);
    const got = reader.push(Buffer.concat(frames.flatMap((f) => [f, hex('72020000')])));
    expect(got.map((m) => m.data.toString('hex'))).to.deep.equal(frames.map((f) => dataOf(f).toString('hex')));
  });
});
