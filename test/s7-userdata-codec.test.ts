import { expect } from 'chai';
import fc from 'fast-check';
import { PlcError, ProtocolError } from '../lib/errors';
import {
  decodeBlockCounts,
  decodeBlockInfo,
  decodeLoadBlock,
  encodeBlockCounts,
  encodeBlockInfo,
  encodeLoadBlock,
  type BlockSpec,
} from '../lib/s7/codec/blocks';
import {
  decodeControl,
  decodeUserdata,
  encodeControlAck,
  encodePlcStart,
  encodePlcStop,
  encodeStartUpload,
  encodeStartUploadAck,
  encodeUploadAck,
  encodeUserdata,
  encodeUserdataNext,
  encodeUserdataRequest,
  encodeUserdataResponse,
  COLD_START_ARG,
  decodePassword,
  encodePassword,
} from '../lib/s7/codec';
import { SERVICE_ERRORS, serviceError } from '../lib/s7/constants';
import { EVENT_DESCRIPTIONS, decodeDiagnosticBuffer, describeEvent, encodeDiagnosticBuffer } from '../lib/s7/codec/diagnostics';
import { STOP_CAUSES } from '../lib/s7/server/services';
import {
  decodeCommunication,
  decodeCommunicationRecords,
  decodeComponentIdentification,
  decodeCpuState,
  encodeCommunication,
  type OperatorFunctions,
  decodeModuleIdentification,
  decodeProtection,
  encodeComponentIdentification,
  encodeCpuState,
  encodeModuleIdentification,
  encodeSzl,
  parseSzl,
} from '../lib/s7/codec/szl';
import { show } from './fixtures/s7';
import { CONTROL, CPU315, PLC4X, SNAP7, UD } from './fixtures/s7-userdata';

const list = (id: number, index: number, recordLength: number, bytes: Buffer) => ({
  id,
  index,
  recordLength,
  records: Array.from({ length: bytes.length / recordLength }, (_, i) => bytes.subarray(i * recordLength, (i + 1) * recordLength)),
});

