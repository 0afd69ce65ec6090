#!/usr/bin/env node
'use strict';
// `npm run bench` runs this first: the anchors (nodes7, @st-one-io/nodes7,
// node-snap7) live in test/interop's own package; install it when they are
// missing, so the benchmark works on a fresh clone after `npm install`.
// Without network the benchmark still runs, without the anchors.
const { spawnSync } = require('node:child_process');
const path = require('node:path');

const INTEROP = path.resolve(__dirname, '../test/interop');
const ANCHORS = ['nodes7', '@st-one-io/nodes7', 'node-snap7'];

const missing = ANCHORS.filter((name) => {
  try {
    require.resolve(name, { paths: [INTEROP] });
    return false;
  } catch {
    return true;
  }
});

if (missing.length > 0) {
  console.log(`Installing the benchmark's anchors into test/interop (missing: ${missing.join(', ')}); snap7 is built from source.`);
  // Under `npm run`, npm_execpath is npm's own CLI: use it with this Node.
  const npm = process.env.npm_execpath;
  const r = npm
    ? spawnSync(process.execPath, [npm, 'ci', '--no-audit', '--no-fund'], { cwd: INTEROP, stdio: 'inherit' })
    : spawnSync('npm', ['ci', '--no-audit', '--no-fund'], { cwd: INTEROP, stdio: 'inherit', shell: process.platform === 'win32' });
  if (r.status !== 0) {
    console.warn(`Could not install them (npm ci exited ${r.status ?? r.signal}); the benchmark runs without the anchors.`);
  }
}
