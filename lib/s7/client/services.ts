/**
 * The S7 system services of S7Client: SZL, identity, diagnostic buffer,
 * clock, CPU state and control, blocks, password. Each request is one job
 * on the session (an AmQ slot, the timeout, the caller's abort signal),
 * like a Read Var; a multi-part answer is asked for part by part.
 * S7Client delegates to this class; its methods carry the documentation.
 * The requests and their answers go through service-transport.ts.
 */
import { PlcError, ProtocolError } from '../../errors';
import { readDbBytes } from './db-read';
import { SERVICE, ServiceTransport } from './service-transport';
import type { RequestOptions } from '../../types';
import { decodeDateAndTime, encodeDateAndTime } from '../../values/time';
import {
  decodeBlockCounts,
  decodeBlockInfo,
  decodeBlockListEntries,
  decodeLoadBlock,
  encodeBlockInfoRequest,
  encodeListTypeRequest,
  type BlockCounts,
  type BlockInfo,
  type UploadedBlock,
} from '../codec/blocks';
import { COLD_START_ARG, encodeEndUpload, encodePlcStart, encodePlcStop, encodeStartUpload, encodeUpload } from '../codec/control';
import { encodePassword, type UserdataPdu } from '../codec/userdata';
import { BLOCK_TYPES, ControlFunction, blockTypeCode, serviceError, type BlockType } from '../constants';
import { decodeDiagnosticBuffer, type DiagnosticEntry } from '../codec/diagnostics';
import {
  SZL,
  decodeComponentIdentification,
  decodeCpuState,
  decodeModuleIdentification,
  decodeProtection,
  parseSzl,
  type CpuMode,
  type CpuState,
  type Protection,
  type SzlList,
} from '../codec/szl';
import { hex4 } from '../../values/text';

/** What `info()` gathers in one object. A field the CPU does not give is undefined. */
export interface PlcInfo {
  orderCode: string | undefined;
  firmware: string | undefined;
  hardwareVersion: number | undefined;
  moduleTypeName: string | undefined;
  serialNumber: string | undefined;
  asName: string | undefined;
  moduleName: string | undefined;
  plantId: string | undefined;
  copyright: string | undefined;
  state: CpuMode | undefined;
  protection: Protection | undefined;
  /** What this connection negotiated. */
  pduSize: number;
  maxJobs: number;
  /** The PLC clock (fields read as UTC, see readClock). */
  clock: Date | undefined;
}

/** How the PLC's clock fields map to a Date: as UTC (default) or as this host's local time. */
export interface ClockOptions extends RequestOptions {
  timeZone?: 'utc' | 'local';
}

export class S7Services extends ServiceTransport {
  // ---------------------------------------------------------------- SZL

  async readSzl(id: number, index = 0, options: RequestOptions = {}): Promise<SzlList> {
    checkWord('SZL ID', id);
    checkWord('SZL index', index);
    const what = `read SZL 0x${hex4(id)} index 0x${hex4(index)}`;
    const first = await this.request(SERVICE.readSzl, what, options.signal, Buffer.of(id >> 8, id & 0xff, index >> 8, index & 0xff));
    if (first.returnCode !== 0xff)
      throw new PlcError(
        'SZL_NOT_AVAILABLE',
        `${this.host.name} ${what}: the PLC has no such list (return code 0x${first.returnCode.toString(16)})`,
      );
    const bytes = await this.allParts(first, SERVICE.readSzl, what, options.signal);
    try {
      return parseSzl(bytes);
    } catch (err) {
      throw this.malformed(err);
    }
  }

  /** Decodes a list, turning a decoder's ProtocolError into a dropped link like any malformed answer. */
  private decoded<T>(list: SzlList, decode: (l: SzlList) => T): T {
    try {
      return decode(list);
    } catch (err) {
      throw this.malformed(err);
    }
  }

