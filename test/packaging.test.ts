/**
 * An offline mirror of the Flow Library scorecard (node-red-dev validate:
 * P01, P03–P07, N01, N02, D01 and the examples rules of NODE-RED.md), run
 * against the tarball `npm pack` produces — what users actually install.
 */
import { expect } from 'chai';
import { execFileSync } from 'node:child_process';
import { packTarball, ROOT } from './support/pack';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';

interface PackageJson {
  name: string;
  license?: string;
  repository?: { url?: string } | string;
  bugs?: unknown;
  keywords?: string[];
  engines?: { node?: string };
  dependencies?: Record<string, string>;
  files?: string[];
  main?: string;
  'node-red'?: { version?: string; nodes?: Record<string, string> };
}

/** Minimal semver range check for the forms package.json uses here: ">=a.b.c", "^a.b.c", "a.x", space-separated ANDs. */
export function admits(range: string, version: string): boolean {
  const v = version.split('.').map(Number);
  const cmp = (a: number[], b: number[]) => {
    for (let i = 0; i < 3; i++) if ((a[i] ?? 0) !== (b[i] ?? 0)) return (a[i] ?? 0) - (b[i] ?? 0);
    return 0;
  };
  return range
    .trim()
    .split(/\s+/)
    .every((part) => {
      const m = /^(>=|>|<=|<|\^|~)?(\d+)(?:\.(\d+|x))?(?:\.(\d+|x))?$/.exec(part);
      if (!m) throw new Error(`unsupported range "${part}"`);
      const b = [Number(m[2]), Number(m[3] === 'x' ? 0 : (m[3] ?? 0)), Number(m[4] === 'x' ? 0 : (m[4] ?? 0))];
      const c = cmp(v, b);
      switch (m[1]) {
        case '>=':
          return c >= 0;
        case '>':
          return c > 0;
        case '<=':
          return c <= 0;
        case '<':
          return c < 0;
        case '^':
          return c >= 0 && v[0] === b[0];
        case '~':
          return c >= 0 && v[0] === b[0] && v[1] === b[1];
        default:
          return m[3] === undefined || m[3] === 'x' ? v[0] === b[0] : c === 0;
      }
    });
}

