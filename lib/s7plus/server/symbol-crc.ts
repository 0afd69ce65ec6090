/**
 * The SymbolCrc the simulated CPU expects for an item of its program: the
 * CRC of the path its LIDs name (codec/symbol-crc.ts), each level the
 * member's name and software type, an array's element type and lower bound;
 * element indexes and the marker 1 of an element of an array of structs are
 * not part of it. A request's non-zero SymbolCrc that differs makes the CPU
 * refuse that item alone with InvalidCRC (services.ts).
 *
 * A multi-dimensional array has no CRC here: no public source says which of
 * its bounds the CRC takes, so the simulator does not check a path through
 * one (and the client sends 0 for it and watches the program instead).
 */
import { symbolCrc, type SymbolLevel } from '../codec/symbol-crc';
import { FIRST_LID, type PlusDb, type PlusMember, type PlusType } from './model';

/** The expected CRC per block and LID path, worked out once per program (a reload builds new PlusDb objects). */
const EXPECTED = new WeakMap<PlusDb, Map<string, number | undefined>>();

/** The CRC of the path `lids` names in `db`; undefined when it names nothing or passes a multi-dimensional array. */
export function expectedCrc(db: PlusDb, lids: readonly number[]): number | undefined {
  let byPath = EXPECTED.get(db);
  if (!byPath) EXPECTED.set(db, (byPath = new Map<string, number | undefined>()));
  const key = lids.join('.');
  if (byPath.has(key)) return byPath.get(key);
  const levels = levelsOf(db.type, lids);
  const crc = levels && symbolCrc(levels);
  byPath.set(key, crc);
  return crc;
}

/** The CRC of a tag of the PLC tag table (an I, Q or M area's type object member): its name and type. */
export function tagCrc(tag: PlusMember): number {
  return symbolCrc([{ name: tag.name, soft: tag.soft }]);
}

function levelsOf(root: PlusType, lids: readonly number[]): SymbolLevel[] | undefined {
  const levels: SymbolLevel[] = [];
  let type: PlusType | undefined = root;
  let i = 0;
  while (i < lids.length) {
    // Members carry LIDs FIRST_LID, FIRST_LID + 1, … in order (model.ts TypeBuilder).
    const m: PlusMember | undefined = type?.members[lids[i]! - FIRST_LID];
    if (!m || m.lid !== lids[i]) return undefined;
    i++;
    if (m.node.kind === 'array') {
      if (m.node.dims.length !== 1) return undefined;
      levels.push({ name: m.name, soft: m.soft, low: m.node.dims[0]!.low });
      // The element's index, then for an element of an array of structs the marker 1 before its member's LID.
      if (i < lids.length) i++;
      if (m.type && i < lids.length) {
        if (lids[i] !== 1) return undefined;
        i++;
      }
    } else levels.push({ name: m.name, soft: m.soft });
    type = m.type;
  }
  return levels;
}
