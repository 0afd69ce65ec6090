/**
 * What the simulated CPU answers each S7CommPlus request with, once the
 * frame and its header are taken apart (session.ts): Explore of the block
 * list, the CPU state and the type-info container; GetMultiVariables and
 * SetMultiVariables by LID (named access) and by address (the classic blob
 * of a standard DB); the session's protection level. Layouts: s7commplus
 * (MIT) client.py (the request builders and answer parsers), server.py.
 */
import type { PlcMemory } from '../../sim/memory';
import type { AreaName } from '../../types';
import { ProtocolError } from '../../errors';
import type { LayoutNode } from '../../symbols/layout-nodes';
import { DataType, dbAccessArea, ITEM_ERROR_UNRESOLVED, Ids, OperatingState, SystemLimits } from '../constants';
import { Reader, Writer } from '../codec/bytes';
import { ITEM_ERROR_INVALID_CRC } from '../codec/symbol-crc';
import { encodeSVlq32, encodeUVlq32, encodeUVlq64 } from '../codec/vlq';
import type { SystemLimitValues } from './limits';
import { resolveAreaLid, resolveLids, type PlusDb, type PlusModel } from './model';
import { expectedCrc, tagCrc } from './symbol-crc';
import { blockList, cpuExecUnit, isTypeObject, typeInfoContainer, typeObjectAttributes } from './typeinfo';
import { blob, readNode, readPValue, writeNode } from './values';
import { daiObject } from '../codec/alarms';
import { writeObject } from '../codec/object';
import type { AlarmSubsystem } from './alarms';

/** What a handler needs of the CPU. */
export interface CpuSide {
  readonly model: PlusModel;
  readonly memory: PlcMemory;
  /** RUN or STOP. */
  mode(): 'RUN' | 'STOP';
  /** What SystemLimits reports: items one Get/SetMultiVariables may carry; more resets the connection. */
  readonly limits: SystemLimitValues;
  /** The alarm subsystem (Program_Alarms of S7PlusOptions.alarms); absent: a CPU without alarms. */
  readonly alarms?: AlarmSubsystem;
}

/** One item address of a request: its SymbolCrc (0: no check), the area, its sub-area and LIDs. */
interface ItemAddress {
  readonly crc: number;
  readonly area: number;
  readonly subArea: number;
  readonly lids: readonly number[];
}

/** Thrown for a request the CPU answers by resetting the connection. */
export class ResetConnection extends ProtocolError {}

/** Explore: the object tree under `exploreId`, or the CPU's "no such object". */
export function explore(cpu: CpuSide, body: Buffer): Buffer {
  const r = new Reader(body);
  const id = r.u32('the Explore id');
  const ok = (objects: Buffer) => Buffer.concat([encodeUVlq64(0n), objects, Buffer.alloc(4)]);
  if (id === Ids.NativeThePlcProgramRID) return ok(blockList(cpu.model, unnamedDbs(cpu)));
  if (id === Ids.NativeTheAlarmSubsystemRID) return activeAlarms(cpu);
  if (id === Ids.NativeTheCpuExecUnitRID) return ok(cpuExecUnit(cpu.mode() === 'RUN' ? OperatingState.Run : OperatingState.Stop));
  if (id === Ids.ObjectOmsTypeInfoContainer) return ok(typeInfoContainer(cpu.model, exploreAttributes(r)));
  // One type object for its modification time (s7commplus (MIT) client.py _read_type_info_time).
  if (isTypeObject(cpu.model, id)) return ok(typeObjectAttributes(cpu.model, id, exploreAttributes(r)));
  return Buffer.concat([encodeUVlq64(EXPLORE_NO_SUCH_OBJECT), Buffer.alloc(8)]);
}

/**
 * The alarms active now, one DAI object each (codec/alarms.ts). With objects, four bytes (the Explore id) go before
 * them, where a PLC puts a few (codec/explore.ts, "preamble") and s7commplus's reader skips four (alarm.py
 * parse_alarm_explore_response); with none, the answer is the return value and the fill.
 */
