'use strict';
// Shared by the interoperability tests: snap7 (node-snap7) as an independent
// peer, promisified, and a free TCP port for its server (snap7 cannot listen
// on port 0 and report the port, so we pick one the OS just handed out).
const net = require('node:net');
const path = require('node:path');

let snap7;
try {
  snap7 = require('node-snap7');
} catch (err) {
  throw new Error(`node-snap7 is not installed: run \`node test/support/install-peers.js interop\` (npm test does)\n${err.message}`, {
    cause: err,
  });
}

function freePort() {
  return new Promise((resolve, reject) => {
    const s = net.createServer();
    s.on('error', reject);
    s.listen(0, '127.0.0.1', () => {
      const { port } = s.address();
      s.close(() => resolve(port));
    });
  });
}

/** A snap7 server on 127.0.0.1 with the given areas ({ db: { 1: Buffer }, MK: Buffer, PE, PA, CT, TM }). */
/**
 * Every snap7 server made in this process, kept referenced until it exits: node-snap7 aborts the process (SIGABRT)
 * now and then, likely when a stopped server is collected while another one runs (seen once in four fresh-clone runs under
 * load, in the before hook of doctor-vs-snap7.test.js); a stopped server holds no socket, so keeping it costs nothing.
 */
const SERVERS = [];

async function startSnap7Server(areas) {
  const server = new snap7.S7Server();
  SERVERS.push(server);
  for (const [db, buf] of Object.entries(areas.db ?? {})) server.RegisterArea(server.srvAreaDB, Number(db), buf);
  for (const name of ['PE', 'PA', 'MK', 'CT', 'TM']) {
    if (areas[name]) server.RegisterArea(server[`srvArea${name}`], areas[name]);
  }
  // Another process may take the port between freePort() and StartTo(): try a few.
  for (let attempt = 0; attempt < 5; attempt++) {
    const port = await freePort();
    server.SetParam(server.LocalPort, port);
    if (server.StartTo('127.0.0.1')) {
      return {
        server,
        port,
        db: (n) => server.GetArea(server.srvAreaDB, n),
        area: (name) => server.GetArea(server[`srvArea${name}`]),
        /** Replaces the contents of registered areas (same sizes). */
        reset: (next) => {
          for (const [db, buf] of Object.entries(next.db ?? {})) server.SetArea(server.srvAreaDB, Number(db), buf);
          for (const name of ['PE', 'PA', 'MK', 'CT', 'TM']) if (next[name]) server.SetArea(server[`srvArea${name}`], next[name]);
        },
        stop: () => {
          server.Stop();
        },
      };
    }
  }
  throw new Error(`snap7 server did not start: ${server.ErrorText(server.LastError())}`);
}

/** A connected snap7 client; every call goes through node-snap7's asynchronous (callback) form,
 * because a blocking call would stall the event loop our server runs on. */
async function snap7Client(port, { rack = 0, slot = 1 } = {}) {
  const client = new snap7.S7Client();
  if (!client.SetParam(client.RemotePort, port)) throw new Error('snap7: cannot set RemotePort');
  const call = (fn, ...args) =>
    new Promise((resolve, reject) => {
      client[fn](...args, (err, result) => {
        if (err) reject(Object.assign(new Error(`snap7 ${fn}: ${client.ErrorText(err)}`), { snap7Code: err }));
        else resolve(result);
      });
    });
  await call('ConnectTo', '127.0.0.1', rack, slot);
  return { client, call, close: () => client.Disconnect() };
}

/** Waits for `emitter` to emit `event` (optionally matching `pred`) within `ms`. */
function eventWithin(emitter, event, ms, pred = () => true) {
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => {
      emitter.off(event, on);
      reject(new Error(`no '${event}' within ${ms} ms`));
    }, ms);
    function on(...args) {
      if (!pred(...args)) return;
      clearTimeout(timer);
      emitter.off(event, on);
      resolve(args);
    }
    emitter.on(event, on);
  });
}

module.exports = {
  snap7,
  /** Our library, built by `npm run build` (loaded on first use so a missing build fails the tests, not the load). */
  get plcwire() {
    return require(path.resolve(__dirname, '../../dist/lib/index.js'));
  },
  freePort,
  startSnap7Server,
  snap7Client,
  eventWithin,
};
