/**
 * The whole program over s7plus:// against our simulator (issue #25): the PLC
 * tag table's I/Q/M names in the browse, in the model a compiled tag table
 * gives, read and written by name; and a download (the simulator's reload)
 * while a client polls by name: the change is noticed by the type objects'
 * modification times, the table browsed again, a removed name fails typed,
 * a moved one reads its own value, and no poll returns another member's value.
 */
import { expect } from 'chai';
import { spawn } from 'node:child_process';
import { once } from 'node:events';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { createClient } from '../lib/connect';
import type { PlcError } from '../lib/errors';
import type { S7PlusClient } from '../lib/s7plus/client';
import type { ProgramChange } from '../lib/s7plus/client/program';
import { S7Server } from '../lib/s7/server';
import { S7PlusService } from '../lib/s7plus/server';
import { generateCertificate } from '../lib/s7plus/transport/cert';
import { compileSymbols } from '../lib/symbols';
import type { SymbolSource } from '../lib/symbols/model';
import { symbolCrc } from '../lib/s7plus/codec/symbol-crc';
import { Ids, SoftDataType } from '../lib/s7plus/constants';
import { DB_NUMBERS, S7PLUS_FIXTURES, SOURCES } from './fixtures/s7plus';
import { startPlusSimulator } from './support/s7plus-sim';
import { until, waitFor } from './support/wait';

const TAGS: SymbolSource = { name: 'PLC tags.csv', content: fs.readFileSync(path.join(S7PLUS_FIXTURES, 'PLC tags.csv'), 'utf8') };

