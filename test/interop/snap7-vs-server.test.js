'use strict';
// snap7's client (an independent implementation) against our S7Server.
const { expect } = require('chai');
const support = require('./support');
const { snap7, snap7Client, eventWithin } = support;

const C = snap7.S7Client.prototype; // area and word-length constants

describe('interop: snap7 client against our S7Server', function () {
  let server;
  let port;
  const clients = [];

  async function start(options = {}) {
    server = new support.plcwire.S7Server({ port: 0, ...options });
    port = await server.listen();
  }
  async function client(opts) {
    const c = await snap7Client(port, opts);
    clients.push(c);
    return c;
  }

  afterEach(async () => {
    for (const c of clients.splice(0)) c.close();
    if (server) await server.close();
    server = undefined;
  });

  it('negotiates the PDU size the profile offers (S7-1200: 240)', async () => {
    await start({ profile: 's7-1200' });
    const { client: c } = await client();
    expect(c.PDULength()).to.equal(240);
  });

  it('answers snap7 its own requested PDU (480) when the profile offers more (S7-1500)', async () => {
    await start({ profile: 's7-1500' });
    const { client: c } = await client();
    expect(c.PDULength()).to.equal(480);
  });

  it('DBRead returns the memory, DBWrite changes it', async () => {
    await start();
    const db1 = server.memory.area('DB', 1);
    db1.writeInt16BE(1234, 2);
    db1.writeFloatBE(3.5, 4);
    const { call } = await client();
    const data = await call('DBRead', 1, 0, 8);
    expect(data.toString('hex')).to.equal('000004d240600000');
    await call('DBWrite', 1, 16, 4, Buffer.from('cafebabe', 'hex'));
    expect(db1.subarray(16, 20).toString('hex')).to.equal('cafebabe');
  });

  it('DBRead of a whole 1024-byte DB arrives through several jobs at PDU 240', async () => {
    await start({ profile: 's7-1200' });
    const db1 = server.memory.area('DB', 1);
    for (let i = 0; i < db1.length; i++) db1[i] = (i * 13) & 0xff;
    const { call } = await client();
    const data = await call('DBRead', 1, 0, 1024);
    expect(data.equals(db1)).to.equal(true);
  });

  it('ReadMultiVars reads DB, M, I, Q, counters and timers in one request', async () => {
    await start();
    const mem = server.memory;
    mem.area('DB', 2).write('plc', 10, 'latin1');
    mem.area('M').writeUInt16BE(0xabcd, 4);
    mem.area('I')[1] = 0x81;
    mem.area('Q')[0] = 0x7e;
    mem.area('C').writeUInt16BE(0x0123, 2 * 3); // C3
    mem.area('T').writeUInt16BE(0x2456, 2 * 5); // T5
    const { call } = await client();
    const r = await call('ReadMultiVars', [
      { Area: C.S7AreaDB, WordLen: C.S7WLByte, DBNumber: 2, Start: 10, Amount: 3 },
      { Area: C.S7AreaMK, WordLen: C.S7WLByte, DBNumber: 0, Start: 4, Amount: 2 },
      { Area: C.S7AreaPE, WordLen: C.S7WLByte, DBNumber: 0, Start: 1, Amount: 1 },
      { Area: C.S7AreaPA, WordLen: C.S7WLByte, DBNumber: 0, Start: 0, Amount: 1 },
      { Area: C.S7AreaCT, WordLen: C.S7WLCounter, DBNumber: 0, Start: 3, Amount: 1 },
      { Area: C.S7AreaTM, WordLen: C.S7WLTimer, DBNumber: 0, Start: 5, Amount: 1 },
    ]);
    expect(r.map((x) => x.Result)).to.deep.equal([0, 0, 0, 0, 0, 0]);
    expect(r.map((x) => x.Data.toString('hex'))).to.deep.equal(['706c63', 'abcd', '81', '7e', '0123', '2456']);
  });

  it('ReadMultiVars fails only the item of a missing DB', async () => {
    await start();
    server.memory.area('DB', 1)[0] = 42;
    const { call } = await client();
    const r = await call('ReadMultiVars', [
      { Area: C.S7AreaDB, WordLen: C.S7WLByte, DBNumber: 1, Start: 0, Amount: 1 },
      { Area: C.S7AreaDB, WordLen: C.S7WLByte, DBNumber: 999, Start: 0, Amount: 1 },
      { Area: C.S7AreaDB, WordLen: C.S7WLByte, DBNumber: 1, Start: 5000, Amount: 2 },
    ]);
    expect(r[0].Result).to.equal(0);
    expect([...r[0].Data]).to.deep.equal([42]);
    expect(r[1].Result).to.not.equal(0);
    expect(r[2].Result).to.not.equal(0);
  });

  it('WriteMultiVars writes several areas in one request', async () => {
    await start();
    const { call } = await client();
    const r = await call('WriteMultiVars', [
      { Area: C.S7AreaDB, WordLen: C.S7WLByte, DBNumber: 3, Start: 100, Amount: 3, Data: Buffer.from('010203', 'hex') },
      { Area: C.S7AreaMK, WordLen: C.S7WLByte, DBNumber: 0, Start: 7, Amount: 1, Data: Buffer.from('ff', 'hex') },
      { Area: C.S7AreaPA, WordLen: C.S7WLByte, DBNumber: 0, Start: 2, Amount: 2, Data: Buffer.from('1234', 'hex') },
    ]);
    expect(r.map((x) => x.Result)).to.deep.equal([0, 0, 0]);
    expect(server.memory.area('DB', 3).subarray(100, 103).toString('hex')).to.equal('010203');
    expect(server.memory.area('M')[7]).to.equal(0xff);
    expect(server.memory.area('Q').readUInt16BE(2)).to.equal(0x1234);
  });

  it('ReadArea and WriteArea of single bits touch only that bit', async () => {
    await start();
    const db1 = server.memory.area('DB', 1);
    db1[10] = 0b0000_1000; // DBX10.3
    const { call } = await client();
    const bit = await call('ReadArea', C.S7AreaDB, 1, 10 * 8 + 3, 1, C.S7WLBit);
    expect([...bit]).to.deep.equal([1]);
    const clear = await call('ReadArea', C.S7AreaDB, 1, 10 * 8 + 2, 1, C.S7WLBit);
    expect([...clear]).to.deep.equal([0]);
    await call('WriteArea', C.S7AreaDB, 1, 10 * 8 + 6, 1, C.S7WLBit, Buffer.of(1));
    expect(db1[10]).to.equal(0b0100_1000);
    await call('WriteArea', C.S7AreaDB, 1, 10 * 8 + 3, 1, C.S7WLBit, Buffer.of(0));
    expect(db1[10]).to.equal(0b0100_0000);
  });

  it('reports the request to observers and serves several snap7 clients at once', async () => {
    await start();
    const seen = eventWithin(server, 'request', 5000);
    const a = await client();
    const b = await client();
    const c = await client();
    expect(server.connectionCount).to.equal(3);
    server.memory.area('DB', 1).writeUInt32BE(0x01020304, 0);
    const reads = await Promise.all([a, b, c].map((x) => x.call('DBRead', 1, 0, 4)));
    for (const d of reads) expect(d.toString('hex')).to.equal('01020304');
    await seen;
  });

  it('our client and snap7 see each other’s writes through the simulator', async () => {
    await start();
    server.memory.area('DB', 4)[4] = 8; // the PLC program declared a STRING[8] there
    const { call } = await client();
    const plc = await support.plcwire.connect(`s7://127.0.0.1:${port}?rack=0&slot=1`);
    try {
      await plc.write({ 'DB4,REAL0': 2.5, 'DB4,S4.8': 'snap' });
      const data = await call('DBRead', 4, 0, 10);
      expect(data.readFloatBE(0)).to.equal(2.5);
      expect(data.subarray(4, 10).toString('hex')).to.equal('0804' + Buffer.from('snap').toString('hex'));
      await call('DBWrite', 4, 0, 4, Buffer.from([0x40, 0x40, 0, 0]));
      expect((await plc.read(['DB4,REAL0']))['DB4,REAL0']).to.equal(3);
    } finally {
      await plc.close();
    }
  });
});