  async cpuState(options: RequestOptions = {}): Promise<CpuState> {
    return this.decoded(await this.readSzl(SZL.CPU_STATE, 0, options), decodeCpuState);
  }

  async protection(options: RequestOptions = {}): Promise<Protection> {
    return this.decoded(await this.readSzl(SZL.PROTECTION, 4, options), decodeProtection);
  }

  async diagnosticBuffer(options: RequestOptions & { max?: number } = {}): Promise<DiagnosticEntry[]> {
    const max = options.max;
    if (max !== undefined && (!Number.isInteger(max) || max < 1 || max > 0xffff)) {
      throw new PlcError('INVALID_VALUE', `diagnosticBuffer: max must be a whole number of entries 1..65535, got ${String(max)}`);
    }
    let list: SzlList;
    if (max === undefined) list = await this.readSzl(SZL.DIAGNOSTICS, 0, options);
    else {
      try {
        list = await this.readSzl(0x01a0, max, options);
      } catch (err) {
        // A CPU without the "n most recent" extract: all entries, cut here.
        if (!(err instanceof PlcError) || err.code !== 'SZL_NOT_AVAILABLE') throw err;
        list = await this.readSzl(SZL.DIAGNOSTICS, 0, options);
      }
    }
    const entries = this.decoded(list, decodeDiagnosticBuffer);
    return max === undefined ? entries : entries.slice(0, max);
  }

  async info(options: RequestOptions = {}): Promise<PlcInfo> {
    // Lists a CPU does not have leave their fields undefined; any other error fails info().
    const optional = async <T>(read: () => Promise<T>): Promise<T | undefined> => {
      try {
        return await read();
      } catch (err) {
        if (err instanceof PlcError && (err.code === 'SZL_NOT_AVAILABLE' || err.code === 'NOT_SUPPORTED' || err.code === 'ACCESS_DENIED'))
          return undefined;
        throw err;
      }
    };
    const module = await optional(async () => this.decoded(await this.readSzl(SZL.MODULE_ID, 0, options), decodeModuleIdentification));
    const component = await optional(async () =>
      this.decoded(await this.readSzl(SZL.COMPONENT_ID, 0, options), decodeComponentIdentification),
    );
    const state = await optional(() => this.cpuState(options));
    const protection = await optional(() => this.protection(options));
    const clock = await optional(() => this.readClock(options));
    return {
      orderCode: module?.orderCode,
      firmware: module?.firmware,
      hardwareVersion: module?.hardwareVersion,
      moduleTypeName: component?.moduleTypeName,
      serialNumber: component?.serialNumber,
      asName: component?.asName,
      moduleName: component?.moduleName,
      plantId: component?.plantId,
      copyright: component?.copyright,
      state: state?.mode,
      protection,
      pduSize: this.host.current()?.pduSize ?? 0,
      maxJobs: this.host.current()?.maxJobs ?? 0,
      clock,
    };
  }

  // ---------------------------------------------------------------- clock

  async readClock(options: ClockOptions = {}): Promise<Date> {
    const what = 'read clock';
    const u = await this.request(SERVICE.readClock, what, options.signal);
    if (u.returnCode !== 0xff || u.data.length !== 10) {
      throw this.malformed(
        new ProtocolError(`${what}: ${u.data.length} data bytes (return code 0x${u.returnCode.toString(16)}), expected 10`),
      );
    }
    const utc = decodeDateAndTime(u.data, 2);
    if (Number.isNaN(utc.getTime()))
      throw new PlcError(
        'PLC_ERROR',
        `${this.host.name} ${what}: the PLC clock holds no valid date (${u.data.subarray(2).toString('hex')})`,
      );
    return options.timeZone === 'local' ? fromLocalFields(utc) : utc;
  }

