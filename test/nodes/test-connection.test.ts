/**
 * The connection dialog's Test connection endpoint: the library's doctor on
 * the runtime, against the S7 simulator and a silent TCP peer over real
 * sockets. It answers with the steps, keeps its deadline, stops when the
 * editor's request goes away, and never leaves a connection open.
 */
import { expect } from 'chai';
import * as http from 'node:http';
import * as net from 'node:net';
import { ALL_NODES, helper, until } from './support';

const lib = require('../../lib/index');

/** A TCP peer that accepts and never answers; `open` counts the sockets still open on its side. */
async function silentPeer(): Promise<{ port: number; accepted: number; open: number; close(): Promise<void> }> {
  const sockets = new Set<net.Socket>();
  let accepted = 0;
  const server = net.createServer((s) => {
    accepted++;
    sockets.add(s);
    s.on('close', () => sockets.delete(s));
    s.on('error', () => undefined);
    s.resume(); // reads and drops what arrives, so the client's close is seen
  });
  await new Promise<void>((r) => server.listen(0, '127.0.0.1', r));
  return {
    port: (server.address() as net.AddressInfo).port,
    get accepted() {
      return accepted;
    },
    get open() {
      return sockets.size;
    },
    close: async () => {
      for (const s of sockets) s.destroy();
      await new Promise<void>((r) => server.close(() => r()));
    },
  };
}

describe('nodes: Test connection (the doctor behind the connection dialog)', function () {
  this.timeout(20000);
  let server: any;
  let port: number;

  beforeEach(async () => {
    server = new lib.S7Server({ port: 0, memory: new lib.PlcMemory(), profile: 's7-1500' });
    port = await server.listen();
    await helper.startServer();
    await helper.load(ALL_NODES, []);
  });

  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
    await server.close();
  });

  it('walks a working connection step by step, reads the given addresses, and closes its connection', async () => {
    const res = await helper
      .request()
      .post('/plcwire/doctor')
      .send({ url: `s7://127.0.0.1:${port}?rack=0&slot=1&timeout=1000`, addresses: ['DB1.DBW0:INT'] })
      .expect(200);
    expect(res.body.ok, JSON.stringify(res.body.steps)).to.equal(true);
    const steps = res.body.steps.map((s: any) => s.step);
    expect(steps).to.include.members(['tcp', 'cotp']);
    expect(steps[steps.length - 1]).to.match(/DB1\.DBW0:INT/);
    for (const s of res.body.steps)
      expect(s).to.have.keys(s.hint === undefined ? ['step', 'ok', 'detail'] : ['step', 'ok', 'detail', 'hint']);
    await until(() => server.connectionCount === 0, 2000, `no connection left (have ${server.connectionCount})`);
  });

  it('on a wrong slot: the failing step with what to change, and no connection left', async () => {
    const res = await helper
      .request()
      .post('/plcwire/doctor')
      .send({ url: `s7://127.0.0.1:${port}?rack=0&slot=5&timeout=1000` })
      .expect(200);
    expect(res.body.ok).to.equal(false);
    const last = res.body.steps[res.body.steps.length - 1];
    expect(last.ok).to.equal(false);
    expect(`${last.detail} ${last.hint}`).to.match(/slot/);
    expect(last.hint).to.match(/slot=1|slot 1/);
    await until(() => server.connectionCount === 0, 2000, `no connection left (have ${server.connectionCount})`);
  });

  it('a URL that is not S7 or not valid fails at the url step', async () => {
    const other = await helper.request().post('/plcwire/doctor').send({ url: 'fetchwrite://127.0.0.1?port=2000' }).expect(200);
    expect(other.body.ok).to.equal(false);
    expect(other.body.steps.map((s: any) => [s.step, s.ok])).to.deep.equal([['url', false]]);
    const bad = await helper.request().post('/plcwire/doctor').send({ url: 's7://127.0.0.1?slott=1' }).expect(200);
    expect(bad.body.steps[0].detail).to.include('slott');
  });

  it('keeps its deadline against a PLC that never answers, and closes the socket', async () => {
    const peer = await silentPeer();
    try {
      const t0 = Date.now();
      const res = await helper
        .request()
        .post('/plcwire/doctor')
        .send({ url: `s7://127.0.0.1:${peer.port}?rack=0&slot=1&timeout=10000`, timeout: 500 })
        .expect(200);
      expect(Date.now() - t0).to.be.lessThan(3000);
      expect(res.body.ok).to.equal(false);
      const last = res.body.steps[res.body.steps.length - 1];
      expect(last.ok, JSON.stringify(res.body)).to.equal(false);
      // The doctor's words for the silence, or for its deadline cutting the walk short.
      expect(last.detail).to.match(/nothing answered|deadline of 500 ms/);
      await until(() => peer.accepted > 0 && peer.open === 0, 2000, 'the doctor closed its socket');
    } finally {
      await peer.close();
    }
  });

  it("stops the doctor and closes its socket when the editor's request goes away", async () => {
    const peer = await silentPeer();
    try {
      // The helper's admin app (what helper.request() drives) on a socket of its own, so the test can hang up mid-request.
      const admin = http.createServer(helper._httpAdmin);
      await new Promise<void>((r) => admin.listen(0, '127.0.0.1', r));
      after.push(() => new Promise<void>((r) => admin.close(() => r())));
      const body = JSON.stringify({ url: `s7://127.0.0.1:${peer.port}?rack=0&slot=1&timeout=10000` });
      const req = http.request(`http://127.0.0.1:${(admin.address() as net.AddressInfo).port}/plcwire/doctor`, {
        method: 'POST',
        headers: { 'content-type': 'application/json', 'content-length': Buffer.byteLength(body) },
      });
      req.on('error', () => undefined);
      req.end(body);
      await until(() => peer.open > 0, 4000, 'the doctor reached the peer');
      const t0 = Date.now();
      req.destroy();
      await until(() => peer.open === 0, 3000, 'the doctor closed its socket after the request went away');
      expect(Date.now() - t0).to.be.lessThan(3000);
    } finally {
      await peer.close();
    }
  });

  const after: (() => Promise<void>)[] = [];
  afterEach(async () => {
    for (const f of after.splice(0)) await f();
  });
});
