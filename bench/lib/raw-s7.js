'use strict';
// A minimal S7 load generator: connects (COTP CR, setup communication), then
// sends one prebuilt Read Var frame, waits for the answer, sends it again.
// It does nothing per request but write a Buffer and count frames, so the
// server under test is what limits requests per second.
const net = require('node:net');
const { FrameCounter } = require('./proxy');

function tpkt(payload) {
  const b = Buffer.alloc(4 + payload.length);
  b[0] = 3;
  b.writeUInt16BE(b.length, 2);
  payload.copy(b, 4);
  return b;
}

// COTP CR with calling TSAP 0x0100 (PG) and called TSAP 0x0101 (rack 0, slot 1); TPDU size 1024 (code 0x0a).
const CONNECTION_REQUEST = tpkt(
  Buffer.from([0x11, 0xe0, 0x00, 0x00, 0x00, 0x01, 0x00, 0xc1, 0x02, 0x01, 0x00, 0xc2, 0x02, 0x01, 0x01, 0xc0, 0x01, 0x0a]),
);

function s7Job(pduRef, parameter) {
  const header = Buffer.from([0x02, 0xf0, 0x80, 0x32, 0x01, 0x00, 0x00, 0, 0, 0, 0, 0x00, 0x00]);
  header.writeUInt16BE(pduRef, 3 + 4);
  header.writeUInt16BE(parameter.length, 3 + 6);
  return tpkt(Buffer.concat([header, parameter]));
}

function setupCommunication(pduSize, amq) {
  const p = Buffer.from([0xf0, 0x00, 0, 0, 0, 0, 0, 0]);
  p.writeUInt16BE(amq, 2);
  p.writeUInt16BE(amq, 4);
  p.writeUInt16BE(pduSize, 6);
  return s7Job(0, p);
}

/** Read Var of `items` ({ offset, bytes }) in DB1, byte transport size. */
function readRequest(items) {
  const p = Buffer.alloc(2 + 12 * items.length);
  p[0] = 0x04;
  p[1] = items.length;
  items.forEach((it, i) => {
    const o = 2 + 12 * i;
    p.set([0x12, 0x0a, 0x10, 0x02], o);
    p.writeUInt16BE(it.bytes, o + 4);
    p.writeUInt16BE(1, o + 6); // DB1
    p[o + 8] = 0x84;
    const bitAddress = it.offset * 8;
    p[o + 9] = (bitAddress >> 16) & 0xff;
    p.writeUInt16BE(bitAddress & 0xffff, o + 10);
  });
  return s7Job(1, p);
}

/** One connection that repeats `request` until stop(); counts answers. */
function openLoad(port, request, host = '127.0.0.1') {
  return new Promise((resolve, reject) => {
    const socket = net.connect(port, host);
    socket.setNoDelay(true);
    let stage = 0;
    let running = false;
    const load = {
      answers: 0,
      errors: 0,
      start() {
        running = true;
        socket.write(request);
      },
      stop() {
        running = false;
      },
      close() {
        socket.destroy();
      },
    };
    const frames = new FrameCounter((f) => {
      if (stage === 0) {
        if (f[5] !== 0xd0) return reject(new Error('connection refused (no COTP CC)'));
        stage = 1;
        socket.write(setupCommunication(240, 1));
      } else if (stage === 1) {
        stage = 2;
        resolve(load);
      } else {
        // Ack data with error class/code 0 and a success return code on the first item.
        if (f[8] === 3 && f[17] === 0 && f[18] === 0 && f[21] === 0xff) load.answers++;
        else load.errors++;
        if (running) socket.write(request);
      }
    });
    socket.on('connect', () => socket.write(CONNECTION_REQUEST));
    socket.on('data', (d) => frames.push(d));
    socket.on('error', reject);
  });
}

module.exports = { openLoad, readRequest };
