/**
 * Apache PLC4X 0.13.1 (plc4j-driver-s7, Java), an S7 client written by others,
 * against our simulator: it connects with the driver's defaults (no
 * controller-type: it identifies the CPU with read SZL 0x0011 first), writes
 * and reads each data type it supports, and the values are checked on both
 * sides (the simulator's memory and what PLC4X prints). The peer is
 * test/interop/plc4x/Plc4xPeer.java, built by `node test/support/install-peers.js plc4x`
 * (npm test's pretest, .ci/run); without java or the built peer the suite
 * skips and says why.
 */
import { expect } from 'chai';
import { spawn, spawnSync } from 'node:child_process';
import * as path from 'node:path';
import { S7Server, type S7Profile, type S7RefusedEvent } from '../lib/s7/server';
import { skipBecause } from './support/skip';

const ROOT = path.resolve(__dirname, '../..');
const DIR = path.join(ROOT, 'test/interop/plc4x');
const { plc4xBuilt, PLC4X_VERSION } = require(path.join(ROOT, 'test/support/install-peers.js')) as {
  plc4xBuilt: () => boolean;
  PLC4X_VERSION: string;
};

interface PeerLine {
  op: 'read' | 'write' | 'cyclic' | 'event';
  tag: string;
  code: string;
  value?: string;
}

/** Why the peer cannot run here, or undefined. */
function missingPeer(): string | undefined {
  const java = spawnSync('java', ['-version'], { encoding: 'utf8', timeout: 60_000 });
  if (java.status !== 0) return `no java (${java.error?.message ?? `exit ${java.status}`})`;
  if (!plc4xBuilt())
    return `the Apache PLC4X ${PLC4X_VERSION} peer is not built: run node test/support/install-peers.js plc4x (needs javac and mvn)`;
  return undefined;
}

/** Runs the peer against `url` with `ops` (r:<tag>, w:<tag>=<value>); its lines, exit code and stderr. */
function plc4x(url: string, ops: string[], ms = 120_000): Promise<{ lines: PeerLine[]; code: number | null; err: string }> {
  return new Promise((resolve, reject) => {
    const child = spawn(
      'java',
      ['-Dorg.slf4j.simpleLogger.defaultLogLevel=warn', '-cp', `build${path.delimiter}lib/*`, 'Plc4xPeer', url, ...ops],
      {
        cwd: DIR,
      },
    );
    let out = '';
    let err = '';
    child.stdout.on('data', (d: Buffer) => (out += d.toString('utf8')));
    child.stderr.on('data', (d: Buffer) => (err += d.toString('utf8')));
    const timer = setTimeout(() => {
      child.kill('SIGKILL');
      reject(new Error(`PLC4X peer gave no answer within ${ms} ms; stderr: ${err.slice(-2000)}`));
    }, ms);
    child.on('error', (e) => {
      clearTimeout(timer);
      reject(e);
    });
    child.on('close', (code) => {
      clearTimeout(timer);
      const lines = out
        .split('\n')
        .filter((l) => l.startsWith('{'))
        .map((l) => JSON.parse(l) as PeerLine);
      resolve({ lines, code, err });
    });
  });
}

/** Days from 1990-01-01 (the S7 DATE epoch) to `iso`. */
const s7Date = (iso: string) => (Date.parse(`${iso}T00:00:00Z`) - Date.parse('1990-01-01T00:00:00Z')) / 86_400_000;

