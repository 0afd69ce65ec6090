/**
 * Fuzz targets of the S7CommPlus codec (lib/s7plus/codec/): every decoder,
 * seeded with the golden TIA frames, the frames the s7commplus package builds
 * (test/fixtures/s7plus/) and our encoders' output.
 */
import fs from 'node:fs';
import path from 'node:path';
import {
  decodeExploreRequest,
  decodeExploreResponse,
  encodeExploreResponse,
  cpuExecUnitObject,
  cpuStateOf,
} from '../../lib/s7plus/codec/explore';
import { encodeFrames, S7pFrameReader } from '../../lib/s7plus/codec/frame';
import { deviceString, parseDeviceString } from '../../lib/s7plus/codec/identity';
import { decodeObject } from '../../lib/s7plus/codec/object';
import { decodePValue, encodePValue, scalar } from '../../lib/s7plus/codec/pvalue';
import {
  decodeCreateObjectRequest,
  decodeCreateObjectResponse,
  decodeDeleteObjectRequest,
  decodeDeleteObjectResponse,
  decodeInitSslRequest,
  decodeInitSslResponse,
  encodeInitSslRequest,
  sessionInfo,
} from '../../lib/s7plus/codec/session';
import {
  challengeOf,
  credentialsBlobValue,
  decodeCredentials,
  decodeSetVariableRequest,
  decodeSetVariableResponse,
  encodeCredentials,
  encodeSetVariableRequest,
  encodeSetVariableResponse,
  legacyAnswerValue,
  legitimateRequest,
  legitimationForm,
  paomString,
  protectionLevelOf,
} from '../../lib/s7plus/codec/legitimation';
import { decodeSubStreamedRequest, decodeSubStreamedResponse, encodeSubStreamedResponse } from '../../lib/s7plus/codec/substreamed';
import { decodeNotification, readSubscription } from '../../lib/s7plus/codec/subscription';
import {
  decodeGetMultiVariablesRequest,
  decodeGetMultiVariablesResponse,
  decodeSetMultiVariablesRequest,
  decodeSetMultiVariablesResponse,
} from '../../lib/s7plus/codec/variables';
import { DataType, FunctionCode, Ids } from '../../lib/s7plus/constants';
import type { FuzzTarget } from './engine';

function fixtureFrames(): Buffer[] {
  const dir = path.join(__dirname, '..', '..', '..', 'test', 'fixtures', 's7plus');
  const read = (f: string) =>
    JSON.parse(fs.readFileSync(path.join(dir, f), 'utf8')) as { frames?: Record<string, string>; bodies?: Record<string, string> };
  const frames = ['golden-tia.json', 's7commplus-frames.json'].flatMap((f) =>
    Object.values(read(f).frames!).map((h) => Buffer.from(h, 'hex')),
  );
  // PLCSIM's Explore answers, behind a response header.
  const plcsim = Object.values(read('plcsim-cpu-exec-unit.json').bodies!).map((h) => Buffer.from('32000004bb0000000734' + h, 'hex'));
  return [...frames, ...plcsim];
}

/** Message data: a whole frame's header and trailer taken off, bare message data as it is. */
function messages(frames: Buffer[]): Buffer[] {
  return frames.map((f) => (f[0] === 0x72 ? f.subarray(4, 4 + f.readUInt16BE(2)) : f));
}

/** The ways a decoder is called: without integrity ids, with them, and for a session of frame version 1. */
function both(decode: (b: Buffer, o: { integrity: boolean; v1?: boolean }) => unknown): (b: Buffer) => void {
  return (b) => {
    try {
      decode(b, { integrity: false });
    } finally {
      // Run also when the first call threw; an error of a later one replaces the first's.
      try {
        decode(b, { integrity: true });
      } finally {
        decode(b, { integrity: false, v1: true });
      }
    }
  };
}

