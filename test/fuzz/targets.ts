/** Fuzz targets of the FETCH/WRITE and freeport decoders. */
import { OpCode, decodeRequest, decodeResponse, encodeRequest, encodeResponse } from '../../lib/fetchwrite/codec';
import { decodeReply, decodeRequest as decodeFreeportRequest, encodeReply, encodeRequest as encodeFreeportRequest, readRequest, writeRequest } from '../../lib/freeport/codec';
import { FreeportParser } from '../../lib/freeport/parser';
import { DOCUMENT_PROFILE } from '../../lib/freeport/profile';
import type { FuzzTarget } from './engine';

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
  return [
    { name: 'FETCH/WRITE decodeResponse', seeds: fwSeeds, run: (b) => void decodeResponse(b) },
    { name: 'FETCH/WRITE decodeRequest', seeds: fwSeeds, run: (b) => void decodeRequest(b) },
    { name: 'freeport decodeRequest', seeds: fpSeeds, run: (b) => void decodeFreeportRequest(b) },
    { name: 'freeport decodeReply', seeds: fpSeeds, run: (b) => void decodeReply(b) },
    {
      name: 'freeport stream parser',
      seeds: [Buffer.concat(fpSeeds)],
      run: (b) => {
        // The parser must never throw, whatever the line carries.
        new FreeportParser(DOCUMENT_PROFILE, 'reply').push(b);
        new FreeportParser(DOCUMENT_PROFILE, 'request').push(b);
      },
    },
  ];
}
