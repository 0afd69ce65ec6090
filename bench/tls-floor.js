#!/usr/bin/env node
'use strict';
// What one request/answer round trip costs the client in Node before any
// protocol work, on loopback, with an echo server in a child process: plain
// TCP (what an S7 PUT/GET job rides on), TLS straight on the TCP socket, and
// TLS over a minimal Duplex that passes bytes to a TCP socket, which is how
// S7CommPlus has to run TLS in Node (inside COTP data frames: Node then wraps
// the Duplex in its JS stream socket). 300 bytes out, 450 back, as a
// 50-item GetMultiVariables by LID. The floor under the S7CommPlus table's
// CPU figures (bench/README.md, "S7CommPlus").
//
//   node bench/tls-floor.js [ms per mode, 1000]
const net = require('node:net');
const path = require('node:path');
const tls = require('node:tls');
const { Duplex } = require('node:stream');
const { fork } = require('node:child_process');
const { DIST } = require('./lib/peers');

const REQUEST = Buffer.alloc(300, 2);
const ANSWER = Buffer.alloc(450, 1);
const WARM = 500;

async function serve() {
  const { generateCertificate } = require(path.join(DIST, 'lib/s7plus/transport/cert.js'));
  const { cert, key } = await generateCertificate();
  const listen = (server) => new Promise((resolve) => server.listen(0, '127.0.0.1', () => resolve(server.address().port)));
  const answer = (socket) => socket.on('data', () => socket.write(ANSWER));
  const tcp = await listen(net.createServer({ noDelay: true }, answer));
  const secure = await listen(tls.createServer({ cert, key }, answer));
  process.send({ tcp, secure });
}

/** A Duplex that hands its writes to `socket` and pushes what `socket` reads: the least a tunnel can do. */
function passThrough(socket) {
  const d = new Duplex({
    write(chunk, _encoding, callback) {
      socket.write(chunk);
      callback();
    },
    read() {},
  });
  socket.on('data', (b) => d.push(b));
  return d;
}

async function measure(socket, ms) {
  const roundTrip = () =>
    new Promise((resolve) => {
      socket.once('data', resolve);
      socket.write(REQUEST);
    });
  for (let i = 0; i < WARM; i++) await roundTrip();
  const cpu0 = process.cpuUsage();
  const until = Date.now() + ms;
  let n = 0;
  while (Date.now() < until) {
    await roundTrip();
    n++;
  }
  const cpu = process.cpuUsage(cpu0);
  socket.destroy();
  return { perSecond: (n * 1000) / ms, cpuUs: (cpu.user + cpu.system) / n };
}

async function main() {
  const ms = Number(process.argv[2] ?? 1000);
  const child = fork(__filename, ['--serve']);
  const ports = await new Promise((resolve) => child.once('message', resolve));
  const connected = (socket, event) => new Promise((resolve) => socket.once(event, () => resolve(socket)));
  const modes = {
    TCP: () => connected(net.connect({ port: ports.tcp, host: '127.0.0.1', noDelay: true }), 'connect'),
    'TLS on the TCP socket': () =>
      connected(tls.connect({ port: ports.secure, host: '127.0.0.1', rejectUnauthorized: false }), 'secureConnect'),
    'TLS over a Duplex': () =>
      connected(
        tls.connect({
          socket: passThrough(net.connect({ port: ports.secure, host: '127.0.0.1', noDelay: true })),
          rejectUnauthorized: false,
        }),
        'secureConnect',
      ),
  };
  console.log(`One round trip, ${REQUEST.length} bytes out and ${ANSWER.length} back, best of 2 rounds of ${ms} ms`);
  for (const [name, open] of Object.entries(modes)) {
    const a = await measure(await open(), ms);
    const b = await measure(await open(), ms);
    const best = a.perSecond >= b.perSecond ? a : b;
    console.log(
      `${name.padEnd(22)} ${best.perSecond.toFixed(0).padStart(7)} round trips/s  ${best.cpuUs.toFixed(1).padStart(6)} µs CPU each`,
    );
  }
  child.kill();
}

if (process.argv[2] === '--serve') serve();
else
  main().catch((err) => {
    console.error(err);
    process.exit(1);
  });
