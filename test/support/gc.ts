import * as v8 from 'node:v8';
import * as vm from 'node:vm';

type Gc = (options?: { type?: 'major' | 'minor' }) => void;
let gc: Gc | undefined;

/** V8's gc() (major, or a minor GC: a scavenge of the young generation) without --expose-gc on the command line. */
export function collectGarbage(type: 'major' | 'minor' = 'major'): void {
  if (!gc) {
    v8.setFlagsFromString('--expose-gc');
    gc = vm.runInNewContext('gc') as Gc;
  }
  // gc() with no argument is a full GC; { type: 'major' } is not one on Node 20.
  if (type === 'minor') gc({ type: 'minor' });
  else gc();
}

/** Bytes in use in V8's young generation ("new space"). */
export function youngBytes(): number {
  return v8.getHeapSpaceStatistics().find((s) => s.space_name === 'new_space')?.space_used_size ?? 0;
}
