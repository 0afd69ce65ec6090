#!/usr/bin/env node
'use strict';
// Installs the test-only packages that live outside the package's own
// dependencies when they are missing, so `npm install && npm test` works on a
// fresh clone (and `npm run bench` finds its anchors):
//   interop: node-snap7 (snap7 built from source), nodes7, @st-one-io/nodes7,
//            node-red-contrib-s7 (the Node-RED benchmark's incumbent)
//   nr5:     Node 22 and Node-RED 5
// Usage: node test/support/install-peers.js interop [nr5]
// Already installed: does nothing (no network). `.ci/run` installs them itself.
const { spawnSync } = require('node:child_process');
const fs = require('node:fs');
const path = require('node:path');

const ROOT = path.resolve(__dirname, '../..');
const PEERS = {
  interop: {
    dir: 'test/interop',
    has: ['node-snap7', 'nodes7', '@st-one-io/nodes7', 'node-red-contrib-s7'].map((p) => `node_modules/${p}/package.json`),
  },
  nr5: { dir: 'test/nr5', has: ['node_modules/node/bin/node', 'node_modules/node-red/package.json'] },
};

for (const name of process.argv.slice(2)) {
  const peer = PEERS[name];
  if (!peer) throw new Error(`install-peers: unknown set "${name}" (${Object.keys(PEERS).join(', ')})`);
  const cwd = path.join(ROOT, peer.dir);
  const missing = peer.has.filter((f) => !fs.existsSync(path.join(cwd, f)));
  if (missing.length === 0) continue;
  console.log(`Installing ${peer.dir} (missing: ${missing.join(', ')})`);
  // Under `npm run`, npm_execpath is npm's own CLI: run it with this Node.
  const npm = process.env.npm_execpath;
  const r = npm
    ? spawnSync(process.execPath, [npm, 'ci', '--no-audit', '--no-fund'], { cwd, stdio: 'inherit' })
    : spawnSync('npm', ['ci', '--no-audit', '--no-fund'], { cwd, stdio: 'inherit', shell: process.platform === 'win32' });
  if (r.status !== 0) {
    // Not fatal: without network the rest still runs, and what needs the peers says so.
    console.warn(`Could not install ${peer.dir} (npm ci exited ${r.status ?? r.signal}).`);
  }
}
