/** Fuzz targets of the FETCH/WRITE and freeport decoders. */
import type { FuzzTarget } from './engine';

export function extraTargets(): FuzzTarget[] {
  return [];
}