function activeAlarms(cpu: CpuSide): Buffer {
  const active = cpu.alarms?.active() ?? [];
  if (active.length === 0) return Buffer.concat([encodeUVlq64(0n), Buffer.alloc(4)]);
  const w = new Writer();
  w.u32(Ids.NativeTheAlarmSubsystemRID);
  for (const dai of active) writeObject(w, daiObject(dai));
  return Buffer.concat([encodeUVlq64(0n), w.toBuffer(), Buffer.alloc(4)]);
}

/** The memory's data blocks no source declares (a profile's or a layout's when no program was given): standard, by address only. */
function unnamedDbs(cpu: CpuSide): number[] {
  return cpu.memory.dataBlockNumbers().filter((number) => !dbOf(cpu.model, dbAccessArea(number)));
}

/** The attribute ids an Explore asks for, after its id (codec/explore.ts: request id, three flags, filter count, count, ids). */
function exploreAttributes(r: Reader): number[] {
  r.uvlq32();
  r.bytes(3, 'the Explore flags');
  if (r.u8('the filter count') !== 0) return [];
  const count = r.uvlq32();
  if (count > r.remaining) throw new ProtocolError(`S7CommPlus: Explore names ${count} attributes in ${r.remaining} bytes`);
  return Array.from({ length: count }, () => r.uvlq32());
}

/**
 * A real S7-1500's ReturnValue for an Explore of an object that does not
 * exist: error flag (bit 63), code -12 in the low 16 bits (s7commplus (MIT)
 * server.py, _EXPLORE_NO_SUCH_OBJECT; ServiceResult.NoSuchObject).
 */
const EXPLORE_NO_SUCH_OBJECT = 0x8020ab001992fff4n;

/**
 * A CPU 1215C FW V4.2 answers a read of more items than its SystemLimits
 * allow with this ReturnValue and no item, whatever the request's size
 * (s7commplus (MIT) client.py, the comment of max_items_per_request; the
 * same for writes is assumed). The simulator answers every profile so.
 */
const TOO_MANY_ITEMS = 0xa027a6000054fffcn;

/** The answer to a Get- or SetMultiVariables of more items than the CPU serves: TOO_MANY_ITEMS, no item (an empty value list and error list for a read). */
function tooMany(read: boolean): Buffer {
  const w = new Writer().uvlq64(TOO_MANY_ITEMS).uvlq32(0);
  return (read ? w.uvlq32(0) : w).toBuffer();
}

/** The item addresses of a request, or undefined when there are more than `max` (the CPU refuses the request: tooMany). */
function readAddresses(r: Reader, max: number): ItemAddress[] | undefined {
  r.u32('the link id');
  const count = r.uvlq32();
  if (count > max) return undefined;
  r.uvlq32();
  const items: ItemAddress[] = [];
  for (let i = 0; i < count; i++) {
    const crc = r.uvlq32();
    const area = r.uvlq32();
    const n = r.uvlq32();
    if (n < 1 || n > 64) throw new ProtocolError(`S7CommPlus item address with ${n} LIDs`);
    const subArea = r.uvlq32();
    const lids: number[] = [];
    for (let k = 1; k < n; k++) lids.push(r.uvlq32());
    items.push({ crc, area, subArea, lids });
  }
  return items;
}

/**
 * Where an item lands: a node of a DB or area (with the SymbolCrc its path has; undefined: a path with no public
 * rule, not checked), a byte range of a standard DB or area, the type object's RID (LID 1), a SystemLimits value, or
 * nothing.
 */
type Target =
  | { kind: 'node'; area: AreaName; db: number; node: LayoutNode; crc: number | undefined }
  | { kind: 'range'; area: AreaName; db: number; byte: number; size: number }
  | { kind: 'rid'; rid: number }
  | { kind: 'limit'; value: number };

