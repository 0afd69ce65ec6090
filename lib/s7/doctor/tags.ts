/**
 * The connection doctor's last steps (lib/s7/doctor/index.ts): each given address
 * is read once over the doctor's client, and a DB address that fails is
 * told apart (a missing DB, one shorter than the address needs, an
 * optimized one) with what to change.
 */
import { abortError, PlcError, toPlcError } from '../../errors';
import { formatAddress, S7_TAG_SYNTAX } from '../../address';
import type { SymbolTable } from '../../symbols/model';
import type { Tag } from '../../types';
import { realsShown } from '../../symbols/reals';
import { textOf } from '../../values/text';
import type { S7Client } from '../client';
import type { Family } from './families';
import { hostPart } from '../../link/url-params';
import { HINT } from './hints';

/** What the steps need of the doctor's walk: its client, its abort, and how a step passes or ends the walk. */
export interface StepContext {
  readonly client: S7Client;
  readonly signal: AbortSignal;
  pass(step: string, detail: string, hint?: string): void;
  fail(step: string, detail: string, hint?: string): never;
  /** An error inside a step: the caller's abort ends the walk, the deadline fails the step, anything else is `other`. */
  failed(step: string, err: unknown, other: (e: PlcError) => never): never;
}

/** The same PLC over S7CommPlus (an S7-1200/1500 serves it on its PUT/GET port): the URL an optimized block is read with. */
function plusUrl(client: S7Client): string {
  const { host, port } = client.endpoint;
  return `s7plus://${hostPart(host)}${port === 102 ? '' : `:${port}`}`;
}

export class TagSteps {
  constructor(
    private readonly c: StepContext,
    private readonly family: Family | undefined,
    /** The table the doctor's client resolves names with (DiagnoseOptions.symbols). */
    private readonly symbols?: SymbolTable,
  ) {}

  /**
   * One step per given text: an S7 address is read as such; anything else is
   * a name, resolved by the client as a read resolves it (the symbol table
   * given to the doctor, lib/symbols/resolve.ts) and read at its address.
   */
  async check(text: string): Promise<void> {
    let asAddress: Error | undefined;
    try {
      S7_TAG_SYNTAX.parse(text);
    } catch (err) {
      asAddress = err as Error;
    }
    if (!asAddress) return this.address(text);
    if (!this.symbols) return this.withoutTable(text, asAddress);
    return this.symbol(text);
  }

  /** Text that is no address, and no table to look it up in: the step says to give the sources. */
  private withoutTable(text: string, asAddress: Error): never {
    const give =
      "give the doctor the sources that declare it: --symbols FILE (with --db NAME=N for TIA's DB sources), or the connection node's Symbol sources";
    if (text.includes('"')) {
      this.c.fail(
        `symbol ${text}`,
        `${text} is a name from the PLC program, and the doctor was given no symbol table to look it up in`,
        `To check a name, ${give}; or give its absolute address (e.g. DB1,REAL0).`,
      );
    }
    this.c.fail(
      `address ${text}`,
      `${asAddress.message}; no symbol table was given to look it up as a name`,
      `Write the address in one of the S7 syntaxes (README, "Addresses"), e.g. DB1,INT0 or DB1.DBW0; if it is a name from the PLC program, ${give}.`,
    );
  }

  /** A name: resolved by the client (its one path for names), then read by that address like one given as such. */
  private async symbol(name: string): Promise<void> {
    const step = `symbol ${name}`;
    let tag: Tag;
    try {
      tag = this.c.client.tag(name);
    } catch (err) {
      // A member of an optimized block exists in the sources but has no address PUT/GET could read.
      if (err instanceof PlcError && err.code === 'OPTIMIZED_BLOCK')
        this.c.fail(step, err.message, HINT.optimizedName(plusUrl(this.c.client)));
      this.c.fail(
        step,
        (err as Error).message,
        'Check the name against the sources (plcwire symbols FILE lists every name they declare), or add the source that declares it.',
      );
    }
    const where = `${name} is ${formatAddress(tag)}`;
    if (tag.area === 'DB') await this.layout(step, where, tag.dbNumber);
    const named: StepContext = {
      ...this.c,
      pass: (s, detail, hint) => this.c.pass(s, `${where}; ${detail}`, hint),
      fail: (s, detail, hint) => this.c.fail(s, `${where}; ${detail}`, hint),
    };
    await new TagSteps(named, this.family).read(step, name, tag);
  }

