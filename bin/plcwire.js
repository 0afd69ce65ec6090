#!/usr/bin/env node
'use strict';
// The installed CLI: compiled code lives in dist/ (built on install by `prepare`).
const { main } = require('../dist/lib/cli/main.js');

const controller = new AbortController();
let signals = 0;
for (const name of ['SIGINT', 'SIGTERM']) {
  process.on(name, () => {
    // First Ctrl-C stops cleanly (closes PLC connections); a second one forces.
    if (++signals > 1) process.exit(130);
    controller.abort();
  });
}

// A reader that went away (`plcwire symbols … | head`, a closed `watch` pipe) is an end, not a crash:
// stop as on Ctrl-C, closing PLC connections, and say nothing more on a stream nobody reads.
let readerGone = false;
process.stdout.on('error', (err) => {
  if (err.code !== 'EPIPE') throw err;
  readerGone = true;
  process.exitCode = 0;
  controller.abort();
  setTimeout(() => process.exit(0), 2000).unref();
});

main(process.argv.slice(2), {
  stdout: process.stdout,
  stderr: process.stderr,
  stdin: process.stdin,
  signal: controller.signal,
}).then((result) => {
  // The reader left (not Ctrl-C): the command did all anyone asked of it.
  const code = readerGone ? 0 : result;
  process.exitCode = code;
  // Everything is closed by now; do not let a stray handle keep a script waiting.
  setTimeout(() => process.exit(code), 2000).unref();
});
