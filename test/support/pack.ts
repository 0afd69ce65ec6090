import { execFileSync } from 'node:child_process';
import * as fs from 'node:fs';
import * as path from 'node:path';

export const ROOT = path.resolve(__dirname, '../../..');

/**
 * Packs the package in `dir` (this one, already built by pretest) into `into`; returns the tarball's path.
 *
 * No script of the package runs: npm 10 (Node 20's, and the one node-red
 * brings into node_modules/.bin, first on the PATH under `npm test`) runs
 * `prepare` in `npm pack` even with --ignore-scripts, which rebuilt dist/
 * under the running suite and took over a minute on a loaded machine. So the
 * script shell is one that runs nothing.
 */
export function packTarball(into: string, dir = ROOT): string {
  const noScripts = path.join(into, 'no-scripts.sh');
  fs.writeFileSync(noScripts, '#!/bin/sh\nexit 0\n', { mode: 0o755 });
  const out = execFileSync('npm', ['pack', '--ignore-scripts', `--script-shell=${noScripts}`, '--json', '--pack-destination', into], {
    cwd: dir,
    encoding: 'utf8',
    stdio: ['ignore', 'pipe', 'pipe'],
  });
  fs.rmSync(noScripts);
  const [info] = JSON.parse(out) as { filename: string }[];
  return path.join(into, info!.filename);
}