describe('S7CommPlus browse of the PLC tag table (I/Q/M names)', function () {
  this.timeout(30000);
  let server: S7Server;
  let service: S7PlusService;
  let client: S7PlusClient;

  before(async () => {
    const cert = await generateCertificate();
    service = new S7PlusService({ sources: [...SOURCES, TAGS], db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await server.listen();
    client = createClient(`s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=10000`) as S7PlusClient;
    await client.connect();
  });
  after(async () => {
    await client?.close();
    await server?.close();
  });

  it('gives each tag as the compiled tag table does (name, type, area, byte, bit, address), reached by its area object and LID', async () => {
    const browsed = await client.browse();
    const compiled = compileSymbols([...SOURCES, TAGS], { db: DB_NUMBERS });
    const tags = compiled.entries.filter((e) => e.db === null);
    expect(tags.map((e) => e.name)).to.deep.equal(['"Start_Button"', '"Motor on"', '"Speed setpoint"', '"Temperature"']);
    for (const c of tags) {
      const b = browsed.lookup(c.name)!;
      expect(b, c.name).to.not.equal(undefined);
      const pick = (e: typeof c) => ({
        name: e.name,
        type: e.type,
        kind: e.kind,
        area: e.area,
        db: e.db,
        byte: e.byte,
        bit: e.bit,
        address: e.address,
      });
      expect(pick(b)).to.deep.equal(pick(c));
    }
    // Each with the SymbolCrc of its name and type (issue #32).
    const crc = (name: string, soft: number) => symbolCrc([{ name, soft }]);
    expect(browsed.lookup('"Start_Button"')!.access).to.deep.equal({
      area: Ids.NativeTheIAreaRID,
      lids: [0xa],
      symbolCrc: crc('Start_Button', SoftDataType.Bool),
    });
    expect(browsed.lookup('"Motor on"')!.access!.area).to.equal(Ids.NativeTheQAreaRID);
    expect(browsed.lookup('"Temperature"')!.access).to.deep.equal({
      area: Ids.NativeTheMAreaRID,
      lids: [0xb],
      symbolCrc: crc('Temperature', SoftDataType.Real),
    });
    // Every DB entry is still there as before.
    expect(browsed.entries.filter((e) => e.db !== null).map((e) => e.name)).to.deep.equal(
      compiled.entries.filter((e) => e.db !== null).map((e) => e.name),
    );
  });

  it('reads a tag by name as the PLC holds it, and writes by name what an address then reads', async () => {
    server.memory.writeBit('I', 0, 0, 0, true);
    server.memory.write('M', 0, 20, Buffer.from([0x41, 0xac, 0x00, 0x00])); // 21.5
    expect(await client.read(['"Start_Button"', 'Start_Button', '"Temperature"'])).to.deep.equal({
      '"Start_Button"': true,
      Start_Button: true,
      '"Temperature"': 21.5,
    });
    await client.write({ '"Speed setpoint"': -1234, '"Motor on"': true });
    expect(await client.read(['MW10:INT', 'Q0.1'])).to.deep.equal({ 'MW10:INT': -1234, 'Q0.1': true });
    expect(server.memory.area('M')!.readInt16BE(10)).to.equal(-1234);
    server.memory.writeBit('I', 0, 0, 0, false);
    expect(await client.read(['"Start_Button"'])).to.deep.equal({ '"Start_Button"': false });
  });

  it('a name the tag table does not have fails INVALID_ADDRESS with the closest names', async () => {
    const err = (await client.read(['"Start_Buton"']).catch((e: Error) => e)) as PlcError;
    expect(err.message).to.match(/Start_Buton/);
    const detailed = await client.readDetailed(['"Start_Buton"']);
    const r = detailed['"Start_Buton"']!;
    expect(r.ok).to.equal(false);
    if (!r.ok) {
      expect(r.error.code).to.equal('INVALID_ADDRESS');
      expect(r.error.message).to.include('"Start_Button"');
    }
  });
});

/** Sources of a program with an optimized DB "Prog" (DB5) and a standard DB "Std" (DB6). */
function program(prog: string, std: string): SymbolSource[] {
  return [
    {
      name: 'Prog.db',
      content: `DATA_BLOCK "Prog"\n{ S7_Optimized_Access := 'TRUE' }\nVERSION : 0.1\n   STRUCT\n${prog}   END_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n`,
    },
    {
      name: 'Std.db',
      content: `DATA_BLOCK "Std"\n{ S7_Optimized_Access := 'FALSE' }\nVERSION : 0.1\n   STRUCT\n${std}   END_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n`,
    },
  ];
}
const NUMBERS = { Prog: 5, Std: 6 };
const V1 = program('      A : Int := 1;\n      B : Int := 2;\n      C : Int := 3;\n', '      X : Int := 10;\n      Y : Int := 20;\n');
// A removed from Prog (B and C take other LIDs), Y moved before X in Std (other bytes and LIDs).
const V2 = program('      B : Int := 2;\n      C : Int := 3;\n', '      Y : Int := 20;\n      X : Int := 10;\n');

describe('S7CommPlus program change (a download while a client polls by name)', function () {
  this.timeout(30000);
  let server: S7Server;
  let service: S7PlusService;
  let client: S7PlusClient;

  beforeEach(async () => {
    let url: string;
    ({ server, service, url } = await startPlusSimulator({ sources: V1, db: NUMBERS }));
    client = createClient(url) as S7PlusClient;
    await client.connect();
  });
  afterEach(async () => {
    await client?.close();
    await server?.close();
  });

  it('the removed name fails typed, the moved ones read their own values, no poll returns a shifted value', async () => {
    const names = ['"Prog".A', '"Prog".B', '"Prog".C', '"Std".X', '"Std".Y'];
    const expected: Record<string, number> = { '"Prog".A': 1, '"Prog".B': 2, '"Prog".C': 3, '"Std".X': 10, '"Std".Y': 20 };
    expect(await client.read(names)).to.deep.equal(expected);
    const seen: { name: string; value: unknown }[] = [];
    const failures: PlcError[] = [];
    const state = { stop: false };
    let changeSeen = false;
    let pollsAfter = 0;
    const changed = waitFor<ProgramChange>(client, 'programChanged', 10000);
    const poll = (async () => {
      while (!state.stop) {
        const afterChange = changeSeen;
        const r = await client.readDetailed(names);
        for (const [name, result] of Object.entries(r)) {
          if (result.ok) seen.push({ name, value: result.value });
          else failures.push(result.error as PlcError);
        }
        if (afterChange) pollsAfter++;
      }
    })();
    // Let a few polls go by on the old program, then download the new one (each poll is several requests).
    await until(() => seen.length >= 10, 10000, 'two polls');
    service.reload(V2, server.memory);
    const change = await changed;
    changeSeen = true;
    // Polls after the change has been seen: the table browsed again.
    await until(() => pollsAfter >= 3, 10000, 'three polls after the change');
    state.stop = true;
    await poll;
    expect(change.before.lookup('"Prog".A')).to.not.equal(undefined);
    expect(change.after.lookup('"Prog".A')).to.equal(undefined);
    // Every value any poll returned is that name's own, before and after the download.
    for (const { name, value } of seen) expect(value, name).to.equal(expected[name]);
    // The only failure is the removed name, typed and named.
    expect(failures.length).to.be.greaterThan(0);
    for (const f of failures) {
      expect(f.code).to.equal('INVALID_ADDRESS');
      expect(f.tag).to.equal('"Prog".A');
    }
    // The moved members are at their new places: Std.Y first (byte 0), Std.X at byte 2.
    const after = await client.browse();
    expect(after.lookup('"Std".Y')!.byte).to.equal(0);
    expect(after.lookup('"Std".X')!.byte).to.equal(2);
    expect(await client.read(['"Prog".B', '"Prog".C', '"Std".X', '"Std".Y', 'DB6.DBW0:INT'])).to.deep.equal({
      '"Prog".B': 2,
      '"Prog".C': 3,
      '"Std".X': 10,
      '"Std".Y': 20,
      'DB6.DBW0:INT': 20,
    });
  });

  it('a write after the download lands in the member named, not in the one that had its LID', async () => {
    expect(await client.read(['"Prog".B'])).to.deep.equal({ '"Prog".B': 2 });
    service.reload(V2, server.memory);
    await client.write({ '"Prog".B': 222 });
    expect(await client.read(['"Prog".B', '"Prog".C'])).to.deep.equal({ '"Prog".B': 222, '"Prog".C': 3 });
  });

  it('a block renamed with its layout unchanged: the new name is found through the block list, the old one then fails typed', async () => {
    expect(await client.read(['"Std".X'])).to.deep.equal({ '"Std".X': 10 });
    const renamed = V1.map((f) =>
      f.name === 'Std.db' ? { name: 'Level.db', content: (f.content as string).replace('"Std"', '"Level"') } : f,
    );
    service.reload(renamed, server.memory, { Prog: 5, Level: 6 });
    // The types' times did not change (same layouts): the unknown name has the block list asked.
    expect(await client.read(['"Level".X'])).to.deep.equal({ '"Level".X': 10 });
    const r = await client.readDetailed(['"Std".X']);
    expect(r['"Std".X']!.ok).to.equal(false);
    if (!r['"Std".X']!.ok) expect(r['"Std".X']!.error.code).to.equal('INVALID_ADDRESS');
  });

  it('a PUT/GET connection open across the download refuses a DB the download made optimized', async () => {
    const s7 = createClient(`s7://127.0.0.1:${server.port}?rack=0&slot=1&timeout=5000`);
    try {
      await s7.connect();
      expect(await s7.read(['DB6.DBW0:INT'])).to.deep.equal({ 'DB6.DBW0:INT': 10 });
      service.reload(
        V1.map((f) => ({ ...f, content: (f.content as string).replace("'FALSE'", "'TRUE'") })),
        server.memory,
      );
      const r = await s7.readDetailed(['DB6.DBW0:INT']);
      expect(r['DB6.DBW0:INT']!.ok).to.equal(false);
      // Over S7CommPlus the block is still there, by name, now without an address (a program change: browsed again).
      expect(await client.read(['"Std".X'])).to.deep.equal({ '"Std".X': 10 });
      expect((await client.browse()).lookup('"Std".X')!.address).to.equal(null);
    } finally {
      await s7.close();
    }
  });

  it('a reload that changes nothing keeps the times, the table and the memory; a read by name costs no check', async () => {
    await client.write({ '"Std".X': 77, '"Prog".C': 33 });
    let changes = 0;
    client.on('programChanged', () => changes++);
    const before = await client.browse();
    service.reload(V1, server.memory);
    const sent = client.stats.requestsSent;
    expect(await client.read(['"Std".X', '"Prog".C'])).to.deep.equal({ '"Std".X': 77, '"Prog".C': 33 });
    // One GetMultiVariables of the two names, each with its SymbolCrc (issue #32): no Explore of the program per read.
    expect(client.stats.requestsSent - sent).to.equal(1);
    expect(changes).to.equal(0);
    expect(await client.browse()).to.equal(before);
    // Addresses alone are not checked: the program does not move them.
    const sent2 = client.stats.requestsSent;
    await client.read(['DB6.DBW0:INT']);
    expect(client.stats.requestsSent - sent2).to.equal(1);
  });
});

describe('plcwire serve s7 loads its program again (SIGHUP, a --source file changed)', function () {
  this.timeout(60000);
  const BIN = path.resolve(__dirname, '../../bin/plcwire.js');

  it('a changed source file is a download the connected client notices; SIGHUP loads again, unchanged; a broken file keeps the program', async () => {
    const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-program-'));
    const write = (sources: SymbolSource[]) => sources.forEach((f) => fs.writeFileSync(path.join(tmp, f.name), f.content as string));
    write(V1);
    const args = [
      'serve',
      's7',
      '--profile',
      's7-1500',
      '--port',
      '0',
      '--source',
      'Prog.db',
      '--source',
      'Std.db',
      '--db',
      'Prog=5',
      '--db',
      'Std=6',
    ];
    const child = spawn(process.execPath, [BIN, ...args], { cwd: tmp, stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    child.stdout.on('data', (d: Buffer) => (out += d.toString()));
    child.stderr.on('data', (d: Buffer) => (out += d.toString()));
    const exited = once(child, 'exit');
    let client: S7PlusClient | undefined;
    try {
      await until(() => /Ctrl-C stops/.test(out), 20000, 'the simulator to start');
      const url = /(s7plus:\/\/\S+)/.exec(out)![1]!;
      client = createClient(`${url}&timeout=10000`) as S7PlusClient;
      await client.connect();
      expect(await client.read(['"Prog".A', '"Prog".C'])).to.deep.equal({ '"Prog".A': 1, '"Prog".C': 3 });
      write(V2);
      await until(
        () => /program loaded again \([^)]*Prog\.db changed[^)]*\): \d+ type objects new or changed/.test(out),
        10000,
        'the reload',
      );
      const r = await client.readDetailed(['"Prog".A', '"Prog".C']);
      expect(r['"Prog".C']).to.deep.equal({ ok: true, value: 3 });
      expect(r['"Prog".A']!.ok).to.equal(false);
      if (!r['"Prog".A']!.ok) expect(r['"Prog".A']!.error.code).to.equal('INVALID_ADDRESS');
      child.kill('SIGHUP');
      await until(() => /program loaded again \(SIGHUP\): unchanged/.test(out), 10000, 'the reload on SIGHUP');
      fs.writeFileSync(path.join(tmp, 'Prog.db'), 'DATA_BLOCK "Prog"\n   STRUCT\n      B : NoSuchType;\n');
      await until(
        () => /program not loaded again \(.*Prog\.db changed\): .*the CPU keeps its program/.test(out),
        10000,
        'the refused reload',
      );
      expect(await client.read(['"Prog".B'])).to.deep.equal({ '"Prog".B': 2 });
      expect(child.exitCode).to.equal(null);
    } finally {
      await client?.close();
      if (child.exitCode === null) child.kill('SIGTERM');
      await exited;
      fs.rmSync(tmp, { recursive: true, force: true });
    }
  });
});