  async setClock(date: Date, options: ClockOptions = {}): Promise<void> {
    // Setting the clock is a control function: it moves every time stamp the PLC makes.
    const refusal = this.controlRefusal('set clock');
    if (refusal) throw refusal;
    if (!(date instanceof Date) || Number.isNaN(date.getTime()))
      throw new PlcError('INVALID_VALUE', `setClock takes a valid Date, got ${String(date)}`);
    const fields = options.timeZone === 'local' ? toLocalFields(date) : date;
    const data = Buffer.alloc(10);
    try {
      encodeDateAndTime(fields, data, 2);
    } catch (err) {
      throw new PlcError('INVALID_VALUE', `setClock: ${err instanceof Error ? err.message : String(err)}`);
    }
    data[1] = fields.getUTCFullYear() >= 2000 ? 0x20 : 0x19;
    await this.request(SERVICE.setClock, 'set clock', options.signal, data);
  }

  // ---------------------------------------------------------------- control

  private async startOrStop(frame: Buffer, func: number, what: string, already: number, signal?: AbortSignal): Promise<void> {
    const refusal = this.controlRefusal(what);
    if (refusal) throw refusal;
    const m = await this.control(frame, what, signal);
    if (m.kind !== 'control-ack') throw this.malformed(new ProtocolError(`the answer to ${what} is a ${m.kind}`));
    // Already in the wanted mode: done (the CPU says so with its state error and this parameter).
    if (m.error !== 0 && m.status === already) return;
    if (m.error !== 0) throw serviceError(m.error, `${this.host.name} ${what}`);
    if (m.func !== func) throw this.malformed(new ProtocolError(`the answer to ${what} echoes function 0x${m.func.toString(16)}`));
  }

  stop(options: RequestOptions = {}): Promise<void> {
    return this.startOrStop(encodePlcStop(), ControlFunction.PlcStop, 'PLC stop', 0x07, options.signal);
  }

  hotStart(options: RequestOptions = {}): Promise<void> {
    return this.startOrStop(encodePlcStart(), ControlFunction.PiService, 'PLC hot start', 0x03, options.signal);
  }

  coldStart(options: RequestOptions = {}): Promise<void> {
    return this.startOrStop(encodePlcStart(COLD_START_ARG), ControlFunction.PiService, 'PLC cold start', 0x03, options.signal);
  }

  // ---------------------------------------------------------------- blocks

  async listBlocks(options: RequestOptions = {}): Promise<BlockCounts> {
    const what = 'list blocks';
    const u = await this.request(SERVICE.listAll, what, options.signal);
    const bytes = await this.allParts(u, SERVICE.listAll, what, options.signal);
    try {
      return decodeBlockCounts(bytes);
    } catch (err) {
      throw this.malformed(err);
    }
  }

  async listBlocksOfType(type: BlockType, options: RequestOptions = {}): Promise<number[]> {
    const code = blockType(type);
    const what = `list blocks of type ${type}`;
    let first: UserdataPdu;
    try {
      first = await this.request(SERVICE.listType, what, options.signal, encodeListTypeRequest(code));
    } catch (err) {
      // "No (further) block of that type": the list is empty.
      if (err instanceof PlcError && err.plcCode === 0xd20e) return [];
      throw err;
    }
    const bytes = await this.allParts(first, SERVICE.listType, what, options.signal);
    try {
      return decodeBlockListEntries(bytes).map((e) => e.number);
    } catch (err) {
      throw this.malformed(err);
    }
  }

  async blockInfo(type: BlockType, number: number, options: RequestOptions = {}): Promise<BlockInfo> {
    const code = blockType(type);
    checkBlockNumber(number);
    const what = `block info of ${type}${number}`;
    const u = await this.request(SERVICE.blockInfo, what, options.signal, encodeBlockInfoRequest(code, number));
    if (u.returnCode !== 0xff)
      throw new PlcError('OBJECT_DOES_NOT_EXIST', `${this.host.name} ${what}: no such block (return code 0x${u.returnCode.toString(16)})`, {
        plcCode: u.returnCode,
      });
    try {
      return decodeBlockInfo(u.data);
    } catch (err) {
      throw this.malformed(err);
    }
  }

