/**
 * The one place tests get a real headless browser: Chromium driven by
 * playwright-core.
 *
 * Which Chromium:
 *   - PLCWIRE_CHROMIUM=<path>: that executable;
 *   - else a system Chromium at /usr/bin/chromium (Debian's package), if there is one;
 *   - else the Chromium inside the @sparticuz/chromium dev dependency: a
 *     brotli-compressed headless build that npm installs like any package and
 *     that is unpacked once per version into the temp directory.
 * PLCWIRE_BROWSER=npm forces the packaged one, PLCWIRE_BROWSER=system forbids it.
 *
 * Either way the browser only talks to 127.0.0.1: the flags below turn off its
 * background traffic (update checks, safe browsing, sync, domain-reliability
 * reports, hyperlink-auditing pings).
 */
import { execFile } from 'node:child_process';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { pathToFileURL } from 'node:url';
import { promisify } from 'node:util';
import type { Browser } from 'playwright-core';

const SYSTEM_CHROMIUM = '/usr/bin/chromium';

const ARGS = [
  '--no-sandbox', // tests run as root on CI
  '--disable-gpu',
  '--disable-background-networking',
  '--disable-component-update',
  '--disable-domain-reliability',
  '--disable-sync',
  '--disable-quic',
  '--no-pings',
  '--no-first-run',
];

export interface ChromiumExecutable {
  /** Where it came from, for messages: "PLCWIRE_CHROMIUM", "system" or "@sparticuz/chromium 143.0.4". */
  source: string;
  path: string;
}

/** Picks the Chromium to run (see the file comment), unpacking the packaged one if that is the choice. */
export async function chromiumExecutable(): Promise<ChromiumExecutable> {
  const want = process.env.PLCWIRE_BROWSER ?? 'auto';
  if (!['auto', 'system', 'npm'].includes(want)) throw new Error(`PLCWIRE_BROWSER=${want}: expected auto, system or npm`);
  if (want !== 'npm') {
    const configured = process.env.PLCWIRE_CHROMIUM;
    if (configured) {
      if (!fs.existsSync(configured)) throw new Error(`PLCWIRE_CHROMIUM=${configured}: no such file`);
      return { source: 'PLCWIRE_CHROMIUM', path: configured };
    }
    if (fs.existsSync(SYSTEM_CHROMIUM)) return { source: 'system', path: SYSTEM_CHROMIUM };
    if (want === 'system') throw new Error(`PLCWIRE_BROWSER=system but ${SYSTEM_CHROMIUM} does not exist and PLCWIRE_CHROMIUM is not set`);
  }
  return packagedChromium();
}

/**
 * Unpacks @sparticuz/chromium into `<tmp>/plcwire-sparticuz-chromium-<version>-uid<uid>`
 * and returns its executable. The package unpacks into whatever TMPDIR says,
 * so it runs in a child process pointed at a fresh staging directory, which is
 * then renamed into place: a half-written or another version's binary is never
 * picked up, and two test runs at once do not unpack into each other.
 */
async function packagedChromium(): Promise<ChromiumExecutable> {
  let entry: string;
  try {
    entry = require.resolve('@sparticuz/chromium');
  } catch (err) {
    throw new Error(`no system Chromium and @sparticuz/chromium is not installed (npm install): ${(err as Error).message}`, { cause: err });
  }
  // The entry point's depth differs between versions (build/index.js, build/cjs/index.cjs): its package.json is the nearest one naming it.
  let root = path.dirname(entry);
  const named = (dir: string) =>
    fs.existsSync(path.join(dir, 'package.json')) &&
    (JSON.parse(fs.readFileSync(path.join(dir, 'package.json'), 'utf8')) as { name?: string }).name === '@sparticuz/chromium';
  while (!named(root)) {
    if (path.dirname(root) === root) throw new Error(`@sparticuz/chromium: no package.json above ${entry}`);
    root = path.dirname(root);
  }
  const pkg = JSON.parse(fs.readFileSync(path.join(root, 'package.json'), 'utf8')) as { version: string };
  const source = `@sparticuz/chromium ${pkg.version}`;
  // Per user: the unpacked binary is executable by its owner only.
  const dir = path.join(os.tmpdir(), `plcwire-sparticuz-chromium-${pkg.version}-uid${process.getuid?.() ?? 0}`);
  const executable = path.join(dir, 'chromium');
  if (fs.existsSync(executable)) return { source, path: executable };

  const staging = fs.mkdtempSync(`${dir}.partial-`);
  try {
    const script = `const { default: c } = await import(${JSON.stringify(pathToFileURL(entry).href)}); process.stdout.write(await c.executablePath());`;
    const { stdout } = await promisify(execFile)(process.execPath, ['--input-type=module', '-e', script], {
      env: { ...process.env, TMPDIR: staging },
      timeout: 120_000,
    });
    if (stdout !== path.join(staging, 'chromium')) throw new Error(`${source} unpacked to ${stdout}, expected ${staging}/chromium`);
    try {
      fs.renameSync(staging, dir);
    } catch (err) {
      // Another run got there first: use its copy.
      if (!fs.existsSync(executable)) throw err;
    }
  } finally {
    fs.rmSync(staging, { recursive: true, force: true });
  }
  return { source, path: executable };
}

/** Launches headless Chromium (see the file comment for which one). */
export async function launchChromium(): Promise<Browser> {
  const { chromium } = await import('playwright-core');
  const exe = await chromiumExecutable();
  try {
    return await chromium.launch({ executablePath: exe.path, headless: true, args: ARGS });
  } catch (err) {
    const message = (err as Error).message;
    const hint = /error while loading shared libraries/.test(message)
      ? ' (the packaged Chromium uses the system libnss3, libnspr4 and libexpat1: apt-get install libnss3)'
      : '';
    throw new Error(`Chromium (${exe.source}, ${exe.path}) did not start${hint}: ${message}`, { cause: err });
  }
}
