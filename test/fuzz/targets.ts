/** Fuzz targets of the FETCH/WRITE and freeport decoders. */
import { OpCode, decodeRequest, decodeResponse, encodeRequest, encodeResponse } from '../../lib/fetchwrite/codec';
import type { FuzzTarget } from './engine';

export function extraTargets(): FuzzTarget[] {
  const fwSeeds = [
    encodeRequest({ op: OpCode.FetchRequest, org: 2, dbNumber: 0, start: 0, length: 2 }),
    encodeRequest({ op: OpCode.WriteRequest, org: 1, dbNumber: 62, start: 1008, length: 2, data: Buffer.from('41B00000', 'hex') }),
    encodeResponse(OpCode.FetchResponse, 0, Buffer.from('1234', 'hex')),
    encodeResponse(OpCode.WriteAck, 0),
    encodeResponse(OpCode.FetchResponse, 2),
  ];
  return [
    { name: 'FETCH/WRITE decodeResponse', seeds: fwSeeds, run: (b) => void decodeResponse(b) },
    { name: 'FETCH/WRITE decodeRequest', seeds: fwSeeds, run: (b) => void decodeRequest(b) },
  ];
}