/** DB1 as the reads find it: each type at its offset, with the value PLC4X should print. */
function fill(db: Buffer): void {
  db.fill(0);
  db[0] = 0b0000_0001; // BOOL DBX0.0
  db[2] = 0xa5; // BYTE
  db.writeUInt16BE(0xbeef, 4); // WORD
  db.writeUInt32BE(0xdeadbeef, 6); // DWORD
  db.writeInt16BE(-1234, 10); // INT
  db.writeInt32BE(-123_456_789, 12); // DINT
  db.writeFloatBE(3.5, 16); // REAL
  db.write('Z', 20, 'latin1'); // CHAR
  db.writeUInt16BE(0x0041, 22); // WCHAR 'A'
  db[24] = 10; // STRING[10]: max 10, length 5
  db[25] = 5;
  db.write('hello', 26, 'latin1');
  db.writeInt32BE(5000, 36); // TIME T#5S
  db.writeUInt16BE(s7Date('2024-01-31'), 40); // DATE D#2024-01-31
  db.writeUInt32BE(43_201_250, 42); // TIME_OF_DAY TOD#12:00:01.250
  db.writeUInt16BE(0x2127, 46); // S5TIME: base 2 (1 s) × 127 = 127 s
  Buffer.from('2401311200012504', 'hex').copy(db, 48); // DATE_AND_TIME DT#2024-01-31-12:00:01.250 (a Wednesday, 4)
  db.writeDoubleBE(-2.25, 56); // LREAL
}

/** Tag, and the text PLC4X prints for it (Java's toString of the value it decodes). */
const READS: readonly (readonly [string, string])[] = [
  ['%DB1:0.0:BOOL', 'true'],
  ['%DB1:2:BYTE', '165'],
  ['%DB1:4:WORD', '48879'],
  ['%DB1:6:DWORD', '3735928559'],
  ['%DB1:10:INT', '-1234'],
  ['%DB1:12:DINT', '-123456789'],
  ['%DB1:16:REAL', '3.5'],
  ['%DB1:20:CHAR', 'Z'],
  ['%DB1:22:WCHAR', 'A'],
  ['%DB1:24:STRING(10)', 'hello'],
  ['%DB1:36:TIME', 'PT5S'],
  ['%DB1:40:DATE', '2024-01-31'],
  ['%DB1:42:TIME_OF_DAY', '12:00:01.250'],
  ['%DB1:42:TOD', '12:00:01.250'],
  ['%DB1:46:S5TIME', 'PT2M7S'],
  ['%DB1:48:DATE_AND_TIME', '2024-01-31T12:00:01.250'],
  ['%DB1:56:LREAL', '-2.25'],
];

/** Tag, the value PLC4X writes, and the bytes the simulator must then hold at the tag's offset. */
const WRITES: readonly (readonly [string, string, number, string])[] = [
  ['%DB1:100.3:BOOL', 'true', 100, '08'],
  ['%DB1:102:BYTE', '90', 102, '5a'],
  ['%DB1:104:WORD', '4660', 104, '1234'],
  ['%DB1:106:INT', '-2', 106, 'fffe'],
  ['%DB1:108:DINT', '-70000', 108, 'fffeee90'],
  ['%DB1:112:REAL', '-1.5', 112, 'bfc00000'],
  ['%DB1:116:CHAR', 'Q', 116, '51'],
  ['%DB1:118:WCHAR', 'B', 118, '0042'],
  ['%DB1:120:LREAL', '0.5', 120, '3fe0000000000000'],
];

