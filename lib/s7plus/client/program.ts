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
import { browseProgram, timesDiffer, typeTimes, type TypeTimes } from './browse';
import type { Program } from './names';
import type { S7PlusSession } from './session';

/** What a check found: the table of the program before and after, and the type objects whose times differ. */
export interface ProgramChange {
  readonly before: SymbolTable;
  readonly after: SymbolTable;
}

export class BrowsedProgram implements Program {
  private browsed: Promise<{ table: SymbolTable; times: TypeTimes }> | undefined;
  /** False once the PLC refused the question for the times: nothing to watch, the table stays as browsed. */
  private watchable = true;

  constructor(
    private readonly session: S7PlusSession,
    private readonly onChange: (change: ProgramChange) => void,
    private readonly signal?: AbortSignal,
  ) {}

  /** The browsed table (browsed at the first call; a failed browse is tried again at the next). */
  table(): Promise<SymbolTable> {
    return this.current().then((b) => b.table);
  }

  private current(): Promise<{ table: SymbolTable; times: TypeTimes }> {
    if (!this.browsed) {
      const browsed = browseProgram(this.session, this.signal);
      this.browsed = browsed;
      browsed.catch(() => {
        if (this.browsed === browsed) this.browsed = undefined;
      });
    }
    return this.browsed;
  }

  /** True when the program changed since the table was browsed; the table is then browsed again. One request. */
  async changed(): Promise<boolean> {
    if (!this.watchable) return false;
    const browsed = this.current();
    const seen = await browsed;
    const now = await typeTimes(this.session, this.signal);
    if (now === undefined) {
      this.watchable = false;
      return false;
    }
    if (!timesDiffer(seen.times, now)) return false;
    // Unless another check browsed again meanwhile, the table goes and is browsed again.
    if (this.browsed === browsed) {
      this.browsed = undefined;
      const after = await this.current();
      this.onChange({ before: seen.table, after: after.table });
    }
    return true;
  }
}
