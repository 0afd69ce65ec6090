#!/usr/bin/env node
'use strict';
// Summarizes V8 CPU profiles (.cpuprofile, from node --cpu-prof): self time
// by function and by file, so a profile of a benchmark process can be read
// without a browser.
//
//   node bench/lib/cpuprofile.js FILE.cpuprofile [--top 30] [--match text]
//
// Only samples inside --match's window are counted when given: the samples
// whose stack contains a frame whose function or URL includes the text
// (e.g. --match nodes/read.js for the read node and everything it calls).
const fs = require('node:fs');
const path = require('node:path');

function load(file) {
  const p = JSON.parse(fs.readFileSync(file, 'utf8'));
  const byId = new Map(p.nodes.map((n) => [n.id, n]));
  const parent = new Map();
  for (const n of p.nodes) for (const c of n.children || []) parent.set(c, n.id);
  // Time per sample: the deltas (µs) attributed to the sample they lead to.
  const self = new Map();
  for (let i = 0; i < p.samples.length; i++) {
    const dt = p.timeDeltas[i + 1] ?? 0;
    self.set(p.samples[i], (self.get(p.samples[i]) || 0) + dt);
  }
  const totalUs = [...self.values()].reduce((a, b) => a + b, 0);
  return { byId, parent, self, totalUs, startTime: p.startTime, endTime: p.endTime };
}

function frameName(n) {
  const f = n.callFrame;
  const url = f.url ? f.url.replace(/^file:\/\//, '') : '';
  const short = url ? `${path.relative(process.cwd(), url) || url}:${f.lineNumber + 1}` : '';
  return `${f.functionName || '(anonymous)'}${short ? ` ${short}` : ''}`;
}

function fileOf(n) {
  const f = n.callFrame;
  if (!f.url) return f.functionName.startsWith('(') ? f.functionName : '(native)';
  const url = f.url.replace(/^file:\/\//, '');
  if (url.startsWith('node:')) return url;
  const rel = path.relative(process.cwd(), url);
  const nm = rel.lastIndexOf('node_modules/');
  if (nm >= 0) {
    const rest = rel.slice(nm + 'node_modules/'.length).split('/');
    return `node_modules/${rest[0].startsWith('@') ? `${rest[0]}/${rest[1]}` : rest[0]}`;
  }
  return rel;
}

function summarize(file, { top = 30, match } = {}) {
  const prof = load(file);
  const inWindow = (id) => {
    if (!match) return true;
    for (let at = id; at !== undefined; at = prof.parent.get(at)) {
      const n = prof.byId.get(at);
      if (frameName(n).includes(match)) return true;
    }
    return false;
  };
  const fns = new Map();
  const files = new Map();
  let counted = 0;
  for (const [id, us] of prof.self) {
    if (!inWindow(id)) continue;
    counted += us;
    const n = prof.byId.get(id);
    const name = frameName(n);
    fns.set(name, (fns.get(name) || 0) + us);
    const f = fileOf(n);
    files.set(f, (files.get(f) || 0) + us);
  }
  const wall = prof.endTime - prof.startTime;
  const pct = (us) => `${((100 * us) / prof.totalUs).toFixed(1).padStart(5)} %`;
  console.log(
    `${file}: ${(wall / 1e6).toFixed(1)} s profiled, ${(prof.totalUs / 1e3).toFixed(0)} ms sampled${match ? `, ${(counted / 1e3).toFixed(0)} ms under "${match}"` : ''}`,
  );
  console.log('\nself time by file:');
  for (const [f, us] of [...files].sort((a, b) => b[1] - a[1]).slice(0, top))
    console.log(`${pct(us)}  ${(us / 1e3).toFixed(1).padStart(8)} ms  ${f}`);
  console.log('\nself time by function:');
  for (const [f, us] of [...fns].sort((a, b) => b[1] - a[1]).slice(0, top))
    console.log(`${pct(us)}  ${(us / 1e3).toFixed(1).padStart(8)} ms  ${f}`);
}

if (require.main === module) {
  const args = process.argv.slice(2);
  const opt = (name) => {
    const i = args.indexOf(`--${name}`);
    return i >= 0 ? args[i + 1] : undefined;
  };
  const files = args.filter((a, i) => !a.startsWith('--') && !(i > 0 && args[i - 1].startsWith('--')));
  for (const f of files) summarize(f, { top: Number(opt('top') || 30), match: opt('match') });
}

module.exports = { summarize };
