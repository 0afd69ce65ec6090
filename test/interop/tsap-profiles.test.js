'use strict';
// snap7's client reaching the TSAP-addressed profiles (s7-200, logo) as it
// reaches such CPUs: SetConnectionParams(ip, localTSAP, remoteTSAP), then Connect().
const { expect } = require('chai');
const support = require('./support');
const { snap7 } = support;

function tsapClient(port, localTsap, remoteTsap) {
  const client = new snap7.S7Client();
  client.SetParam(client.RemotePort, port);
  client.SetConnectionParams('127.0.0.1', localTsap, remoteTsap);
  const call = (fn, ...args) =>
    new Promise((resolve, reject) =>
      client[fn](...args, (err, result) => (err ? reject(new Error(`snap7 ${fn}: ${client.ErrorText(err)}`)) : resolve(result))),
    );
  return { client, call };
}

describe('interop: snap7 client against the s7-200 and logo profiles', function () {
  this.timeout(15000);
  let server;
  const clients = [];
  afterEach(async () => {
    for (const c of clients.splice(0)) c.client.Disconnect();
    if (server) await server.close();
    server = undefined;
  });

  for (const [profile, local, remote] of [
    ['s7-200', 0x1000, 0x1001],
    ['logo', 0x0100, 0x0200],
  ]) {
    it(`${profile}: connects with its TSAPs, negotiates PDU 240, reads and writes V as DB1; DB2 and other TSAPs are refused`, async () => {
      server = new support.plcwire.S7Server({ port: 0, profile });
      const port = await server.listen();
      const c = tsapClient(port, local, remote);
      clients.push(c);
      await c.call('Connect');
      expect(c.client.PDULength()).to.equal(240);
      await c.call('DBWrite', 1, 100, 3, Buffer.from([1, 2, 3]));
      expect(server.memory.area('DB', 1).subarray(100, 103).toString('hex')).to.equal('010203');
      expect((await c.call('DBRead', 1, 100, 3)).toString('hex')).to.equal('010203');
      const missing = await c.call('DBRead', 2, 0, 1).then(
        () => undefined,
        (e) => e,
      );
      expect(missing && missing.message).to.match(/not available|does not exist/i);
      const wrong = tsapClient(port, local, 0x0301);
      clients.push(wrong);
      const refused = await wrong.call('Connect').then(
        () => undefined,
        (e) => e,
      );
      expect(refused, 'rack 0 slot 1 TSAP').to.be.instanceOf(Error);
      expect(server.connectionCount).to.equal(1);
    });
  }
});
