/**
 * A PLC that answers badly (issue #31): our simulator with one fault put into
 * its GetMultiVariables answers (a ReturnValue the client does not know beside
 * the values, PValue flag bits no public source explains, an item left out),
 * our client and the CLI over real sockets. Which answers are not to be
 * trusted: lib/s7plus/client/refusals.ts (s7commplus (MIT), client.py
 * _parse_read_response takes no value beside a non-zero ReturnValue).
 */
import { expect } from 'chai';
import { spawn } from 'node:child_process';
import { once } from 'node:events';
import * as path from 'node:path';
import { createClient } from '../lib/connect';
import type { PlcError, TagResult } from '../lib/errors';
import type { S7PlusClient } from '../lib/s7plus/client';
import { encodeUVlq64 } from '../lib/s7plus/codec/vlq';
import * as services from '../lib/s7plus/server/services';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { startPlusSimulator, type PlusSimulator } from './support/s7plus-sim';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');

/** A change to the simulator's answer of a read (item 1 first: 00 | 01 <flags> <type> …). */
type Fault = (answer: Buffer) => Buffer;
const returnValue =
  (code: bigint): Fault =>
  (a) =>
    Buffer.concat([encodeUVlq64(code), a.subarray(1)]);
const flags =
  (bits: number): Fault =>
  (a) => {
    const b = Buffer.from(a);
    b[2]! |= bits;
    return b;
  };
/** No value and no error for any item: 0 (ReturnValue), 0 (end of values), 0 (end of errors). */
const nothing: Fault = () => Buffer.from([0, 0, 0]);

describe('S7CommPlus: a PLC that answers badly (one fault in its read answers)', function () {
  this.timeout(30000);
  const real = services.getMultiVariables;
  let fault: Fault | undefined;
  let sim: PlusSimulator;
  let client: S7PlusClient;

  before(async () => {
    (services as { getMultiVariables: typeof real }).getMultiVariables = (cpu, body) => (fault ?? ((a) => a))(real(cpu, body));
    sim = await startPlusSimulator({ sources: SOURCES, db: DB_NUMBERS });
    client = createClient(sim.url) as S7PlusClient;
    await client.connect();
  });
  afterEach(() => (fault = undefined));
  after(async () => {
    (services as { getMultiVariables: typeof real }).getMultiVariables = real;
    await client?.close();
    await sim?.server.close();
  });

  /** The one tag's error of a read with `f` in the PLC's answers (by address DB1.DBW0, by name "Recipe".Step). */
  async function refused(f: Fault, tag: string): Promise<PlcError> {
    fault = f;
    const results: Record<string, TagResult<unknown>> = await client.readDetailed([tag]);
    fault = undefined;
    const r = results[tag]!;
    expect(r.ok, `${tag} was refused`).to.equal(false);
    return (r as { error: PlcError }).error;
  }

  for (const tag of ['DB1.DBW0:INT', '"Recipe".Step']) {
    for (const code of [4n, 0x11n, 0x8104n]) {
      it(`${tag}: a ReturnValue of 0x${code.toString(16)} beside the value says the read failed: no value, PLC_ERROR with the code`, async () => {
        const err = await refused(returnValue(code), tag);
        expect(err.code).to.equal('PLC_ERROR');
        expect(err.plcCode).to.equal(Number(code));
        expect(err.message).to.include(`return value 0x${code.toString(16)}, which says it failed: no value of it is taken`);
      });
    }

    for (const bits of [0x80, 0x01, 0x08]) {
      it(`${tag}: a value with PValue flag bit 0x${bits.toString(16)} (no public source explains it) is refused with PROTOCOL_ERROR`, async () => {
        const err = await refused(flags(bits), tag);
        expect(err.code).to.equal('PROTOCOL_ERROR');
        expect(err.message).to.include(`whose bits 0x${bits.toString(16)} no public source explains`);
      });
    }

    it(`${tag}: an item the PLC left out of its answer is that tag's PLC_ERROR, and the link stays`, async () => {
      const err = await refused(nothing, tag);
      expect(err.code).to.equal('PLC_ERROR');
      expect(err.message).to.include('neither a value nor an error for this item');
      expect(client.state).to.equal('connected');
      expect(Object.keys(await client.read([tag]))).to.deep.equal([tag]);
    });
  }

  for (const [what, f] of [
    ['an item the PLC left out', nothing],
    ['a ReturnValue of 0x4 beside the value', returnValue(4n)],
  ] as const) {
    it(`the CLI: ${what} exits 1 (a tag error), not 3 (a connection error)`, async () => {
      fault = f;
      const child = spawn(process.execPath, [BIN, 'read', sim.url, 'DB1.DBW0:INT'], { stdio: ['ignore', 'pipe', 'pipe'] });
      let err = '';
      child.stderr.on('data', (d: Buffer) => (err += d.toString()));
      child.stdout.resume();
      const [code] = (await once(child, 'exit')) as [number];
      expect(code, err).to.equal(1);
      expect(err).to.include('DB1.DBW0:INT');
    });
  }
});
