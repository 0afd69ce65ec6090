import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import { once } from 'node:events';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { PassThrough } from 'node:stream';
import { parseAddress } from '../lib/address';
import { EXIT } from '../lib/cli/io';
import { main } from '../lib/cli/main';
import { toJson } from '../lib/cli/values';
import { S7Server, type S7Profile } from '../lib/s7/server';
import { compileSymbols } from '../lib/symbols/compile';
import type { DataTypeName } from '../lib/types';
import { encodeInto, JS_TYPES } from '../lib/values';
import { CPU315 } from './fixtures/s7-userdata';
import { freePort } from './support/net';
import { until, waitFor } from './support/wait';

const BIN = path.resolve(__dirname, '../../bin/plcwire.js');

/** Runs the CLI in-process with captured output. */
async function cli(args: string[], stdinIsTty = false): Promise<{ code: number; out: string; err: string }> {
  const stdout = new PassThrough();
  const stderr = new PassThrough();
  const stdin = Object.assign(new PassThrough(), { isTTY: stdinIsTty });
  let out = '';
  let err = '';
  stdout.on('data', (d: Buffer) => (out += d.toString()));
  stderr.on('data', (d: Buffer) => (err += d.toString()));
  const code = await main(args, { stdout, stderr, stdin, signal: new AbortController().signal });
  return { code, out, err };
}

/** Runs the real bin in a child process; collects output until it exits. */
function run(args: string[]): { child: ChildProcess; output: () => { out: string; err: string }; exit: Promise<number> } {
  const child = spawn(process.execPath, [BIN, ...args], { stdio: ['pipe', 'pipe', 'pipe'] });
  let out = '';
  let err = '';
  child.stdout!.on('data', (d: Buffer) => (out += d.toString()));
  child.stderr!.on('data', (d: Buffer) => (err += d.toString()));
  const exit = once(child, 'exit').then(([code]) => code as number);
  return { child, output: () => ({ out, err }), exit };
}

/** `promise`, or a rejection naming `what` once `deadline` (ms since the epoch) has passed. */
async function beforeDeadline<T>(promise: Promise<T>, deadline: number, what: string): Promise<T> {
  let timer: NodeJS.Timeout | undefined;
  const late = new Promise<never>((_, reject) => {
    timer = setTimeout(() => reject(new Error(`${what}: not done before the test's deadline`)), Math.max(0, deadline - Date.now()));
  });
  try {
    return await Promise.race([promise, late]);
  } finally {
    clearTimeout(timer);
  }
}

/**
 * A JSON parser that keeps every integer exact: an integer literal becomes a
 * bigint, any other number a number. JSON.parse would round 18446744073709551615.
 */
function parseExactJson(text: string): unknown {
  let i = 0;
  const fail = (what: string): never => {
    throw new SyntaxError(`${what} at ${i} in ${JSON.stringify(text.slice(0, 200))}`);
  };
  const space = () => {
    while (/\s/.test(text[i] ?? '')) i++;
  };
  const value = (): unknown => {
    space();
    const c = text[i];
    if (c === '{') {
      i++;
      const out: Record<string, unknown> = {};
      space();
      if (text[i] === '}') return (i++, out);
      for (;;) {
        space();
        const key = value();
        if (typeof key !== 'string') fail('object key');
        space();
        if (text[i++] !== ':') fail('expected ":"');
        out[key as string] = value();
        space();
        const next = text[i++];
        if (next === '}') return out;
        if (next !== ',') fail('expected "," or "}"');
      }
    }
    if (c === '[') {
      i++;
      const out: unknown[] = [];
      space();
      if (text[i] === ']') return (i++, out);
      for (;;) {
        out.push(value());
        space();
        const next = text[i++];
        if (next === ']') return out;
        if (next !== ',') fail('expected "," or "]"');
      }
    }
    if (c === '"') {
      // JSON strings exclude the control characters U+0000..U+001F (RFC 8259, section 7).
      // eslint-disable-next-line no-control-regex
      const m = /^"(?:[^"\\\u0000-\u001f]|\\["\\/bfnrt]|\\u[0-9a-fA-F]{4})*"/.exec(text.slice(i));
      if (!m) fail('bad string');
      i += m![0].length;
      return JSON.parse(m![0]) as string;
    }
    const m = /^-?(?:0|[1-9]\d*)(\.\d+)?([eE][-+]?\d+)?/.exec(text.slice(i));
    if (m) {
      i += m[0].length;
      return m[1] === undefined && m[2] === undefined ? BigInt(m[0]) : Number(m[0]);
    }
    for (const [word, v] of [
      ['true', true],
      ['false', false],
      ['null', null],
    ] as const) {
      if (text.startsWith(word, i)) return ((i += word.length), v);
    }
    return fail('unexpected character');
  };
  const result = value();
  space();
  if (i !== text.length) fail('trailing text');
  return result;
}

/**
 * One tag of every type in the type table, with a value at the edge of its
 * range and what an exact JSON parser must read back (integers as bigint,
 * dates as ISO text).
 */
