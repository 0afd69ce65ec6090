'use strict';
// A counting TCP proxy between a client and a server: it reassembles TPKT
// frames in both directions and counts S7 Read Var jobs (ROSCTR 1, function
// 0x04) and the bytes of those jobs and of every frame the server sends back
// after the handshake. It works for any client, so every library is counted
// the same way.
//
// S7CommPlus over TLS travels as TLS records inside COTP data (DT) frames,
// so its requests cannot be read: the proxy counts, from the client to the
// server, the TLS application-data records (content type 23, reassembled
// from the DT payloads, which may cut a record anywhere) and the COTP data
// units (DT frames with the EOT bit: one per write the client's COTP layer
// makes). A client that sends each S7CommPlus request as one TLS record
// (ours does; bench/run.js prints our own count beside it) sends one record
// per request. `plus` holds these counters and the bytes of all frames both
// ways since the last reset.
const net = require('node:net');

const TPKT_HEADER = 4;
const COTP_DT = 3;
const COTP_DT_CODE = 0xf0;
const COTP_EOT = 0x80;
/** The S7CommPlus frame's first byte (before InitSSL the protocol travels in plain text). */
const S7P_START = 0x72;
const TLS_RECORD_HEADER = 5;
const TLS_APPLICATION_DATA = 23;

/** TLS records cut from a byte stream (the DT payloads of one direction), each's content type to `onRecord`. */
class TlsRecordCounter {
  constructor(onRecord) {
    this.pending = Buffer.alloc(0);
    this.onRecord = onRecord;
  }
  push(chunk) {
    this.pending = this.pending.length ? Buffer.concat([this.pending, chunk]) : chunk;
    while (this.pending.length >= TLS_RECORD_HEADER) {
      const len = TLS_RECORD_HEADER + this.pending.readUInt16BE(3);
      if (this.pending.length < len) break;
      this.onRecord(this.pending[0]);
      this.pending = this.pending.subarray(len);
    }
  }
}

/** The counters of S7CommPlus traffic since the last reset. */
function plusCounters() {
  return { tlsRecords: 0, dataUnits: 0, plainMessages: 0, bytesToServer: 0, bytesToClient: 0 };
}

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
    this.plus = plusCounters();
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
    let plus; // this connection speaks S7CommPlus: its first DT payload does not start an S7 PDU
    let tls = false; // its DT payloads are TLS records (after InitSSL)
    const records = new TlsRecordCounter((type) => {
      if (type === TLS_APPLICATION_DATA) this.plus.tlsRecords++;
    });
    const up = new FrameCounter((f) => {
      this.plus.bytesToServer += f.length;
      const dt = f.length > TPKT_HEADER + COTP_DT && f[5] === COTP_DT_CODE;
      if (dt && plus === undefined) plus = f[TPKT_HEADER + COTP_DT] !== 0x32;
      if (dt && plus) {
        const payload = f.subarray(TPKT_HEADER + COTP_DT);
        if (f[6] & COTP_EOT) this.plus.dataUnits++;
        if (!tls && payload[0] === S7P_START) this.plus.plainMessages++;
        else {
          tls = true;
          records.push(payload);
        }
        return;
      }
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
      this.plus.bytesToClient += f.length;
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
