'use strict';
// The floor for a poll: a "client" that sends prebuilt Read Var requests and
// parses nothing but the frame boundaries, with the same PDUs per poll and
// about the same bytes per poll as our client's plan for the benchmark's
// scattered tables (100 tags: 1 PDU of 14 items, ~1150 bytes; 1000 tags:
// 9 PDUs, ~13,400 bytes — bench/README.md's table). What it costs per poll
// is the kernel's and Node's socket and timer path that every client pays.
const net = require('node:net');

function tpkt(payload) {
  const b = Buffer.alloc(4 + payload.length);
  b[0] = 3;
  b.writeUInt16BE(b.length, 2);
  payload.copy(b, 4);
  return b;
}

// COTP CR, calling TSAP 0x0100, called TSAP 0x0101 (rack 0, slot 1), TPDU size 1024.
const CR = tpkt(Buffer.from([0x11, 0xe0, 0, 0, 0, 1, 0, 0xc1, 2, 1, 0, 0xc2, 2, 1, 1, 0xc0, 1, 0x0a]));

function job(pduRef, parameter) {
  const header = Buffer.from([0x02, 0xf0, 0x80, 0x32, 0x01, 0, 0, 0, 0, 0, 0, 0, 0]);
  header.writeUInt16BE(pduRef, 7);
  header.writeUInt16BE(parameter.length, 9);
  return tpkt(Buffer.concat([header, parameter]));
}

function setup(pdu) {
  const p = Buffer.from([0xf0, 0, 0, 8, 0, 8, 0, 0]);
  p.writeUInt16BE(pdu, 6);
  return job(0, p);
}

/** Read Var of `count` items of `bytes` bytes each, spread through DB1. */
function readJob(pduRef, count, bytes, first) {
  const p = Buffer.alloc(2 + 12 * count);
  p[0] = 0x04;
  p[1] = count;
  for (let i = 0; i < count; i++) {
    const o = 2 + 12 * i;
    p.set([0x12, 0x0a, 0x10, 0x02], o);
    p.writeUInt16BE(bytes, o + 4);
    p.writeUInt16BE(1, o + 6);
    p[o + 8] = 0x84;
    const bit = (first + i * (bytes + 40)) * 8;
    p[o + 9] = (bit >> 16) & 0xff;
    p.writeUInt16BE(bit & 0xffff, o + 10);
  }
  return job(pduRef, p);
}

/** The poll's requests for a table of `tags` scattered tags (see the header). */
function pollRequests(tags) {
  if (tags <= 100) return [readJob(1, 14, 60, 0)];
  return Array.from({ length: 9 }, (_, i) => readJob(1 + i, 8, 150, i * 1600));
}

/** Opens a raw connection: { read(): Promise<void> (all of the poll's answers arrived), close() }. */
function openRaw({ port, tags, pdu = 960 }) {
  const requests = pollRequests(tags);
  return new Promise((resolve, reject) => {
    const socket = net.connect(port, '127.0.0.1');
    socket.setNoDelay(true);
    let stage = 0;
    let pending = 0;
    let done;
    let held = Buffer.alloc(0);
    const frame = (f) => {
      if (stage === 0) {
        if (f[5] !== 0xd0) return reject(new Error('no COTP CC'));
        stage = 1;
        socket.write(setup(pdu));
      } else if (stage === 1) {
        stage = 2;
        resolve({
          read() {
            pending = requests.length;
            const p = new Promise((r) => (done = r));
            socket.cork();
            for (const r of requests) socket.write(r);
            socket.uncork();
            return p;
          },
          close: () => new Promise((r) => socket.end(r)),
        });
      } else if (--pending === 0) done();
    };
    socket.on('connect', () => socket.write(CR));
    socket.on('data', (d) => {
      held = held.length ? Buffer.concat([held, d]) : d;
      while (held.length >= 4) {
        const len = held.readUInt16BE(2);
        if (held.length < len) break;
        frame(held.subarray(0, len));
        held = held.subarray(len);
      }
    });
    socket.on('error', reject);
  });
}

module.exports = { openRaw };
