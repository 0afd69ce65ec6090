'use strict';
// A TCP proxy in front of one simulated PLC that plays the network and
// transport faults of the chaos run on what the PLC sends back; what the
// client sends always reaches the PLC at once (so a write the PLC received is
// applied and recorded, whatever happens to its answer).
//   pass      answers go through
//   silent    answers are swallowed (sockets stay open)
//   slow      every answer is delayed by `delayMs` (in order)
//   half      the next answer is cut in half, then silence
//   garbage   the next answer is replaced by garbage, then pass
//   backlog   new connections are accepted and never answered nor forwarded
//   refuse    new connections are closed at once
// and for S7CommPlus over TLS (the answers are TLS records in COTP data frames):
//   alert     the next request's TLS record is corrupted on its way (its last byte, in the authentication
//             tag, flipped): the PLC's own TLS refuses it with a fatal alert (bad_record_mac) and closes, a
//             real alert under the session's keys, which a proxy could not forge
//   recordReset  half of the next answer (inside its TLS record), then RST
// and reset() (RST on every connection), gone() / back() (the listener closes
// and reopens on the same port: connection refused meanwhile).
const net = require('node:net');

const GARBAGE = Buffer.from('HTTP/1.1 400 Bad Request\r\n\r\n\u00ff\u0000garbage');

class ChaosProxy {
  constructor(target) {
    this.target = target;
    this.mode = 'pass';
    this.delayMs = 0;
    this.port = 0;
    this.server = undefined;
    this.pairs = new Set();
    this.held = new Set();
    this.timers = new Set();
  }

  async listen() {
    const server = net.createServer((socket) => this.accept(socket));
    server.on('error', () => undefined);
    this.server = server;
    await new Promise((resolve, reject) => {
      server.once('error', reject);
      server.listen(this.port, '127.0.0.1', () => {
        server.off('error', reject);
        resolve();
      });
    });
    this.port = server.address().port;
    return this.port;
  }

  setMode(mode, delayMs = 0) {
    this.mode = mode;
    this.delayMs = delayMs;
    if (mode !== 'backlog') this.releaseHeld();
  }

  /** RST on every connection (clients and the PLC side). */
  reset() {
    for (const p of [...this.pairs]) p.reset();
    this.releaseHeld();
  }

  releaseHeld() {
    for (const s of this.held) s.resetAndDestroy();
    this.held.clear();
  }

  /** The listener goes away (and every connection with it). */
  async gone() {
    const server = this.server;
    this.server = undefined;
    this.reset();
    if (server) await new Promise((resolve) => server.close(() => resolve()));
  }

  async back() {
    if (!this.server) await this.listen();
  }

  async close() {
    for (const t of this.timers) clearTimeout(t);
    this.timers.clear();
    await this.gone();
  }

  accept(client) {
    client.on('error', () => undefined);
    if (this.mode === 'refuse') return void client.resetAndDestroy();
    if (this.mode === 'backlog') {
      this.held.add(client);
      client.on('close', () => this.held.delete(client));
      return;
    }
    client.setNoDelay(true);
    const upstream = net.connect({ host: '127.0.0.1', port: this.target, noDelay: true });
    upstream.on('error', () => undefined);
    const pair = {
      client,
      reset: () => {
        if (!client.destroyed) client.resetAndDestroy();
        upstream.destroy();
      },
    };
    this.pairs.add(pair);
    const end = () => {
      this.pairs.delete(pair);
      client.destroy();
      upstream.destroy();
    };
    client.on('close', end);
    upstream.on('close', end);
    client.on('data', (chunk) => upstream.write(this.mode === 'alert' ? this.corrupt(chunk) : chunk));
    upstream.on('data', (chunk) => this.answer(chunk, client));
  }

  /** The next request with its last byte (the TLS record's authentication tag) flipped: the PLC's TLS answers a fatal alert. */
  corrupt(chunk) {
    this.mode = 'pass';
    const bad = Buffer.from(chunk);
    bad[bad.length - 1] ^= 0xff;
    return bad;
  }

  answer(chunk, client) {
    switch (this.mode) {
      case 'silent':
      case 'backlog':
      case 'refuse':
        return;
      case 'slow':
        return this.later(client, chunk, this.delayMs);
      case 'half':
        this.mode = 'silent';
        return this.later(client, chunk.subarray(0, Math.max(1, chunk.length >> 1)), 0);
      case 'garbage':
        this.mode = 'pass';
        return this.later(client, GARBAGE, 0);
      case 'recordReset':
        this.mode = 'pass';
        if (!client.destroyed) client.write(chunk.subarray(0, Math.max(1, chunk.length >> 1)), () => client.resetAndDestroy());
        return;
      default:
        return this.later(client, chunk, 0);
    }
  }

  /** Sends `bytes` to `client` after `ms`, never before what was queued earlier (a slow answer is not overtaken). */
  later(client, bytes, ms) {
    const queue = (client.chaosQueue ??= []);
    if (ms === 0 && queue.length === 0) {
      if (!client.destroyed) client.write(bytes);
      return;
    }
    queue.push({ due: Date.now() + ms, bytes });
    if (queue.length === 1) this.drain(client);
  }

  drain(client) {
    const queue = client.chaosQueue;
    while (queue.length > 0 && queue[0].due <= Date.now()) {
      const { bytes } = queue.shift();
      if (!client.destroyed) client.write(bytes);
    }
    if (queue.length === 0 || client.destroyed) return void (queue.length = 0);
    const t = setTimeout(() => {
      this.timers.delete(t);
      this.drain(client);
    }, queue[0].due - Date.now());
    this.timers.add(t);
  }
}

module.exports = { ChaosProxy };
