'use strict';
// Counters and timers asked for the way snap7, nodes7 and @st-one-io/nodes7
// ask, against our S7Server (the CPU's rules and their sources are in
// lib/s7/server/jobs.ts, COUNTERS_AND_TIMERS).
const { once } = require('node:events');
const path = require('node:path');
const { expect } = require('chai');
const support = require('./support');
const { snap7, snap7Client } = support;

const C = snap7.S7Client.prototype;
const peer = (name) => require(path.join(__dirname, 'node_modules', name));

describe('interop: counters and timers as other clients ask for them', function () {
  this.timeout(15000);
  let server;
  let port;
  const closers = [];

  beforeEach(async () => {
    server = new support.plcwire.S7Server({ port: 0, profile: 's7-300' });
    port = await server.listen();
    const c = server.memory.area('C');
    const t = server.memory.area('T');
    for (let n = 0; n < 64; n++) c.writeUInt16BE(0x0100 + n, n * 2); // Cn holds 0x01nn: a wrong number shows
    t.writeUInt16BE(0x2123, 0); // T0: 123 × 10 s
    t.writeUInt16BE(0x0042, 13 * 2);
  });

  afterEach(async () => {
    for (const close of closers.splice(0)) await close();
    await server.close();
  });

  it('snap7: CTRead/TMRead/CTWrite by number, and a timer asked as BYTE at a bit address gets "address out of range"', async () => {
    const { call, close } = await snap7Client(port, { rack: 0, slot: 2 });
    closers.push(async () => close());
    expect((await call('CTRead', 5, 2)).toString('hex')).to.equal('01050106');
    expect((await call('TMRead', 13, 1)).toString('hex')).to.equal('0042');
    await call('CTWrite', 7, 1, Buffer.from([0x09, 0x99]));
    expect(server.memory.area('C').readUInt16BE(7 * 2)).to.equal(0x0999);
    // What python-snap7's read_area did before its fix #121 (gijzelaerr/python-snap7#62): WordLen BYTE, Start 13 → bit address 104.
    const err = await call('ReadArea', C.S7AreaTM, 0, 13, 2, C.S7WLByte).then(
      () => undefined,
      (e) => e,
    );
    expect(err && err.message).to.match(/address out of range/i);
  });

  it('nodes7 0.3.18 reads C and T with its octet-string check, and sends the number × 8 as a real CPU would read it', async () => {
    const NodeS7 = peer('nodes7');
    const conn = new NodeS7({ silent: true });
    await new Promise((resolve, reject) =>
      conn.initiateConnection({ host: '127.0.0.1', port, rack: 0, slot: 2, timeout: 5000 }, (err) =>
        err ? reject(new Error(JSON.stringify(err))) : resolve(),
      ),
    );
    closers.push(() => new Promise((resolve) => conn.dropConnection(() => resolve())));
    conn.setTranslationCB((tag) => tag);
    conn.addItems(['C0', 'T0', 'C5']);
    const values = await new Promise((resolve, reject) =>
      conn.readAllItems((bad, v) => (bad ? reject(new Error(`bad quality: ${JSON.stringify(v)}`)) : resolve(v))),
    );
    // nodes7 decodes C/T words as plain integers; its "C5" goes out as address 40 (5 × 8), so it gets C40.
    expect(values).to.deep.equal({ C0: 0x0100, T0: 0x2123, C5: 0x0100 + 40 });
  });

  it('@st-one-io/nodes7 1.1.2 asks C with transport size 0x09 and is refused with "invalid address" (0x05)', async () => {
    const { S7Endpoint, S7ItemGroup } = peer('@st-one-io/nodes7');
    const plc = new S7Endpoint({ host: '127.0.0.1', port, rack: 0, slot: 2, autoReconnect: 0, s7ConnOpts: { timeout: 5000 } });
    plc.on('error', () => undefined);
    const connected = once(plc, 'connect');
    await plc.connect();
    await connected;
    closers.push(() => plc.disconnect());
    const refused = waitForRequest(server);
    const group = new S7ItemGroup(plc);
    group.addItems(['C5']);
    const err = await group.readAllItems().then(
      () => undefined,
      (e) => e,
    );
    expect(await refused).to.include({ kind: 'read', items: 1 });
    expect(err && err.message).to.match(/Invalid address/);
  });
});

function waitForRequest(server) {
  return new Promise((resolve) => server.once('request', resolve));
}
