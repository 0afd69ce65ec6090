/** Fuzz targets of the FETCH/WRITE and freeport decoders. */
import { OpCode, decodeRequest, decodeResponse, encodeRequest, encodeResponse } from '../../lib/fetchwrite/codec';
import {
  decodeReply,
  decodeRequest as decodeFreeportRequest,
  encodeReply,
  encodeRequest as encodeFreeportRequest,
  readRequest,
  writeRequest,
} from '../../lib/freeport/codec';
import { FreeportParser } from '../../lib/freeport/parser';
import { DEFAULT_FREEPORT_PROFILE } from '../../lib/freeport/profile';
import { decodeBlockCounts, decodeBlockInfo, decodeBlockListEntries, decodeLoadBlock, encodeBlockInfo } from '../../lib/s7/codec/blocks';
import {
  decodeControl,
  decodeUserdata,
  encodeControlAck,
  encodePlcStart,
  encodePlcStop,
  encodeStartUpload,
  encodeStartUploadAck,
  encodeUploadAck,
  encodeUserdataNext,
  encodeUserdataRequest,
  encodeUserdataResponse,
  COLD_START_ARG,
} from '../../lib/s7/codec';
import { decodeDiagnosticBuffer } from '../../lib/s7/codec/diagnostics';
import { IDENTITIES } from '../../lib/s7/server/profiles';
import { CpuServices, newServiceSession } from '../../lib/s7/server/services';
import {
  decodeComponentIdentification,
  decodeCpuState,
  decodeLeds,
  decodeModuleIdentification,
  decodeProtection,
  decodeSzlIds,
  parseSzl,
} from '../../lib/s7/codec/szl';
import { PlcMemory } from '../../lib/sim/memory';
import type { FuzzTarget } from './engine';

/** Userdata and control frames of both directions: requests (for the simulator) and answers (for the client). */
export function serviceSeeds(): Buffer[] {
  const szl = Buffer.from(
    '00A0000000140002' + '4302FF68C7000000081477149402042352163886' + '1381FE64C772430408147714940204235216387' + '6',
    'hex',
  );
  return [
    encodeUserdataRequest(4, 1, Buffer.from('00110000', 'hex')),
    encodeUserdataNext(4, 1, 3, 3),
    encodeUserdataRequest(7, 1),
    encodeUserdataRequest(7, 2, Buffer.from('00202612012130456783', 'hex')),
    encodeUserdataRequest(3, 1),
    encodeUserdataRequest(3, 2, Buffer.of(0x30, 0x41)),
    encodeUserdataRequest(3, 3, Buffer.from('0A00001A', 'latin1')),
    encodeUserdataRequest(5, 1, Buffer.from('2630101720365543', 'hex')),
    encodeUserdataResponse(1, 4, 1, { sequence: 3, dataUnitRef: 3, last: false, data: szl.subarray(0, 20) }),
    encodeUserdataResponse(1, 4, 1, { data: szl }),
    encodeUserdataResponse(1, 4, 1, { errorCode: 0xd401 }),
    encodeUserdataResponse(2, 3, 3, {
      data: encodeBlockInfo({
        type: 'DB',
        number: 1,
        languageCode: 5,
        mc7Size: 10,
        author: 'A',
        family: 'F',
        name: 'N',
        version: 0x10,
        checksum: 1,
        codeTime: new Date(0),
        interfaceTime: new Date(0),
      }),
    }),
    encodePlcStop(),
    encodePlcStart(),
    encodePlcStart(COLD_START_ARG),
    encodeStartUpload(0x41, 1),
    encodeStartUploadAck(1, 7, 102),
    encodeUploadAck(1, Buffer.from('7070010105', 'hex'), true),
    encodeControlAck(1, 0x29, 7, 0x8402),
  ];
}

/** Every decoder a userdata answer's data can reach, on the same bytes. */
function decodeServiceData(b: Buffer): void {
  const typed = (f: () => unknown) => {
    try {
      f();
    } catch (err) {
      if (!(err instanceof Error) || !('code' in err)) throw err;
    }
  };
  typed(() => {
    const list = parseSzl(b);
    for (const decode of [
      decodeSzlIds,
      decodeModuleIdentification,
      decodeComponentIdentification,
      decodeProtection,
      decodeCpuState,
      decodeLeds,
      decodeDiagnosticBuffer,
    ])
      typed(() => decode(list));
  });
  typed(() => decodeBlockInfo(b));
  typed(() => decodeBlockCounts(b));
  typed(() => decodeBlockListEntries(b));
  typed(() => decodeLoadBlock(b));
}

export function extraTargets(): FuzzTarget[] {
  const fwSeeds = [
    encodeRequest({ op: OpCode.FetchRequest, org: 2, dbNumber: 0, start: 0, length: 2 }),
    encodeRequest({ op: OpCode.WriteRequest, org: 1, dbNumber: 62, start: 1008, length: 2, data: Buffer.from('41B00000', 'hex') }),
    encodeResponse(OpCode.FetchResponse, 0, Buffer.from('1234', 'hex')),
    encodeResponse(OpCode.WriteAck, 0),
    encodeResponse(OpCode.FetchResponse, 2),
  ];
  const fpSeeds = [
    Buffer.from('qR0504E627A1C325Q', 'latin1'),
    encodeFreeportRequest(readRequest(6)),
    encodeFreeportRequest(writeRequest(5, Buffer.from('E627A1C3', 'hex'))),
    encodeReply({ data: Buffer.from('E627A1C3', 'hex') }),
  ];
  const services = serviceSeeds();
  const cpu = new CpuServices(new PlcMemory(), IDENTITIES['s7-300'], { maxConnections: 16 });
  return [
    { name: 'S7 decodeUserdata', seeds: services, run: (b) => void decodeUserdata(b) },
    { name: 'S7 decodeControl', seeds: services, run: (b) => void decodeControl(b) },
    { name: 'S7 SZL/block decoders (data)', seeds: services.map((f) => f.subarray(33)), run: decodeServiceData },
    {
      // The simulator's services on hostile requests: an answer or a ProtocolError, never anything else.
      name: 'S7 simulator services',
      seeds: services,
      run: (b) => {
        const session = newServiceSession();
        if (b[8] === 7) cpu.serveUserdata(b, session, 240);
        else cpu.serveControl(b, session, 240);
      },
    },
    { name: 'FETCH/WRITE decodeResponse', seeds: fwSeeds, run: (b) => void decodeResponse(b) },
    { name: 'FETCH/WRITE decodeRequest', seeds: fwSeeds, run: (b) => void decodeRequest(b) },
    { name: 'freeport decodeRequest', seeds: fpSeeds, run: (b) => void decodeFreeportRequest(b) },
    { name: 'freeport decodeReply', seeds: fpSeeds, run: (b) => void decodeReply(b) },
    {
      name: 'freeport stream parser',
      seeds: [Buffer.concat(fpSeeds)],
      run: (b) => {
        // The parser must never throw, whatever the line carries.
        new FreeportParser(DEFAULT_FREEPORT_PROFILE, 'reply').push(b);
        new FreeportParser(DEFAULT_FREEPORT_PROFILE, 'request').push(b);
      },
    },
  ];
}
