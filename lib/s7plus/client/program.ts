/**
 * The PLC's program as one session knows it: the table browsed once
 * (browse.ts), and the check whether a download changed the program since.
 * The check is one Explore of the type-info container for attribute 529 (each
 * type object's VariableTypeStructModificationTime); a time that differs, a
 * type object that came or went, means the program changed: the table is
 * browsed again and the change counted (the `programChanged` event).
 * Source: s7commplus (MIT), client.py refresh_caches_if_program_changed and
 * _read_type_info_time (it asks each block's type object; one question to
 * the container asks all of them at once).
 */
import type { SymbolTable } from '../../symbols/model';
import { PlcError } from '../../errors';
import { Ids } from '../constants';
import { blockWords, browseProgram, type BrowsedTable } from './browse';
import type { Program } from './names';
import { dataBlocks, explore } from './services';
import type { S7PlusSession } from './session';
import { timesOf, type TypeTimes } from './typeinfo';

/** The block list is asked again for an unknown name at most this often (as s7commplus's auto refresh: 10 s). */
const BLOCK_LIST_MS = 10_000;

/** What a check found: the browsed table of the program before the download and after it (the `programChanged` event). */
export interface ProgramChange {
  readonly before: SymbolTable;
  readonly after: SymbolTable;
}

export class BrowsedProgram implements Program {
  private browsed: Promise<BrowsedTable> | undefined;
  /** The last table a browse gave, for what must know it at once (how a REAL is shown: lib/symbols/reals.ts). */
  latest: SymbolTable | undefined;
  /** False once the PLC refused the question for the times: nothing to watch, the table stays as browsed. */
  private watchable = true;
  /** When the block list was last asked for an unknown name. */
  private blockListAt = -Infinity;

  constructor(
    private readonly session: S7PlusSession,
    private readonly onChange: (change: ProgramChange) => void,
  ) {}

  /** The browsed table (browsed at the first call, with its `signal`; a failed browse is tried again at the next). */
  table(signal?: AbortSignal): Promise<SymbolTable> {
    return this.current(signal).then((b) => b.table);
  }

  private current(signal?: AbortSignal): Promise<BrowsedTable> {
    if (!this.browsed) {
      const browsed = browseProgram(this.session, signal);
      this.browsed = browsed;
      browsed.then((b) => (this.latest = b.table)).catch(() => undefined);
      browsed.catch(() => {
        if (this.browsed === browsed) this.browsed = undefined;
      });
    }
    return this.browsed;
  }

  /**
   * True when the program changed since the table was browsed; the table is then browsed again. One request; with
   * `unknownName` (a name the table does not have: a block renamed keeps its layout and its times) the block list
   * too, at most every 10 s.
   */
  async changed(unknownName = false): Promise<boolean> {
    const browsed = this.current();
    const seen = await browsed;
    let differs = false;
    if (this.watchable) {
      const now = await typeTimes(this.session);
      if (now === undefined) this.watchable = false;
      else differs = timesDiffer(seen.times, now);
    }
    if (!differs && unknownName && Date.now() - this.blockListAt >= BLOCK_LIST_MS) {
      this.blockListAt = Date.now();
      differs = blockWords(await dataBlocks(this.session)) !== seen.blocks;
    }
    if (!differs) return false;
    // Unless another check browsed again meanwhile, the table goes and is browsed again.
    if (this.browsed === browsed) {
      this.browsed = undefined;
      const after = await this.current();
      this.onChange({ before: seen.table, after: after.table });
    }
    return true;
  }
}

/**
 * The type objects' modification times now: one Explore of the type-info container asking for attribute 529 only,
 * which the PLC answers with each type object's head and time (about 20 bytes a type). Undefined when the PLC refuses
 * the question (the program cannot be watched this way; a link error still throws).
 */
async function typeTimes(session: S7PlusSession, signal?: AbortSignal): Promise<TypeTimes | undefined> {
  try {
    return timesOf(await explore(session, Ids.ObjectOmsTypeInfoContainer, [Ids.VariableTypeStructModificationTime], 'its types', signal));
  } catch (err) {
    if (err instanceof PlcError && (err.code === 'PLC_ERROR' || err.code === 'OBJECT_DOES_NOT_EXIST')) return undefined;
    throw err;
  }
}

/** True when two sets of modification times differ: a type object changed, came or went. */
function timesDiffer(a: TypeTimes, b: TypeTimes): boolean {
  if (a.size !== b.size) return true;
  for (const [rid, time] of a) if (b.get(rid) !== time) return true;
  return false;
}
