'use strict';
/**
 * The demo's MQTT broker: aedes (a dev dependency) in this process on
 * 127.0.0.1, so the Sparkplug B and MQTT gateway examples imported into
 * `npm start` have a broker with nothing installed. A broker already on the
 * port (mosquitto, say) is used instead: the demo says so and starts none.
 * Resolves { url, close() }; close() drops every client and the port.
 */
const net = require('node:net');

async function startDemoBroker(port = 1883) {
  let Aedes;
  try {
    ({ Aedes } = require('aedes'));
  } catch {
    return { url: undefined, note: 'no in-process MQTT broker: aedes is not installed (a dev dependency)', close: async () => undefined };
  }
  const broker = await Aedes.createBroker();
  const sockets = new Set();
  const server = net.createServer((socket) => {
    sockets.add(socket);
    socket.on('close', () => sockets.delete(socket));
    broker.handle(socket);
  });
  const listening = await new Promise((resolve, reject) => {
    server.once('error', (err) => (err.code === 'EADDRINUSE' ? resolve(false) : reject(err)));
    server.listen(port, '127.0.0.1', () => resolve(true));
  });
  if (!listening) {
    await new Promise((resolve) => broker.close(resolve));
    return { url: `mqtt://127.0.0.1:${port}`, note: `a broker is already on port ${port}: the demo uses it`, close: async () => undefined };
  }
  const url = `mqtt://127.0.0.1:${server.address().port}`;
  return {
    url,
    note: 'in-process (aedes)',
    close: async () => {
      await new Promise((resolve) => broker.close(resolve));
      for (const s of sockets) s.destroy();
      await new Promise((resolve) => server.close(resolve));
    },
  };
}

module.exports = { startDemoBroker };