const EVERY_TYPE: readonly { type: DataTypeName; address: string; value: unknown; json: unknown }[] = [
  { type: 'BOOL', address: 'DB1,X0.3', value: true, json: true },
  { type: 'BYTE', address: 'DB1,BYTE1', value: 200, json: 200n },
  { type: 'WORD', address: 'DB1,WORD2', value: 0xbeef, json: 48879n },
  { type: 'DWORD', address: 'DB1,DWORD4', value: 4000000000, json: 4000000000n },
  { type: 'LWORD', address: 'DB1,LWORD8', value: 0x8000000000000001n, json: 9223372036854775809n },
  { type: 'SINT', address: 'DB1,SINT16', value: -100, json: -100n },
  { type: 'USINT', address: 'DB1,USINT17', value: 250, json: 250n },
  { type: 'INT', address: 'DB1,INT18', value: -30000, json: -30000n },
  { type: 'UINT', address: 'DB1,UINT20', value: 60000, json: 60000n },
  { type: 'DINT', address: 'DB1,DINT22', value: -2000000000, json: -2000000000n },
  { type: 'UDINT', address: 'DB1,UDINT26', value: 4000000001, json: 4000000001n },
  { type: 'LINT', address: 'DB1,LINT30', value: -1234567890123n, json: -1234567890123n },
  { type: 'LINT', address: 'DB1,LINT38', value: -(2n ** 63n), json: -9223372036854775808n },
  { type: 'ULINT', address: 'DB1,ULINT46', value: 2n ** 64n - 1n, json: 18446744073709551615n },
  { type: 'REAL', address: 'DB1,REAL54', value: 1.5, json: 1.5 },
  { type: 'LREAL', address: 'DB1,LREAL58', value: -0.1, json: -0.1 },
  { type: 'CHAR', address: 'DB1,CHAR66', value: 'A', json: 'A' },
  { type: 'WCHAR', address: 'DB1,WCHAR68', value: 'Ω', json: 'Ω' },
  { type: 'STRING', address: 'DB1,S70.12', value: 'say "hi"\\', json: 'say "hi"\\' },
  { type: 'WSTRING', address: 'DB1,WSTRING86.4', value: 'Grüß', json: 'Grüß' },
  { type: 'S5TIME', address: 'DB1,S5TIME100', value: 1230, json: 1230n },
  { type: 'TIME', address: 'DB1,TIME102', value: -86400000, json: -86400000n },
  { type: 'LTIME', address: 'DB1,LTIME106', value: 2n ** 53n + 1n, json: 9007199254740993n },
  { type: 'DATE', address: 'DB1,DATE114', value: new Date('2024-05-01T00:00:00Z'), json: '2024-05-01T00:00:00.000Z' },
  { type: 'TIME_OF_DAY', address: 'DB1,TOD116', value: 45296789, json: 45296789n },
  { type: 'DATE_AND_TIME', address: 'DB1,DT120', value: new Date('2023-12-31T23:59:58.123Z'), json: '2023-12-31T23:59:58.123Z' },
  { type: 'DTL', address: 'DB1,DTL128', value: new Date('2024-02-29T12:34:56.789Z'), json: '2024-02-29T12:34:56.789Z' },
  { type: 'COUNTER', address: 'C5', value: 999, json: 999n },
  { type: 'TIMER', address: 'T3', value: 9990000, json: 9990000n },
];

