/**
 * The CPU services over S7CommPlus, by Explore: the operating state (the
 * object theCPUexecUnit) and the data blocks of the program (thePLCProgram,
 * each DB with its name and number). Ids and layouts from s7commplus (MIT),
 * client.py (get_cpu_state, list_datablocks, _parse_explore_datablocks).
 */
import { PlcError } from '../../errors';
import { cpuStateOf, type CpuState } from '../codec/explore';
import { attributeOf, walkObjects, type PObject } from '../codec/object';
import { Ids, serviceResultCode } from '../constants';
import { exploreAsk } from './asks';
import type { S7PlusSession } from './session';

export type { CpuState } from '../codec/explore';

/** A data block of the PLC's program. */
export interface S7PlusDataBlock {
  number: number;
  /** Its name in the program ("Tank"); the PLC's text as it came. */
  name: string;
}

/** An Explore of `exploreId` (with these attributes): the objects of the answer; a refusal is a PlcError. */
export async function explore(
  session: S7PlusSession,
  exploreId: number,
  attributes: number[],
  what: string,
  signal?: AbortSignal,
): Promise<PObject[]> {
  const body = await session.request(exploreAsk(exploreId, attributes), { signal });
  if (body.returnValue !== 0n) {
    const code = serviceResultCode(body.returnValue);
    throw new PlcError(
      code === -12 ? 'OBJECT_DOES_NOT_EXIST' : 'PLC_ERROR',
      `the PLC refused to tell ${what} (0x${body.returnValue.toString(16)})`,
      {
        plcCode: code,
      },
    );
  }
  return body.objects;
}

/** RUN, STOP or UNKNOWN, from theCPUexecUnit. */
export async function cpuState(session: S7PlusSession, signal?: AbortSignal): Promise<CpuState> {
  return cpuStateOf(await explore(session, Ids.NativeTheCpuExecUnitRID, [], 'its operating state', signal));
}

/** The data blocks of the program, by number. */
export async function dataBlocks(session: S7PlusSession, signal?: AbortSignal): Promise<S7PlusDataBlock[]> {
  const objects = await explore(
    session,
    Ids.NativeThePlcProgramRID,
    [Ids.ObjectVariableTypeName, Ids.BlockBlockNumber],
    'its data blocks',
    signal,
  );
  const blocks = new Map<number, S7PlusDataBlock>();
  for (const o of walkObjects(objects)) {
    if (o.classId !== Ids.DBClassRID || (o.relationId & 0xffff0000) >>> 0 !== Ids.DBAccessAreaBase) continue;
    const number = o.relationId & 0xffff;
    const name = attributeOf(o, Ids.ObjectVariableTypeName)?.value;
    blocks.set(number, { number, name: typeof name === 'string' ? name : `DB${number}` });
  }
  return [...blocks.values()].sort((a, b) => a.number - b.number);
}
