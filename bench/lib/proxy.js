'use strict';
// A counting TCP proxy between a client and a server: it reassembles TPKT
// frames in both directions and counts S7 Read Var jobs (ROSCTR 1, function
// 0x04) and the bytes of those jobs and of every frame the server sends back
// after the handshake. It works for any client, so every library is counted
// the same way.
const net = require('node:net');

const TPKT_HEADER = 4;
const COTP_DT = 3;

class FrameCounter {
  constructor(onFrame) {
    this.pending = Buffer.alloc(0);
    this.onFrame = onFrame;
  }
  push(chunk) {
    this.pending = this.pending.length ? Buffer.concat([this.pending, chunk]) : chunk;
    while (this.pending.length >= TPKT_HEADER) {
      const len = this.pending.readUInt16BE(2);
      if (len < TPKT_HEADER || this.pending.length < len) break;
      this.onFrame(this.pending.subarray(0, len));
      this.pending = this.pending.subarray(len);
    }
  }
}

/** S7 header of a COTP DT frame, or undefined for COTP CR/CC/DR. */
function s7Header(frame) {
  if (frame.length < TPKT_HEADER + COTP_DT + 10 || frame[5] !== 0xf0) return undefined;
  const s7 = TPKT_HEADER + COTP_DT;
  if (frame[s7] !== 0x32) return undefined;
  const rosctr = frame[s7 + 1];
  const headerLength = rosctr === 2 || rosctr === 3 ? 12 : 10;
  return { rosctr, fn: frame[s7 + headerLength] };
}

class CountingProxy {
  constructor(targetPort, targetHost = '127.0.0.1') {
    this.targetPort = targetPort;
    this.targetHost = targetHost;
    this.sockets = new Set();
    this.reset();
    this.server = net.createServer((client) => this.accept(client));
  }
  reset() {
    this.readJobs = 0;
    this.writeJobs = 0;
    this.jobs = 0;
    this.bytesToServer = 0;
    this.bytesToClient = 0;
    this.maxItemsPerJob = 0;
    this.items = 0;
  }
  listen() {
    return new Promise((resolve) => this.server.listen(0, '127.0.0.1', () => resolve(this.server.address().port)));
  }
  accept(client) {
    const upstream = net.connect(this.targetPort, this.targetHost);
    client.setNoDelay(true);
    upstream.setNoDelay(true);
    this.sockets.add(client).add(upstream);
    let counting = false; // after the setup communication ack
    const up = new FrameCounter((f) => {
      const h = s7Header(f);
      if (!h || h.rosctr !== 1) return;
      if (h.fn === 0xf0) return;
      counting = true;
      this.jobs++;
      if (h.fn === 0x04) this.readJobs++;
      if (h.fn === 0x05) this.writeJobs++;
      const items = f[TPKT_HEADER + COTP_DT + 11];
      this.items += items;
      this.maxItemsPerJob = Math.max(this.maxItemsPerJob, items);
      this.bytesToServer += f.length;
    });
    const down = new FrameCounter((f) => {
      if (counting) this.bytesToClient += f.length;
    });
    client.on('data', (d) => {
      up.push(d);
      upstream.write(d);
    });
    upstream.on('data', (d) => {
      down.push(d);
      client.write(d);
    });
    const close = () => {
      client.destroy();
      upstream.destroy();
      this.sockets.delete(client);
      this.sockets.delete(upstream);
    };
    client.on('error', close).on('close', close);
    upstream.on('error', close).on('close', close);
  }
  close() {
    for (const s of this.sockets) s.destroy();
    return new Promise((resolve) => this.server.close(() => resolve()));
  }
}

module.exports = { CountingProxy, FrameCounter };