describe('plcwire CLI', function () {
  this.timeout(15000);
  let server: S7Server;
  let url: string;
  let requests: number;

  beforeEach(async () => {
    server = new S7Server({ port: 0 });
    const port = await server.listen();
    url = `s7://127.0.0.1:${port}?rack=0&slot=1`;
    requests = 0;
    server.on('request', () => requests++);
    const db1 = server.memory.area('DB', 1)!;
    db1.writeInt16BE(1234, 2);
    db1.writeFloatBE(1.5, 4);
    db1[12] = 0b0000_0100;
    db1[20] = 10; // STRING[10]'s declared max length, as the PLC program sets it
  });

  afterEach(() => server.close());

  describe('read', () => {
    it('prints one JSON object keyed by the addresses as given', async () => {
      const r = await cli(['read', url, 'DB1,INT2', 'DB1.DBD4:REAL', 'db1,x12.2', '--json']);
      expect(r.err).to.equal('');
      expect(r.code).to.equal(EXIT.OK);
      expect(JSON.parse(r.out)).to.deep.equal({ 'DB1,INT2': 1234, 'DB1.DBD4:REAL': 1.5, 'db1,x12.2': true });
    });

    it('prints "address = value" lines for people', async () => {
      const r = await cli(['read', url, 'DB1,INT2', 'DB1,S20.10']);
      expect(r.code).to.equal(EXIT.OK);
      expect(r.out).to.equal('DB1,INT2 = 1234\nDB1,S20.10 = ""\n');
    });

    it('reports a missing DB on its tag, keeps the others, and exits 1', async () => {
      const r = await cli(['read', url, 'DB1,INT2', 'DB999,INT0', '--json']);
      expect(r.code).to.equal(EXIT.TAG_ERROR);
      expect(JSON.parse(r.out)).to.deep.equal({ 'DB1,INT2': 1234, 'DB999,INT0': null });
      expect(r.err).to.match(/DB999,INT0/);
      expect(r.err.trim().split('\n')).to.have.length(1);
    });

    it('refuses a malformed address with exit 2 before connecting', async () => {
      const r = await cli(['read', url, 'DB1,INT2', 'DB0,INT2']);
      expect(r.code).to.equal(EXIT.USAGE);
      expect(r.err).to.match(/^plcwire: invalid address "DB0,INT2": .+\n$/);
      expect(requests).to.equal(0);
      expect(server.connectionCount).to.equal(0);
    });

    it('exits 3 with one line when nothing listens', async () => {
      const port = await freePort();
      const r = await cli(['read', `s7://127.0.0.1:${port}?timeout=2000`, 'DB1,INT2']);
      expect(r.code).to.equal(EXIT.CONNECTION);
      expect(r.err).to.match(/127\.0\.0\.1/);
      expect(r.err).not.to.match(/\n\s+at /);
    });

    it('exits 2 on an unknown URL parameter or option', async () => {
      expect((await cli(['read', `${url}&slto=1`, 'DB1,INT2'])).code).to.equal(EXIT.USAGE);
      expect((await cli(['read', url, 'DB1,INT2', '--jsn'])).code).to.equal(EXIT.USAGE);
    });
  });

  describe('as a new user meets it', () => {
    it('prints a REAL with the digits TIA shows (40.4, not 40.400001525878906), in text and --json; LREAL as JavaScript prints it', async () => {
      const db1 = server.memory.area('DB', 1)!;
      db1.writeFloatBE(40.4, 4);
      db1.writeFloatBE(0.1, 30);
      db1.writeFloatBE(1e-7, 34);
      db1.writeDoubleBE(0.1, 40);
      db1.writeFloatBE(40.4, 48);
      db1.writeFloatBE(-3.3, 52);
      const tags = ['DB1.DBD4:REAL', 'DB1,REAL30', 'DB1,REAL34', 'DB1.DBB40:LREAL', 'DB1,REAL48.2'];
      const text = await cli(['read', url, ...tags]);
      expect(text.code, text.err).to.equal(0);
      expect(text.out).to.equal(
        'DB1.DBD4:REAL = 40.4\nDB1,REAL30 = 0.1\nDB1,REAL34 = 1e-7\nDB1.DBB40:LREAL = 0.1\nDB1,REAL48.2 = [40.4, -3.3]\n',
      );
      const json = await cli(['read', url, ...tags, '--json']);
      expect(json.out).to.equal(
        '{"DB1.DBD4:REAL":40.4,"DB1,REAL30":0.1,"DB1,REAL34":1e-7,"DB1.DBB40:LREAL":0.1,"DB1,REAL48.2":[40.4,-3.3]}\n',
      );
      // An LREAL holding the float32 nearest 40.4 is that number, not 40.4.
      db1.writeDoubleBE(Math.fround(40.4), 40);
      expect((await cli(['read', url, 'DB1.DBB40:LREAL'])).out).to.equal('DB1.DBB40:LREAL = 40.400001525878906\n');
    });

    it('a tag name without --symbols: the address error says it looks like one, and a second line names --symbols (exit 2, nothing sent)', async () => {
      const r = await cli(['read', url, '"Plant".Level']);
      expect(r.code).to.equal(EXIT.USAGE);
      const lines = r.err.trimEnd().split('\n');
      expect(lines).to.have.length(2);
      expect(lines[0]).to.match(/^plcwire: invalid address "Plant"\.Level: not an S7 address .*; it looks like a tag name: /);
      expect(lines[0]).to.not.include('""');
      expect(lines[1]).to.equal('plcwire: give them with --symbols (and --db for TIA blocks), e.g. --symbols Plant.db --db Plant=1');
      expect(requests).to.equal(0);
      const plain = await cli(['read', url, 'Tank.Level']);
      expect(plain.err).to.match(/^plcwire: invalid address "Tank\.Level": .*looks like a tag name/);
      expect(plain.err).to.include('--symbols Tank.db --db Tank=1');
    });
  });

  describe('toJson', () => {
    it('writes bigints (in arrays too) as bare digits and everything else as JSON.stringify does', () => {
      expect(toJson({ a: [1n, -(2n ** 63n)], b: 2n ** 64n - 1n })).to.equal('{"a":[1,-9223372036854775808],"b":18446744073709551615}');
      const plain = {
        n: 1.5,
        s: 'x"\\\u0001é',
        t: true,
        z: null,
        u: undefined,
        nan: NaN,
        inf: -Infinity,
        arr: [undefined, 1, [2]],
        d: new Date(0),
        o: {},
      };
      expect(toJson(plain)).to.equal(JSON.stringify(plain));
      expect(toJson(undefined)).to.equal('null');
    });
  });

  describe('write', () => {
    it('writes values of several types and prints an acknowledgement per tag', async () => {
      const r = await cli(['write', url, 'DB1,INT2=-5', 'DB1.DBD4:REAL=2.25', 'DB1,X12.3=true', 'DB1,S20.10=hello']);
      expect(r.err).to.equal('');
      expect(r.code).to.equal(EXIT.OK);
      const db1 = server.memory.area('DB', 1)!;
      expect(db1.readInt16BE(2)).to.equal(-5);
      expect(db1.readFloatBE(4)).to.equal(2.25);
      expect(db1[12]).to.equal(0b0000_1100);
      expect(db1.subarray(20, 27).toString('latin1')).to.equal('\x0a\x05hello');
      expect(r.out.split('\n').filter(Boolean)).to.have.length(4);
    });

    it('refuses an out-of-range value with exit 2 and sends nothing', async () => {
      const r = await cli(['write', url, 'DB1,INT2=40000']);
      expect(r.code).to.equal(EXIT.USAGE);
      expect(r.err).to.match(/DB1,INT2/);
      expect(server.connectionCount).to.equal(0);
      expect(server.memory.area('DB', 1)!.readInt16BE(2)).to.equal(1234);
    });

    it('refuses to write to a remote PLC from a script without --yes (exit 4, never connects)', async () => {
      const r = await cli(['write', 's7://10.255.255.1?timeout=1000', 'DB1,INT2=1'], false);
      expect(r.code).to.equal(EXIT.REFUSED);
      expect(r.err).to.match(/--yes/);
    });

    it('refuses writes on a read-only connection (exit 4)', async () => {
      const r = await cli(['write', `${url}&readOnly=true`, 'DB1,INT2=7']);
      expect(r.code).to.equal(EXIT.REFUSED);
      expect(server.memory.area('DB', 1)!.readInt16BE(2)).to.equal(1234);
    });
  });

  describe('other protocols', () => {
    it('serve fetchwrite and serve freeport --tcp run simulators that read and write work against', async () => {
      const [fetchPort, writePort, busPort] = [await freePort(), await freePort(), await freePort()];
      const fw = run(['serve', 'fetchwrite', '--fetch-port', String(fetchPort), '--write-port', String(writePort)]);
      const fp = run(['serve', 'freeport', '--tcp', String(busPort), '--stations', '5,6']);
      try {
        await until(() => /listening/.test(fw.output().out) && /answering on tcp/.test(fp.output().out), 10000, 'both simulators up');
        const fwUrl = `fetchwrite://127.0.0.1?fetchPort=${fetchPort}&writePort=${writePort}`;
        expect((await cli(['write', fwUrl, 'DB1,INT4=-12', 'MB3=7'])).code).to.equal(EXIT.OK);
        const r1 = await cli(['read', fwUrl, 'DB1,INT4', 'MB3', '--json']);
        expect(JSON.parse(r1.out)).to.deep.equal({ 'DB1,INT4': -12, MB3: 7 });
        const fpUrl = `freeport+tcp://127.0.0.1:${busPort}`;
        const w = await cli(['write', fpUrl, 'ST6,B0.4=[230,39,161,195]']);
        expect(w.code, w.err).to.equal(EXIT.OK);
        const r2 = await cli(['read', fpUrl, 'ST6,DWORD0', 'ST5,INT0', '--json']);
        expect(r2.err).to.equal('');
        expect(JSON.parse(r2.out)).to.deep.equal({ 'ST6,DWORD0': 0xe627a1c3, 'ST5,INT0': 0 });
        const bad = await cli(['read', fpUrl, 'ST5,INT3']);
        expect(bad.code).to.equal(EXIT.USAGE);
      } finally {
        fw.child.kill('SIGINT');
        fp.child.kill('SIGINT');
      }
      expect(await fw.exit).to.equal(0);
      expect(await fp.exit).to.equal(0);
    });
  });

  describe('the installed binary', () => {
    it('demo prints try: lines that work as printed (by address; from the shipped Plant.db, by name; the optimized DB browsed and by name over s7plus://), until Ctrl-C', async function () {
      // One deadline for the whole (the demo's start and every line it prints, run one after the other),
      // not one per step: on a loaded machine (2 cores, load 4-5) a step takes what it takes.
      const WHOLE_MS = 120_000;
      this.timeout(WHOLE_MS + 10_000);
      const deadline = Date.now() + WHOLE_MS;
      const demo = run(['demo']);
      const children: ChildProcess[] = [];
      try {
        const started = waitFor(demo.child.stdout!, 'data', WHOLE_MS, () => /^Ctrl-C stops\.$/m.test(demo.output().out));
        const died = demo.exit.then((code) => Promise.reject(new Error(`the demo exited (${code}) before it printed what to try`)));
        await beforeDeadline(Promise.race([started, died]), deadline, 'the demo prints what to try');
        const lines = [...demo.output().out.matchAll(/^ {2}npx plcwire (.+)$/gm)].map((m) => m[1]!);
        expect(lines.some((l) => l.includes('"Plant".Level') && l.includes('--symbols'))).to.equal(true);
        // The S7CommPlus lines: pinned by the printed fingerprint, never insecure, no source file.
        const plus = lines.filter((l) => l.includes('s7plus://'));
        expect(plus.map((l) => l.split(' ')[0])).to.deep.equal(['browse', 'watch', 'write', 'alarms']);
        // The tank's high level on both generations (issue #33): the classic S7-300's alarms and the S7-1200's.
        expect(lines.filter((l) => l.startsWith('alarms ')).map((l) => l.split('://')[0])).to.deep.equal(['alarms "s7', 'alarms "s7plus']);
        for (const l of plus)
          expect(l)
            .to.match(/\?fingerprint=[0-9A-F]{64}"/)
            .and.not.match(/insecure|--symbols/);
        for (const line of lines) {
          // As a user pastes it into a shell; `watch` and `alarms --watch` run until Ctrl-C, so they are read once.
          const command = line.replace(/^watch /, 'read ').replace(/ --watch$/, '');
          const child = spawn('sh', ['-c', `"${process.execPath}" "${BIN}" ${command}`], { stdio: ['ignore', 'pipe', 'pipe'] });
          children.push(child);
          let out = '';
          let err = '';
          child.stdout.on('data', (d: Buffer) => (out += d.toString()));
          child.stderr.on('data', (d: Buffer) => (err += d.toString()));
          const [code] = await beforeDeadline(once(child, 'exit'), deadline, command);
          expect(code, `${command}\n${err}`).to.equal(0);
          // browse lists the PLC's names with their types; read and write show name = value.
          if (command.startsWith('browse '))
            expect(out, command)
              .to.match(/^"Tank"\.Setpoint\s+REAL\b/m)
              .and.match(/^"Tank"\.Levels\[4\]\s/m);
          // The active alarms now: the high level's line (ALARM_SQ 257, Program_Alarm 1) while it is active, else none.
          else if (command.startsWith('alarms ')) expect(out + err, command).to.match(/^(257|1) .* (coming|going) |no active alarms/m);
          else expect(out, command).to.match(/ = /);
        }
      } finally {
        for (const child of children) if (child.exitCode === null) child.kill('SIGKILL');
        demo.child.kill('SIGINT');
      }
      expect(await beforeDeadline(demo.exit, deadline + 5000, 'the demo exits on Ctrl-C')).to.equal(0);
    });

    it('serve s7 runs the simulator until Ctrl-C, and read/write talk to it', async () => {
      const port = await freePort();
      const srv = run(['serve', 's7', '--port', String(port), '--profile', 's7-1200']);
      try {
        await until(() => /listening on 127\.0\.0\.1:\d+/.test(srv.output().out), 10000, 'serve prints its address');
        const target = `s7://127.0.0.1:${port}`;
        const w = run(['write', target, 'MW10=321']);
        expect(await w.exit, w.output().err).to.equal(0);
        const r = run(['read', target, 'MW10', '--json']);
        expect(await r.exit, r.output().err).to.equal(0);
        expect(JSON.parse(r.output().out)).to.deep.equal({ MW10: 321 });
      } finally {
        srv.child.kill('SIGINT');
      }
      expect(await srv.exit).to.equal(0);
    });

    for (const [profile, tsaps] of [
      ['s7-200', 'localTsap=1000&remoteTsap=1001'],
      ['logo', 'localTsap=0100&remoteTsap=0200'],
    ] as const) {
      it(`serve s7 --profile ${profile} answers its TSAP URL with V memory and refuses rack/slot`, async () => {
        const port = await freePort();
        const srv = run(['serve', 's7', '--port', String(port), '--profile', profile]);
        try {
          await until(() => /^try: /m.test(srv.output().out), 10000, 'serve prints how to reach it');
          const target = /^try: plcwire read "([^"]+)"/m.exec(srv.output().out)![1]!;
          expect(target).to.equal(`s7://127.0.0.1:${port}?${tsaps}`);
          const w = run(['write', target, 'VW10=321', 'V3.1=true']);
          expect(await w.exit, w.output().err).to.equal(0);
          const r = run(['read', target, 'VW10', 'VB3', 'DB2,INT0', '--json']);
          expect(await r.exit).to.equal(EXIT.TAG_ERROR);
          expect(JSON.parse(r.output().out)).to.deep.equal({ VW10: 321, VB3: 2, 'DB2,INT0': null });
          expect(r.output().err).to.match(/DB2,INT0.*0x0A/);
          const slot = run(['read', `s7://127.0.0.1:${port}?rack=0&slot=1&timeout=2000`, 'VW10']);
          expect(await slot.exit).to.equal(EXIT.CONNECTION);
          // The simulator says which connection it refused and why (issue #31: never silently).
          await until(
            () => /^refused 127\.0\.0\.1:\d+ \(wrong-tsap\): .+ — frame 03/m.test(srv.output().out),
            10000,
            'serve logs the refusal',
          );
        } finally {
          srv.child.kill('SIGINT');
        }
        expect(await srv.exit).to.equal(0);
      });
    }

    it('serve s7 names the profiles when given an unknown one', async () => {
      const r = await cli(['serve', 's7', '--port', '0', '--profile', 's7-201']);
      expect(r.code).to.equal(EXIT.USAGE);
      expect(r.err).to.match(/--profile must be one of s7-300, s7-400, s7-1200, s7-1500, s7-200, logo/);
    });

    it('watch prints changes and survives the PLC going away and coming back', async () => {
      const port = server.port;
      const w = run(['watch', url, 'DB1,INT2', '--interval', '50', '--json']);
      try {
        await until(() => w.output().out.includes('1234'), 10000, 'first value');
        server.memory.area('DB', 1)!.writeInt16BE(77, 2);
        await until(() => w.output().out.includes('"DB1,INT2":77'), 5000, 'changed value');
        const memory = server.memory;
        await server.close();
        await until(() => /disconnected|reconnecting/.test(w.output().err), 5000, 'link loss reported');
        server = new S7Server({ port, memory });
        await server.listen();
        memory.area('DB', 1)!.writeInt16BE(78, 2);
        await until(() => w.output().out.includes('"DB1,INT2":78'), 10000, 'value after reconnect');
      } finally {
        w.child.kill('SIGINT');
      }
      expect(await w.exit).to.equal(EXIT.INTERRUPTED);
      const lines = w
        .output()
        .out.trim()
        .split('\n')
        .map((l) => JSON.parse(l) as { values: Record<string, number> });
      expect(lines.map((l) => l.values['DB1,INT2'])).to.deep.equal([1234, 77, 78]);
    });

    describe('--json keeps every type exact', () => {
      beforeEach(() => {
        const db1 = server.memory.area('DB', 1)!;
        db1[70] = 12; // STRING[12]'s and WSTRING[4]'s declared max lengths, as the PLC program sets them
        db1.writeUInt16BE(4, 86);
        for (const { address, value } of EVERY_TYPE) {
          const tag = parseAddress(address);
          const target = tag.area === 'DB' ? db1 : server.memory.area(tag.area)!;
          encodeInto(tag, value, target, tag.area === 'C' || tag.area === 'T' ? tag.byteOffset * 2 : tag.byteOffset);
        }
      });
      const expected = Object.fromEntries(EVERY_TYPE.map((t) => [t.address, t.json]));

      it('the table covers every type a tag can have', () => {
        expect([...new Set(EVERY_TYPE.map((t) => t.type))].sort()).to.deep.equal(Object.keys(JS_TYPES).sort());
        for (const { address, type } of EVERY_TYPE) expect(parseAddress(address).type, address).to.equal(type);
      });

      it('read --json prints 64-bit integers as bare digits, exactly, and every other type as JSON', async () => {
        const r = run(['read', url, ...EVERY_TYPE.map((t) => t.address), '--json']);
        expect(await r.exit, r.output().err).to.equal(0);
        const out = r.output().out;
        expect(out).to.include('"DB1,LINT30":-1234567890123,');
        expect(out).to.include('"DB1,ULINT46":18446744073709551615,');
        expect(out).not.to.match(/bigint|\\u0000/);
        expect(parseExactJson(out.trim())).to.deep.equal(expected);
      });

      it('watch --json prints the same exact values', async () => {
        const w = run(['watch', url, ...EVERY_TYPE.map((t) => t.address), '--interval', '50', '--json']);
        try {
          await until(() => w.output().out.includes('\n'), 10000, 'first line');
        } finally {
          w.child.kill('SIGINT');
        }
        expect(await w.exit).to.equal(EXIT.INTERRUPTED);
        const first = parseExactJson(w.output().out.split('\n')[0]!) as { time: string; values: unknown };
        expect(first.time).to.match(/^\d{4}-\d\d-\d\dT/);
        expect(first.values).to.deep.equal(expected);
      });
    });

    it('watch exits 130 on Ctrl-C (SIGINT) and on SIGTERM, as the exit-code table says', async () => {
      for (const signal of ['SIGINT', 'SIGTERM'] as const) {
        const w = run(['watch', url, 'DB1,INT2', '--interval', '50']);
        await until(() => w.output().out.includes('DB1,INT2 = 1234\n'), 10000, 'the first line');
        w.child.kill(signal);
        expect(await w.exit, `${signal}: ${w.output().err}`).to.equal(EXIT.INTERRUPTED);
      }
    });

    it("<command> --help, -h and help <command> print that command's usage, options and an example (exit 0)", async () => {
      const ways = [
        ['read', '--help'],
        ['read', '-h'],
        ['help', 'read'],
        ['read', 's7://h', '--help', '--nope'],
      ];
      const outs = await Promise.all(
        ways.map(async (args) => {
          const r = run(args);
          return { code: await r.exit, ...r.output() };
        }),
      );
      for (const o of outs) {
        expect(o.code, o.err).to.equal(0);
        expect(o.out).to.equal(outs[0]!.out);
      }
      const read = outs[0]!.out;
      expect(read).to.match(/^usage: plcwire read <url> <address\|symbol>\.\.\./);
      expect(read)
        .to.match(/^ {2}--symbols file /m)
        .and.match(/^ {2}--json /m)
        .and.match(/^example:\n {2}plcwire read "s7:\/\//m);
      expect(read, "only read's usage").to.not.match(/plcwire (write|serve|watch) /);
      for (const command of ['write', 'watch', 'symbols', 'info', 'szl', 'diag', 'clock', 'blocks', 'cpu', 'doctor', 'serve', 'demo']) {
        const r = await cli([command, '--help']);
        expect(r.code, command).to.equal(0);
        expect(r.out, command)
          .to.match(new RegExp(`^usage: plcwire ${command}\\b`))
          .and.match(/\nexamples?:\n {2}plcwire /);
      }
      const global = await cli(['--help']);
      expect(global.out)
        .to.match(/^usage:\n {2}plcwire read /)
        .and.match(/plcwire serve s7 /);
    });

    it('--version prints the version of package.json (exit 0); serve --help names --tls-cert, --tls-key and --password-file', async () => {
      const pkg = JSON.parse(fs.readFileSync(path.resolve(__dirname, '../../package.json'), 'utf8')) as { version: string };
      const v = run(['--version']);
      expect(await v.exit, v.output().err).to.equal(0);
      expect(v.output().out).to.equal(`${pkg.version}\n`);
      const serveHelp = await cli(['serve', '--help']);
      for (const option of ['--tls-cert', '--tls-key', '--password-file'])
        expect(serveHelp.out).to.match(new RegExp(`^ {2}${option} `, 'm'));
      expect((await cli(['--help'])).out).to.match(/--version/);
    });

    it('prints usage and exits 2 without a command', async () => {
      const r = run([]);
      expect(await r.exit).to.equal(2);
      expect(r.output().out).to.match(/usage:/);
    });
  });
});