/** A range of bytes by the classic-blob LIDs (marker, byte, count) within `length` bytes. */
function range(lids: readonly number[], area: AreaName, db: number, length: number): Target | undefined {
  const [, byte, size] = lids as [number, number, number];
  return byte + size <= length && size > 0 ? { kind: 'range', area, db, byte, size } : undefined;
}

/** The model's DBs by access area, made once per model: every item of every read looks its DB up. */
const DBS_BY_AREA = new WeakMap<PlusModel, ReadonlyMap<number, PlusDb>>();

function dbOf(model: PlusModel, area: number): PlusDb | undefined {
  let byArea = DBS_BY_AREA.get(model);
  if (!byArea) {
    byArea = new Map(model.dbs.map((d) => [d.rid, d]));
    DBS_BY_AREA.set(model, byArea);
  }
  return byArea.get(area);
}

/** The SystemLimits item a LID names (constants.ts SystemLimits), or undefined. */
/** An item address without its SymbolCrc: what a subscription's reference names. */
type ItemPath = Omit<ItemAddress, 'crc'>;

function limit(cpu: CpuSide, item: ItemPath): Target | undefined {
  if (item.subArea !== SystemLimits.SubArea || item.lids.length !== 1) return undefined;
  if (item.lids[0] === SystemLimits.TagsPerReadRequest) return { kind: 'limit', value: cpu.limits.tagsPerRead };
  if (item.lids[0] === SystemLimits.TagsPerWriteRequest) return { kind: 'limit', value: cpu.limits.tagsPerWrite };
  return undefined;
}

function target(cpu: CpuSide, item: ItemPath): Target | undefined {
  const lids = item.lids;
  if (item.area === SystemLimits.ObjectRoot) return limit(cpu, item);
  const blob = lids.length === 3 && lids[0] === Ids.LidClassicBlob;
  const area = cpu.model.areas.find((a) => a.rid === item.area);
  if (area) {
    // I, Q, M: by address (the classic blob) or a tag table name by its LID.
    if (item.subArea !== Ids.ControllerAreaValueActual) return undefined;
    if (blob) return range(lids, area.area, 0, cpu.memory.area(area.area)?.length ?? 0);
    const tag = resolveAreaLid(area, lids);
    return tag ? { kind: 'node', area: area.area, db: 0, node: tag.node, crc: tagCrc(tag) } : undefined;
  }
  if ((item.area & 0xffff0000) >>> 0 !== Ids.DBAccessAreaBase || item.subArea !== Ids.DBValueActual) return undefined;
  const db = dbOf(cpu.model, item.area);
  if (!db) {
    // A data block of the memory that no source declares: standard access, reached by address alone.
    const number = item.area & 0xffff;
    return blob ? range(lids, 'DB', number, cpu.memory.area('DB', number)?.length ?? 0) : undefined;
  }
  if (lids.length === 1 && lids[0] === 1) return { kind: 'rid', rid: db.type.rid };
  // By address: standard DBs only; an optimized one has no offsets to give.
  if (blob) return db.optimized ? undefined : range(lids, 'DB', db.number, db.length);
  const node = resolveLids(db, lids);
  return node ? { kind: 'node', area: 'DB', db: db.number, node, crc: expectedCrc(db, lids) } : undefined;
}

/**
 * True when the CPU refuses the item for its SymbolCrc: a non-zero CRC that is not its path's, or one given for
 * what has no symbol (an address, LID 1, a SystemLimits value). 0 asks for no check.
 */
function crcRefused(item: ItemAddress, t: Target | undefined): boolean {
  if (item.crc === 0 || !t) return false;
  return t.kind !== 'node' || (t.crc !== undefined && t.crc !== item.crc);
}

/** Per item its PValue, or its error (a bigint). */
function itemList(results: readonly (Buffer | bigint)[]): Buffer {
  // One Writer for the answer rather than a Buffer per item number joined at the end (50 items a request).
  const w = new Writer().uvlq64(0n);
  results.forEach((v, i) => {
    if (typeof v !== 'bigint') w.uvlq32(i + 1).bytes(v);
  });
  w.uvlq32(0);
  results.forEach((v, i) => {
    if (typeof v === 'bigint') w.uvlq32(i + 1).uvlq64(v);
  });
  return w.uvlq32(0).toBuffer();
}

