#!/usr/bin/env node
'use strict';
// The path of one poll, measured: client.read() of three addresses on a
// connected S7Client against the simulator, with the call stack taken where
// the request frame is written to the socket and where the answer's REAL is
// decoded. Prints each path's frames in lib/ (innermost last) and its hops:
// calls from one file into another. Run after a build: node bench/poll-hops.js
const net = require('node:net');
const path = require('node:path');
const { S7Server } = require('../dist/lib/s7/server');
const { S7Client } = require('../dist/lib');
const { parseUrl } = require('../dist/lib/url');
const { FrameReader } = require('../dist/lib/link/framer');

const LIB = path.join(__dirname, '..', 'dist', 'lib') + path.sep;
const ADDRESSES = ['DB1.DBW0', 'DB1.DBD4:REAL', 'M0.1'];

/** The frames of a stack inside dist/lib/, outermost first, as "file function". */
function libFrames(stack) {
  const frames = [];
  for (const line of stack.split('\n').slice(1)) {
    const m = /at (?:async )?(?:(.*?) \()?(\/[^):]+):\d+:\d+\)?$/.exec(line.trim());
    if (!m || !m[2].startsWith(LIB)) continue;
    frames.push({ file: path.relative(LIB, m[2]).replace(/\.js$/, '.ts'), fn: (m[1] ?? '<anonymous>').replace(/^Object\.|^Socket\./, '') });
  }
  return frames.reverse();
}

/**
 * The call tree that the probes' stacks share (root first), and its hops: a
 * call from a function in one file to one in another. Calls that returned
 * before a probe fired are seen only through the probes inside them.
 */
function report(title, stacks) {
  const root = { children: new Map() };
  for (const { stack, leaf } of stacks) {
    let node = root;
    const frames = libFrames(stack);
    if (frames[0]?.file.startsWith('s7/server/')) continue; // the simulator's side
    for (const f of leaf ? [...frames, leaf] : frames) {
      const key = `${f.file} ${f.fn}`;
      if (!node.children.has(key)) node.children.set(key, { ...f, children: new Map() });
      node = node.children.get(key);
    }
  }
  let calls = 0;
  let hops = 0;
  const lines = [];
  const walk = (node, parent, depth) => {
    for (const child of node.children.values()) {
      calls++;
      const hop = parent !== undefined && child.file !== parent.file;
      if (hop) hops++;
      lines.push(`  ${hop ? '→' : ' '} ${'  '.repeat(depth)}${child.fn}  (${child.file})`);
      walk(child, child, depth + 1);
    }
  };
  walk(root, undefined, 0);
  console.log(`${title}: ${calls} calls in lib/, ${hops} hops between files`);
  for (const l of lines) console.log(l);
  return hops;
}

/** Replaces obj[key] (a method, or a plain counter given as `counter`) with one that records a stack when `armed()`. */
function probe(obj, key, stacks, armed, leaf) {
  const own = Object.getOwnPropertyDescriptor(obj, key);
  let d = own;
  for (let o = obj; !d; o = Object.getPrototypeOf(o)) d = Object.getOwnPropertyDescriptor(Object.getPrototypeOf(o), key);
  if (typeof d.value === 'function') {
    const f = d.value;
    obj[key] = function (...args) {
      if (armed()) stacks.push({ stack: new Error().stack, leaf });
      return f.apply(this, args);
    };
  } else {
    let v = d.value;
    Object.defineProperty(obj, key, {
      configurable: true,
      enumerable: true,
      get: () => v,
      set: (x) => {
        if (armed()) stacks.push({ stack: new Error().stack });
        v = x;
      },
    });
  }
  return () => (own ? Object.defineProperty(obj, key, own) : delete obj[key]);
}

async function main() {
  Error.stackTraceLimit = 100;
  const server = new S7Server({ port: 0, profile: 's7-1200' });
  await server.listen();
  const client = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?timeout=5000`));
  await client.connect();
  await client.read(ADDRESSES); // plans and compiles: the path below is a steady poll's
  const out = [];
  const back = [];
  let phase = 'idle';
  const restore = [
    // The client's request leaves before the simulator answers: the first socket write is the client's.
    probe(net.Socket.prototype, 'write', out, () => phase === 'out' && !out.some((s) => s.leaf), { file: 'node:net', fn: 'socket.write' }),
    probe(client.stats, 'pdusSent', out, () => phase === 'out'),
    probe(client.stats, 'bytesReceived', back, () => phase === 'back'),
    probe(FrameReader.prototype, 'push', back, () => phase === 'back', { file: 'link/framer.ts', fn: 'FrameReader.push' }),
    probe(Buffer.prototype, 'readFloatBE', back, () => phase === 'back', { file: 'node:buffer', fn: 'buffer.readFloatBE' }),
  ];
  try {
    phase = 'out';
    const done = client.read(ADDRESSES);
    phase = 'back';
    await done;
  } finally {
    phase = 'idle';
    restore.forEach((r) => r());
  }
  const a = report('out: client.read() to socket.write()', out);
  const b = report("back: the socket's data to the REAL's decoder", back);
  console.log(`total: ${a + b} hops`);
  await client.close();
  await server.close();
}

main().catch((err) => {
  console.error(err);
  process.exit(1);
});