describe('packaging: Flow Library scorecard, offline, on the packed tarball', function () {
  this.timeout(240000); // npm pack and tar of the whole package: a deadline sized for a loaded 2-core machine
  let dir: string;
  let pkgDir: string;
  let pkg: PackageJson;
  let files: string[];

  before(() => {
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-pack-'));
    const tarball = packTarball(dir);
    execFileSync('tar', ['-xzf', tarball, '-C', dir]);
    pkgDir = path.join(dir, 'package');
    pkg = JSON.parse(fs.readFileSync(path.join(pkgDir, 'package.json'), 'utf8')) as PackageJson;
    files = listFiles(pkgDir).map((f) => path.relative(pkgDir, f).split(path.sep).join('/'));
  });

  after(() => fs.rmSync(dir, { recursive: true, force: true }));

  it('P01: has a license and the LICENSE file', () => {
    expect(pkg.license).to.equal('Apache-2.0');
    expect(files).to.include('LICENSE');
    expect(fs.readFileSync(path.join(pkgDir, 'LICENSE'), 'utf8')).to.match(/Apache License\s+Version 2\.0/);
  });

  it('P03: names a repository and where to report bugs', () => {
    const url = typeof pkg.repository === 'string' ? pkg.repository : pkg.repository?.url;
    expect(url).to.match(/^git\+https:\/\/github\.com\//);
    expect(pkg.bugs).to.be.ok;
  });

  it('P04: is a scoped name', () => {
    expect(pkg.name).to.equal('@plcwire/node-red-siemens');
  });

  it('P05: has the node-red keyword', () => {
    expect(pkg.keywords).to.include('node-red');
  });

  it('P06: node-red.version admits Node-RED 4 and the latest 5.x', () => {
    const range = pkg['node-red']?.version ?? '';
    for (const v of ['4.0.0', '4.1.15', '5.0.7', '5.9.0']) expect(admits(range, v), `${range} admits ${v}`).to.equal(true);
  });

  it('P07: engines admits Node 20 and 22.9', () => {
    const range = pkg.engines?.node ?? '';
    for (const v of ['20.0.0', '22.9.0', '24.0.0']) expect(admits(range, v), `${range} admits ${v}`).to.equal(true);
  });

  it('D01: at most 6 runtime dependencies, none of them Node-RED, the test helper or a dashboard', () => {
    const deps = Object.keys(pkg.dependencies ?? {});
    expect(deps.length).to.be.at.most(6);
    for (const d of deps) expect(d).not.to.match(/^node-red$|node-red-node-test-helper|dashboard|^@node-red\//);
  });

  it('N01: every node type has the plcwire- prefix and none is taken by another package', () => {
    const types = Object.keys(pkg['node-red']?.nodes ?? {});
    expect(types).to.include.members(['plcwire-connection', 'plcwire-read', 'plcwire-write', 'plcwire-heartbeat']);
    const taken = [
      's7 endpoint',
      's7 in',
      's7 out',
      's7 control',
      's7-config',
      's7-read',
      's7-write',
      's7-trigger',
      's7-browse',
      's7-control',
    ];
    for (const t of types) {
      expect(t).to.match(/^plcwire-/);
      expect(taken).not.to.include(t);
    }
  });

  it('N02: each node is a .js file in the tarball with its .html beside it, icons and en-US/zh-CN/de locales', () => {
    const nodes = pkg['node-red']?.nodes ?? {};
    for (const [type, file] of Object.entries(nodes)) {
      expect(file, type).to.match(/\.js$/);
      expect(files, type).to.include(file.replace(/^\.\//, ''));
      const html = file.replace(/^\.\//, '').replace(/\.js$/, '.html');
      expect(files, type).to.include(html);
      const text = fs.readFileSync(path.join(pkgDir, html), 'utf8');
      expect(text).to.include(`RED.nodes.registerType('${type}'`);
      expect(text).to.match(/<script type="text\/javascript">/);
      const base = path.posix.dirname(file.replace(/^\.\//, ''));
      const name = path.posix.basename(file, '.js');
      for (const lang of ['en-US', 'zh-CN', 'de']) {
        expect(files, `${type} ${lang} messages`).to.include(`${base}/locales/${lang}/${name}.json`);
      }
      expect(
        files.some((f) => f.startsWith(`${base}/icons/`) && f.endsWith('.svg')),
        `${type} icon`,
      ).to.equal(true);
    }
  });

  it('ships the editor code the dialogs share in resources/, and each dialog loads it from the URL Node-RED serves it at', () => {
    expect(files).to.include('resources/plcwire-editor.js');
    for (const file of Object.values(pkg['node-red']?.nodes ?? {})) {
      const html = file.replace(/^\.\//, '').replace(/\.js$/, '.html');
      const text = fs.readFileSync(path.join(pkgDir, html), 'utf8');
      const sources = [...text.matchAll(/<script\b[^>]*\bsrc="([^"]+)"/g)].map((m) => m[1]!);
      expect(sources, html).to.deep.equal([`resources/${pkg.name}/plcwire-editor.js`]);
    }
    expect(fs.readFileSync(path.join(pkgDir, 'resources/plcwire-editor.js'), 'utf8')).to.match(
      /^\/\*\*[\s\S]*?\*\/\n\(function \(\) \{[\s\S]*\}\)\(\);\n$/,
    );
  });

  it('node entry files load as CommonJS and export a plain function', () => {
    for (const file of Object.values(pkg['node-red']?.nodes ?? {})) {
      const text = fs.readFileSync(path.join(pkgDir, file), 'utf8');
      expect(text, file).to.match(/module\.exports\s*=\s*(function|\(RED\)|RED\s*=>)|module\.exports\s*=\s*\w+;?\s*$/m);
    }
  });

  it('examples: each file is a JSON array, and every non-config node appears in at least one', () => {
    const examples = files.filter((f) => f.startsWith('examples/') && f.endsWith('.json'));
    expect(examples.length).to.be.at.least(4);
    const used = new Set<string>();
    for (const f of examples) {
      const flow = JSON.parse(fs.readFileSync(path.join(pkgDir, f), 'utf8')) as { type: string }[];
      expect(flow, f).to.be.an('array');
      flow.forEach((n) => used.add(n.type));
      if (!f.startsWith('examples/Dashboard 2/')) {
        expect(
          flow.filter((n) => n.type.startsWith('ui-')),
          `${f} uses no third-party nodes`,
        ).to.deep.equal([]);
      }
    }
    for (const type of Object.keys(pkg['node-red']?.nodes ?? {})) {
      if (type === 'plcwire-connection') continue;
      expect(used.has(type), `${type} appears in an example`).to.equal(true);
    }
  });

  it('every README image shows on the package page: a file in the tarball, or an https URL of a file of this repository', () => {
    const readme = fs.readFileSync(path.join(pkgDir, 'README.md'), 'utf8');
    const sources = imageSources(readme);
    expect(sources, 'images in the README').not.to.deep.equal([]);
    const url = typeof pkg.repository === 'string' ? pkg.repository : (pkg.repository?.url ?? '');
    const repo = /github\.com\/([^/]+\/[^/.]+)/.exec(url)?.[1];
    for (const src of sources) {
      if (/^[a-z][a-z0-9+.-]*:/i.test(src)) {
        expect(src, 'an absolute image URL').to.match(/^https:\/\//);
        const raw = /^https:\/\/raw\.githubusercontent\.com\/([^/]+\/[^/]+)\/[^/]+\/(.+)$/.exec(src);
        if (raw) {
          expect(raw[1], src).to.equal(repo);
          expect(fs.existsSync(path.join(ROOT, raw[2]!)), `${raw[2]} in the repository`).to.equal(true);
        }
      } else {
        expect(files, `${src} in the tarball`).to.include(path.posix.normalize(src));
      }
    }
  });

  it('ships the compiled library, the CLI and the docs, and no tests or sources', () => {
    expect(files).to.include.members(['dist/lib/index.js', 'dist/lib/index.d.ts', 'bin/plcwire.js', 'README.md']);
    // plcwire demo names it in its try: lines.
    expect(files).to.include('demo/Plant.db');
    expect(
      files.filter((f) => f.startsWith('dist/test/') || f.startsWith('test/') || (f.endsWith('.ts') && !f.endsWith('.d.ts'))),
    ).to.deep.equal([]);
  });
});

/** Markdown without fenced code blocks and inline code, where links are not links. */
function proseOf(markdown: string): string {
  return withoutFences(markdown).replace(/`[^`\n]*`/g, '');
}

/** The Markdown without its fenced code blocks (a `# comment` in a shell block is no heading). */
function withoutFences(markdown: string): string {
  return markdown.replace(/^(```|~~~)[^\n]*\n[\s\S]*?^\1[^\n]*$/gm, '');
}

/** Sources of the images a Markdown file shows: `![alt](src)` and `<img src="…">`. */
function imageSources(markdown: string): string[] {
  const prose = proseOf(markdown);
  const md = [...prose.matchAll(/!\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+"[^"]*")?\s*\)/g)].map((m) => m[1]!);
  const html = [...prose.matchAll(/<img\s[^>]*\bsrc=["']([^"']+)["']/gi)].map((m) => m[1]!);
  return [...md, ...html];
}

/** The anchors GitHub and npm give a file's headings (lower case, punctuation dropped, spaces to hyphens, repeats numbered). */
function headingAnchors(markdown: string): Set<string> {
  const anchors = new Set<string>();
  const seen = new Map<string, number>();
  // A heading's code span is part of its anchor ("From `plcwire browse` to …": #from-plcwire-browse-to-…), its backticks are not.
  for (const m of withoutFences(markdown).matchAll(/^#{1,6}\s+(.+?)\s*#*\s*$/gm)) {
    const base = m[1]!
      .toLowerCase()
      .replace(/[^\p{L}\p{N}\s_-]/gu, '')
      .trim()
      .replace(/\s/g, '-');
    const n = seen.get(base) ?? 0;
    seen.set(base, n + 1);
    anchors.add(n === 0 ? base : `${base}-${n}`);
  }
  return anchors;
}

describe('packaging: links of the README and docs/', () => {
  it('every relative link names a file of the repository, and every #anchor a heading of the file it points into', () => {
    const pages = [
      'README.md',
      ...fs
        .readdirSync(path.join(ROOT, 'docs'))
        .filter((f) => f.endsWith('.md'))
        .map((f) => `docs/${f}`),
    ];
    const broken: string[] = [];
    for (const page of pages) {
      const text = fs.readFileSync(path.join(ROOT, page), 'utf8');
      for (const m of proseOf(text).matchAll(/\]\(\s*<?([^)\s>]+)>?(?:\s+"[^"]*")?\s*\)/g)) {
        const target = m[1]!;
        if (/^[a-z][a-z0-9+.-]*:/i.test(target)) continue;
        const [file, anchor] = target.split('#') as [string, string | undefined];
        const resolved = file === '' ? page : path.posix.normalize(path.posix.join(path.posix.dirname(page), file));
        const full = path.join(ROOT, resolved);
        if (!fs.existsSync(full)) {
          broken.push(`${page}: ${target} (no ${resolved})`);
        } else if (anchor !== undefined && !headingAnchors(fs.readFileSync(full, 'utf8')).has(anchor)) {
          broken.push(`${page}: ${target} (no heading #${anchor} in ${resolved})`);
        }
      }
    }
    expect(broken).to.deep.equal([]);
  });

  it('every repository path a doc names in `code` is a file or folder of the repository (docs/*.md, README.md, lib/**/README.md)', () => {
    const docs = [
      'README.md',
      ...fs
        .readdirSync(path.join(ROOT, 'docs'))
        .filter((f) => f.endsWith('.md'))
        .map((f) => `docs/${f}`),
      ...listFiles(path.join(ROOT, 'lib'))
        .filter((f) => path.basename(f) === 'README.md')
        .map((f) => path.relative(ROOT, f).split(path.sep).join('/')),
    ];
    expect(docs).to.include.members(['docs/architecture.md', 'lib/s7plus/README.md', 'lib/s7/README.md']);
    const named = docs.flatMap((doc) => repositoryPaths(doc).map((p) => ({ doc, ...p })));
    // The reader sees what it is meant to: architecture.md alone names dozens of files.
    expect(named.filter((n) => n.doc === 'docs/architecture.md').length).to.be.greaterThan(50);
    expect(named.some((n) => n.doc === 'lib/s7/README.md' && n.resolved.startsWith('lib/s7/'))).to.equal(true);
    const missing = named
      .filter((n) => NOT_IN_A_CLONE[n.resolved] === undefined && !fs.existsSync(path.join(ROOT, n.resolved)))
      .map((n) => `${n.doc}: \`${n.text}\` (no ${n.resolved})`);
    expect([...new Set(missing)]).to.deep.equal([]);
  });
});

/** Paths the docs name that a fresh clone does not hold, each with why. */
const NOT_IN_A_CLONE: Readonly<Record<string, string>> = {
  'test/interop/.venv': 'made by npm test (test/support/install-peers.js): the awlsim peer',
  'test/interop/.venv-s7commplus': 'made by npm test (test/support/install-peers.js): the s7commplus peer',
  'docs/connections.rst': "the s7commplus project's documentation, cited as a source in docs/s7commplus.md",
  'docs/data-access.rst': "the s7commplus project's documentation, cited as a source in docs/s7commplus.md",
};

/**
 * The paths a doc names in `code` outside its code blocks, with what each resolves to: one whose first folder
 * is a top-level entry of the repository ("lib/s7/plan/", "test/support/wait.ts") from the root; in a README
 * inside lib/, one whose first folder is beside that README ("client/handshake.ts" in lib/s7plus/README.md)
 * from there. Placeholders ("lib/<protocol>/url.ts"), globs, URLs and words with a slash are not paths.
 */
function repositoryPaths(doc: string): { text: string; resolved: string }[] {
  const prose = withoutFences(fs.readFileSync(path.join(ROOT, doc), 'utf8'));
  const dir = path.posix.dirname(doc);
  const out: { text: string; resolved: string }[] = [];
  for (const m of prose.matchAll(/`([\w.-]+(?:\/[\w.-]*)+)`/g)) {
    const text = m[1]!;
    const first = text.split('/')[0]!;
    if (fs.existsSync(path.join(ROOT, first)) && first !== '.' && first !== '..') out.push({ text, resolved: text });
    else if (dir.startsWith('lib/') && fs.existsSync(path.join(ROOT, dir, first))) out.push({ text, resolved: `${dir}/${text}` });
  }
  return out;
}

function listFiles(dir: string): string[] {
  return fs.readdirSync(dir, { withFileTypes: true }).flatMap((e) => {
    const p = path.join(dir, e.name);
    return e.isDirectory() ? listFiles(p) : [p];
  });
}

describe('packaging: the Dashboard 2 example', () => {
  it("is exactly the npm start demo flow on the demo plant's ports (regenerate with node demo/flows.js)", () => {
    const { demoFlow, DEMO_URLS } = require(path.join(__dirname, '../../demo/flows.js')) as {
      demoFlow(u: unknown): unknown[];
      DEMO_URLS: unknown;
    };
    const file = path.join(__dirname, '../../examples/Dashboard 2/Plant dashboard for all three protocols.json');
    const flow = JSON.parse(fs.readFileSync(file, 'utf8')) as { type: string; path?: string }[];
    expect(flow).to.deep.equal(demoFlow(DEMO_URLS));
    for (const type of ['ui-base', 'ui-theme', 'ui-page', 'ui-group'])
      expect(
        flow.some((n) => n.type === type),
        type,
      ).to.equal(true);
    expect(flow.some((n) => n.type === 'comment' && /node-red-dashboard/.test((n as { name?: string }).name ?? ''))).to.equal(true);
  });
});
