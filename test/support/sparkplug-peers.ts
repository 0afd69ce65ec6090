/**
 * The outside programs the Sparkplug B tests need, and what to do without
 * them: mosquitto (Debian's package) and the Eclipse Tahu host
 * (test/support/tahu.ts). A test skips and says why, except under
 * PLCWIRE_REQUIRE_SPARKPLUG=1 (.ci/run), where a missing one fails it.
 */
import { spawnSync } from 'node:child_process';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { skipBecause } from './skip';

/** mosquitto's path: on the PATH, or in /usr/sbin where Debian puts it (often not on a user's PATH). */
export function mosquittoPath(): string | undefined {
  for (const dir of [...(process.env.PATH ?? '').split(path.delimiter), '/usr/sbin', '/usr/local/sbin']) {
    const file = path.join(dir, 'mosquitto');
    if (dir && fs.existsSync(file)) return file;
  }
  return undefined;
}

/** Why mosquitto cannot run here, or undefined. */
export function missingMosquitto(): string | undefined {
  const bin = mosquittoPath();
  if (!bin) return 'no mosquitto on the PATH or in /usr/sbin (Debian package mosquitto)';
  const r = spawnSync(bin, ['-h'], { encoding: 'utf8', timeout: 10_000 });
  return /mosquitto version/.test(`${r.stdout}${r.stderr}`) ? undefined : `${bin} -h does not answer as mosquitto`;
}

/** True when a missing peer must fail the test rather than skip it (.ci/run sets it). */
export const sparkplugRequired = (): boolean => process.env.PLCWIRE_REQUIRE_SPARKPLUG === '1';

/**
 * In a before hook: skips the suite and says why when `missing` names a peer that is not here, or fails it
 * under PLCWIRE_REQUIRE_SPARKPLUG=1. `missing` defaults to mosquitto's check.
 */
export function requirePeers(ctx: Mocha.Context, missing: string | undefined = missingMosquitto()): void {
  if (!missing) return;
  if (sparkplugRequired()) throw new Error(`PLCWIRE_REQUIRE_SPARKPLUG=1 but ${missing}`);
  skipBecause(ctx, missing);
}
