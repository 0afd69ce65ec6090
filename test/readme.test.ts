/**
 * The README as a test: a README that lies fails here.
 *
 * Shell blocks (```sh and ```console) that run without a PLC (every plcwire
 * command in them names 127.0.0.1 or no PLC at all) run as written, one block
 * at a time, from the clone's root, through `sh`. Only what a test must move is
 * moved: the README's ports become free ones, `npx plcwire` the clone's
 * bin/plcwire.js (npx adds nothing but its own start-up, which took over a
 * minute here under load), and a `fingerprint=` the one the block's simulator
 * printed, as a user copies it. What a block says is checked:
 * - a command ending in `&` runs until the block ends, then stops on Ctrl-C
 *   (the last started first) with exit 0, or the `(exit N)` shown under it; a
 *   simulator (`plcwire serve`, `plcwire demo`) is ready when it printed
 *   `Ctrl-C stops.`, any other (`plcwire sparkplug`, a broker) when it printed
 *   the lines shown under it, which it must show; `mosquitto` is the broker's
 *   binary (test/support/mosquitto.ts), and a block that starts one is skipped
 *   with the reason where it is not installed;
 * - in ```sh, the `# ` lines after a command are what it prints (stdout or
 *   stderr, each in order, `…` standing for any text, times and fingerprints
 *   as any, `#   ` with more spaces continuing the line above); a remark in
 *   parentheses after two or more spaces ends a line, `(exit N)` giving the
 *   exit code (else 0); a comment that begins with `{` or `[` is JSON that
 *   its `--json` output holds (`…` in an object or array: more members, in a
 *   string: any text); two or more spaces before `#` on a command start a remark;
 * - in ```console, `$ ` lines are commands, the other lines their output as
 *   above, and `$ echo $?` the previous command's exit code;
 * - a file a command names (--source, --symbols, --layout, a .db argument) exists.
 * Files a block makes in the root (`sed … > Optimized.db`) are removed after it.
 *
 * ```js blocks are ES modules a user saves as a .mjs file: each runs as written
 * with `@plcwire/node-red-siemens` resolving to this clone, the PLC URLs in it
 * pointing at simulators of the kind the URL names, and must exit 0 by itself
 * (nothing left open), printing nothing on stderr.
 */
import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import { once } from 'node:events';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { FetchWriteServer } from '../lib/fetchwrite/server';
import { FreeportBus } from '../lib/freeport/bus';
import { S7Server } from '../lib/s7/server';
import { PLANT_SOURCE, TANK_SOURCE } from '../lib/plant/source';
import { haveMosquitto, MOSQUITTO } from './support/mosquitto';
import { freePort } from './support/net';
import { openPtyPair, ptyUnavailable } from './support/pty';
import { startPlusSimulator } from './support/s7plus-sim';
import { skipBecause } from './support/skip';

const ROOT = path.resolve(__dirname, '../..');
const BIN = path.join(ROOT, 'bin/plcwire.js');
const README = fs.readFileSync(path.join(ROOT, 'README.md'), 'utf8');
/** One deadline for a whole block (every command in it, one after the other), not one per step. */
const BLOCK_MS = 120_000;

interface Block {
  lang: string;
  line: number;
  text: string;
}

function fencedBlocks(markdown: string): Block[] {
  const blocks: Block[] = [];
  const lines = markdown.split('\n');
  for (let i = 0; i < lines.length; i++) {
    const open = /^(\s*)```(\w*)\s*$/.exec(lines[i]!);
    if (!open) continue;
    const indent = open[1]!.length;
    const body: string[] = [];
    let j = i + 1;
    for (; j < lines.length && !/^\s*```\s*$/.test(lines[j]!); j++) body.push(lines[j]!.slice(indent));
    blocks.push({ lang: open[2]!, line: i + 1, text: body.join('\n') });
    i = j;
  }
  return blocks;
}

// ---------------------------------------------------------------------------------------------------------------
// Shell blocks

interface Step {
  command: string;
  background: boolean;
  expected: string[];
  exit: number;
}

