/** Fuzz targets of the cyclic-data codec (lib/s7/codec/cyclic.ts) and the simulator's cyclic service (issue #33). */
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
} from '../../lib/s7/codec/cyclic';
import { decodeUserdata } from '../../lib/s7/codec/userdata';
import { CyclicService } from '../../lib/s7/server/cyclic';
import { IDENTITIES } from '../../lib/s7/server/profiles';
import { PlcMemory } from '../../lib/sim/memory';
import type { FuzzTarget } from './engine';

/** Frames of both directions: registrations, unsubscribes, answers and pushes. */
export function cyclicSeeds(): Buffer[] {
  const values = encodeCyclicValues([
    { returnCode: 0xff, transportSize: 4, data: Buffer.from('123456', 'hex') },
    { returnCode: 0x0a, transportSize: 0, data: Buffer.alloc(0) },
    { returnCode: 0xff, transportSize: 9, data: Buffer.from('0102', 'hex') },
  ]);
  const items = [
    { area: 0x84, dbNumber: 1, transportSize: 2, count: 3, address: 0 },
    { area: 0x83, dbNumber: 0, transportSize: 2, count: 1, address: 16 },
  ];
  return [
    encodeCyclicSubscribe({ subfunction: CyclicSubfunction.Memory, timeBase: 0, factor: 2, items }),
    encodeCyclicSubscribe({ subfunction: CyclicSubfunction.ChangeDriven, timeBase: 1, factor: 1, items }),
    encodeCyclicUnsubscribe(3),
    encodeCyclicAnswer(7, CyclicSubfunction.Memory, 1, values),
    encodeCyclicAnswer(8, CyclicSubfunction.Memory, 0, undefined, 0xd805),
    encodeCyclicPush(CyclicSubfunction.Memory, 1, values),
  ];
}

/** A socket as the service sees it: written to, never closing. */
function fakeSocket(): never {
  return { destroyed: false, write: () => true, once: () => undefined } as never;
}

export function cyclicTargets(): FuzzTarget[] {
  const seeds = cyclicSeeds();
  const memory = new PlcMemory({ dataBlocks: { 1: 100 }, flags: 16 });
  const ctx = { memory, pduSize: 240 };
  return [
    {
      name: 'S7 cyclic data (client side)',
      seeds,
      run: (b) => {
        const u = decodeUserdata(b);
        if (u.params.subfunction === CyclicSubfunction.Unsubscribe) decodeCyclicUnsubscribe(u.data);
        else decodeCyclicValues(u.data);
      },
    },
    {
      name: 'S7 cyclic registration (data)',
      seeds: seeds.slice(0, 2).map((f) => decodeUserdata(f).data),
      run: (b) => void decodeCyclicSubscribe(CyclicSubfunction.Memory, b),
    },
    {
      // Every well-formed registration starts a job: the service ends them all after each input.
      name: 'S7 simulator cyclic service',
      seeds,
      run: (b) => {
        const service = new CyclicService(IDENTITIES['s7-300']);
        try {
          service.serve(b, fakeSocket(), ctx);
        } finally {
          service.close();
        }
      },
    },
  ];
}
