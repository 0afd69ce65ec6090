import { expect } from 'chai';
import { PlcError } from '../lib/errors';
import { S7Client } from '../lib/s7/client';
import { S7Server, type S7Profile, type S7RequestEvent } from '../lib/s7/server';
import { decodeLeds, decodeModuleIdentification, decodeSzlIds, SZL } from '../lib/s7/codec/szl';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { waitFor } from './support/wait';

const SLOT: Record<S7Profile, number> = { 's7-300': 2, 's7-400': 2, 's7-1200': 1, 's7-1500': 1, 's7-200': 1, logo: 1 };

async function rejection(p: Promise<unknown>): Promise<PlcError> {
  try {
    await p;
  } catch (err) {
    expect(err).to.be.instanceOf(PlcError);
    return err as PlcError;
  }
  throw new Error('expected a rejection');
}

describe('S7 system services: client against the simulator', function () {
  this.timeout(10000);
  const open: { close(): Promise<void> }[] = [];
  let requests: S7RequestEvent[];

  async function start(
    profile: S7Profile = 's7-300',
    query = '',
    layout?: Record<number, number>,
  ): Promise<{ server: S7Server; client: S7Client }> {
    const server = new S7Server({ port: 0, profile, ...(layout ? { layout: { dataBlocks: layout } } : {}) });
    await server.listen();
    open.push(server);
    requests = [];
    server.on('request', (r: S7RequestEvent) => requests.push(r));
    const client = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?slot=${SLOT[profile]}&timeout=2000${query}`) as S7Endpoint);
    open.unshift(client);
    await client.connect();
    return { server, client };
  }

  afterEach(async () => {
    for (const x of open.splice(0)) await x.close();
  });

  describe('identity', () => {
    it("info() of an S7-300: the profile's order code, firmware, names, RUN, protection 1, negotiated PDU/AmQ, the clock", async () => {
      const { client } = await start('s7-300', '&pdu=480');
      const info = await client.info();
      expect(info).to.deep.include({
        orderCode: '6ES7 315-2EH14-0AB0',
        firmware: 'V3.2.6',
        hardwareVersion: 4,
        moduleTypeName: 'CPU 315-2 PN/DP',
        serialNumber: 'S C-PW0000012019',
        asName: 'PLCWIRE-SIM',
        copyright: 'Original Siemens Equipment',
        state: 'RUN',
        pduSize: 240,
        maxJobs: 1,
      });
      expect(info.protection).to.deep.include({ level: 1, keySwitch: 'RUN-P' });
      expect(Math.abs(info.clock!.getTime() - Date.now())).to.be.below(2000);
    });

    it('an identity given to the server is what info() reads (S7-1500 profile)', async () => {
      const server = new S7Server({
        port: 0,
        profile: 's7-1500',
        identity: { asName: 'LINE 4 PRESS', serialNumber: 'S V-L4P000001', firmware: 'V3.1.0' },
      });
      await server.listen();
      open.push(server);
      const client = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}`) as S7Endpoint);
      open.unshift(client);
      await client.connect();
      expect(await client.info()).to.deep.include({
        asName: 'LINE 4 PRESS',
        serialNumber: 'S V-L4P000001',
        firmware: 'V3.1.0',
        orderCode: '6ES7 516-3AN02-0AB0',
        pduSize: 960,
      });
    });

    it('readSzl(0) lists the SZL IDs the CPU serves, and each of them reads', async () => {
      const { client } = await start('s7-1200');
      const ids = decodeSzlIds(await client.readSzl(SZL.IDS));
      expect(ids).to.include.members([0x0011, 0x001c, 0x0131, 0x0232, 0x0424, 0x0074, 0x00a0]);
      const index: Record<number, number> = { 0x0131: 1, 0x0232: 4, 0x0111: 1, 0x011c: 1, 0x01a0: 1 };
      for (const id of ids) {
        const list = await client.readSzl(id, index[id] ?? 0);
        expect(list.id, `0x${id.toString(16)}`).to.equal(id);
      }
      expect(decodeModuleIdentification(await client.readSzl(0x0111, 7)).firmware).to.equal('V4.7.0');
    });

    it('an SZL the CPU lacks is SZL_NOT_AVAILABLE naming the request, and the connection stays up', async () => {
      const { client } = await start('s7-1200');
      const err = await rejection(client.readSzl(0x0d91, 0));
      expect(err.code).to.equal('SZL_NOT_AVAILABLE');
      expect(err.message).to.match(/read SZL 0x0d91 index 0x0000: the PLC answered 0xd401/);
      expect((await rejection(client.readSzl(0x0131, 9))).code).to.equal('SZL_NOT_AVAILABLE');
      expect(await client.read(['DB1,INT0'])).to.deep.equal({ 'DB1,INT0': 0 });
      expect(client.state).to.equal('connected');
    });

    it('system services share the AmQ slots with polls: reads and info() at once on an S7-300 (AmQ 1) all succeed', async () => {
      const { server, client } = await start('s7-300');
      server.memory.area('DB', 1)!.writeInt16BE(4711, 0);
      const results = await Promise.all([
        client.read(['DB1,INT0']),
        client.info(),
        client.read(['DB1,INT0']),
        client.cpuState(),
        client.readClock(),
      ]);
      expect(results[0]).to.deep.equal({ 'DB1,INT0': 4711 });
      expect(results[2]).to.deep.equal({ 'DB1,INT0': 4711 });
      expect((results[3] as { mode: string }).mode).to.equal('RUN');
    });

    it('before connecting: NOT_CONNECTED, nothing sent', async () => {
      const server = new S7Server({ port: 0 });
      await server.listen();
      open.push(server);
      const client = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}`) as S7Endpoint);
      open.unshift(client);
      expect((await rejection(client.info())).code).to.equal('NOT_CONNECTED');
    });

    it('an aborted request rejects with ABORTED', async () => {
      const { client } = await start('s7-1500');
      const ac = new AbortController();
      ac.abort();
      expect((await rejection(client.readSzl(0x0011, 0, { signal: ac.signal }))).code).to.equal('ABORTED');
    });
  });

  describe('diagnostic buffer and multi-part answers', () => {
    it('at PDU 240 a 43-entry buffer comes in several parts; every entry arrives, newest first, with the event IDs of the transitions', async () => {
      const { server, client } = await start('s7-300', '&pdu=240');
      for (let i = 0; i < 10; i++) {
        server.stop();
        server.start(i % 2 ? 'cold' : 'warm');
      }
      requests.length = 0;
      const entries = await client.diagnosticBuffer();
      expect(entries.length).to.equal(43);
      // 43 × 20 bytes + 8 header in parts of 214 bytes: 5 parts, each a userdata request.
      expect(requests.filter((r) => r.kind === 'userdata').length).to.equal(5);
      expect(entries.map((e) => e.eventId).slice(0, 8)).to.deep.equal([0x4302, 0x4301, 0x1385, 0x4304, 0x4302, 0x4301, 0x1381, 0x4304]);
      expect(entries.map((e) => e.time.getTime())).to.deep.equal(server.diagnostics.map((e) => e.time.getTime()));
      expect(entries[3]!.description).to.match(/STOP by a programming device/);
    });

    it('diagnosticBuffer({ max: 2 }) reads the 2 most recent entries (SZL 0x01A0)', async () => {
      const { server, client } = await start('s7-1500');
      server.stop('io-error');
      const entries = await client.diagnosticBuffer({ max: 2 });
      expect(entries.map((e) => e.eventId)).to.deep.equal([0x4563, 0x4302]);
      expect((await rejection(client.diagnosticBuffer({ max: 0 }))).code).to.equal('INVALID_VALUE');
    });
  });

  describe('clock', () => {
    it('readClock follows the server clock offset; setClock moves it (UTC fields)', async () => {
      const { server, client } = await start('s7-1200', '&control=true');
      server.clockOffset = -3_600_000;
      expect(Math.abs((await client.readClock()).getTime() - (Date.now() - 3_600_000))).to.be.below(1500);
      const target = new Date('2031-07-08T09:10:11.120Z');
      await client.setClock(target);
      expect(Math.abs(server.clockOffset - (target.getTime() - Date.now()))).to.be.below(1500);
      const back = await client.readClock();
      expect(back.getTime() - target.getTime()).to.be.within(0, 1500);
    });

    it("{ timeZone: 'local' } writes and reads the host's local fields", async () => {
      const { server, client } = await start('s7-1200', '&control=true');
      const target = new Date(2030, 0, 2, 3, 4, 5, 600);
      await client.setClock(target, { timeZone: 'local' });
      const fields = server.cpu.now();
      expect([fields.getUTCHours(), fields.getUTCMinutes()]).to.deep.equal([3, 4]);
      expect((await client.readClock({ timeZone: 'local' })).getTime() - target.getTime()).to.be.within(0, 1500);
    });

    it('setClock is refused without control=true and on a read-only connection before anything is sent, and a date outside 1990..2089 is INVALID_VALUE', async () => {
      for (const query of ['', '&readOnly=true', '&control=true&readOnly=true']) {
        const { client } = await start('s7-1200', query);
        requests.length = 0;
        const err = await rejection(client.setClock(new Date()));
        expect(err.code, query).to.equal('WRITE_NOT_ALLOWED');
        expect(err.message, query).to.match(query.includes('readOnly') ? /read-only/ : /control=true/);
        expect(requests, query).to.deep.equal([]);
      }
      const rw = await start('s7-1200', '&control=true');
      expect((await rejection(rw.client.setClock(new Date('2100-01-01T00:00:00Z')))).code).to.equal('INVALID_VALUE');
    });
  });

  describe('CPU state and control', () => {
    it('stop/hotStart/coldStart are refused with WRITE_NOT_ALLOWED before anything is sent unless the URL says control=true', async () => {
      const { server, client } = await start('s7-300');
      requests.length = 0;
      for (const call of [() => client.stop(), () => client.hotStart(), () => client.coldStart()]) {
        const err = await rejection(call());
        expect(err.code).to.equal('WRITE_NOT_ALLOWED');
        expect(err.message).to.match(/control=true/);
      }
      expect(requests).to.deep.equal([]);
      expect(server.state).to.equal('RUN');
      const ro = await start('s7-300', '&control=true&readOnly=true');
      expect(await rejection(ro.client.stop())).to.deep.include({ code: 'WRITE_NOT_ALLOWED' });
      expect(ro.server.state).to.equal('RUN');
    });

    it('with control=true the state follows stop and start, STOP still serves reads, each transition is logged', async () => {
      const { server, client } = await start('s7-300', '&control=true');
      server.memory.area('DB', 2)!.writeUInt16BE(0xbeef, 0);
      const modes: string[] = [];
      server.on('mode', (m: string) => modes.push(m));
      await client.stop();
      expect(server.state).to.equal('STOP');
      expect(await client.cpuState()).to.deep.include({ mode: 'STOP', modeCode: 4, eventId: 0x4304 });
      expect(await client.read(['DB2,WORD0'])).to.deep.equal({ 'DB2,WORD0': 0xbeef });
      // Already in STOP: not an error, nothing changes.
      await client.stop();
      await client.hotStart();
      expect(await client.cpuState()).to.deep.include({ mode: 'RUN', eventId: 0x4302 });
      await client.stop();
      await client.coldStart();
      await client.hotStart();
      expect(modes).to.deep.equal(['STOP', 'RUN', 'STOP', 'RUN']);
      expect(server.diagnostics.slice(0, 4).map((e) => e.eventId)).to.deep.equal([0x4302, 0x4301, 0x1385, 0x4304]);
      expect((await client.diagnosticBuffer({ max: 1 }))[0]!.eventId).to.equal(0x4302);
    });

    it('a stop from the API with a cause logs that cause; cpuState() and the LEDs follow', async () => {
      const { server, client } = await start('s7-1500');
      expect(server.stop('time-error')).to.equal(true);
      expect(server.stop()).to.equal(false);
      expect(await client.cpuState()).to.deep.include({ mode: 'STOP', eventId: 0x4568 });
      const leds = decodeLeds(await client.readSzl(SZL.LEDS));
      expect(leds.filter((l) => l.on).map((l) => l.name)).to.deep.equal(['STOP']);
      expect(() => server.stop('nonsense' as never)).to.throw(TypeError);
      server.start();
      expect(
        decodeLeds(await client.readSzl(SZL.LEDS))
          .filter((l) => l.on)
          .map((l) => l.name),
      ).to.deep.equal(['RUN']);
    });
  });

  describe('blocks', () => {
    it('listBlocks counts a DB per data block of the layout; listBlocksOfType comes in parts at PDU 240 and lists them all', async () => {
      const layout = Object.fromEntries(Array.from({ length: 120 }, (_, i) => [i + 1, 16 + i]));
      const { client } = await start('s7-300', '&pdu=240', layout);
      const counts = await client.listBlocks();
      expect(counts).to.deep.include({ DB: 120, OB: 8, FC: 2 });
      requests.length = 0;
      const dbs = await client.listBlocksOfType('DB');
      expect(dbs).to.deep.equal(Array.from({ length: 120 }, (_, i) => i + 1));
      // 480 bytes of entries in parts of 212 (whole 4-byte entries): 3 requests.
      expect(requests.filter((r) => r.kind === 'userdata').length).to.equal(3);
      expect(await client.listBlocksOfType('OB')).to.deep.equal([1, 35, 80, 82, 86, 100, 121, 122]);
    });

    it("blockInfo of a DB gives the DB's true length; a missing block is OBJECT_DOES_NOT_EXIST", async () => {
      const { client } = await start('s7-400', '', { 1: 100, 7: 333 });
      expect(await client.blockInfo('DB', 7)).to.deep.include({
        type: 'DB',
        number: 7,
        mc7Size: 333,
        dataLength: 333,
        language: 'DB',
        name: 'DB7',
        author: 'PLCWIRE',
      });
      expect(await client.blockInfo('OB', 1)).to.deep.include({ type: 'OB', language: 'STL', dataLength: undefined });
      const err = await rejection(client.blockInfo('DB', 8));
      expect(err.code).to.equal('OBJECT_DOES_NOT_EXIST');
      expect(err.message).to.match(/block info of DB8/);
      expect((await rejection(client.blockInfo('XX' as never, 1))).code).to.equal('INVALID_VALUE');
    });

    it('uploadBlock returns the DB in load-memory form with its data; readDb equals a read of the whole DB', async () => {
      const { server, client } = await start('s7-300', '&pdu=240', { 3: 1000 });
      const db = server.memory.area('DB', 3)!;
      for (let i = 0; i < db.length; i++) db[i] = (i * 7) & 0xff;
      const up = await client.uploadBlock('DB', 3);
      expect(up).to.deep.include({ type: 'DB', number: 3 });
      expect(up.bytes.length).to.equal(1000 + 92);
      expect(up.code.equals(db)).to.equal(true);
      const data = await client.readDb(3);
      expect(data.equals(db)).to.equal(true);
      expect((await rejection(client.uploadBlock('DB', 4))).code).to.equal('OBJECT_DOES_NOT_EXIST');
    });

    it('an S7-1500 has no block functions: NOT_SUPPORTED, the connection stays up', async () => {
      const { client } = await start('s7-1500');
      for (const call of [
        () => client.listBlocks(),
        () => client.blockInfo('DB', 1),
        () => client.uploadBlock('DB', 1),
        () => client.setPassword('x'),
      ]) {
        expect((await rejection(call())).code).to.equal('NOT_SUPPORTED');
      }
      expect(await client.read(['DB1,BYTE0'])).to.deep.equal({ 'DB1,BYTE0': 0 });
    });
  });

  describe('protection', () => {
    it('level 2 refuses writes and stop with ACCESS_DENIED until the password; a wrong password is ACCESS_DENIED; clearPassword protects again', async () => {
      const { server, client } = await start('s7-300', '&control=true');
      server.setProtection(2, 'secret');
      expect((await client.info()).protection).to.deep.include({ level: 2, configuredLevel: 2 });
      expect(await client.read(['DB1,INT0'])).to.deep.equal({ 'DB1,INT0': 0 });
      const write = await rejection(client.write({ 'DB1,INT0': 5 }));
      expect(write.code).to.equal('TAG_ERRORS');
      expect((write as unknown as { errors: Record<string, PlcError> }).errors['DB1,INT0']!.code).to.equal('ACCESS_DENIED');
      expect((await rejection(client.stop())).code).to.equal('ACCESS_DENIED');
      expect((await rejection(client.setPassword('wrong'))).code).to.equal('ACCESS_DENIED');
      await client.setPassword('secret');
      expect((await client.info()).protection!.level).to.equal(1);
      await client.write({ 'DB1,INT0': 5 });
      await client.stop();
      expect(server.state).to.equal('STOP');
      await client.clearPassword();
      expect((await rejection(client.hotStart())).code).to.equal('ACCESS_DENIED');
    });

    it('level 3 refuses reads and upload too', async () => {
      const { server, client } = await start('s7-300');
      server.setProtection(3, 'pw3');
      const read = await rejection(client.read(['DB1,INT0']));
      expect((read as unknown as { errors: Record<string, PlcError> }).errors['DB1,INT0']!.code).to.equal('ACCESS_DENIED');
      expect((await rejection(client.uploadBlock('DB', 1))).code).to.equal('ACCESS_DENIED');
      await client.setPassword('pw3');
      expect((await client.uploadBlock('DB', 1)).code.length).to.equal(1024);
      expect(() => server.setProtection(2)).to.throw(TypeError);
    });

    it('a password longer than 8 characters is INVALID_VALUE before anything is sent', async () => {
      const { client } = await start('s7-300');
      requests.length = 0;
      expect((await rejection(client.setPassword('123456789'))).code).to.equal('INVALID_VALUE');
      expect(requests).to.deep.equal([]);
    });
  });

  it('the server emits "diagnostic" for every entry it logs', async () => {
    const { server } = await start('s7-1200');
    const logged = waitFor<{ eventId: number }>(server.cpu, 'diagnostic');
    server.stop();
    expect((await logged).eventId).to.equal(0x4304);
  });
});