  /**
   * The client's layout check of the name's DB (the one it starts on
   * connect, shared): a DB whose length in the PLC differs from the sources'
   * has its names at other offsets than the PLC program, a failed step. A
   * PLC that cannot tell (S7-1200/1500) leaves the read to speak.
   */
  private async layout(step: string, where: string, db: number): Promise<void> {
    let checks;
    try {
      checks = await this.c.client.checkLayout({ signal: this.c.signal });
    } catch (err) {
      if (this.c.signal.aborted) return this.c.failed(step, err, (p) => this.c.fail(step, p.message));
      return; // the link dropped during the check: the read below reconnects and tells
    }
    const c = checks.find((x) => x.db === db);
    if (c?.status !== 'mismatch') return;
    const block = c.block === `DB${db}` ? `DB${db}` : `DB${db} "${c.block}"`;
    if (c.actual === null)
      this.c.fail(
        step,
        `${where}; ${block} is not in the PLC (the sources declare it with ${c.declared} bytes)`,
        'Check the DB number (--db NAME=N, or the DB numbers of the connection) against the PLC program, and that the DB is downloaded to the CPU.',
      );
    this.c.fail(
      step,
      `${where}; ${block} is ${c.actual} bytes in the PLC, the sources declare ${c.declared}: the PLC program's DB is not the one the sources describe, and names after the first change would read other members' bytes`,
      'Export the DB source again from the PLC project (TIA Portal: right-click the DB → Generate source from blocks) and give that one, or download the DB as the sources declare it.',
    );
  }

  private async address(address: string): Promise<void> {
    const step = `address ${address}`;
    const client = this.c.client;
    let tag: Tag;
    try {
      tag = client.tag(address);
    } catch (err) {
      this.c.fail(
        step,
        (err as Error).message,
        'Write the address in one of the S7 syntaxes (README, "Addresses"), e.g. DB1,INT0 or DB1.DBW0.',
      );
    }
    await this.read(step, address, tag);
  }

  private async read(step: string, address: string, tag: Tag): Promise<void> {
    const client = this.c.client;
    try {
      if (tag.area === 'DB') await this.dbAddress(step, tag);
      else {
        const r = (await client.readDetailed([address], { signal: this.c.signal }))[address]!;
        if (r.ok) this.c.pass(step, `${address} = ${textOf(realsShown(client, undefined, address, r.value))}`);
        else
          this.c.fail(
            step,
            r.error.message,
            r.error.code === 'ADDRESS_OUT_OF_RANGE'
              ? `The ${tag.area} area of this CPU is smaller than the address needs: check the offset.`
              : undefined,
          );
      }
    } catch (err) {
      return this.c.failed(step, err, (p) => this.c.fail(step, p.message));
    }
  }

  /** Waits until the client is connected again (it reconnects by itself after a dropped link), within the deadline. */
  private async reconnected(): Promise<void> {
    const client = this.c.client;
    if (client.state === 'connected') return;
    await new Promise<void>((resolve, reject) => {
      const done = (err?: Error) => {
        client.removeListener('connected', onConnected);
        this.c.signal.removeEventListener('abort', onAbort);
        if (err) reject(err);
        else resolve();
      };
      const onConnected = () => done();
      const onAbort = () => done(abortError('waiting for the connection', this.c.signal));
      if (this.c.signal.aborted) return onAbort();
      client.on('connected', onConnected);
      this.c.signal.addEventListener('abort', onAbort, { once: true });
    });
  }

