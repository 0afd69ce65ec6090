/**
 * The shape of lib/, read from its sources: the import graph has no cycle,
 * the layers point one way, no file is over 400 lines unless named with a
 * reason, and nothing exported is left unused (knip, with the exceptions
 * knip.jsonc names and explains).
 */
import { expect } from 'chai';
import { spawnSync } from 'node:child_process';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';

const ROOT = path.resolve(__dirname, '../..');
const LIB = path.join(ROOT, 'lib');

interface Edge {
  /** The specifier as written. */
  spec: string;
  /** Resolved .ts file (relative to the repository root) for a relative specifier, else undefined. */
  to: string | undefined;
  /** `import type` / `export type`: erased at compile time. */
  typeOnly: boolean;
}

function tsFiles(dir: string): string[] {
  return fs.readdirSync(dir, { withFileTypes: true }).flatMap((e) => {
    const full = path.join(dir, e.name);
    if (e.isDirectory()) return tsFiles(full);
    return e.name.endsWith('.ts') && !e.name.endsWith('.d.ts') ? [full] : [];
  });
}

// `import … from '…'`, `export … from '…'` (also over several lines), `import '…'`, `import('…')`, `require('…')`.
const IMPORT =
  /^\s*(?:import|export)\s+(type\s+)?[^'";]*?\bfrom\s*['"]([^'"]+)['"]|^\s*import\s*['"]([^'"]+)['"]|\bimport\(\s*['"]([^'"]+)['"]\s*\)|\brequire\(\s*['"]([^'"]+)['"]\s*\)/gm;

function edgesOf(file: string): Edge[] {
  const source = fs.readFileSync(file, 'utf8');
  const edges: Edge[] = [];
  for (const m of source.matchAll(IMPORT)) {
    const spec = (m[2] ?? m[3] ?? m[4] ?? m[5])!;
    let to: string | undefined;
    if (spec.startsWith('.')) {
      const base = path.resolve(path.dirname(file), spec);
      const found = [`${base}.ts`, path.join(base, 'index.ts')].find((f) => fs.existsSync(f));
      to = path
        .relative(ROOT, found ?? base)
        .split(path.sep)
        .join('/');
    }
    edges.push({ spec, to, typeOnly: m[1] !== undefined });
  }
  return edges;
}

const GRAPH = new Map<string, Edge[]>(tsFiles(LIB).map((f) => [path.relative(ROOT, f).split(path.sep).join('/'), edgesOf(f)]));

/** Every cycle closed by a back edge of a depth-first walk (none means the graph is acyclic). */
function cycles(graph: Map<string, Edge[]>): string[][] {
  const state = new Map<string, 'open' | 'done'>();
  const stack: string[] = [];
  const found: string[][] = [];
  const visit = (file: string): void => {
    state.set(file, 'open');
    stack.push(file);
    for (const { to } of graph.get(file) ?? []) {
      if (to === undefined || !graph.has(to)) continue;
      if (state.get(to) === 'open') found.push([...stack.slice(stack.indexOf(to)), to]);
      else if (!state.has(to)) visit(to);
    }
    stack.pop();
    state.set(file, 'done');
  };
  for (const file of [...graph.keys()].sort()) if (!state.has(file)) visit(file);
  return found;
}

function violations(filter: (file: string) => boolean, forbidden: (edge: Edge) => boolean): string[] {
  const out: string[] = [];
  for (const [file, edges] of GRAPH) {
    if (!filter(file)) continue;
    for (const e of edges) if (forbidden(e)) out.push(`${file} imports ${e.spec}`);
  }
  return out;
}

/** Longest a file in lib/ may be: past it, a file does several jobs and is split by job (issue #24). */
const MAX_LINES = 400;

/**
 * Files allowed past MAX_LINES, each with its reason. A pure table may stay
 * long; a file another piece of work is reshaping stays until that lands.
 */
const LONG_FILES: Readonly<Record<string, string>> = {
  'lib/s7plus/constants.ts':
    'the one table of every S7CommPlus id, opcode, function code and attribute number with its source, which issue #25 asks for in one place',
};

/** Lines of a file as `wc -l` counts them (a last line without a newline counts too). */
function lineCount(file: string): number {
  const text = fs.readFileSync(file, 'utf8');
  if (text === '') return 0;
  return text.split('\n').length - (text.endsWith('\n') ? 1 : 0);
}

/** Files over `max` lines that `allowed` does not name, as `file: n lines`. */
function overLong(lines: ReadonlyMap<string, number>, allowed: Readonly<Record<string, string>>, max: number): string[] {
  return [...lines]
    .filter(([file, n]) => n > max && allowed[file] === undefined)
    .map(([file, n]) => `${file}: ${n} lines`)
    .sort();
}

const LINES = new Map<string, number>([...GRAPH.keys()].map((f) => [f, lineCount(path.join(ROOT, f))]));

/**
 * ISO-on-TCP (lib/iso/) is a codec folder: TPKT and COTP, pure. Files that open sockets or run timers
 * for the ISO connect step are named here and left out of the purity check (they are not codecs): the
 * connect step (TCP, then COTP CR → CC) and the handshake's frame waiter.
 */
const ISO_IMPURE: readonly string[] = ['lib/iso/connect.ts', 'lib/iso/frames.ts'];

/** The protocol folders, and ISO-on-TCP below the two that speak it (s7, s7plus). */
const PROTOCOL_FOLDER = /^lib\/(s7|s7plus|fetchwrite|freeport|iso)\//;

/** Every file from which one of `targets` is reached by imports (type imports included), the targets too. */
function reaching(graph: Map<string, Edge[]>, targets: readonly string[]): Set<string> {
  const found = new Set(targets);
  for (let grown = true; grown;) {
    grown = false;
    for (const [file, edges] of graph) {
      if (!found.has(file) && edges.some((e) => e.to !== undefined && found.has(e.to))) {
        found.add(file);
        grown = true;
      }
    }
  }
  return found;
}

const isCodec = (file: string) =>
  file.startsWith('lib/s7/codec/') ||
  file.startsWith('lib/s7plus/codec/') ||
  (file.startsWith('lib/iso/') && !ISO_IMPURE.includes(file)) ||
  /^lib\/[^/]+\/codec\.ts$/.test(file);

describe('architecture of lib/', () => {
  it('the import reader finds the imports it is meant to check', () => {
    // Guards the checks below against a reader that silently sees nothing.
    const main = GRAPH.get('lib/cli/main.ts')!.map((e) => e.to ?? e.spec);
    expect(main).to.include.members(['lib/cli/io.ts', 'lib/cli/args.ts', 'lib/cli/demo.ts', 'lib/connect.ts']);
    const server = GRAPH.get('lib/s7/server/server.ts')!;
    expect(server.find((e) => e.to === 'lib/s7/server/profiles.ts' && !e.typeOnly)).to.not.equal(undefined);
    expect(GRAPH.get('lib/iso/tpkt.ts')!.find((e) => e.to === 'lib/link/framer.ts')?.typeOnly).to.equal(true);
    expect(GRAPH.size).to.be.greaterThan(50);
  });

  it('has no import cycle, type-only imports included', () => {
    expect(cycles(GRAPH).map((c) => c.join(' -> '))).to.deep.equal([]);
  });

  it('a cycle is found when there is one', () => {
    const edge = (to: string): Edge => ({ spec: to, to, typeOnly: false });
    const graph = new Map([
      ['a', [edge('b')]],
      ['b', [edge('c')]],
      ['c', [edge('a')]],
    ]);
    expect(cycles(graph)).to.deep.equal([['a', 'b', 'c', 'a']]);
  });

  it('only the CLI imports the CLI', () => {
    expect(
      violations(
        (f) => !f.startsWith('lib/cli/'),
        (e) => e.to?.startsWith('lib/cli/') === true,
      ),
    ).to.deep.equal([]);
  });

  it('no module imports the CLI entry (main.ts): the commands share lib/cli/io.ts', () => {
    expect(
      violations(
        () => true,
        (e) => e.to === 'lib/cli/main.ts',
      ),
    ).to.deep.equal([]);
  });

  it('lib imports nothing from outside lib (nodes, test, bench, dist)', () => {
    expect(
      violations(
        () => true,
        (e) => e.to !== undefined && !e.to.startsWith('lib/'),
      ),
    ).to.deep.equal([]);
  });

  it('the codecs are pure: no Node or npm module, no run-time import of link/ (only its FrameCheck contract as a type)', () => {
    const codecs = [...GRAPH.keys()].filter(isCodec);
    expect(codecs).to.include.members(['lib/s7/codec/pdu.ts', 'lib/fetchwrite/codec.ts', 'lib/freeport/codec.ts']);
    // The S7 payload codecs (SZL, blocks, diagnostic buffer) are codecs too, and checked as such.
    expect(codecs).to.include.members(['lib/s7/codec/szl.ts', 'lib/s7/codec/blocks.ts', 'lib/s7/codec/diagnostics.ts']);
    // TPKT and COTP, shared by every driver over ISO-on-TCP, are codecs too.
    expect(codecs).to.include.members(['lib/iso/tpkt.ts', 'lib/iso/cotp.ts', 'lib/iso/constants.ts']);
    // The S7CommPlus codec (VLQ, PValues, objects, messages) too.
    expect(codecs).to.include.members(['lib/s7plus/codec/vlq.ts', 'lib/s7plus/codec/pvalue.ts', 'lib/s7plus/codec/frame.ts']);
    const bad = violations(
      isCodec,
      (e) => (e.to === undefined && e.spec !== 'node:buffer') || (e.to?.startsWith('lib/link/') === true && !e.typeOnly),
    );
    expect(bad).to.deep.equal([]);
  });

  it('the planners are pure too: no Node or npm module, nothing of link/ at run time', () => {
    const isPlanner = (file: string) => file.startsWith('lib/s7/plan/') || file === 'lib/fetchwrite/plan.ts';
    expect([...GRAPH.keys()].filter(isPlanner)).to.include.members(['lib/s7/plan/index.ts', 'lib/fetchwrite/plan.ts']);
    const bad = violations(isPlanner, (e) => e.to === undefined || (e.to.startsWith('lib/link/') && !e.typeOnly));
    expect(bad).to.deep.equal([]);
  });

  it('the shared link layer (lib/link/) imports nothing of a protocol, type imports included', () => {
    const protocol = (to: string) => to === 'lib/url.ts' || to === 'lib/connect.ts' || /^lib\/(s7|s7plus|fetchwrite|freeport)\//.test(to);
    const links = [...GRAPH.keys()].filter((f) => f.startsWith('lib/link/'));
    expect(links).to.include.members(['lib/link/serial.ts', 'lib/link/supervisor.ts', 'lib/link/driver.ts']);
    expect(
      violations(
        (f) => f.startsWith('lib/link/'),
        (e) => e.to !== undefined && protocol(e.to),
      ),
    ).to.deep.equal([]);
  });

  it('ISO-on-TCP (lib/iso/) imports nothing of a protocol over it (s7, s7plus, fetchwrite, freeport), type imports included', () => {
    const iso = [...GRAPH.keys()].filter((f) => f.startsWith('lib/iso/'));
    expect(iso).to.include.members(['lib/iso/tpkt.ts', 'lib/iso/cotp.ts', 'lib/iso/constants.ts']);
    // S7 reaches TPKT and COTP through lib/iso/: the rule guards a real edge.
    expect(GRAPH.get('lib/s7/codec/pdu.ts')!.some((e) => e.to === 'lib/iso/tpkt.ts')).to.equal(true);
    expect(
      violations(
        (f) => f.startsWith('lib/iso/'),
        (e) => e.to !== undefined && /^lib\/(s7|s7plus|fetchwrite|freeport)\//.test(e.to),
      ),
    ).to.deep.equal([]);
  });

  it('the link layer (lib/link/) imports nothing of the tag client (lib/client/) or of symbols (lib/symbols/), type imports included', () => {
    const clientFiles = [...GRAPH.keys()].filter((f) => f.startsWith('lib/client/'));
    expect(clientFiles).to.include.members(['lib/client/base.ts', 'lib/client/lists.ts', 'lib/client/symbols.ts']);
    expect(
      violations(
        (f) => f.startsWith('lib/link/'),
        (e) => e.to !== undefined && /^lib\/(client|symbols)\//.test(e.to),
      ),
    ).to.deep.equal([]);
  });

  it('the tag client (lib/client/) imports nothing of a protocol, type imports included', () => {
    const protocol = (to: string) => to === 'lib/url.ts' || to === 'lib/connect.ts' || /^lib\/(s7|s7plus|fetchwrite|freeport)\//.test(to);
    expect(
      violations(
        (f) => f.startsWith('lib/client/'),
        (e) => e.to !== undefined && protocol(e.to),
      ),
    ).to.deep.equal([]);
  });

  it('a protocol folder imports no other protocol folder, and nothing that leads to lib/url.ts or lib/drivers.ts, type imports included', () => {
    const protocolOf = (file: string) => PROTOCOL_FOLDER.exec(file)?.[1];
    expect([...GRAPH.keys()].filter((f) => protocolOf(f) !== undefined).length).to.be.greaterThan(100);
    const registry = reaching(GRAPH, ['lib/url.ts', 'lib/drivers.ts']);
    // The registry really is reached from above: the rule guards real edges.
    expect(registry.has('lib/doctor/index.ts') && registry.has('lib/connect.ts')).to.equal(true);
    const bad: string[] = [];
    for (const [file, edges] of GRAPH) {
      const own = protocolOf(file);
      if (own === undefined) continue;
      for (const e of edges) {
        if (e.to === undefined) continue;
        const other = protocolOf(e.to);
        if (other !== undefined && other !== own && other !== 'iso') bad.push(`${file} imports ${e.spec} (another protocol)`);
        if (own === 'iso' && other !== undefined && other !== 'iso') bad.push(`${file} imports ${e.spec} (a protocol over ISO-on-TCP)`);
        if (registry.has(e.to)) bad.push(`${file} imports ${e.spec} (which leads to the registry)`);
      }
    }
    expect(bad).to.deep.equal([]);
  });

  it('the doctor (lib/doctor/) stands above the protocols: no protocol folder imports it; their steps see its walk through lib/doctor-steps.ts, which imports no protocol', () => {
    expect(GRAPH.get('lib/s7/doctor/index.ts')!.some((e) => e.to === 'lib/doctor-steps.ts')).to.equal(true);
    expect(GRAPH.get('lib/doctor/index.ts')!.some((e) => e.to === 'lib/drivers.ts')).to.equal(true);
    const bad = [
      ...violations(
        (f) => PROTOCOL_FOLDER.test(f),
        (e) => e.to?.startsWith('lib/doctor/') === true,
      ),
      ...violations(
        (f) => f === 'lib/doctor-steps.ts',
        (e) => e.to !== undefined && (PROTOCOL_FOLDER.test(e.to) || e.to === 'lib/url.ts' || e.to === 'lib/drivers.ts'),
      ),
    ];
    expect(bad).to.deep.equal([]);
  });

  it('no file of lib/s7/ imports lib/s7plus/: the S7-1200/1500 CPU serving both on one port is composed above them (lib/cpu/)', () => {
    // The composition imports both: the rule guards a real pair of folders.
    const cpu = GRAPH.get('lib/cpu/serve.ts')!.map((e) => e.to);
    expect(cpu).to.include.members(['lib/s7/server/index.ts', 'lib/s7plus/server/serve.ts']);
    expect(
      violations(
        (f) => f.startsWith('lib/s7/'),
        (e) => e.to?.startsWith('lib/s7plus/') === true,
      ),
    ).to.deep.equal([]);
  });

  it("an ABORTED error is made in lib/errors.ts only (abortError), so every abort reads the same and keeps the signal's reason", () => {
    const making = /new\s+\w*Error\(\s*'ABORTED'/;
    const makers = [...GRAPH.keys()].filter((f) => making.test(fs.readFileSync(path.join(ROOT, f), 'utf8')));
    // The pattern finds the one maker that must stay: it is not blind.
    expect(makers).to.include('lib/errors.ts');
    expect(makers.filter((f) => f !== 'lib/errors.ts')).to.deep.equal([]);
  });

  it(`no file in lib/ is over ${MAX_LINES} lines, except the ones LONG_FILES names with a reason`, () => {
    expect(overLong(LINES, LONG_FILES, MAX_LINES)).to.deep.equal([]);
  });

  it('every file LONG_FILES names exists and is still over the limit (an entry that is no longer needed goes)', () => {
    const stale = Object.keys(LONG_FILES).filter((f) => (LINES.get(f) ?? 0) <= MAX_LINES);
    expect(stale).to.deep.equal([]);
  });

  it('the line count is the one wc -l gives, and a long file is found when there is one', () => {
    const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-lines-'));
    try {
      fs.writeFileSync(path.join(dir, 'a.ts'), 'one\ntwo\n');
      fs.writeFileSync(path.join(dir, 'b.ts'), 'one\ntwo');
      fs.writeFileSync(path.join(dir, 'c.ts'), '');
      expect([lineCount(path.join(dir, 'a.ts')), lineCount(path.join(dir, 'b.ts')), lineCount(path.join(dir, 'c.ts'))]).to.deep.equal([
        2, 2, 0,
      ]);
    } finally {
      fs.rmSync(dir, { recursive: true, force: true });
    }
    const lines = new Map([
      ['lib/a.ts', 401],
      ['lib/b.ts', 400],
      ['lib/c.ts', 900],
    ]);
    expect(overLong(lines, { 'lib/c.ts': 'a table' }, 400)).to.deep.equal(['lib/a.ts: 401 lines']);
    // The reader sees the real files: the longest of lib/ has hundreds of lines.
    expect(Math.max(...LINES.values())).to.be.greaterThan(300);
  });

  it('has no unused file, export or type (knip)', function () {
    this.timeout(60_000);
    const knip = path.join(ROOT, 'node_modules/knip/bin/knip.js'); // a dev dependency; its exports map hides bin/
    const run = spawnSync(process.execPath, [knip, '--no-progress', '--no-config-hints'], { cwd: ROOT, encoding: 'utf8', timeout: 55_000 });
    expect(run.error, String(run.error)).to.equal(undefined);
    expect(`${run.stdout}${run.stderr}`.trim(), 'knip found unused code (see knip.jsonc for the exceptions)').to.equal('');
    expect(run.status).to.equal(0);
  });
});
