'use strict';
// Where the benchmark finds the independent peers and our library.
// nodes7, @st-one-io/nodes7 and node-snap7 live in test/interop's own package
// (one install serves the interoperability tests and the benchmark, and keeps
// them out of the main package's dependencies).
const path = require('node:path');

const ROOT = path.resolve(__dirname, '../..');
const INTEROP = path.join(ROOT, 'test/interop');

function peer(name) {
  try {
    return require(require.resolve(name, { paths: [INTEROP] }));
  } catch (err) {
    if (err && err.code === 'MODULE_NOT_FOUND') {
      throw new Error(`${name} is not installed: run \`(cd test/interop && npm ci)\` first`, { cause: err });
    }
    throw err;
  }
}

// PLCWIRE_DIST=/other/checkout/dist benchmarks another build (e.g. a commit in a worktree).
const DIST = process.env.PLCWIRE_DIST ? path.resolve(process.env.PLCWIRE_DIST) : path.join(ROOT, 'dist');

function plcwire() {
  try {
    return require(path.join(DIST, 'lib/index.js'));
  } catch (err) {
    throw new Error(`dist/ is not built (run \`npm run build\`): ${err.message}`, { cause: err });
  }
}

module.exports = { peer, plcwire, ROOT, DIST };