describe('S7 userdata codec', () => {
  describe('frames of the protocol layout', () => {
    it('encodes a read SZL request byte for byte and decodes its parameter head', () => {
      expect(
        show(encodeUserdata(5, { method: 0x11, type: 4, group: 4, subfunction: 1, sequence: 0 }, Buffer.of(0x00, 0x11, 0x00, 0x00))),
      ).to.equal(show(UD.szlRequest));
      const u = decodeUserdata(UD.szlRequest);
      expect(u).to.deep.include({ pduRef: 5, returnCode: 0xff, transportSize: 0x09 });
      expect(u.params).to.deep.equal({ method: 0x11, type: 4, group: 4, subfunction: 1, sequence: 0 });
      expect(show(u.data)).to.equal('00110000');
    });

    it('decodes the first part of a multi-part answer: sequence, data unit reference, "more follows"', () => {
      const u = decodeUserdata(UD.szlFirstOfTwo);
      expect(u.params).to.deep.equal({
        method: 0x12,
        type: 8,
        group: 4,
        subfunction: 1,
        sequence: 3,
        dataUnitRef: 3,
        lastDataUnit: false,
        errorCode: 0,
      });
      expect(u.data.length).to.equal(12);
    });

    it('encodes the request for the next part with the CPU sequence and data unit reference echoed', () => {
      const next = encodeUserdataNext(4, 1, 3, 3);
      next.writeUInt16BE(6, 11);
      expect(show(next)).to.equal(show(UD.szlNext));
      expect(decodeUserdata(UD.szlNext).params).to.deep.equal({
        method: 0x12,
        type: 4,
        group: 4,
        subfunction: 1,
        sequence: 3,
        dataUnitRef: 3,
        lastDataUnit: true,
        errorCode: 0,
      });
    });

    it('joins a two-part diagnostic buffer answer into its list and reads both entries with their time stamps', () => {
      const first = decodeUserdata(UD.szlFirstOfTwo);
      const last = decodeUserdata(UD.szlLastOfTwo);
      expect(last.params.lastDataUnit).to.equal(true);
      const szl = parseSzl(Buffer.concat([first.data, last.data]));
      expect(szl).to.deep.include({ id: 0x00a0, index: 0, recordLength: 20 });
      expect(szl.records.map(show)).to.deep.equal([show(CPU315.diagnostics.subarray(0, 20)), show(CPU315.diagnostics.subarray(20))]);
    });

    it('encodes a CPU answer of each kind: data, more parts, an error with the empty item', () => {
      const err = encodeUserdataResponse(7, 4, 1, { errorCode: 0xd401 });
      expect(show(err)).to.equal(show(UD.szlNotAvailable));
      const first = encodeUserdataResponse(5, 4, 1, {
        sequence: 3,
        dataUnitRef: 3,
        last: false,
        data: Buffer.concat([Buffer.from('00A0000000140002', 'hex'), CPU315.diagnostics.subarray(0, 4)]),
      });
      expect(show(first)).to.equal(show(UD.szlFirstOfTwo));
      const clock = encodeUserdataResponse(8, 7, 1, { data: UD.clockAnswer.subarray(33) });
      expect(show(clock)).to.equal(show(UD.clockAnswer));
    });

    it('encodes read clock, set clock, block info and password requests byte for byte', () => {
      const at = (f: Buffer, ref: number) => (f.writeUInt16BE(ref, 11), f);
      expect(show(at(encodeUserdataRequest(7, 1), 8))).to.equal(show(UD.clockRequest));
      expect(show(at(encodeUserdataRequest(7, 2, UD.setClock.subarray(29)), 9))).to.equal(show(UD.setClock));
      expect(show(at(encodeUserdataRequest(3, 3, Buffer.from('0A00007A', 'latin1')), 10))).to.equal(show(UD.blockInfoRequest));
      expect(show(at(encodeUserdataRequest(5, 1, encodePassword('secret')), 11))).to.equal(show(UD.setPassword));
      expect(decodePassword(encodePassword('secret'))).to.equal('secret  ');
    });
  });

  describe('every length checked', () => {
    const frames = Object.entries(UD);

    it('every truncation of every frame (TPKT length adjusted) is a ProtocolError', () => {
      for (const [name, frame] of frames) {
        for (let cut = 4; cut < frame.length; cut++) {
          const short = Buffer.from(frame.subarray(0, cut));
          short.writeUInt16BE(cut, 2);
          expect(() => decodeUserdata(short), `${name} cut at ${cut}`).to.throw(ProtocolError);
        }
      }
    });

    it('every wrong parameter length, data length, item length and parameter length byte is a ProtocolError (but a request item that overstates its length)', () => {
      for (const [name, frame] of frames) {
        for (const [at, width] of [
          [13, 2],
          [15, 2],
          [20, 1],
          [17 + frame.readUInt16BE(13) + 2, 2],
        ] as const) {
          const base = width === 2 ? frame.readUInt16BE(at) : frame[at]!;
          for (const delta of [-4, -1, 1, 4, 0x100]) {
            const bad = Buffer.from(frame);
            const v = base + delta;
            if (v < 0 || v > (width === 2 ? 0xffff : 0xff)) continue;
            if (width === 2) bad.writeUInt16BE(v, at);
            else bad[at] = v;
            // A request's item that announces more than the S7 header holds is read by the header (Apache PLC4X's
            // SZL request, fixtures PLC4X.szlRequest): the bytes present are the data. Anything else is an error.
            const request = frame[21] === 0x11;
            if (request && at === 17 + frame.readUInt16BE(13) + 2 && delta > 0) {
              expect(decodeUserdata(bad).data, `${name}: byte ${at} ${base} → ${v}`).to.deep.equal(decodeUserdata(frame).data);
              continue;
            }
            expect(() => decodeUserdata(bad), `${name}: byte ${at} ${base} → ${v}`).to.throw(ProtocolError);
          }
        }
      }
    });

    it("Apache PLC4X's SZL request (item announces 12 bytes, the header holds 4) gives SZL ID and index; an answer that does so is refused", () => {
      const u = decodeUserdata(PLC4X.szlRequest);
      expect(u.data.toString('hex')).to.equal('00110000');
      const answer = Buffer.from(UD.szlLastOfTwo);
      answer.writeUInt16BE(0x0030, answer.length - 38); // announces 48 bytes, 36 arrived
      expect(() => decodeUserdata(answer)).to.throw(ProtocolError, /announces 48 bytes, 36 present/);
    });

    it('a wrong parameter head, a "last data unit" byte other than 00/01 and a non-userdata PDU are ProtocolErrors', () => {
      const head = Buffer.from(UD.szlRequest);
      head[18] = 0x02;
      expect(() => decodeUserdata(head)).to.throw(ProtocolError, /head/);
      const last = Buffer.from(UD.szlFirstOfTwo);
      last[26] = 0x05;
      expect(() => decodeUserdata(last)).to.throw(ProtocolError, /last data unit/);
      const job = Buffer.from(UD.szlRequest);
      job[8] = 1;
      expect(() => decodeUserdata(job)).to.throw(ProtocolError, /ROSCTR/);
    });

    it('property: any bytes decode to a userdata PDU or a ProtocolError, never anything else', () => {
      fc.assert(
        fc.property(
          fc.constantFrom(...frames.map(([, f]) => f)),
          fc.array(fc.tuple(fc.nat(80), fc.integer({ min: 0, max: 255 })), { maxLength: 6 }),
          (frame, edits) => {
            const b = Buffer.from(frame);
            for (const [at, v] of edits) if (at < b.length) b[at] = v;
            try {
              decodeUserdata(b);
            } catch (err) {
              if (!(err instanceof ProtocolError)) throw err;
            }
          },
        ),
        { numRuns: 3000 },
      );
    });
  });

  describe('SZL lists', () => {
    it('a list whose record bytes do not add up to N_DR × LENTHDR is a ProtocolError naming it', () => {
      const szl = Buffer.concat([Buffer.from('00A0000000140002', 'hex'), CPU315.diagnostics.subarray(0, 30)]);
      expect(() => parseSzl(szl)).to.throw(ProtocolError, /SZL 0x00a0 index 0x0000 announces 2 records of 20 bytes, 30 bytes arrived/);
      expect(() => parseSzl(Buffer.from('0011', 'hex'))).to.throw(ProtocolError, /header/);
    });

    it('a header-only extract (0x0Fxx) announces records and carries none; the count it announced is kept', () => {
      expect(parseSzl(Buffer.from('0F1100000' + '01C0004', 'hex'))).to.deep.equal({
        id: 0x0f11,
        index: 0,
        recordLength: 28,
        records: [],
        count: 4,
      });
      // A CPU 315-2 PN/DP: 10 component identification records of 34 bytes exist.
      expect(parseSzl(CPU315.componentIdHeaderOnly)).to.deep.include({ id: 0x0f1c, recordLength: 34, records: [], count: 10 });
      // The simulator sends back the count it was given.
      const back = encodeSzl({ id: 0x0f1c, index: 0, recordLength: 34, records: [], count: 10 }, true);
      expect(show(back)).to.equal(show(CPU315.componentIdHeaderOnly));
    });

    it('SZL 0x0131 index 2 of a CPU 315-2 PN/DP is the test and commissioning functions record, not index 1 (issue #31)', () => {
      const l = list(0x0131, 2, 40, CPU315.communicationIndex2);
      expect(decodeCommunicationRecords(l)).to.deep.equal([
        {
          index: 2,
          // funkt_0 BE, funkt_1 FD, funkt_2 4F (bits 0-2 named, 3-7 reserved)
          functions: [
            'block status',
            'variable status',
            'output ISTACK',
            'output BSTACK',
            'output LSTACK',
            'force selection',
            'modify variable',
            'breakpoint',
            'exit HOLD',
            'memory reset',
            'disable job',
            'enable job',
            'delete job',
            'read job list',
            'read job',
            'replace job',
          ],
          // trgereig_0 7D: bits 0, 2-6
          triggers: ['immediately', 'main cycle start', 'main cycle end', 'RUN-STOP transition', 'after code address', 'code address area'],
          forceableVariables: 10,
          runtimeLimitSeconds: 0,
        },
      ]);
      // The index-1 decoder no longer reads it as PDU size and connections.
      expect(() => decodeCommunication(l)).to.throw(ProtocolError, /no index 1 record.*it sent index 2/);
    });

    it('SZL 0x0131 index 3 is the operator interface functions; an index without a public layout stays its record', () => {
      const [three] = decodeCommunicationRecords(list(0x0131, 3, 40, CPU315.communicationIndex3));
      expect(three).to.deep.include({
        index: 3,
        maxConsistentBytes: 240,
        maxCyclicReadJobs: 16,
        cyclicPeriodMinMs: 100,
        cyclicPeriodMaxMs: 52_100,
      });
      expect((three as OperatorFunctions).functions).to.include.members(['read once', 'write once', 'bit memory', 'user DB', 'S7 timer']);
      expect(decodeCommunicationRecords(list(0x0131, 9, 40, CPU315.communicationIndex9))).to.deep.equal([
        { index: 9, record: CPU315.communicationIndex9.toString('hex') },
      ]);
      // Index 1 as the simulator sends it, through the same dispatch.
      const one = encodeCommunication({ maxPdu: 960, maxConnections: 16, mpiRate: 187_500, busRate: 10_000_000 });
      expect(decodeCommunicationRecords(one)).to.deep.equal([
        { index: 1, maxPdu: 960, maxConnections: 16, mpiRate: 187_500, busRate: 10_000_000 },
      ]);
      expect(() => decodeCommunicationRecords(list(0x0131, 2, 20, CPU315.communicationIndex2.subarray(0, 20)))).to.throw(
        ProtocolError,
        /20 bytes/,
      );
    });

    it('reads module identification of a CPU 315-2 PN/DP: order code, hardware 4, firmware V3.2.6', () => {
      const m = decodeModuleIdentification(list(0x0011, 0, 28, CPU315.moduleId));
      expect(m).to.deep.include({ orderCode: '6ES7 315-2EH14-0AB0', hardwareVersion: 4, firmware: 'V3.2.6' });
      const back = encodeModuleIdentification('6ES7 315-2EH14-0AB0', 4, 'V3.2.6');
      expect(decodeModuleIdentification(back)).to.deep.include({
        orderCode: '6ES7 315-2EH14-0AB0',
        hardwareVersion: 4,
        firmware: 'V3.2.6',
      });
      expect(show(back.records[2]!)).to.equal(show(CPU315.moduleId.subarray(28)));
    });

    it('reads the protection record: level 1, mode selector RUN-P', () => {
      expect(decodeProtection(list(0x0232, 4, 40, CPU315.protection))).to.deep.equal({
        level: 1,
        switchLevel: 1,
        configuredLevel: 0,
        keySwitch: 'RUN-P',
        startupSwitch: undefined,
      });
    });

    it('reads the CPU state record: RUN (code 8), the transition event and its BCD time', () => {
      const s = decodeCpuState(list(0x0424, 0, 20, CPU315.cpuState));
      expect(s).to.deep.include({ mode: 'RUN', modeCode: 8, previousCode: 0, eventId: 0x5144 });
      expect(s.time.toISOString()).to.equal('1994-02-05T02:01:55.906Z');
      const stop = decodeCpuState(encodeCpuState(4, 0x4304, new Date('2026-01-02T03:04:05.060Z'), 8));
      expect(stop).to.deep.include({ mode: 'STOP', modeCode: 4, previousCode: 8, eventId: 0x4304 });
    });

    it('component identification keeps the record order 1, 2, 3, 4, 5, 7 (clients read fixed offsets) and trims the padding', () => {
      const c = {
        asName: 'LINE 4',
        moduleName: 'PLC_1',
        plantId: 'PLANT-A',
        copyright: 'Original Siemens Equipment',
        serialNumber: 'S C-X1234',
        moduleTypeName: 'CPU 1516-3 PN/DP',
      };
      const l = encodeComponentIdentification(c);
      expect(l.records.map((r) => r.readUInt16BE(0))).to.deep.equal([1, 2, 3, 4, 5, 7]);
      const bytes = encodeSzl(l).subarray(4);
      expect(bytes.subarray(2 + 140, 2 + 140 + 9).toString('latin1')).to.equal('S C-X1234');
      expect(decodeComponentIdentification(l)).to.deep.include(c);
    });
  });

  describe('diagnostic buffer', () => {
    it('takes the time stamp from the last 8 bytes of each 20-byte entry (BCD), not from the info fields', () => {
      const [a, b] = decodeDiagnosticBuffer(list(0x00a0, 0, 20, CPU315.diagnostics));
      expect(a).to.deep.include({
        eventId: 0x4302,
        priority: 0xff,
        ob: 0x68,
        dataId: 0xc700,
        info1: 0,
        info2: 0x0814,
        info3: 0x7714,
        description: 'Mode transition STARTUP to RUN',
      });
      expect(a!.time.toISOString()).to.equal('1994-02-04T23:52:16.388Z');
      expect(b).to.deep.include({ eventId: 0x1381, priority: 0xfe, ob: 100, description: 'Manual warm restart requested' });
      expect(b!.time.toISOString()).to.equal('1994-02-04T23:52:16.387Z');
    });

    it('keeps the number of an event it does not describe, and encodes entries back byte for byte', () => {
      expect(describeEvent(0xc711)).to.equal('event 0xc711');
      const entries = decodeDiagnosticBuffer(list(0x00a0, 0, 20, CPU315.diagnostics));
      expect(show(encodeSzl(encodeDiagnosticBuffer(entries)).subarray(8))).to.equal(show(CPU315.diagnostics));
      expect(encodeDiagnosticBuffer(entries, 1)).to.deep.include({ id: 0x01a0, index: 1 });
    });

    it('entries of another size are a ProtocolError', () => {
      expect(() => decodeDiagnosticBuffer(list(0x00a0, 0, 10, CPU315.diagnostics))).to.throw(ProtocolError, /20/);
    });

    it('0x494E, as a real buffer holds it, is "STOP caused by power failure" (issue #31)', () => {
      const entry = Buffer.from(CPU315.diagnostics.subarray(0, 20));
      entry.writeUInt16BE(0x494e, 0);
      expect(decodeDiagnosticBuffer(list(0x00a0, 0, 20, entry))[0]).to.deep.include({
        eventId: 0x494e,
        description: 'STOP caused by power failure',
      });
    });

    it("the table's coverage: every event the simulator logs, every STOP cause, classes 1, 2, 3, 4 and 6 of the published lists", () => {
      const logged = [0x1381, 0x1382, 0x1385, 0x4301, 0x4302, ...Object.values(STOP_CAUSES)];
      for (const id of logged) expect(EVENT_DESCRIPTIONS, `0x${id.toString(16)}`).to.have.property(String(id));
      const classes = new Set(Object.keys(EVENT_DESCRIPTIONS).map((k) => Number(k) >> 12));
      expect([...classes].sort()).to.deep.equal([1, 2, 3, 4, 6]);
      // Each text is its own (no copy-paste of one text under two IDs).
      const texts = Object.values(EVENT_DESCRIPTIONS);
      expect(new Set(texts).size).to.equal(texts.length);
      // The STOP causes and defects of class 4 the manuals list: 0x4520-0x4532, 0x4541-0x4548, 0x4562-0x456F, 0x494D-0x494F.
      const stops = [0x4520, 0x4521, 0x4522, 0x4523, 0x4524, 0x4525, 0x4527, 0x4528, 0x4530, 0x4531, 0x4532];
      stops.push(0x4541, 0x4542, 0x4543, 0x4544, 0x4545, 0x4546, 0x4547, 0x4548);
      stops.push(0x4562, 0x4563, 0x4567, 0x4568, 0x456a, 0x456b, 0x456c, 0x456d, 0x456e, 0x456f, 0x494d, 0x494e, 0x494f);
      for (const id of stops) expect(describeEvent(id), `0x${id.toString(16)}`).to.match(/^(STOP|DEFECT)/);
      // Coming and going of one asynchronous error differ in bit 8 only, and their texts say which.
      expect(describeEvent(0x39c4)).to.equal('Distributed I/O: station failure');
      expect(describeEvent(0x38c4)).to.equal('Distributed I/O: station back');
    });

    it('an ID without its own text is named by its class and whether it is coming or going', () => {
      expect(describeEvent(0x39ff)).to.equal('asynchronous error 0x39ff, coming');
      expect(describeEvent(0x38ff)).to.equal('asynchronous error 0x38ff, going');
      expect(describeEvent(0xa001)).to.equal('user-defined event 0xa001, going');
      expect(describeEvent(0x5144)).to.equal('mode run-time event 0x5144, coming');
      expect(describeEvent(0x0001)).to.equal('event 0x0001');
    });
  });

  describe('blocks', () => {
    const spec: BlockSpec = {
      type: 'DB',
      number: 7,
      languageCode: 5,
      mc7Size: 10,
      author: 'PLCWIRE',
      family: 'SIM',
      name: 'DB7',
      version: 0x12,
      checksum: 0xbeef,
      codeTime: new Date('2019-11-18T10:11:12.345Z'),
      interfaceTime: new Date('1999-11-18T00:00:00.000Z'),
    };

    it('block info round-trips every field; time stamps count days from 1984 and ms of the day', () => {
      const b = encodeBlockInfo(spec);
      expect(b.length).to.equal(78);
      // 1999-11-18 is day 5800 after 1984-01-01.
      expect(b.readUInt16BE(28 + 4)).to.equal(5800);
      expect(decodeBlockInfo(b)).to.deep.include({
        type: 'DB',
        number: 7,
        language: 'DB',
        mc7Size: 10,
        dataLength: 10,
        loadSize: 102,
        author: 'PLCWIRE',
        family: 'SIM',
        name: 'DB7',
        version: '1.2',
        checksum: 0xbeef,
        protected: false,
      });
      expect(decodeBlockInfo(b).codeTime.toISOString()).to.equal('2019-11-18T10:11:12.345Z');
      expect(() => decodeBlockInfo(b.subarray(0, 40))).to.throw(ProtocolError, /78/);
    });

    it('the block list of all types comes as 7 entries of 4 bytes, in the CPU order OB FB FC DB SDB SFC SFB', () => {
      const bytes = encodeBlockCounts({ OB: 3, DB: 100, FC: 2 });
      expect(show(bytes)).to.equal('30380003' + '30450000' + '30430002' + '30410064' + '30420000' + '30440000' + '30460000');
      expect(decodeBlockCounts(bytes)).to.deep.equal({ OB: 3, FB: 0, FC: 2, DB: 100, SDB: 0, SFC: 0, SFB: 0 });
      expect(() => decodeBlockCounts(bytes.subarray(0, 6))).to.throw(ProtocolError);
    });

    it('the load-memory form: 36-byte header, the code, 56-byte footer; a header that announces more code than arrived is a ProtocolError', () => {
      const code = Buffer.from('0102030405060708090a', 'hex');
      const block = encodeLoadBlock(spec, code);
      expect(block.length).to.equal(102);
      expect(decodeLoadBlock(block)).to.deep.include({ type: 'DB', number: 7 });
      expect(show(decodeLoadBlock(block).code)).to.equal(show(code));
      expect(() => decodeLoadBlock(block.subarray(0, 40))).to.throw(ProtocolError, /announces 10 bytes/);
    });

    it("snap7's answer to block info of a DB it does not have is malformed: a TPKT frame 78 bytes longer than its S7 lengths, and with no answer before it not even an S7 header", () => {
      const after = SNAP7.blockInfoMissingAfterAnswer;
      const first = SNAP7.blockInfoMissingFirst;
      expect([after.length, after.readUInt16BE(2), first.readUInt16BE(2)]).to.deep.equal([111, 111, 111]);
      // The S7 header counts 10 + 12 + 4 bytes of the 104 after the COTP header; the rest is zeros.
      expect(after.subarray(33).equals(Buffer.alloc(78))).to.equal(true);
      expect(() => decodeUserdata(after)).to.throw(
        ProtocolError,
        'S7 lengths (header 10 + parameters 12 + data 4) do not match the PDU (104)',
      );
      expect(() => decodeUserdata(first)).to.throw(ProtocolError, 'S7 protocol id 0x0, expected 0x32');
      // The same answer framed as its S7 header says is a legitimate error answer: block not found.
      const framed = Buffer.from(after.subarray(0, 33));
      framed.writeUInt16BE(33, 2);
      expect(show(framed)).to.equal(show(SNAP7.blockInfoMissingWellFormed));
      const u = decodeUserdata(SNAP7.blockInfoMissingWellFormed);
      expect(u).to.deep.include({ returnCode: 0x0a, transportSize: 0 });
      expect(u.params).to.deep.include({ type: 8, group: 3, subfunction: 3, errorCode: 0xd209, lastDataUnit: true });
      expect(serviceError(u.params.errorCode!, 'x').code).to.equal('OBJECT_DOES_NOT_EXIST');
    });
  });

  describe('control jobs', () => {
    const at = (f: Buffer, ref: number) => (f.writeUInt16BE(ref, 11), f);

    it('encodes PLC stop, hot start and cold start byte for byte and decodes them', () => {
      expect(show(at(encodePlcStop(), 12))).to.equal(show(CONTROL.stop));
      expect(show(at(encodePlcStart(), 13))).to.equal(show(CONTROL.hotStart));
      expect(show(at(encodePlcStart(COLD_START_ARG), 14))).to.equal(show(CONTROL.coldStart));
      expect(decodeControl(CONTROL.stop)).to.deep.equal({ kind: 'stop', pduRef: 12 });
      expect(decodeControl(CONTROL.hotStart)).to.deep.equal({ kind: 'start', pduRef: 13, cold: false, service: 'P_PROGRAM' });
      expect(decodeControl(CONTROL.coldStart)).to.deep.equal({ kind: 'start', pduRef: 14, cold: true, service: 'P_PROGRAM' });
    });

    it('decodes a refused stop: the header error and the status parameter 07 (already in STOP)', () => {
      expect(decodeControl(CONTROL.stopRefused)).to.deep.equal({ kind: 'control-ack', pduRef: 12, func: 0x29, status: 7, error: 0x8402 });
      expect(show(encodeControlAck(12, 0x29, 7, 0x8402))).to.equal(show(CONTROL.stopRefused));
    });

    it('encodes and decodes the upload sequence: start (file name "_0A00001A"), its answer, a part', () => {
      expect(show(at(encodeStartUpload(0x41, 1), 15))).to.equal(show(CONTROL.startUpload));
      expect(decodeControl(CONTROL.startUpload)).to.deep.equal({ kind: 'start-upload', pduRef: 15, blockType: 0x41, number: 1 });
      expect(show(encodeStartUploadAck(15, 7, 102))).to.equal(show(CONTROL.startUploadAck));
      expect(decodeControl(CONTROL.startUploadAck)).to.deep.equal({ kind: 'start-upload-ack', pduRef: 15, uploadId: 7, loadLength: 102 });
      expect(show(encodeUploadAck(16, Buffer.from('70700101', 'hex'), true))).to.equal(show(CONTROL.uploadAck));
      const part = decodeControl(CONTROL.uploadAck);
      expect(part).to.deep.include({ kind: 'upload-ack', more: true });
    });

    it('every truncation and every wrong length of a control frame is a ProtocolError', () => {
      for (const [name, frame] of Object.entries(CONTROL)) {
        for (let cut = 4; cut < frame.length; cut++) {
          const short = Buffer.from(frame.subarray(0, cut));
          short.writeUInt16BE(cut, 2);
          expect(() => decodeControl(short), `${name} cut at ${cut}`).to.throw(ProtocolError);
        }
      }
      const len = Buffer.from(CONTROL.uploadAck);
      len.writeUInt16BE(5, 19 + 2);
      expect(() => decodeControl(len)).to.throw(ProtocolError, /announces 5 bytes/);
      const name = Buffer.from(CONTROL.startUploadAck);
      name[29] = 0x41;
      expect(() => decodeControl(name)).to.throw(ProtocolError, /not a number/);
    });
  });

  describe('error codes', () => {
    it('maps every service error code to its typed code and words, naming the request', () => {
      for (const [key, [code, words]] of Object.entries(SERVICE_ERRORS)) {
        const err = serviceError(Number(key), 's7://plc read SZL 0x0011');
        expect(err).to.be.instanceOf(PlcError);
        expect(err.code, key).to.equal(code);
        expect(err.plcCode).to.equal(Number(key));
        expect(err.message).to.equal(`s7://plc read SZL 0x0011: the PLC answered 0x${Number(key).toString(16).padStart(4, '0')}: ${words}`);
      }
      expect(serviceError(0xd401, 'x').code).to.equal('SZL_NOT_AVAILABLE');
      expect(serviceError(0xd241, 'x').code).to.equal('ACCESS_DENIED');
      expect(serviceError(0x8104, 'x').code).to.equal('NOT_SUPPORTED');
      expect(serviceError(0xe201, 'x')).to.deep.include({ code: 'PLC_ERROR', plcCode: 0xe201 });
    });
  });
});