describe('plcwire system commands (the installed binary against the simulator)', function () {
  this.timeout(20000);
  let server: S7Server;
  let connections: number;
  let requests: number;

  async function start(profile: S7Profile, layout?: Record<string, number>): Promise<string> {
    server = new S7Server({ port: 0, profile, ...(layout ? { layout: { dbs: layout } } : {}) });
    const port = await server.listen();
    connections = 0;
    requests = 0;
    server.on('connection', () => connections++);
    server.on('request', () => requests++);
    return `s7://127.0.0.1:${port}?rack=0&slot=${profile === 's7-300' ? 2 : 1}`;
  }

  async function plcwire(args: string[]): Promise<{ code: number; out: string; err: string }> {
    const r = run(args);
    const code = await r.exit;
    return { code, ...r.output() };
  }

  afterEach(() => server.close());

  it('info --json gives identity, the state as the library and TIA spell it (RUN, STOP) and the clock in ISO 8601', async () => {
    const url = await start('s7-1500');
    const r = await plcwire(['info', url, '--json']);
    expect(r.code, r.err).to.equal(0);
    const info = JSON.parse(r.out) as Record<string, unknown>;
    expect(info).to.include({
      orderCode: '6ES7 516-3AN02-0AB0',
      firmware: 'V3.1.0',
      moduleTypeName: 'CPU 1516-3 PN/DP',
      serialNumber: 'S V-PW0000042019',
      asName: 'PLCWIRE-SIM',
      moduleName: 'PLC_1',
      state: 'RUN',
      pduSize: 960,
    });
    expect(info.clock).to.match(/^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z$/);
    expect(Math.abs(Date.parse(info.clock as string) - Date.now())).to.be.below(10_000);
    server.stop();
    const text = await plcwire(['info', url]);
    expect(text.out)
      .to.match(/^orderCode: 6ES7 516-3AN02-0AB0$/m)
      .and.match(/^state: STOP$/m);
  });

  it('szl --json gives the records as hex and the decoded form; a list the CPU lacks exits 1, a bad ID 2', async () => {
    const url = await start('s7-300');
    let r = await plcwire(['szl', url, '0x0011', '--json']);
    expect(r.code, r.err).to.equal(0);
    const list = JSON.parse(r.out) as {
      id: string;
      index: string;
      recordLength: number;
      records: string[];
      decoded: { orderCode: string };
    };
    expect(list).to.include({ id: '0x0011', index: '0x0000', recordLength: 28 });
    expect(list.records[0]).to.match(/^0001364553372033/); // index 1, "6ES7 3…"
    expect(list.decoded.orderCode).to.equal('6ES7 315-2EH14-0AB0');
    r = await plcwire(['szl', url, '0232', '4', '--json']);
    expect((JSON.parse(r.out) as { decoded: { level: number } }).decoded.level).to.equal(1);
    r = await plcwire(['szl', url, '0x0f99', '--json']);
    expect(r.code).to.equal(EXIT.TAG_ERROR);
    expect(r.err).to.contain('SZL');
    r = await plcwire(['szl', url, 'xyz']);
    expect(r.code).to.equal(EXIT.USAGE);
  });

  it('read and write print TIME, DATE, TIME_OF_DAY, S5TIME and DATE_AND_TIME as TIA does; --json keeps the numbers (issue #31)', async () => {
    const url = await start('s7-300');
    const tags = ['DB1,TIME0', 'DB1,DATE4', 'DB1,TOD6', 'DB1,S5TIME10', 'DB1,DT12'];
    let r = await plcwire(['write', url, 'DB1,TIME0=5000', 'DB1,DATE4=2024-01-31', 'DB1,TOD6=43200000', 'DB1,S5TIME10=127000']);
    expect(r.code, r.err).to.equal(0);
    expect(r.out)
      .to.match(/^DB1,TIME0 = T#5S ok$/m)
      .and.match(/^DB1,DATE4 = D#2024-01-31 ok$/m);
    r = await plcwire(['write', url, 'DB1,DT12=2024-01-31T12:00:01.250Z']);
    expect(r.code, r.err).to.equal(0);
    r = await plcwire(['read', url, ...tags]);
    expect(r.code, r.err).to.equal(0);
    expect(r.out.trim().split('\n')).to.deep.equal([
      'DB1,TIME0 = T#5S',
      'DB1,DATE4 = D#2024-01-31',
      'DB1,TOD6 = TOD#12:00:00.000',
      'DB1,S5TIME10 = S5T#2M_7S',
      'DB1,DT12 = DT#2024-01-31-12:00:01.250',
    ]);
    r = await plcwire(['read', url, ...tags, '--json']);
    expect(JSON.parse(r.out)).to.deep.equal({
      'DB1,TIME0': 5000,
      'DB1,DATE4': '2024-01-31T00:00:00.000Z',
      'DB1,TOD6': 43_200_000,
      'DB1,S5TIME10': 127_000,
      'DB1,DT12': '2024-01-31T12:00:01.250Z',
    });
  });

  it('szl prints the count a header-only extract announces, and 0x0131 by the index its record carries (issue #31)', async () => {
    const url = await start('s7-300');
    let r = await plcwire(['szl', url, '0x0f11']);
    expect(r.code, r.err).to.equal(0);
    expect(r.out).to.match(/^SZL 0x0f11 index 0x0000: 3 record\(s\) of 28 bytes exist \(header only, none sent\)$/m);
    r = await plcwire(['szl', url, '0x0f11', '--json']);
    expect(JSON.parse(r.out)).to.deep.include({ id: '0x0f11', count: 3, records: [] });
    r = await plcwire(['szl', url, '0x0131', '1', '--json']);
    expect((JSON.parse(r.out) as { decoded: unknown }).decoded).to.deep.equal([
      { index: 1, maxPdu: 240, maxConnections: 16, mpiRate: 187_500, busRate: 10_000_000 },
    ]);
  });

  it('szl 0x0131 2 and 3: the S7-300 answers its test and commissioning and operator interface records as its CPU 315-2 PN/DP does (issue #31)', async () => {
    const url = await start('s7-300');
    let r = await plcwire(['szl', url, '0x0131', '2', '--json']);
    expect(r.code, r.err).to.equal(0);
    const two = JSON.parse(r.out) as { index: string; records: string[]; decoded: Record<string, unknown>[] };
    expect(two.index).to.equal('0x0002');
    // The CPU's own record, byte for byte (test/fixtures/s7-userdata.ts says where it comes from).
    expect(two.records).to.deep.equal([CPU315.communicationIndex2.toString('hex')]);
    expect(two.decoded[0]).to.deep.include({ index: 2, forceableVariables: 10, runtimeLimitSeconds: 0 });
    expect(two.decoded[0]!.functions).to.include.members([
      'block status',
      'variable status',
      'force selection',
      'modify variable',
      'breakpoint',
    ]);
    r = await plcwire(['szl', url, '0x0131', '3', '--json']);
    expect(r.code, r.err).to.equal(0);
    const three = JSON.parse(r.out) as { records: string[]; decoded: unknown[] };
    expect(three.records).to.deep.equal([CPU315.communicationIndex3.toString('hex')]);
    expect(three.decoded[0]).to.deep.include({
      index: 3,
      maxConsistentBytes: 240,
      maxCyclicReadJobs: 16,
      cyclicPeriodMinMs: 100,
      cyclicPeriodMaxMs: 52_100,
    });
    // The text output names the index the record carries.
    r = await plcwire(['szl', url, '0x0131', '2']);
    expect(r.code, r.err).to.equal(0);
    expect(r.out)
      .to.match(/index 0x0002/)
      .and.match(/force selection/);
    // An index that CPU does not have is refused, as before.
    r = await plcwire(['szl', url, '0x0131', '9']);
    expect(r.code).to.equal(EXIT.TAG_ERROR);
  });

  it('diag --max gives the most recent entries, newest first', async () => {
    const url = await start('s7-300');
    server.stop('programming-error');
    const r = await plcwire(['diag', url, '--max', '2', '--json']);
    expect(r.code, r.err).to.equal(0);
    const entries = JSON.parse(r.out) as { eventId: string; description: string; time: string }[];
    expect(entries).to.have.length(2);
    expect(entries[0]!.eventId).to.equal('0x4562');
    expect(entries[0]!.time).to.match(/^\d{4}-/);
    const text = await plcwire(['diag', url, '--max', '1']);
    expect(text.out.trim().split('\n')).to.have.length(1);
    expect(text.out).to.contain('0x4562');
  });

  it('clock reads; clock --set needs control=true and --yes, and then sets', async () => {
    const url = await start('s7-1500');
    let r = await plcwire(['clock', url, '--json']);
    expect(r.code, r.err).to.equal(0);
    expect(Math.abs(Date.parse((JSON.parse(r.out) as { clock: string }).clock) - Date.now())).to.be.below(10_000);
    connections = 0;
    r = await plcwire(['clock', url, '--set', '2024-05-01T12:00:00Z', '--yes']);
    expect(r.code).to.equal(EXIT.REFUSED);
    expect(r.err).to.contain('control=true');
    r = await plcwire(['clock', `${url}&control=true`, '--set', '2024-05-01T12:00:00Z']);
    expect(r.code).to.equal(EXIT.REFUSED);
    expect(r.err).to.contain('--yes');
    expect(connections, 'refused before connecting').to.equal(0);
    expect(Math.abs(server.clockOffset)).to.be.below(1000);
    r = await plcwire(['clock', `${url}&control=true`, '--set', '2024-05-01T12:00:00Z', '--yes', '--json']);
    expect(r.code, r.err).to.equal(0);
    expect((JSON.parse(r.out) as { clock: string }).clock).to.match(/^2024-05-01T12:00:0/);
    expect(server.clockOffset).to.be.below(-1e10);
    r = await plcwire(['clock', url, '--set', 'yesterday']);
    expect(r.code).to.equal(EXIT.USAGE);
  });

  it("blocks gives counts per type, the numbers of one type, one block's info; an S7-1500 has no block functions (exit 1)", async () => {
    let url = await start('s7-300', { 1: 100, 5: 20 });
    let r = await plcwire(['blocks', url, '--json']);
    expect(r.code, r.err).to.equal(0);
    expect(JSON.parse(r.out)).to.include({ DB: 2, OB: 8 });
    r = await plcwire(['blocks', url, 'db', '--json']);
    expect(JSON.parse(r.out)).to.deep.equal({ type: 'DB', numbers: [1, 5] });
    r = await plcwire(['blocks', url, 'DB', '5', '--json']);
    expect(JSON.parse(r.out)).to.include({ type: 'DB', number: 5, mc7Size: 20 });
    r = await plcwire(['blocks', url, 'DB', '6']);
    expect(r.code).to.equal(EXIT.TAG_ERROR);
    r = await plcwire(['blocks', url, 'XB']);
    expect(r.code).to.equal(EXIT.USAGE);
    await server.close();
    url = await start('s7-1500');
    r = await plcwire(['blocks', url]);
    expect(r.code).to.equal(EXIT.TAG_ERROR);
    expect(r.err).to.contain('does not offer the service');
  });

  it('cpu stop/start: exit 4 and nothing sent without control=true or without --yes; with both, the CPU changes mode', async () => {
    const url = await start('s7-300');
    let r = await plcwire(['cpu', url, 'stop', '--yes']);
    expect(r.code).to.equal(EXIT.REFUSED);
    expect(r.err).to.contain('control=true');
    r = await plcwire(['cpu', `${url}&control=true`, 'stop']);
    expect(r.code).to.equal(EXIT.REFUSED);
    expect(connections, 'nothing sent').to.equal(0);
    expect(requests).to.equal(0);
    expect(server.state).to.equal('RUN');
    r = await plcwire(['cpu', `${url}&control=true`, 'stop', '--yes', '--json']);
    expect(r.code, r.err).to.equal(0);
    expect(JSON.parse(r.out)).to.deep.equal({ state: 'STOP' });
    expect(server.state).to.equal('STOP');
    r = await plcwire(['cpu', `${url}&control=true`, 'cold-start', '--yes']);
    expect(r.out.trim()).to.equal('the CPU is in RUN');
    expect(server.diagnostics[2]!.description).to.equal('Manual cold restart requested');
    r = await plcwire(['cpu', `${url}&control=true`, 'reboot', '--yes']);
    expect(r.code).to.equal(EXIT.USAGE);
  });

  it('doctor exits 0 when every step passes, 3 at a failed connection step, 1 at a failed address, and prints { ok, steps } with --json', async () => {
    const url = await start('s7-300', { 1: 100 });
    let r = await plcwire(['doctor', url, 'DB1,INT0', '--json']);
    expect(r.code, r.err).to.equal(0);
    const report = JSON.parse(r.out) as { ok: boolean; steps: { step: string; ok: boolean; detail: string; hint?: string }[] };
    expect(report.ok).to.equal(true);
    expect(report.steps.map((s) => s.step)).to.deep.equal([
      'resolve',
      'tcp',
      'cotp',
      'setup',
      'identity',
      'protection',
      'putget',
      'address DB1,INT0',
    ]);
    r = await plcwire(['doctor', url, 'DB1,INT0', 'DB1,DINT98']);
    expect(r.code).to.equal(EXIT.TAG_ERROR);
    expect(r.out).to.match(/^FAIL address DB1,DINT98: DB1 has 100 bytes \(block info\); DB1,DINT98 needs bytes 98\.\.101$/m);
    expect(r.out).to.match(/^ {5}fix: The address lies past the end of DB1/m);
    r = await plcwire(['doctor', url.replace('slot=2', 'slot=1')]);
    expect(r.code).to.equal(EXIT.CONNECTION);
    expect(r.out).to.contain('use ?rack=0&slot=2 in the URL');
    r = await plcwire(['doctor', 's7://127.0.0.1?slot=42']);
    expect(r.code).to.equal(EXIT.USAGE);
    await until(() => server.connectionCount === 0, 2000, 'no connection left');
  });

  it('doctor resolves names through --symbols and --db as read does: the name step shows its address, an unknown name exits 1 with the closest names', async () => {
    const plantDb = path.resolve(__dirname, '../../demo/Plant.db');
    server = new S7Server({
      port: 0,
      profile: 's7-300',
      symbols: compileSymbols([{ name: 'Plant.db', content: fs.readFileSync(plantDb) }], { db: { Plant: 1 } }),
    });
    const url = `s7://127.0.0.1:${await server.listen()}?rack=0&slot=2`;
    let r = await plcwire(['doctor', url, '"Plant".Level', 'DB1,INT4', '--symbols', plantDb, '--db', 'Plant=1', '--json']);
    expect(r.code, r.out + r.err).to.equal(0);
    const report = JSON.parse(r.out) as { ok: boolean; steps: { step: string; ok: boolean; detail: string }[] };
    expect(report.ok).to.equal(true);
    expect(report.steps.slice(-2)).to.deep.equal([
      {
        step: 'symbol "Plant".Level',
        ok: true,
        detail: '"Plant".Level is DB1.DBD0:REAL; DB1 exists, 20 bytes (block info); "Plant".Level = 20',
      },
      { step: 'address DB1,INT4', ok: true, detail: 'DB1 exists, 20 bytes (block info); DB1,INT4 = 0' },
    ]);
    r = await plcwire(['doctor', url, 'Plant.Levle', '--symbols', plantDb, '--db', 'Plant=1', '--strict-symbols']);
    expect(r.code, r.out + r.err).to.equal(EXIT.TAG_ERROR);
    expect(r.out).to.match(/^FAIL symbol Plant\.Levle: unknown symbol Plant\.Levle; did you mean "Plant"\.Level\?/m);
    // Without --symbols the name's step says to give them (it used to fail as "not an S7 address").
    r = await plcwire(['doctor', url, '"Plant".Level']);
    expect(r.code).to.equal(EXIT.TAG_ERROR);
    expect(r.out).to.match(/^FAIL symbol "Plant"\.Level: .*no symbol table/m);
    expect(r.out).to.contain('--symbols FILE');
    // The flags are checked as read checks them, before anything is sent.
    r = await plcwire(['doctor', url, '"Plant".Level', '--db', 'Plant=1']);
    expect(r.code).to.equal(EXIT.USAGE);
    expect(r.err).to.contain('--db numbers the blocks of --symbols files: give --symbols too');
    await until(() => server.connectionCount === 0, 2000, 'no connection left');
  });

  it('serve s7 --max-items serves that many items per job, and the client learns it', async () => {
    server = new S7Server({ port: 0 }); // for afterEach
    const port = await freePort();
    const srv = run(['serve', 's7', '--port', String(port), '--max-items', '3']);
    try {
      await until(() => /listening on 127\.0\.0\.1:\d+, at most 3 items per job/.test(srv.output().out), 10000, 'serve prints its limit');
      const r = run(['read', `s7://127.0.0.1:${port}?slot=1`, 'MB0', 'MB2', 'MB4', 'MB6', 'MB8', '--json']);
      expect(await r.exit, r.output().err).to.equal(0);
      expect(JSON.parse(r.output().out)).to.deep.equal({ MB0: 0, MB2: 0, MB4: 0, MB6: 0, MB8: 0 });
    } finally {
      srv.child.kill('SIGINT');
    }
    expect(await srv.exit).to.equal(0);
    const bad = run(['serve', 's7', '--port', '0', '--max-items', '0']);
    expect(await bad.exit).to.equal(EXIT.USAGE);
  });
});