/** Why a shell block cannot run here, or undefined when it can. */
function notRunnable(block: Block): string | undefined {
  const commands =
    block.lang === 'console'
      ? block.text.split('\n').filter((l) => l.startsWith('$ '))
      : block.text.split('\n').filter((l) => l && !l.startsWith('#'));
  if (commands.length === 0) return 'no command';
  if (commands.some((c) => /\bnpm\b/.test(c))) return 'npm';
  if (!commands.some((c) => /\bplcwire\b/.test(c))) return 'no plcwire command';
  if (commands.some((c) => /<\w|\[--|\.\.\./.test(c))) return 'a synopsis';
  if (commands.some((c) => /:\/\/(?!127\.0\.0\.1)/.test(c))) return 'a PLC beyond this machine';
  return undefined;
}

const REMARK = /\s{2,}#\s.*$/;
const ANNOTATION = /\s{2,}\(([^()]*)\)$/;

function stepsOf(block: Block): Step[] {
  const steps: Step[] = [];
  const lines = block.text.split('\n');
  for (const [k, raw] of lines.entries()) {
    if (block.lang === 'console') {
      if (raw.startsWith('$ ')) {
        const command = raw.slice(2);
        if (command === 'echo $?') continue;
        steps.push({ command: command.replace(/\s*&$/, ''), background: /&$/.test(command), expected: [], exit: 0 });
      } else if (/^\d+$/.test(raw) && lines[k - 1] === '$ echo $?') {
        steps[steps.length - 1]!.exit = Number(raw);
      } else if (raw !== '' && steps.length > 0) steps[steps.length - 1]!.expected.push(raw);
      continue;
    }
    if (raw.startsWith('#')) {
      const expected = steps[steps.length - 1]?.expected;
      if (!expected) continue;
      // `#   more` continues the line above (the README wraps long lines).
      if (/^#\s{2,}/.test(raw) && expected.length > 0) expected[expected.length - 1] += ` ${raw.slice(1).trim()}`;
      else expected.push(raw.replace(/^# ?/, ''));
    } else if (raw.trim() !== '') {
      const command = raw.replace(REMARK, '').trimEnd();
      steps.push({ command: command.replace(/\s*&$/, ''), background: /&$/.test(command), expected: [], exit: 0 });
    }
  }
  // A remark in parentheses after two or more spaces ends a line: `(exit N)`, `(on stderr)`.
  for (const step of steps) {
    step.expected = step.expected.map((line) => {
      const remark = ANNOTATION.exec(line);
      if (!remark) return line;
      const code = /\bexit (\d+)/.exec(remark[1]!);
      if (code) step.exit = Number(code[1]);
      return line.slice(0, remark.index);
    });
  }
  return steps;
}

/** Times, fingerprints and runs of spaces as any: what a run cannot reproduce. */
function normal(text: string): string {
  return text
    .replace(/\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(\.\d+)?Z/g, '<time>')
    .replace(/\b[0-9A-F]{64}\b/g, '<fingerprint>')
    .replace(/\s+/g, ' ')
    .trim();
}

function lineMatcher(expected: string): RegExp {
  const parts = normal(expected)
    .split('…')
    .map((p) => p.replace(/[.*+?^${}()|[\]\\]/g, '\\$&'));
  return new RegExp(`^${parts.join('.*')}$`);
}

/** Expected JSON from a comment: `…` as a member or element means more; in a string, any text. */
type Expected =
  | { kind: 'object'; members: [string, Expected][]; more: boolean }
  | { kind: 'array'; items: Expected[]; more: boolean }
  | { kind: 'string'; pattern: RegExp; text: string }
  | { kind: 'value'; value: unknown };

function parseExpected(text: string): Expected {
  let i = 0;
  const space = () => {
    while (/\s/.test(text[i] ?? '')) i++;
  };
  const fail = (what: string): never => {
    throw new SyntaxError(`${what} at ${i} in ${text}`);
  };
  const value = (): Expected => {
    space();
    const c = text[i];
    if (c === '{' || c === '[') {
      const close = c === '{' ? '}' : ']';
      i++;
      const members: [string, Expected][] = [];
      const items: Expected[] = [];
      let more = false;
      for (;;) {
        space();
        if (text[i] === close) {
          i++;
          break;
        }
        if (text[i] === '…') {
          i++;
          more = true;
        } else if (c === '{') {
          const key = value();
          if (key.kind !== 'string') fail('a key');
          space();
          if (text[i++] !== ':') fail('":"');
          members.push([(key as { text: string }).text, value()]);
        } else items.push(value());
        space();
        if (text[i] === ',') i++;
      }
      return c === '{' ? { kind: 'object', members, more } : { kind: 'array', items, more };
    }
    if (c === '"') {
      const m = /^"(?:[^"\\]|\\.)*"/.exec(text.slice(i)) ?? fail('a string');
      i += m[0].length;
      const s = JSON.parse(m[0]) as string;
      return { kind: 'string', text: s, pattern: lineMatcher(s) };
    }
    const m = /^(-?\d+(\.\d+)?([eE][-+]?\d+)?|true|false|null)/.exec(text.slice(i)) ?? fail('a value');
    i += m[0].length;
    return { kind: 'value', value: JSON.parse(m[0]) as unknown };
  };
  const result = value();
  space();
  if (i !== text.length) fail('trailing text');
  return result;
}

/** Where `actual` does not hold what `expected` shows, or undefined. */
function mismatch(expected: Expected, actual: unknown, at = '$'): string | undefined {
  switch (expected.kind) {
    case 'value':
      return Object.is(expected.value, actual) || expected.value === actual
        ? undefined
        : `${at}: ${JSON.stringify(actual)}, not ${JSON.stringify(expected.value)}`;
    case 'string':
      return typeof actual === 'string' && expected.pattern.test(normal(actual))
        ? undefined
        : `${at}: ${JSON.stringify(actual)}, not ${JSON.stringify(expected.text)}`;
    case 'object': {
      if (typeof actual !== 'object' || actual === null || Array.isArray(actual)) return `${at}: not an object`;
      const keys = Object.keys(actual);
      if (!expected.more && keys.length !== expected.members.length) return `${at}: keys ${keys.join(', ')}`;
      for (const [key, e] of expected.members) {
        if (!Object.hasOwn(actual, key)) return `${at}: no key ${key}`;
        const why = mismatch(e, (actual as Record<string, unknown>)[key], `${at}.${key}`);
        if (why) return why;
      }
      return undefined;
    }
    case 'array': {
      if (!Array.isArray(actual)) return `${at}: not an array`;
      if (!expected.more) {
        if (actual.length !== expected.items.length) return `${at}: ${actual.length} items, not ${expected.items.length}`;
        for (const [k, e] of expected.items.entries()) {
          const why = mismatch(e, actual[k], `${at}[${k}]`);
          if (why) return why;
        }
        return undefined;
      }
      // With `…`: the items shown, in their order, among the others.
      let k = 0;
      for (const e of expected.items) {
        while (k < actual.length && mismatch(e, actual[k]) !== undefined) k++;
        if (k === actual.length) return `${at}: no item like ${JSON.stringify(e)}`;
        k++;
      }
      return undefined;
    }
  }
}

/** Splits a step's expected lines into JSON (balanced brackets, joined) and text lines. */
function expectations(lines: string[]): { json: string[]; text: { line: string; stderr: boolean }[] } {
  const json: string[] = [];
  const text: { line: string; stderr: boolean }[] = [];
  for (let k = 0; k < lines.length; k++) {
    if (/^[[{]/.test(lines[k]!)) {
      let joined = lines[k]!;
      while (!balanced(joined) && k + 1 < lines.length) joined += lines[++k]!.trimStart();
      json.push(joined);
    } else text.push({ line: lines[k]!, stderr: false });
  }
  return { json, text };
}

function balanced(text: string): boolean {
  let depth = 0;
  let inString = false;
  for (let k = 0; k < text.length; k++) {
    const c = text[k];
    if (inString) {
      if (c === '\\') k++;
      else if (c === '"') inString = false;
    } else if (c === '"') inString = true;
    else if (c === '{' || c === '[') depth++;
    else if (c === '}' || c === ']') depth--;
  }
  return depth === 0;
}

interface Running {
  child: ChildProcess;
  out: () => string;
  err: () => string;
  exit: Promise<number>;
}

function shell(command: string, cwd: string): Running {
  // As a user without a password in the environment runs it.
  const env = { ...process.env };
  delete env.PLCWIRE_PASSWORD;
  const child = spawn('sh', ['-c', command], { cwd, stdio: ['ignore', 'pipe', 'pipe'], env });
  let out = '';
  let err = '';
  child.stdout!.on('data', (d: Buffer) => (out += d.toString()));
  child.stderr!.on('data', (d: Buffer) => (err += d.toString()));
  const exit = once(child, 'exit').then(
    ([code, signal]) => (code as number | null) ?? 128 + (os.constants.signals[signal as NodeJS.Signals] ?? 0),
  );
  return { child, out: () => out, err: () => err, exit };
}

async function beforeDeadline<T>(promise: Promise<T>, deadline: number, what: string): Promise<T> {
  let timer: NodeJS.Timeout | undefined;
  const late = new Promise<never>((_, reject) => {
    timer = setTimeout(() => reject(new Error(`${what}: not done before the block's deadline`)), Math.max(0, deadline - Date.now()));
  });
  try {
    return await Promise.race([promise, late]);
  } finally {
    clearTimeout(timer);
  }
}

/** The files a command names, which must exist (relative to the root). */
function namedFiles(command: string): string[] {
  const words = command.match(/'[^']*'|"[^"]*"|\S+/g) ?? [];
  const files: string[] = [];
  for (const [k, w] of words.entries()) {
    if (['--source', '--symbols', '--layout', '--password-file', '--tls-cert', '--tls-key'].includes(words[k - 1] ?? '')) files.push(w);
    else if (/^[\w./-]+\.(db|udt|awl|json|csv|xlsx)$/.test(w) && words[k - 1] !== '>') files.push(w);
  }
  return files.map((f) => f.replace(/^['"]|['"]$/g, ''));
}

function checkOutput(step: Step, run: { out: string; err: string }, where: string): void {
  const { json, text } = expectations(step.expected);
  for (const shown of json) {
    const expected = parseExpected(shown);
    const actual = JSON.parse(run.out) as unknown;
    const why = mismatch(expected, actual);
    expect(why, `${where}: the --json output ${run.out.trim()} does not hold ${shown}`).to.equal(undefined);
  }
  const streams = { out: run.out.split('\n').map(normal), err: run.err.split('\n').map(normal) };
  const from = { out: 0, err: 0 };
  for (const { line } of text) {
    const pattern = lineMatcher(line);
    const found = (['out', 'err'] as const).find((s) => streams[s].slice(from[s]).some((l) => pattern.test(l)));
    expect(found, `${where}: "${line}" is not in what it printed:\n${run.out}${run.err}`).to.not.equal(undefined);
    from[found!] += streams[found!].slice(from[found!]).findIndex((l) => pattern.test(l)) + 1;
  }
}

/** A simulator: ready when it printed `Ctrl-C stops.` (other background commands: when they printed their shown lines). */
const SIMULATOR = /\bplcwire (?:serve|demo)\b/;

/** Whether every line shown (already ported) is in what a background command printed so far, in order. */
function printed(expected: string[], run: Running): boolean {
  try {
    checkOutput({ command: '', background: true, expected, exit: 0 }, { out: run.out(), err: run.err() }, '');
    return true;
  } catch {
    return false;
  }
}

/** Resolves once `ready()` holds after some output of the command; cancel() removes its listeners either way. */
function untilReady(run: Running, ready: () => boolean): { done: Promise<void>; cancel: () => void } {
  let cancel = (): void => undefined;
  const done = new Promise<void>((resolve) => {
    const check = (): void => {
      if (!ready()) return;
      cancel();
      resolve();
    };
    cancel = () => {
      run.child.stdout!.off('data', check);
      run.child.stderr!.off('data', check);
    };
    run.child.stdout!.on('data', check);
    run.child.stderr!.on('data', check);
  });
  return { done, cancel };
}

async function runBlock(block: Block): Promise<void> {
  const deadline = Date.now() + BLOCK_MS;
  const ports = new Map<string, string>();
  for (const m of block.text.matchAll(/(?::|--port )(10\d{3})\b/g)) if (!ports.has(m[1]!)) ports.set(m[1]!, String(await freePort()));
  const moved = (text: string) => text.replace(/\b10\d{3}\b/g, (p) => ports.get(p) ?? p);
  const before = new Set(fs.readdirSync(ROOT));
  const background: { step: Step; run: Running }[] = [];
  const failures: string[] = [];
  let fingerprint: string | undefined;
  try {
    for (const step of stepsOf(block)) {
      const where = `README.md:${block.line}: ${step.command}`;
      let command = moved(step.command)
        .replace(/\bnpx plcwire\b/g, `"${process.execPath}" "${BIN}"`)
        .replace(/^mosquitto\b/, `"${MOSQUITTO}"`);
      if (fingerprint) command = command.replace(/fingerprint=(?:[0-9A-Fa-f:]+|…)/g, `fingerprint=${fingerprint}`);
      for (const file of namedFiles(step.command)) expect(fs.existsSync(path.join(ROOT, file)), `${where}: ${file} exists`).to.equal(true);
      const expected = step.expected.map(moved);
      // A simulator is the shell's process itself (exec), so that Ctrl-C reaches it as from a terminal.
      const run = shell(step.background ? `exec ${command}` : command, ROOT);
      if (step.background) {
        background.push({ step, run });
        const simulator = SIMULATOR.test(step.command);
        expect(
          simulator || expected.length > 0,
          `${where}: a background command that is not a simulator shows what it prints when ready`,
        ).to.equal(true);
        const ready = () => (simulator ? /^Ctrl-C stops\.$/m.test(run.out()) : printed(expected, run));
        const started = untilReady(run, ready);
        const died = run.exit.then((code) => Promise.reject(new Error(`${where}: exited (${code}) at start: ${run.err()}`)));
        try {
          await beforeDeadline(Promise.race([started.done, died]), deadline, where);
        } finally {
          started.cancel();
        }
        fingerprint = /certificate SHA-256 ([0-9A-F]{64})/.exec(run.out())?.[1] ?? fingerprint;
        checkOutput({ ...step, expected }, { out: run.out(), err: run.err() }, where);
        continue;
      }
      const code = await beforeDeadline(run.exit, deadline, where);
      expect(code, `${where}: exit code\n${run.out()}${run.err()}`).to.equal(step.exit);
      checkOutput({ ...step, expected }, { out: run.out(), err: run.err() }, where);
    }
  } finally {
    // The last started first: an edge node sends its NDEATH before the broker it is on stops.
    const stopped: { step: Step; run: Running; code: number | string }[] = [];
    for (const { step, run } of [...background].reverse()) {
      if (run.child.exitCode === null && run.child.signalCode === null) run.child.kill('SIGINT');
      const code = await beforeDeadline(run.exit, Date.now() + 10_000, `${step.command} stops on Ctrl-C`).catch((err: Error) => {
        run.child.kill('SIGKILL');
        return err.message;
      });
      stopped.push({ step, run, code });
    }
    for (const entry of fs.readdirSync(ROOT)) if (!before.has(entry)) fs.rmSync(path.join(ROOT, entry), { recursive: true, force: true });
    failures.push(
      ...stopped
        .filter((s) => s.code !== s.step.exit)
        .map((s) => `README.md:${block.line}: ${s.step.command} on Ctrl-C: ${s.code}, not ${s.step.exit}\n${s.run.err()}`),
    );
  }
  expect(failures).to.deep.equal([]);
}

describe('README.md as a test', function () {
  this.timeout(BLOCK_MS + 20_000);
  const blocks = fencedBlocks(README);
  const shellBlocks = blocks.filter((b) => b.lang === 'sh' || b.lang === 'console');

  it('runs the shell blocks that start a simulator, and every block with a plcwire command is run or has a reason not to be', () => {
    const run = shellBlocks.filter((b) => notRunnable(b) === undefined);
    expect(run.filter((b) => /plcwire serve/.test(b.text)).length).to.be.at.least(5);
    for (const b of shellBlocks.filter((x) => /plcwire serve \S+.*&$/m.test(x.text)))
      expect(notRunnable(b), `README.md:${b.line}`).to.equal(undefined);
  });

  for (const block of shellBlocks.filter((b) => notRunnable(b) === undefined)) {
    const first = stepsOf(block)[0]!.command;
    it(`README.md:${block.line}: ${first} … runs as written`, async function () {
      if (/^mosquitto\b/m.test(block.text) && !haveMosquitto())
        skipBecause(this, `a block that starts a broker: mosquitto is not at ${MOSQUITTO} (apt install mosquitto, or set MOSQUITTO)`);
      await runBlock(block);
    });
  }

  it("the command summary names every command and option of plcwire's usage", async () => {
    const summary = blocks.find((b) => b.lang === 'sh' && /^npx plcwire read {2}<url>/m.test(b.text));
    expect(summary, 'the command summary').to.not.equal(undefined);
    const usage = shell(`"${process.execPath}" "${BIN}" --help`, ROOT);
    expect(await usage.exit).to.equal(0);
    const commands = new Set([...usage.out().matchAll(/^ {2}plcwire (\w+)/gm)].map((m) => m[1]!));
    const options = new Set([...usage.out().matchAll(/--[a-z][\w-]*/g)].map((m) => m[0]));
    expect([...commands]).to.include.members(['read', 'browse', 'serve', 'demo']);
    for (const c of commands) expect(summary!.text, `plcwire ${c}`).to.match(new RegExp(`^npx plcwire ${c}\\b`, 'm'));
    for (const o of options) expect(summary!.text, o).to.include(o);
  });

  describe('library snippets (```js), as .mjs files', () => {
    const snippets = blocks.filter((b) => b.lang === 'js');
    let dir: string;

    before(() => {
      dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-readme-'));
      // As after `npm install @plcwire/node-red-siemens`: the package resolves to this clone.
      fs.mkdirSync(path.join(dir, 'node_modules/@plcwire'), { recursive: true });
      fs.symlinkSync(ROOT, path.join(dir, 'node_modules/@plcwire/node-red-siemens'));
    });

    after(() => fs.rmSync(dir, { recursive: true, force: true }));

    it('there are snippets, and each imports the package', () => {
      expect(snippets.length).to.be.at.least(8);
      for (const s of snippets) expect(s.text, `README.md:${s.line}`).to.match(/^import .* from '@plcwire\/node-red-siemens';$/m);
    });

    for (const snippet of snippets) {
      it(`README.md:${snippet.line}: ${
        snippet.text
          .split('\n')
          .find((l) => /connect\(|new \w+Server/.test(l))
          ?.trim() ?? snippet.text.split('\n')[0]
      }`, async function () {
        const closers: (() => Promise<unknown>)[] = [];
        try {
          const code = await pointedAtSimulators(snippet.text, dir, closers, this);
          const file = path.join(dir, `readme-${snippet.line}.mjs`);
          fs.writeFileSync(file, code);
          const run = shell(`"${process.execPath}" "${file}"`, ROOT);
          const exit = await beforeDeadline(run.exit, Date.now() + 60_000, `README.md:${snippet.line} exits by itself`);
          expect(exit, `README.md:${snippet.line}\n${run.err()}`).to.equal(0);
          expect(run.err(), `README.md:${snippet.line}`).to.equal('');
        } finally {
          for (const close of closers) await close();
        }
      });
    }
  });
});

/**
 * The snippet with each PLC URL pointing at a simulator of its kind: an
 * S7-1200 for rack 0, slot 1, an S7-300 for slot 2, a CP for FETCH/WRITE, a
 * freeport bus on a pseudo-terminal for a serial device, the demo CPU (DB1
 * "Plant", the optimized DB2 "Tank") for s7plus://.
 */
async function pointedAtSimulators(code: string, dir: string, closers: (() => Promise<unknown>)[], test: Mocha.Context): Promise<string> {
  let out = code;
  for (const m of code.matchAll(/'(s7|s7plus|fetchwrite|freeport):\/\/([^'?]*)(\?[^']*)?'/g)) {
    const [literal, scheme, , query = ''] = m as unknown as [string, string, string, string?];
    let url: string;
    if (scheme === 's7') {
      const server = new S7Server({ port: 0, profile: /slot=2/.test(query) ? 's7-300' : 's7-1200' });
      closers.push(() => server.close());
      url = `s7://127.0.0.1:${await server.listen()}${query}`;
    } else if (scheme === 'fetchwrite') {
      const server = new FetchWriteServer({ fetchPort: 0, writePort: 0 });
      closers.push(() => server.close());
      const ports = await server.listen();
      url = `fetchwrite://127.0.0.1?fetchPort=${ports.fetchPort}&writePort=${ports.writePort}`;
    } else if (scheme === 's7plus') {
      const sim = await startPlusSimulator({ sources: [PLANT_SOURCE, TANK_SOURCE], db: { Plant: 1, Tank: 2 } });
      closers.push(() => sim.server.close());
      url = `s7plus://127.0.0.1:${sim.server.port}?fingerprint=${sim.service.fingerprint!}`;
    } else {
      const why = ptyUnavailable();
      if (why) skipBecause(test, `a serial device for the freeport snippet (a pseudo-terminal pair): ${why}`);
      const pty = await openPtyPair(fs.mkdtempSync(path.join(dir, 'pty-')));
      const bus = new FreeportBus({ stations: { 5: Buffer.alloc(4), 6: Buffer.alloc(4) } });
      await bus.attachSerial(pty.station, { baudRate: Number(/baud=(\d+)/.exec(query)?.[1] ?? 9600) });
      closers.push(async () => {
        await bus.close();
        await pty.stop();
      });
      url = `freeport://${pty.master}${query}`;
    }
    out = out.replace(literal, `'${url}'`);
  }
  return out;
}
