'use strict';
// snap7's client (an independent implementation) runs its whole
// system-function surface against our S7Server: every call succeeds and its
// values agree with the simulator's state and with what a Read Var reads.
const { expect } = require('chai');
const support = require('./support');
const { snap7Client } = support;

describe('interop: snap7 client system functions against our S7Server', function () {
  this.timeout(15000);
  let server;
  let port;
  const clients = [];

  async function start(options = {}) {
    server = new support.plcwire.S7Server({ port: 0, profile: 's7-300', ...options });
    port = await server.listen();
  }
  async function client() {
    const c = await snap7Client(port, { rack: 0, slot: 2 });
    clients.push(c);
    return c;
  }

  afterEach(async () => {
    for (const c of clients.splice(0)) c.close();
    if (server) await server.close();
    server = undefined;
  });

  it('GetCpuInfo, GetOrderCode and GetCpInfo give the profile identity and the negotiated PDU', async () => {
    await start();
    const { call, client: c } = await client();
    const id = support.plcwire.S7_IDENTITIES['s7-300'];
    const cpu = await call('GetCpuInfo');
    // snap7 returns the fixed-width fields as they are; the simulator pads them with NULs, as a CPU does.
    expect(cpu).to.deep.equal({
      ModuleTypeName: id.moduleTypeName,
      SerialNumber: id.serialNumber,
      ASName: id.asName,
      Copyright: id.copyright,
      ModuleName: id.moduleName,
    });
    expect(await call('GetOrderCode')).to.deep.equal({ Code: `${id.orderCode} `, V1: 3, V2: 2, V3: 6 });
    expect(await call('GetCpInfo')).to.deep.include({ MaxPduLength: c.PDULength(), MaxConnections: 16 });
  });

  it('ReadSZLList lists what ReadSZL then reads; ReadSZL of the diagnostic buffer arrives whole in several parts at PDU 240', async () => {
    await start();
    for (let i = 0; i < 10; i++) {
      server.stop();
      server.start();
    }
    const { call, client: c } = await client();
    expect(c.PDULength()).to.equal(240);
    const ids = await call('ReadSZLList');
    expect(ids).to.include.members([0x0011, 0x001c, 0x0131, 0x0232, 0x0424, 0x0074, 0x00a0]);
    const raw = await call('ReadSZL', 0x00a0, 0);
    // snap7 returns LENTHDR and N_DR (little-endian, its own conversion), then the records.
    expect([raw.readUInt16LE(0), raw.readUInt16LE(2)]).to.deep.equal([20, 43]);
    expect(raw.length).to.equal(4 + 43 * 20);
    const list = {
      id: 0xa0,
      index: 0,
      recordLength: 20,
      records: Array.from({ length: 43 }, (_, i) => raw.subarray(4 + i * 20, 24 + i * 20)),
    };
    const entries = support.plcwire.decodeDiagnosticBuffer(list);
    expect(entries.map((e) => [e.eventId, e.time.getTime()])).to.deep.equal(server.diagnostics.map((e) => [e.eventId, e.time.getTime()]));
  });

  it('PlcStatus follows PlcStop, PlcHotStart and PlcColdStart; each transition lands in the diagnostic buffer', async () => {
    await start();
    const { call } = await client();
    expect(await call('PlcStatus')).to.equal(0x08);
    await call('PlcStop');
    expect(server.state).to.equal('STOP');
    expect(await call('PlcStatus')).to.equal(0x04);
    await call('PlcStop').then(
      () => expect.fail('a second stop succeeded'),
      (e) => expect(e.message).to.match(/already/i),
    );
    await call('PlcHotStart');
    expect(await call('PlcStatus')).to.equal(0x08);
    await call('PlcStop');
    await call('PlcColdStart');
    expect(server.state).to.equal('RUN');
    expect(server.diagnostics.slice(0, 8).map((e) => e.eventId)).to.deep.equal([
      0x4302, 0x4301, 0x1385, 0x4304, 0x4302, 0x4301, 0x1381, 0x4304,
    ]);
  });

  it('SetPlcDateTime sets the simulator clock (the fields snap7 sends), GetPlcDateTime reads it back', async () => {
    await start();
    const { call } = await client();
    const target = new Date(2031, 6, 8, 9, 10, 11);
    await call('SetPlcDateTime', target);
    const fields = server.cpu.now();
    // snap7 sends the Date's local fields; the simulator keeps them as its clock's (UTC) fields.
    expect([
      fields.getUTCFullYear(),
      fields.getUTCMonth(),
      fields.getUTCDate(),
      fields.getUTCHours(),
      fields.getUTCMinutes(),
    ]).to.deep.equal([2031, 6, 8, 9, 10]);
    const back = await call('GetPlcDateTime');
    // node-snap7 converts with mktime on a tm whose DST flag it never sets: compare within the hour.
    const diff = Math.abs(back.getTime() - target.getTime()) % 3_600_000;
    expect(Math.min(diff, 3_600_000 - diff)).to.be.below(2500);
    // SetPlcSystemDateTime sends the host's local time fields: the clock then runs that far from UTC.
    await call('SetPlcSystemDateTime');
    expect(Math.abs(server.clockOffset + new Date().getTimezoneOffset() * 60_000)).to.be.below(2500);
  });

  it('ListBlocks, ListBlocksOfType (several parts at PDU 240) and GetAgBlockInfo agree with the memory layout', async () => {
    await start({ layout: { dbs: Object.fromEntries(Array.from({ length: 150 }, (_, i) => [String(i + 1), 10 + i])) } });
    const { call } = await client();
    expect(await call('ListBlocks')).to.deep.equal({
      OBCount: 8,
      FBCount: 1,
      FCCount: 2,
      SFBCount: 6,
      SFCCount: 8,
      DBCount: 150,
      SDBCount: 4,
    });
    expect(await call('ListBlocksOfType', 0x41)).to.deep.equal(Array.from({ length: 150 }, (_, i) => i + 1));
    expect(await call('ListBlocksOfType', 0x43)).to.deep.equal([1, 2]);
    const info = await call('GetAgBlockInfo', 0x41, 42);
    expect(info).to.deep.include({
      BlkType: 0x0a,
      BlkNumber: 42,
      BlkLang: 5,
      MC7Size: 51,
      LoadSize: 51 + 92,
      Author: 'PLCWIRE',
      Family: 'SIM',
      Header: 'DB42',
    });
    expect(await call('GetAgBlockInfo', 0x38, 1)).to.deep.include({ BlkType: 0x08, BlkNumber: 1, BlkLang: 1 });
  });

  it('DBGet equals a Read Var of the whole DB; FullUpload and Upload carry the same data', async () => {
    await start({ layout: { dbs: { 1: 700 } } });
    const db = server.memory.area('DB', 1);
    for (let i = 0; i < db.length; i++) db[i] = (i * 31) & 0xff;
    const { call } = await client();
    const got = await call('DBGet', 1);
    expect(got.equals(db)).to.equal(true);
    expect(got.equals(await call('DBRead', 1, 0, 700))).to.equal(true);
    const full = await call('FullUpload', 0x41, 1, 4096);
    expect(full.length).to.equal(700 + 92);
    expect(full.subarray(36, 36 + 700).equals(db)).to.equal(true);
    const body = await call('Upload', 0x41, 1, 4096);
    expect(body.equals(db)).to.equal(true);
  });

  it('GetProtection, SetSessionPassword and ClearSessionPassword follow the protection level; a protected CPU refuses stop until the password', async () => {
    await start();
    server.setProtection(2, 'secret');
    const { call } = await client();
    expect(await call('GetProtection')).to.deep.equal({ sch_schal: 1, sch_par: 2, sch_rel: 2, bart_sch: 2, anl_sch: 0 });
    await call('PlcStop').then(
      () => expect.fail('stop was allowed'),
      () => undefined,
    );
    expect(server.state).to.equal('RUN');
    await call('SetSessionPassword', 'wrong').then(
      () => expect.fail('a wrong password was taken'),
      (e) => expect(e.message).to.match(/password/i),
    );
    await call('SetSessionPassword', 'secret');
    expect((await call('GetProtection')).sch_rel).to.equal(1);
    await call('PlcStop');
    expect(server.state).to.equal('STOP');
    await call('ClearSessionPassword');
    expect((await call('GetProtection')).sch_rel).to.equal(2);
  });
});