  private async dbAddress(step: string, tag: Tag): Promise<void> {
    const client = this.c.client;
    const db = tag.dbNumber;
    const end = tag.byteOffset + tag.byteLength;
    const needs = `${tag.address} needs bytes ${tag.byteOffset}..${end - 1}`;
    const missing = (how: string) =>
      this.c.fail(
        step,
        `DB${db} does not exist (${how})`,
        `Check the DB number in the PLC program and that the DB is downloaded to the CPU (an instance DB counts too).`,
      );
    let length: number | undefined;
    try {
      length = (await client.blockInfo('DB', db, { signal: this.c.signal })).mc7Size;
    } catch (err) {
      const e = toPlcError(err);
      if (e.code === 'OBJECT_DOES_NOT_EXIST') missing('block info: no such block');
      // S7-1200/1500 (and S7-200, LOGO!) offer no block info over S7comm: the reads below tell.
      // A malformed answer (snap7's server answers block info of a missing DB so) dropped the link: read once it is back.
      if (e.code === 'PROTOCOL_ERROR') await this.reconnected();
      else if (e.code !== 'NOT_SUPPORTED' && e.code !== 'ACCESS_DENIED') throw err;
    }
    if (length !== undefined && end > length) {
      this.c.fail(
        step,
        `DB${db} has ${length} bytes (block info); ${needs}`,
        `The address lies past the end of DB${db}: check the offset against the DB (the Offset column of the DB editor), or extend the DB and download it.`,
      );
    }
    const read = async (address: string) => (await client.readDetailed([address], { signal: this.c.signal }))[address]!;
    const r = await read(tag.address);
    if (r.ok) {
      const size =
        length !== undefined ? `${length} bytes (block info)` : 'its length is not known (this CPU offers no block info over S7comm)';
      return this.c.pass(step, `DB${db} exists, ${size}; ${tag.address} = ${textOf(realsShown(client, undefined, tag.address, r.value))}`);
    }
    if (r.error.code === 'OBJECT_DOES_NOT_EXIST') missing(`the CPU answered the read: ${r.error.message}`);
    if (r.error.code !== 'ADDRESS_OUT_OF_RANGE' || length !== undefined) this.c.fail(step, r.error.message);
    // No block info: the CPU said "out of range". Byte 0 tells a short DB from one that serves no absolute address.
    const readable = async (offset: number) => {
      const b = await read(`DB${db},B${offset}`);
      if (b.ok) return true;
      if (b.error.code === 'ADDRESS_OUT_OF_RANGE') return false;
      throw b.error;
    };
    if (!(await readable(0))) {
      const family = this.family;
      const modern = family === 'S7-1200' || family === 'S7-1500' || family === undefined;
      if (!modern)
        this.c.fail(
          step,
          `DB${db} exists but not even its byte 0 can be read: it is empty`,
          'Give the DB its variables in the PLC program and download it.',
        );
      this.c.fail(
        step,
        `DB${db} exists (the CPU did not answer "object does not exist") but not even its byte 0 can be read: it is probably an optimized DB ` +
          '(an S7-1200/1500 answers "address out of range" for every absolute address of a DB with optimized block access; an empty DB answers the same)',
        HINT.optimizedDb(plusUrl(client)),
      );
    }
    // The DB's length: the first byte that cannot be read, by bisection (about 16 one-byte reads at most).
    let lo = 0; // readable
    let hi = end - 1; // the address's last byte
    if (await readable(hi)) this.c.fail(step, r.error.message);
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (await readable(mid)) lo = mid;
      else hi = mid;
    }
    this.c.fail(
      step,
      `DB${db} has ${hi} bytes (found by reading single bytes); ${needs}`,
      `The address lies past the end of DB${db}: check the offset against the DB (the Offset column of the DB editor), or extend the DB and download it.`,
    );
  }
}
