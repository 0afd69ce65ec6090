/**
 * A download on the simulated S7-1200/1500 (lib/cpu/serve.ts): the --source files loaded again into the S7CommPlus
 * service and the S7 simulator's memory on SIGHUP or when one of them changes.
 */
import * as fs from 'node:fs';
import type { PlcMemory } from '../sim/memory';
import type { ServeFlags } from '../sim/serve';
import type { S7PlusService } from '../s7plus/server';

/** How often a --source file's size and time are looked at (by path: a file an editor replaced is seen too). */
const WATCH_MS = 500;

/** A file's time and size, or 'missing'. */
function stamp(file: string): string {
  try {
    const st = fs.statSync(file);
    return `${st.mtimeMs} ${st.size}`;
  } catch {
    return 'missing';
  }
}

/**
 * Loads the --source files again into `service` (S7PlusService.reload: a download) on SIGHUP and when one of them
 * changes, and says what changed; sources that do not compile leave the running program and say why. Returns the
 * function that stops watching.
 */
export function reloadOnChange(service: S7PlusService, memory: PlcMemory, flags: ServeFlags): () => void {
  const reload = (why: string) => {
    try {
      const files = flags.sourceFiles();
      const before = service.model;
      const after = service.reload(files?.sources ?? [], memory, files?.db);
      const changed = [...after.times].filter(([rid, time]) => before.times.get(rid) !== time).length;
      const gone = [...before.times.keys()].filter((rid) => !after.times.has(rid)).length;
      flags.say(
        changed + gone === 0
          ? `program loaded again (${why}): unchanged`
          : `program loaded again (${why}): ${changed} type objects new or changed, ${gone} gone; clients browse again`,
      );
    } catch (err) {
      flags.say(`program not loaded again (${why}): ${(err as Error).message}; the CPU keeps its program`);
    }
  };
  const onHangup = () => reload('SIGHUP');
  process.on('SIGHUP', onHangup);
  // Each file's size and time as it is now, taken at once: a change made the moment after this call is seen (fs.watchFile
  // takes its first look later, on its own, and missed a file written in between).
  const seen = new Map(flags.sourcePaths().map((file) => [file, stamp(file)]));
  let looking = false;
  const timer = setInterval(() => {
    if (looking) return;
    looking = true;
    void Promise.all(
      [...seen].map(async ([file, was]) => {
        const now = await fs.promises.stat(file).then(
          (st) => `${st.mtimeMs} ${st.size}`,
          () => 'missing',
        );
        if (now === was) return undefined;
        seen.set(file, now);
        return file;
      }),
    ).then((files) => {
      looking = false;
      const changed = files.filter((f): f is string => f !== undefined);
      if (changed.length > 0) reload(changed.map((file) => `${file} changed`).join(', '));
    });
  }, WATCH_MS);
  timer.unref();
  return () => {
    process.off('SIGHUP', onHangup);
    clearInterval(timer);
  };
}