  async uploadBlock(type: BlockType, number: number, options: RequestOptions = {}): Promise<UploadedBlock> {
    const code = blockType(type);
    checkBlockNumber(number);
    const what = `upload of ${type}${number}`;
    const start = await this.control(encodeStartUpload(code, number), `start ${what}`, options.signal);
    if (start.kind === 'control-ack' && start.error !== 0) throw serviceError(start.error, `${this.host.name} start ${what}`);
    if (start.kind !== 'start-upload-ack') throw this.malformed(new ProtocolError(`the answer to start ${what} is a ${start.kind}`));
    const chunks: Buffer[] = [];
    let total = 0;
    try {
      for (;;) {
        const m = await this.control(encodeUpload(start.uploadId), what, options.signal);
        if (m.kind === 'control-ack' && m.error !== 0) throw serviceError(m.error, `${this.host.name} ${what}`);
        if (m.kind !== 'upload-ack') throw this.malformed(new ProtocolError(`the answer to ${what} is a ${m.kind}`));
        chunks.push(Buffer.from(m.chunk));
        total += m.chunk.length;
        if (total > start.loadLength)
          throw this.malformed(new ProtocolError(`${what}: ${total} bytes arrived, the block has ${start.loadLength}`));
        if (!m.more) break;
        if (m.chunk.length === 0) throw this.malformed(new ProtocolError(`${what}: an empty part that says more follow`));
      }
    } finally {
      // The CPU holds the upload open until it is ended; end it even when a part failed (best effort).
      await this.control(encodeEndUpload(start.uploadId), `end ${what}`, options.signal).catch(() => undefined);
    }
    const bytes = Buffer.concat(chunks);
    try {
      return decodeLoadBlock(bytes);
    } catch (err) {
      throw this.malformed(err);
    }
  }

  async readDb(number: number, options: RequestOptions = {}): Promise<Buffer> {
    const info = await this.blockInfo('DB', number, options);
    if (info.mc7Size === 0) return Buffer.alloc(0);
    return readDbBytes(this.host.session(), number, info.mc7Size, options.signal);
  }

  // ---------------------------------------------------------------- password

  async setPassword(password: string, options: RequestOptions = {}): Promise<void> {
    const data = encodePassword(password);
    await this.request(SERVICE.setPassword, 'set password', options.signal, data);
  }

  async clearPassword(options: RequestOptions = {}): Promise<void> {
    await this.request(SERVICE.clearPassword, 'clear password', options.signal);
  }
}

function blockType(type: string): number {
  const code = blockTypeCode(type);
  if (code === undefined) throw new PlcError('INVALID_VALUE', `unknown block type "${type}" (${Object.keys(BLOCK_TYPES).join(', ')})`);
  return code;
}

function checkBlockNumber(n: number): void {
  if (!Number.isInteger(n) || n < 0 || n > 65535) throw new PlcError('INVALID_VALUE', `a block number is 0..65535, got ${String(n)}`);
}

function checkWord(what: string, n: number): void {
  if (!Number.isInteger(n) || n < 0 || n > 0xffff) throw new PlcError('INVALID_VALUE', `${what} must be 0..0xFFFF, got ${String(n)}`);
}

/** A Date whose UTC fields are `d`'s local fields (to write local wall time). */
function toLocalFields(d: Date): Date {
  return new Date(Date.UTC(d.getFullYear(), d.getMonth(), d.getDate(), d.getHours(), d.getMinutes(), d.getSeconds(), d.getMilliseconds()));
}

/** The Date whose local fields are `utc`'s UTC fields (to read local wall time). */
function fromLocalFields(utc: Date): Date {
  return new Date(
    utc.getUTCFullYear(),
    utc.getUTCMonth(),
    utc.getUTCDate(),
    utc.getUTCHours(),
    utc.getUTCMinutes(),
    utc.getUTCSeconds(),
    utc.getUTCMilliseconds(),
  );
}
