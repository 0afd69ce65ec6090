'use strict';
// Table printing for the scaling benchmarks (the same layout as bench/run.js's tables).

const fmt = (v, digits = 0) =>
  v === undefined || v === null || Number.isNaN(v) ? '–' : Math.abs(v) >= 1e5 ? v.toExponential(2) : v.toFixed(digits);

/** Prints rows under a title; the first `left` columns are left-aligned, the rest right-aligned. */
function printTable(title, header, rows, left = 2) {
  const widths = header.map((h, i) => Math.max(h.length, ...rows.map((r) => String(r[i] ?? '').length)));
  const line = (cells) =>
    cells
      .map((c, i) => (i < left ? String(c ?? '').padEnd(widths[i]) : String(c ?? '').padStart(widths[i])))
      .join('  ')
      .trimEnd();
  console.log(`\n${title}`);
  console.log(line(header));
  console.log(widths.map((w) => '-'.repeat(w)).join('  '));
  for (const r of rows) console.log(line(r));
}

/** The value of `args` after `--name`, or `dflt`. */
function option(args, name, dflt) {
  const i = args.indexOf(`--${name}`);
  return i >= 0 ? args[i + 1] : dflt;
}

module.exports = { fmt, printTable, option };
