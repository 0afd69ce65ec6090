'use strict';
// Our S7 client against snap7's server (an independent implementation).
// snap7's server serves at most 20 items per job (it answers the first 20
// of a longer read as if that were all; a longer write overruns its table):
// the client sends 20 by default, and learns the limit from a short answer.
const net = require('node:net');
const { expect } = require('chai');
const support = require('./support');
const { startSnap7Server, eventWithin } = support;
const { CountingProxy, FrameCounter } = require('../../bench/lib/proxy');

/** A read ack with its fill bytes zeroed: snap7 leaves whatever its answer buffer held there (the protocol gives them no value). */
function withoutFill(frame) {
  const out = Buffer.from(frame);
  const count = out[20];
  let p = 21;
  for (let i = 0; i < count && p + 4 <= out.length; i++) {
    const len = out[p] === 0xff ? (out.readUInt16BE(p + 2) + 7) >> 3 : 0; // BYTE data: length in bits
    p += 4 + len;
    if (len & 1 && i < count - 1) out[p++] = 0;
  }
  return out;
}

/** One raw job on a fresh S7 connection (rack 0, slot 1, PDU 960): the answer frame as the server sent it. */
function rawJob(port, job) {
  const { s7 } = support.plcwire;
  return new Promise((resolve, reject) => {
    const socket = net.connect(port, '127.0.0.1');
    let stage = 0;
    const frames = new FrameCounter((f) => {
      stage++;
      if (stage === 1) socket.write(s7.encodeSetupCommunication(0, { maxAmqCalling: 1, maxAmqCalled: 1, pduSize: 960 }));
      else if (stage === 2) socket.write(job);
      else {
        socket.destroy();
        resolve(Buffer.from(f));
      }
    });
    socket.on('connect', () =>
      socket.write(s7.encodeConnectionRequest({ sourceRef: 1, callingTsap: 0x0100, calledTsap: 0x0101, tpduSize: 0x0a })),
    );
    socket.on('data', (d) => frames.push(d));
    socket.on('error', reject);
  });
}

function memory() {
  const db1 = Buffer.alloc(1024);
  db1.writeInt16BE(1234, 2);
  db1.writeFloatBE(3.5, 4);
  db1.writeInt32BE(-100000, 8);
  db1[12] = 0b0000_0100; // DB1.DBX12.2
  db1[20] = 10; // STRING[10] at 20: max length, current length, chars
  db1[21] = 5;
  db1.write('hello', 22, 'latin1');
  for (let i = 0; i < 5; i++) db1.writeFloatBE(i + 0.25, 40 + 4 * i);
  db1.writeBigInt64BE(-(2n ** 40n), 64);
  db1.writeDoubleBE(Math.PI, 72);
  for (let i = 0; i < 300; i++) db1[100 + i] = i & 0xff;
  db1[420] = 10; // a STRING[10] the PLC program declared, still empty
  const db2 = Buffer.alloc(256);
  db2.writeUInt16BE(0xbeef, 0);
  const MK = Buffer.alloc(256);
  MK.writeInt16BE(-7, 10);
  MK[3] = 0b0000_0010; // M3.1
  const PE = Buffer.alloc(64);
  PE[0] = 0x5a;
  const PA = Buffer.alloc(64);
  PA.writeUInt16BE(0x1234, 2);
  const db3 = Buffer.alloc(4096);
  db3[0] = 254; // a STRING[254] the PLC program declared, still empty
  for (let i = 0; i < 100; i++) db3[1000 + 30 * i] = i;
  return { db: { 1: db1, 2: db2, 3: db3 }, MK, PE, PA };
}

