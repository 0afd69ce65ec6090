/**
 * The connection doctor's last steps (lib/s7/doctor.ts): each given address
 * is read once over the doctor's client, and a DB address that fails is
 * told apart (a missing DB, one shorter than the address needs, an
 * optimized one) with what to change.
 */
import { PlcError, toPlcError } from '../errors';
import type { Tag } from '../types';
import { valueToText } from '../values/text';
import type { S7Client } from './client';

export type Family = 'S7-300' | 'S7-400' | 'S7-1200' | 'S7-1500' | 'S7-200' | 'LOGO!';

/** What the steps need of the doctor's walk: its client, its abort, and how a step passes or ends the walk. */
export interface StepContext {
  readonly client: S7Client;
  readonly signal: AbortSignal;
  pass(step: string, detail: string, hint?: string): void;
  fail(step: string, detail: string, hint?: string): never;
  /** An error inside a step: the caller's abort ends the walk, the deadline fails the step, anything else is `other`. */
  failed(step: string, err: unknown, other: (e: PlcError) => never): never;
}

const OPTIMIZED_HINT =
  'Switch the DB to standard access: TIA Portal → the DB\'s Properties → Attributes → untick "Optimized block access", compile and download; the DB editor then shows each variable\'s absolute offset (the Offset column) to use in the address.';

export class TagSteps {
  constructor(
    private readonly c: StepContext,
    private readonly family: Family | undefined,
  ) {}

  async address(address: string): Promise<void> {
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
    try {
      if (tag.area === 'DB') await this.dbAddress(step, tag);
      else {
        const r = (await client.readDetailed([address], { signal: this.c.signal }))[address]!;
        if (r.ok) this.c.pass(step, `${address} = ${valueToText(r.value)}`);
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
      const onAbort = () => done(new PlcError('ABORTED', 'aborted'));
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
      return this.c.pass(step, `DB${db} exists, ${size}; ${tag.address} = ${valueToText(r.value)}`);
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
        OPTIMIZED_HINT,
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
