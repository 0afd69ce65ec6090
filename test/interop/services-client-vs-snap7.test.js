'use strict';
// Our S7Client's system services against snap7's server (an independent
// implementation), checked against what snap7's own client reads from the
// same server.
//
// What snap7's server implements, found by running each function: SZL reads
// from canned lists of a real CPU 315-2 PN/DP (0x0424 with its live RUN/STOP
// status and clock), read clock (the host's local time), set clock (accepted,
// the clock does not change), list blocks and the list of DBs, block info of
// DBs, PLC stop/hot start/cold start (the status follows), and the password
// (always accepted). What it lacks: upload (always "protection level"
// 0xD241), block info of anything but a DB (its answer's data length field
// says 4 while 82 bytes follow: a malformed frame), lists of other block
// types (0xD20E, none), a diagnostic buffer other than its canned one, and
// multi-part answers (a list longer than the PDU is cut, not continued).
const { expect } = require('chai');
const support = require('./support');
const { startSnap7Server, snap7Client } = support;

describe('interop: system services of our S7Client against snap7 server', function () {
  this.timeout(15000);
  let snap;
  let peer;
  let client;

  // One snap7 server (and one snap7 client) for the file: node-snap7 aborts the process (a libuv
  // handle closed twice) after several servers were created and stopped (see client-vs-snap7).
  before(async () => {
    snap = await startSnap7Server({ db: { 1: Buffer.alloc(64), 3: Buffer.from(Array.from({ length: 300 }, (_, i) => i & 0xff)) } });
    peer = await snap7Client(snap.port, { rack: 0, slot: 2 });
  });
  after(() => {
    peer.close();
    snap.stop();
  });
  beforeEach(async () => {
    const { S7Client, parseUrl } = support.plcwire;
    client = new S7Client(parseUrl(`s7://127.0.0.1:${snap.port}?slot=2&control=true&timeout=3000`));
    await client.connect();
  });
  afterEach(async () => {
    await client.close();
    // Every test leaves snap7's CPU in RUN.
    snap.server.SetCpuStatus(0x08);
  });

  it('the SZL ID list equals snap7 ReadSZLList', async () => {
    const ids = support.plcwire.decodeSzlIds(await client.readSzl(0));
    expect(ids).to.deep.equal(await peer.call('ReadSZLList'));
    expect(ids.length).to.be.above(50);
  });

  it('SZL 0x0011 records equal the bytes snap7 ReadSZL returns (after its 4-byte header, which it turns little-endian)', async () => {
    const list = await client.readSzl(0x0011, 0);
    const raw = await peer.call('ReadSZL', 0x0011, 0);
    expect([raw.readUInt16LE(0), raw.readUInt16LE(2)]).to.deep.equal([list.recordLength, list.records.length]);
    expect(Buffer.concat(list.records).equals(raw.subarray(4))).to.equal(true);
  });

  it('identity: order code, names and serial number equal snap7 GetOrderCode / GetCpuInfo', async () => {
    const info = await client.info();
    const order = await peer.call('GetOrderCode');
    const cpu = await peer.call('GetCpuInfo');
    expect(info.orderCode).to.equal(order.Code.trim());
    expect(info).to.deep.include({
      moduleTypeName: cpu.ModuleTypeName,
      serialNumber: cpu.SerialNumber,
      asName: cpu.ASName,
      moduleName: cpu.ModuleName,
      copyright: cpu.Copyright,
    });
    // snap7's client takes the version from the last record of the list, here the boot loader's
    // (index 0x81: 'A' 32.9.9); the firmware record (index 7) says V3.2.6, which is what we report.
    expect([order.V1, order.V2, order.V3]).to.deep.equal([32, 9, 9]);
    expect(info.firmware).to.equal('V3.2.6');
    expect(info.hardwareVersion).to.equal(4);
  });

  it('communication capabilities (SZL 0x0131 index 1) equal snap7 GetCpInfo', async () => {
    const c = support.plcwire.decodeCommunication(await client.readSzl(0x0131, 1));
    const cp = await peer.call('GetCpInfo');
    expect(c).to.deep.equal({ maxPdu: cp.MaxPduLength, maxConnections: cp.MaxConnections, mpiRate: cp.MaxMpiRate, busRate: cp.MaxBusRate });
  });

  it('protection (SZL 0x0232 index 4) equals snap7 GetProtection', async () => {
    const p = (await client.info()).protection;
    const g = await peer.call('GetProtection');
    expect([p.switchLevel, p.configuredLevel, p.level, p.keySwitch, p.startupSwitch]).to.deep.equal([
      g.sch_schal,
      g.sch_par,
      g.sch_rel,
      'RUN-P',
      undefined,
    ]);
    expect(g.bart_sch).to.equal(2);
  });

  it('the CPU state follows our stop and hot start, as snap7 PlcStatus and the server see it', async () => {
    expect((await client.cpuState()).mode).to.equal('RUN');
    await client.stop();
    expect((await client.cpuState()).mode).to.equal('STOP');
    expect(await peer.call('PlcStatus')).to.equal(0x04);
    expect(snap.server.GetCpuStatus()).to.equal(0x04);
    await client.hotStart();
    expect((await client.cpuState()).mode).to.equal('RUN');
    expect(await peer.call('PlcStatus')).to.equal(0x08);
  });

  it("the clock: snap7's server answers the host's local time; readClock({ timeZone: 'local' }) gives it", async () => {
    const ours = await client.readClock({ timeZone: 'local' });
    expect(Math.abs(ours.getTime() - Date.now())).to.be.below(2500);
    // node-snap7 turns the fields into a Date with mktime on a tm whose DST flag it never sets, so its
    // result can be whole hours off: compare minutes and seconds.
    const theirs = await peer.call('GetPlcDateTime');
    const diff = Math.abs(ours.getTime() - theirs.getTime()) % 3_600_000;
    expect(Math.min(diff, 3_600_000 - diff)).to.be.below(2500);
    // Set clock is accepted (and ignored) by snap7's server.
    await client.setClock(new Date());
  });

  it('block counts, the DB list and block info of a DB equal snap7 ListBlocks / ListBlocksOfType / GetAgBlockInfo', async () => {
    const counts = await client.listBlocks();
    const theirs = await peer.call('ListBlocks');
    expect(counts).to.deep.equal({
      OB: theirs.OBCount,
      FB: theirs.FBCount,
      FC: theirs.FCCount,
      DB: theirs.DBCount,
      SDB: theirs.SDBCount,
      SFC: theirs.SFCCount,
      SFB: theirs.SFBCount,
    });
    expect(await client.listBlocksOfType('DB')).to.deep.equal(await peer.call('ListBlocksOfType', 0x41));
    expect(await client.listBlocksOfType('OB')).to.deep.equal([]);
    const info = await client.blockInfo('DB', 3);
    const bi = await peer.call('GetAgBlockInfo', 0x41, 3);
    expect(info).to.deep.include({
      number: bi.BlkNumber,
      languageCode: bi.BlkLang,
      flags: bi.BlkFlags,
      mc7Size: bi.MC7Size,
      dataLength: 300,
      loadSize: bi.LoadSize,
      localDataSize: bi.LocalData,
      sbbLength: bi.SBBLength,
      checksum: bi.CheckSum,
    });
    expect(info.codeTime.toISOString().slice(0, 10).replace(/-/g, '/')).to.equal(bi.CodeDate);
  });

  it('readDb equals snap7 DBGet', async () => {
    const ours = await client.readDb(3);
    expect(ours.equals(await peer.call('DBGet', 3))).to.equal(true);
    expect(ours.equals(snap.db(3))).to.equal(true);
  });

  it('the diagnostic buffer: the canned entries of the real CPU, with their 1994 time stamps', async () => {
    const entries = await client.diagnosticBuffer();
    expect(entries.length).to.equal(10);
    expect(entries[0]).to.deep.include({ eventId: 0x4302, description: 'Mode transition STARTUP to RUN', ob: 0x68 });
    expect(entries[0].time.toISOString()).to.equal('1994-02-04T23:52:16.388Z');
    // snap7 has no "n most recent" list (0x01A0): max falls back to the whole buffer, cut here.
    expect((await client.diagnosticBuffer({ max: 3 })).map((e) => e.eventId)).to.deep.equal(entries.slice(0, 3).map((e) => e.eventId));
  });

  it('what snap7 lacks is a typed error: upload ACCESS_DENIED, a missing SZL SZL_NOT_AVAILABLE, block info of an OB a PROTOCOL_ERROR (its malformed answer)', async () => {
    expect(await client.uploadBlock('DB', 3).catch((e) => e.code)).to.equal('ACCESS_DENIED');
    await peer.call('FullUpload', 0x41, 3, 1000).then(
      () => expect.fail('snap7 uploaded'),
      (e) => expect(e.message).to.match(/protection level/),
    );
    expect(await client.readSzl(0x0d91, 5).catch((e) => e.code)).to.equal('SZL_NOT_AVAILABLE');
    await client.setPassword('anything');
    expect(await client.blockInfo('OB', 1).catch((e) => e.code)).to.equal('PROTOCOL_ERROR');
    // The link comes back (the client reconnects) and serves again.
    await support.eventWithin(client, 'connected', 5000);
    expect((await client.cpuState()).mode).to.equal('RUN');
  });

  it('at PDU 240 snap7 cuts a list longer than the PDU instead of sending more parts: PROTOCOL_ERROR naming the shortfall', async () => {
    const { S7Client, parseUrl } = support.plcwire;
    const small = new S7Client(parseUrl(`s7://127.0.0.1:${snap.port}?slot=2&pdu=240&timeout=3000`));
    try {
      await small.connect();
      expect(small.pduSize).to.equal(240);
      const err = await small.readSzl(0).catch((e) => e);
      expect(err.code).to.equal('PROTOCOL_ERROR');
      expect(err.message).to.match(/SZL 0x0000 index 0x0000 announces 112 records of 2 bytes, 206 bytes arrived/);
    } finally {
      await small.close();
    }
  });
});