export function s7plusTargets(): FuzzTarget[] {
  const frames = fixtureFrames();
  const data = [
    ...messages(frames),
    encodeInitSslRequest(1),
    encodeExploreResponse({
      header: { functionCode: FunctionCode.Explore, sequence: 1, transportFlags: 0 },
      body: { returnValue: 0n, objects: [cpuExecUnitObject('RUN')] },
    }),
  ];
  // The values inside the messages, for the PValue and object decoders on their own.
  const values = data.flatMap((d) => [d.subarray(14), d.subarray(10), d.subarray(11)]);
  return [
    {
      name: 'S7+ frame reader (stream)',
      seeds: [
        Buffer.concat(
          frames.map((f) =>
            f[0] === 0x72 && f.length === 4 + f.readUInt16BE(2)
              ? Buffer.concat([f, Buffer.from('72020000', 'hex')])
              : encodeFrames(2, f, 50),
          ),
        ),
      ],
      run: (b) => {
        const reader = new S7pFrameReader({ maxMessage: 1 << 16 });
        for (let at = 0; at < b.length; at += 61) reader.push(b.subarray(at, at + 61));
      },
    },
    { name: 'S7+ decodePValue', seeds: values, run: (b) => void decodePValue(b, 0) },
    {
      // The CPU's identity: a ServerSessionVersion struct with its device string, as an S7-1200 sends it (legitimation.py's example).
      name: 'S7+ device string',
      seeds: [Buffer.from('00170000013a823b000403823f00151b313b36455337203231352d31424734302d30584230203b56342e3200', 'hex'), ...values],
      run: (b) => {
        parseDeviceString(b.toString('latin1'));
        const device = deviceString(decodePValue(b, 0).value);
        if (device !== undefined) parseDeviceString(device);
      },
    },
    {
      name: 'S7+ decodeObject',
      seeds: values.map((v) => v.subarray(v.indexOf(0xa1) < 0 ? 0 : v.indexOf(0xa1))),
      run: (b) => void decodeObject(b, 0),
    },
    { name: 'S7+ InitSSL req/res', seeds: data, run: (b) => void (b[0] === 0x31 ? decodeInitSslRequest(b) : decodeInitSslResponse(b)) },
    {
      name: 'S7+ CreateObject req/res',
      seeds: data,
      run: both((b, o) => {
        if (b[0] === 0x31) readSubscriptionIfOne(decodeCreateObjectRequest(b, o).body.object);
        else sessionInfoIfOk(decodeCreateObjectResponse(b, o).body);
      }),
    },
    {
      name: 'S7+ DeleteObject req/res',
      seeds: data,
      run: both((b, o) => (b[0] === 0x31 ? decodeDeleteObjectRequest(b, o) : decodeDeleteObjectResponse(b, o))),
    },
    {
      name: 'S7+ Explore req/res',
      seeds: data,
      run: both((b, o) => (b[0] === 0x31 ? decodeExploreRequest(b, o) : cpuStateOf(decodeExploreResponse(b, o).body.objects))),
    },
    {
      name: 'S7+ GetMultiVariables req/res',
      seeds: data,
      run: both((b, o) => (b[0] === 0x31 ? decodeGetMultiVariablesRequest(b, o) : decodeGetMultiVariablesResponse(b, o))),
    },
    {
      name: 'S7+ SetMultiVariables req/res',
      seeds: data,
      run: both((b, o) => (b[0] === 0x31 ? decodeSetMultiVariablesRequest(b, o) : decodeSetMultiVariablesResponse(b, o))),
    },
    {
      name: 'S7+ SubStreamed req/res',
      seeds: data,
      run: both((b, o) =>
        b[0] === 0x31
          ? decodeSubStreamedRequest(b, o)
          : decodeSubStreamedResponse(b, b[4] === 0x86 ? FunctionCode.GetVarSubStreamed : FunctionCode.SetVarSubStreamed, o),
      ),
    },
    { name: 'S7+ decodeNotification', seeds: data, run: (b) => void decodeNotification(b) },
    ...legitimationTargets(data),
  ];
}

/** The legitimation's decoders (codec/legitimation.ts), seeded with our encoders' requests and answers and s7commplus's frames. */
function legitimationTargets(data: Buffer[]): FuzzTarget[] {
  const credentials = encodeCredentials({ type: 1, username: Buffer.alloc(0), password: Buffer.alloc(20, 0xa5) });
  const sets = [
    encodeSetVariableRequest({ ...legitimateRequest(3, 0x3a0, Ids.Legitimate, credentialsBlobValue(Buffer.alloc(48, 1))), integrityId: 2 }),
    encodeSetVariableRequest(legitimateRequest(3, 0x3a0, Ids.ServerSessionResponse, legacyAnswerValue(Buffer.alloc(20, 2)))),
    encodeSetVariableResponse({
      header: { functionCode: FunctionCode.SetVariable, sequence: 3, transportFlags: 0 },
      body: { returnValue: 0x8000n },
      integrityId: 9,
    }),
  ];
  const paom = encodePValue({
    flags: 0,
    type: DataType.Struct,
    value: {
      id: Ids.SessionVersionStruct,
      members: [
        { key: 315, value: { flags: 0, type: DataType.UDInt, value: 2 } },
        { key: Ids.SessionVersionSystemPaomString, value: { flags: 0, type: DataType.WString, value: '1;6ES7 513-1AL02-0AB0;V3.1' } },
      ],
    },
  });
  return [
    {
      name: 'S7+ SetVariable req/res',
      seeds: [...sets, ...data],
      run: both((b, o) => (b[0] === 0x31 ? decodeSetVariableRequest(b, o) : decodeSetVariableResponse(b, o))),
    },
    { name: 'S7+ legitimation credentials', seeds: [credentials], run: (b) => void decodeCredentials(b) },
    {
      name: 'S7+ protection level, challenge (GetVarSubStreamed answers)',
      seeds: [
        ...[scalar(DataType.UDInt, 2), legacyAnswerValue(Buffer.alloc(20, 7)), credentialsBlobValue(Buffer.alloc(20, 8))].map((value, i) =>
          encodeSubStreamedResponse({
            header: { functionCode: FunctionCode.GetVarSubStreamed, sequence: 4, transportFlags: 0 },
            body: { returnValue: 0n, marker: 0, value },
            integrityId: i,
          }),
        ),
        ...data,
      ],
      run: both((b, o) => {
        const value = decodeSubStreamedResponse(b, FunctionCode.GetVarSubStreamed, o).body.value;
        if (value?.type === DataType.UDInt) protectionLevelOf(value);
        else challengeOf(value);
      }),
    },
    {
      name: 'S7+ ServerSessionVersion device string',
      seeds: [paom],
      run: (b) => {
        const s = paomString(decodePValue(b, 0).value);
        if (s !== undefined) legitimationForm(s);
      },
    },
  ];
}

function readSubscriptionIfOne(obj: Parameters<typeof readSubscription>[0]): void {
  if (obj.classId === 1001) readSubscription(obj);
}

function sessionInfoIfOk(body: Parameters<typeof sessionInfo>[0]): void {
  if (body.returnValue === 0n && body.objectIds.length > 0) sessionInfo(body);
}