/** The PValue an item address names now, or undefined when it names nothing the CPU serves. */
export function itemValue(cpu: CpuSide, item: ItemPath): Buffer | undefined {
  return valueOf(cpu, target(cpu, item));
}

function valueOf(cpu: CpuSide, t: Target | undefined): Buffer | undefined {
  if (!t) return undefined;
  if (t.kind === 'rid') return Buffer.concat([Buffer.from([0x00, DataType.RID]), u32be(t.rid)]);
  if (t.kind === 'limit') return Buffer.concat([Buffer.from([0x00, DataType.DInt]), encodeSVlq32(t.value)]);
  const image = cpu.memory.area(t.area, t.db);
  if (!image || (t.kind === 'node' ? t.node.byte + t.node.size : t.byte + t.size) > image.length) return undefined;
  return t.kind === 'node' ? readNode(t.node, image) : blob(Buffer.from(image.subarray(t.byte, t.byte + t.size)));
}

/** GetMultiVariables: each item's value, or its error (InvalidCRC for a SymbolCrc not its path's). */
export function getMultiVariables(cpu: CpuSide, body: Buffer): Buffer {
  const items = readAddresses(new Reader(body), cpu.limits.tagsPerRead);
  if (!items) return tooMany(true);
  return itemList(
    items.map((item) => {
      const t = target(cpu, item);
      if (crcRefused(item, t)) return ITEM_ERROR_INVALID_CRC;
      return valueOf(cpu, t) ?? ITEM_ERROR_UNRESOLVED;
    }),
  );
}

function u32be(v: number): Buffer {
  const b = Buffer.alloc(4);
  b.writeUInt32BE(v >>> 0);
  return b;
}

/** SetMultiVariables of data: each item written, or its error (nothing of that item written). */
export function setMultiVariables(cpu: CpuSide, body: Buffer, mayWrite: boolean): Buffer {
  const r = new Reader(body);
  const items = readAddresses(r, cpu.limits.tagsPerWrite);
  if (!items) return tooMany(false);
  const values = new Map<number, Buffer>();
  for (let i = 0; i < items.length; i++) {
    const nr = r.uvlq32();
    if (nr === 0) break;
    if (nr > items.length || values.has(nr)) throw new ProtocolError(`S7CommPlus write names item ${nr} of ${items.length}`);
    values.set(nr, readPValue(r));
  }
  const errors: Buffer[] = [];
  items.forEach((item, i) => {
    const raw = values.get(i + 1);
    const t = target(cpu, item);
    if (crcRefused(item, t)) return void errors.push(encodeUVlq32(i + 1), encodeUVlq64(ITEM_ERROR_INVALID_CRC));
    let ok = false;
    // Without the password (read access) every write is refused.
    if (!mayWrite) ok = false;
    else if (raw && t?.kind === 'node' && cpu.memory.check(t.area, t.db, t.node.byte, t.node.size) === undefined)
      ok = writeNode(t.node, cpu.memory, t.area, t.db, raw);
    else if (raw && t?.kind === 'range' && raw.length === t.size && cpu.memory.check(t.area, t.db, t.byte, t.size) === undefined) {
      cpu.memory.write(t.area, t.db, t.byte, raw);
      ok = true;
    }
    if (!ok) errors.push(encodeUVlq32(i + 1), encodeUVlq64(ITEM_ERROR_UNRESOLVED));
  });
  return Buffer.concat([encodeUVlq64(0n), ...errors, encodeUVlq32(0)]);
}

/** GetVarSubStreamed of the session's protection level (1842), the one address the simulator serves this way. */
export function getVarSubStreamed(level: number): Buffer {
  return Buffer.concat([encodeUVlq64(0n), Buffer.from([0x00, 0x00, 0x04]), encodeUVlq32(level)]);
}