describe('interop: our S7Client against snap7 server', function () {
  let peer;
  let plc;

  // One snap7 server for the file: node-snap7 aborts the process (a libuv
  // handle closed twice) after several servers were created and stopped.
  // Each test starts from fresh area contents instead.
  before(async () => {
    peer = await startSnap7Server(memory());
  });
  after(() => peer.stop());
  beforeEach(async () => {
    peer.reset(memory());
    plc = await support.plcwire.connect(`s7://127.0.0.1:${peer.port}?rack=0&slot=1&pdu=240&timeout=5000`);
  });
  afterEach(async () => {
    if (plc) await plc.close();
    plc = undefined;
  });

  it('reads scalars, bits, strings and arrays from DB, M, I and Q in one call', async () => {
    const v = await plc.read([
      'DB1,INT2',
      'DB1.DBD4:REAL',
      'DB1,DINT8',
      'DB1,X12.2',
      'DB1,X12.3',
      'DB1,S20.10',
      'DB1,REAL40.5',
      'DB1.DBB64:LINT',
      'DB1,LREAL72',
      'DB2,WORD0',
      'MW10',
      'M3.1',
      'IB0',
      'QW2',
    ]);
    expect(v).to.deep.equal({
      'DB1,INT2': 1234,
      'DB1.DBD4:REAL': 3.5,
      'DB1,DINT8': -100000,
      'DB1,X12.2': true,
      'DB1,X12.3': false,
      'DB1,S20.10': 'hello',
      'DB1,REAL40.5': [0.25, 1.25, 2.25, 3.25, 4.25],
      'DB1.DBB64:LINT': -(2n ** 40n),
      'DB1,LREAL72': Math.PI,
      'DB2,WORD0': 0xbeef,
      MW10: 0xfff9, // MW is a WORD (unsigned), as in nodes7
      'M3.1': true,
      IB0: 0x5a,
      QW2: 0x1234,
    });
  });

  it('writes every type it reads, and snap7 holds the bytes', async () => {
    await plc.write({
      'DB1,INT400': -2,
      'DB1,REAL404': 1.5,
      'DB1,S420.10': 'abc',
      'DB1,DINT440.2': [7, -8],
      MW20: 99,
    });
    const db1 = peer.db(1);
    expect(db1.readInt16BE(400)).to.equal(-2);
    expect(db1.readFloatBE(404)).to.equal(1.5);
    // STRING keeps the declared max length (10) and sets the current length.
    expect(db1.subarray(420, 425).toString('hex')).to.equal('0a03616263');
    expect(db1.readInt32BE(440)).to.equal(7);
    expect(db1.readInt32BE(444)).to.equal(-8);
    expect(peer.area('MK').readInt16BE(20)).to.equal(99);
  });

  it('writes single bits without touching the neighbouring bits', async () => {
    await plc.write({ 'DB1,X12.0': true, 'DB1,X12.2': false, 'M3.7': true });
    expect(peer.db(1)[12]).to.equal(0b0000_0001);
    expect(peer.area('MK')[3]).to.equal(0b1000_0010);
  });

  it('reports a missing DB and an out-of-range address per tag, and still returns the good tags', async () => {
    const r = await plc.readDetailed(['DB1,INT2', 'DB99,INT0', 'DB2,INT1000', 'MW10']);
    expect(r['DB1,INT2']).to.deep.equal({ ok: true, value: 1234 });
    expect(r.MW10).to.deep.equal({ ok: true, value: 65529 }); // MW is a WORD (unsigned); -7 as INT is MW10:INT
    expect(r['DB99,INT0'].ok).to.equal(false);
    expect(r['DB99,INT0'].error.code).to.equal('OBJECT_DOES_NOT_EXIST');
    expect(r['DB99,INT0'].error.message).to.contain('DB99,INT0');
    expect(r['DB2,INT1000'].ok).to.equal(false);
    expect(r['DB2,INT1000'].error.code).to.equal('ADDRESS_OUT_OF_RANGE');
  });

  it('sends 100 scattered tags in requests of at most 19 items, and every value is right', async () => {
    const proxy = new CountingProxy(peer.port);
    const port = await proxy.listen();
    const viaProxy = await support.plcwire.connect(`s7://127.0.0.1:${port}?rack=0&slot=1&pdu=240&timeout=5000`);
    try {
      // 30 bytes apart: too far to merge into one range, so each tag is an item.
      const addresses = Array.from({ length: 100 }, (_, i) => `DB3,BYTE${1000 + 30 * i}`);
      proxy.reset();
      const v = await viaProxy.read(addresses);
      addresses.forEach((a, i) => expect(v[a], a).to.equal(i));
      expect(proxy.items, 'items sent').to.be.greaterThan(20);
      expect(proxy.maxItemsPerJob).to.be.within(1, 19);
      expect(proxy.readJobs).to.be.at.least(Math.ceil(proxy.items / 19));
    } finally {
      await viaProxy.close();
      await proxy.close();
    }
  });

  describe('more separate tags than snap7 serves in one job (20), at PDU 960', () => {
    let proxy;
    let wide;
    /** Tags 30 bytes apart in DB3 (too far apart to share an item cheaply); DB3,BYTE(1000 + 30i) holds i. */
    const separate = (n) => Array.from({ length: n }, (_, i) => `DB3,BYTE${1000 + 30 * i}`);
    beforeEach(async () => {
      proxy = new CountingProxy(peer.port);
      const port = await proxy.listen();
      wide = (query = '') => support.plcwire.connect(`s7://127.0.0.1:${port}?timeout=5000${query}`);
    });
    afterEach(() => proxy.close());

    for (const n of [21, 60]) {
      it(`reads ${n} separate tags in jobs of at most 20 items, every value right`, async () => {
        const c = await wide();
        try {
          expect(c.pduSize).to.equal(960);
          proxy.reset();
          const v = await c.read(separate(n));
          separate(n).forEach((a, i) => expect(v[a], a).to.equal(i));
          expect(proxy.maxItemsPerJob).to.be.within(1, 20);
        } finally {
          await c.close();
        }
      });
    }

    it('writes 30 separate items in jobs of at most 20: snap7 holds every value and still serves', async () => {
      const c = await wide();
      try {
        const values = Object.fromEntries(separate(30).map((a, i) => [a, 200 + i]));
        proxy.reset();
        await c.write(values);
        expect(proxy.writeJobs).to.equal(2);
        expect(proxy.maxItemsPerJob).to.be.within(1, 20);
        const db3 = peer.db(3);
        separate(30).forEach((a, i) => expect(db3[1000 + 30 * i], a).to.equal(200 + i));
      } finally {
        await c.close();
      }
      // The server process is still there and answers a new connection.
      const again = await wide();
      try {
        expect(await again.read(['DB3,BYTE1000'])).to.deep.equal({ 'DB3,BYTE1000': 200 });
      } finally {
        await again.close();
      }
    });

    it("told maxItems=60, the client learns snap7's 20 from its answer: itemLimit event, and that poll returns every value", async () => {
      const c = await wide('&maxItems=60');
      try {
        const learnt = eventWithin(c, 'itemLimit', 5000);
        proxy.reset();
        const v = await c.read(separate(60));
        separate(60).forEach((a, i) => expect(v[a], a).to.equal(i));
        const [event] = await learnt;
        expect(event).to.deep.equal({ limit: 20, was: 60 });
        expect(c.maxItems).to.equal(20);
        proxy.reset();
        await c.read(separate(60));
        expect(proxy.maxItemsPerJob).to.be.within(1, 20);
      } finally {
        await c.close();
      }
    });

    it("our simulator with maxItems 20 answers a read of 21 items byte for byte as snap7's server does (fill bytes aside)", async () => {
      const { s7, S7Server } = support.plcwire;
      const items = separate(21).map((_, i) => ({ area: 0x84, dbNumber: 3, transportSize: 0x02, count: 1, address: (1000 + 30 * i) * 8 }));
      const job = s7.encodeReadRequest(7, items);
      const sim = new S7Server({ port: 0, maxItems: 20, layout: { dataBlocks: { 3: 4096 } } });
      await sim.listen();
      try {
        sim.memory.area('DB', 3).set(peer.db(3));
        const theirs = await rawJob(peer.port, job);
        const ours = await rawJob(sim.port, job);
        // A read ack of the first 20 items (item count 0x14), as if the job had been those alone.
        expect(theirs[20]).to.equal(0x14);
        expect(withoutFill(ours).toString('hex')).to.equal(withoutFill(theirs).toString('hex'));
      } finally {
        await sim.close();
      }
    });
  });

  it('splits an array larger than one PDU into several jobs', async () => {
    const v = await plc.read(['DB1,BYTE100.300']);
    expect(v['DB1,BYTE100.300']).to.deep.equal(Array.from({ length: 300 }, (_, i) => i & 0xff));
    const bytes = Array.from({ length: 600 }, (_, i) => (i * 7) & 0xff);
    await plc.write({ 'DB1,BYTE400.600': bytes });
    expect([...peer.db(1).subarray(400, 1000)]).to.deep.equal(bytes);
  });

  it('reads and writes a STRING[254] across several jobs at PDU 240', async () => {
    const text = 'x'.repeat(200) + 'y'.repeat(54);
    await plc.write({ 'DB3,S0.254': text });
    const db3 = peer.db(3);
    expect(db3[0]).to.equal(254);
    expect(db3[1]).to.equal(254);
    expect(db3.subarray(2, 256).toString('latin1')).to.equal(text);
    expect((await plc.read(['DB3,S0.254']))['DB3,S0.254']).to.equal(text);
  });
});