for (const [profile, query, what] of [
  ['s7-1500', '', 'no parameters'],
  // An S7-300's CPU sits in slot 2, as on the rack: the address, not a controller type.
  ['s7-300', '?remote-slot=2', 'only the CPU slot (remote-slot=2)'],
] as const satisfies readonly (readonly [S7Profile, string, string])[]) {
  describe(`interop: Apache PLC4X ${PLC4X_VERSION} against the ${profile} simulator (${what})`, function () {
    this.timeout(300_000);
    let server: S7Server | undefined;
    const refused: S7RefusedEvent[] = [];

    before(function () {
      const missing = missingPeer();
      if (missing) skipBecause(this, missing);
    });

    beforeEach(async () => {
      server = new S7Server({ port: 0, profile });
      server.on('refused', (e: S7RefusedEvent) => refused.push(e));
      await server.listen();
      fill(server.memory.area('DB', 1)!);
    });

    afterEach(async () => {
      await server?.close();
      server = undefined;
      refused.length = 0;
    });

    it('connects with its default identification (SZL 0x0011) and reads each type it supports, values as written in the CPU', async () => {
      const r = await plc4x(
        `s7://127.0.0.1:${server!.port}${query}`,
        READS.map(([tag]) => `r:${tag}`),
      );
      expect(refused, 'no frame refused').to.deep.equal([]);
      expect(r.code, r.err.slice(-3000)).to.equal(0);
      expect(r.lines.map((l) => [l.tag, l.code, l.value])).to.deep.equal(READS.map(([tag, value]) => [tag, 'OK', value]));
    });

    it('writes each type; the simulator holds the bytes, and PLC4X reads back what it wrote', async () => {
      const db = server!.memory.area('DB', 1)!;
      const ops = [...WRITES.map(([tag, value]) => `w:${tag}=${value}`), ...WRITES.map(([tag]) => `r:${tag}`)];
      const r = await plc4x(`s7://127.0.0.1:${server!.port}${query}`, ops);
      expect(refused, 'no frame refused').to.deep.equal([]);
      expect(r.code, r.err.slice(-3000)).to.equal(0);
      const writes = r.lines.filter((l) => l.op === 'write');
      expect(writes.map((l) => [l.tag, l.code])).to.deep.equal(WRITES.map(([tag]) => [tag, 'OK']));
      for (const [tag, , offset, bytes] of WRITES) {
        expect(db.subarray(offset, offset + bytes.length / 2).toString('hex'), tag).to.equal(bytes);
      }
      const reads = r.lines.filter((l) => l.op === 'read');
      expect(reads.map((l) => [l.tag, l.code, l.value])).to.deep.equal(
        WRITES.map(([tag, value]) => [tag, 'OK', tag.endsWith('REAL') ? String(Number(value)) : value]),
      );
    });
  });
}

// Cyclic data (issue #33): PLC4X's CYC(<time base>:<factor>) subscriptions against the S7-300 simulator.
describe(`interop: Apache PLC4X ${PLC4X_VERSION} cyclic subscriptions against the s7-300 simulator`, function () {
  this.timeout(300_000);
  let server: S7Server | undefined;

  before(function () {
    const missing = missingPeer();
    if (missing) skipBecause(this, missing);
  });

  afterEach(async () => {
    await server?.close();
    server = undefined;
  });

  it('CYC(B01SEC:3) on DB1 INT: subscribed, an event every 300 ms, a change in the CPU shows in the next ones', async () => {
    server = new S7Server({ port: 0, profile: 's7-300', layout: { dataBlocks: { 1: 64 } } });
    const refused: S7RefusedEvent[] = [];
    server.on('refused', (e: S7RefusedEvent) => refused.push(e));
    await server.listen();
    const db = server.memory.area('DB', 1)!;
    db.writeInt16BE(4242, 0);
    // The value changes once the CPU pushed twice (its reads of the job's items), so events carry both.
    let pushes = 0;
    server.memory.on('read', () => {
      if (++pushes === 3) db.writeInt16BE(-77, 0);
    });
    const tag = 'CYC(B01SEC:3):%DB1.DBW0:INT';
    // PLC4X offers subscriptions only on a connection whose controller type it was told (S7_300/S7_400).
    const r = await plc4x(`s7://127.0.0.1:${server.port}?remote-slot=2&controller-type=S7_300`, [`c:3000:${tag}`]);
    expect(refused, 'no frame refused').to.deep.equal([]);
    expect(r.code, r.err.slice(-3000)).to.equal(0);
    expect(r.lines[0]).to.deep.equal({ op: 'cyclic', tag, code: 'OK' });
    const values = r.lines.filter((l) => l.op === 'event').map((l) => l.value);
    expect(values.length, values.join(',')).to.be.greaterThan(3);
    expect(values[0]).to.equal('4242');
    expect(values.at(-1)).to.equal('-77');
  });
});
