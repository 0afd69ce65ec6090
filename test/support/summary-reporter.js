'use strict';
// Mocha's spec reporter, plus the plain closing line CI reads: "N passed, N failed[, N skipped]".
// Before it, one line per reason a test was skipped (test/support/skip.ts records the reason), so
// a test that did not run is never just a number: "skipped: 3 (socat is not installed)".
const Mocha = require('mocha');

const SKIP_REASON = Symbol.for('plcwire.skipReason');

/** The reason recorded on a skipped test or the nearest suite above it. */
function reasonOf(test) {
  for (let r = test; r; r = r.parent) if (typeof r[SKIP_REASON] === 'string') return r[SKIP_REASON];
  return undefined;
}

class SummaryReporter extends Mocha.reporters.Spec {
  constructor(runner, options) {
    super(runner, options);
    const skipped = new Map(); // reason -> count
    const unexplained = []; // full titles of tests skipped without a reason (it.skip, a bare this.skip())
    runner.on(Mocha.Runner.constants.EVENT_TEST_PENDING, (test) => {
      const reason = reasonOf(test);
      if (reason === undefined) unexplained.push(test.fullTitle());
      else skipped.set(reason, (skipped.get(reason) ?? 0) + 1);
    });
    runner.once(Mocha.Runner.constants.EVENT_RUN_END, () => {
      const { passes, failures, pending } = runner.stats;
      // Printed after the spec reporter's epilogue so the count line is the last line.
      process.nextTick(() => {
        let out = '\n';
        for (const [reason, n] of skipped) out += `skipped: ${n} (${reason})\n`;
        for (const title of unexplained) out += `skipped: 1 (no reason given, use skipBecause from test/support/skip.ts): ${title}\n`;
        const tail = pending ? `, ${pending} skipped` : '';
        process.stdout.write(`${out}${passes} passed, ${failures} failed${tail}\n`);
      });
    });
  }
}

module.exports = SummaryReporter;
