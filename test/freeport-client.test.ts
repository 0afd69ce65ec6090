import { expect } from 'chai';
import { MockBinding, type MockPortBinding } from '@serialport/binding-mock';
import type { BindingInterface } from '@serialport/bindings-interface';
import { PlcError, TagErrors, type TagResult } from '../lib/errors';
import { FreeportBus } from '../lib/freeport/bus';
import { FreeportClient } from '../lib/freeport/client';
import type { FreeportRequest } from '../lib/freeport/codec';
import type { FreeportEndpoint } from '../lib/url';
import { activeHandles, settle, waitFor } from './support/wait';

const PATH = '/dev/ttyFREEPORT';
const FAST = { backoff: { initialDelay: 10, maxDelay: 50, jitter: 0 } };

function serialEndpoint(over: Partial<FreeportEndpoint> = {}): FreeportEndpoint {
  return {
    protocol: 'freeport',
    transport: { kind: 'serial', path: PATH, baudRate: 9600, parity: 'none', dataBits: 8, stopBits: 1 },
    timeout: 100,
    retries: 1,
    interFrameGapMs: 0,
    ...over,
  };
}

/** The bus wired into MockBinding, keeping the ports the master opened (for what went over the wire). */
function inProcess(bus: FreeportBus): { binding: BindingInterface; ports: MockPortBinding[] } {
  const ports: MockPortBinding[] = [];
  const wired = bus.mockBinding(MockBinding);
  return {
    ports,
    binding: {
      list: () => wired.list(),
      open: async (options) => {
        const port = await wired.open(options);
        ports.push(port);
        return port;
      },
    },
  };
}

function codes(results: Record<string, TagResult<unknown>>): Record<string, string> {
  return Object.fromEntries(Object.entries(results).map(([k, r]) => [k, r.ok ? 'ok' : r.error.code]));
}

function record(bus: FreeportBus): { requests: FreeportRequest[]; times: number[] } {
  const log = { requests: [] as FreeportRequest[], times: [] as number[] };
  bus.on('request', (r: FreeportRequest) => {
    log.requests.push(r);
    log.times.push(Date.now());
  });
  return log;
}

describe('freeport master against simulated stations, in-process (@serialport/binding-mock)', () => {
  let bus: FreeportBus;
  let client: FreeportClient;
  let ports: MockPortBinding[];

  beforeEach(async () => {
    MockBinding.reset();
    MockBinding.createPort(PATH, { echo: false, record: true });
    bus = new FreeportBus({
      stations: {
        5: Buffer.from([0x41, 0x20, 0x00, 0x00]), // REAL 10.0
        6: Buffer.from([0x12, 0x34, 0x56, 0x78]),
        7: Buffer.from([0x00, 0x00, 0x00, 0x00]),
      },
    });
    const wired = inProcess(bus);
    ports = wired.ports;
    client = new FreeportClient(serialEndpoint(), { binding: wired.binding, ...FAST });
    await client.connect();
  });

  afterEach(async () => {
    await client.close();
    await bus.close();
    MockBinding.reset();
  });

  it('reads several tags of one station with one request', async () => {
    const log = record(bus);
    const values = await client.read(['ST6,DWORD0', 'ST6,BYTE1', 'ST6,INT2', 'ST6,X0.4', 'ST6,X0.0', 'ST6,B0.4', 'ST5,REAL0']);
    expect(values).to.deep.equal({
      'ST6,DWORD0': 0x12345678,
      'ST6,BYTE1': 0x34,
      'ST6,INT2': 0x5678,
      'ST6,X0.4': true, // 0x12 = 0001 0010
      'ST6,X0.0': false,
      'ST6,B0.4': [0x12, 0x34, 0x56, 0x78],
      'ST5,REAL0': 10,
    });
    expect(log.requests.map((r) => [r.command, r.station, r.length])).to.deep.equal([
      ['read', 6, 4],
      ['read', 5, 4],
    ]);
  });

  it('writes E6 27 A1 C3 to station 5 as exactly qR0504E627A1C325Q and checks the acknowledgement', async () => {
    await client.write({ 'ST5,DWORD0': 0xe627a1c3 });
    expect(ports[0]!.lastWrite?.toString('latin1')).to.equal('qR0504E627A1C325Q');
    expect(bus.station(5).data).to.deep.equal(Buffer.from([0xe6, 0x27, 0xa1, 0xc3]));
  });

  it('writes from byte 0 directly with LE = its length, the rest of the area untouched', async () => {
    const log = record(bus);
    await client.write({ 'ST6,INT0': -2 });
    expect(log.requests.map((r) => [r.command, r.length])).to.deep.equal([['write', 2]]);
    expect(bus.station(6).data).to.deep.equal(Buffer.from([0xff, 0xfe, 0x56, 0x78]));
  });

  it('writes a bit or bytes not starting at byte 0 by read-modify-write of the 4 bytes', async () => {
    const log = record(bus);
    await client.write({ 'ST6,INT2': 0x0102 });
    expect(bus.station(6).data).to.deep.equal(Buffer.from([0x12, 0x34, 0x01, 0x02]));
    await client.write({ 'ST6,X0.0': true });
    expect(bus.station(6).data).to.deep.equal(Buffer.from([0x13, 0x34, 0x01, 0x02]));
    expect(log.requests.map((r) => [r.command, r.length])).to.deep.equal([
      ['read', 4],
      ['write', 4],
      ['read', 4],
      ['write', 4],
    ]);
  });

  it('merges several writes to one station into one read-modify-write', async () => {
    const log = record(bus);
    await client.write({ 'ST7,X0.1': true, 'ST7,BYTE2': 0xaa, 'ST7,X3.7': true, 'ST5,DWORD0': 1 });
    expect(bus.station(7).data).to.deep.equal(Buffer.from([0x02, 0x00, 0xaa, 0x80]));
    expect(bus.station(5).data.readUInt32BE(0)).to.equal(1);
    expect(log.requests.map((r) => `${r.command}${r.station}`)).to.deep.equal(['read7', 'write7', 'write5']);
  });

  it('reports a write the station did not take (never a silently dropped write)', async () => {
    bus.station(5).ignoreWrites = true;
    const results = await client.writeDetailed({ 'ST5,DWORD0': 7, 'ST6,BYTE0': 1 });
    expect(results['ST6,BYTE0']).to.deep.equal({ ok: true, value: undefined });
    const r = results['ST5,DWORD0']!;
    expect(r.ok).to.equal(false);
    if (!r.ok) {
      expect(r.error.code).to.equal('PLC_ERROR');
      expect(r.error.message).to.include('station 5').and.include('sent 00 00 00 07, it holds 41 20 00 00');
    }
  });

  it('refuses bad addresses and values per tag before anything is sent', async () => {
    const log = record(bus);
    const results = await client.writeDetailed({ 'ST5,DWORD1': 1, 'ST5,INT0': 70000, 'ST5,X0.9': true, 'ST999,BYTE0': 1 });
    expect(codes(results)).to.deep.equal({
      'ST5,DWORD1': 'INVALID_ADDRESS',
      'ST5,INT0': 'INVALID_VALUE',
      'ST5,X0.9': 'INVALID_ADDRESS',
      'ST999,BYTE0': 'INVALID_ADDRESS',
    });
    expect(log.requests).to.have.length(0);
  });

  it('a silent station times out, named, while the bus keeps serving the others', async () => {
    bus.station(6).silent = true;
    const log = record(bus);
    const results = await client.readDetailed(['ST5,REAL0', 'ST6,DWORD0', 'ST7,DWORD0']);
    expect(results['ST5,REAL0']).to.deep.equal({ ok: true, value: 10 });
    expect(results['ST7,DWORD0']).to.deep.equal({ ok: true, value: 0 });
    const silent = results['ST6,DWORD0']!;
    expect(silent.ok).to.equal(false);
    if (!silent.ok) {
      expect(silent.error.code).to.equal('TIMEOUT');
      expect(silent.error.message).to.equal(`station 6 on freeport://${PATH} did not answer (2 attempts of 100 ms)`);
    }
    expect(log.requests.filter((r) => r.station === 6)).to.have.length(2); // retries = 1
    expect(client.state).to.equal('connected');
    expect(await client.read(['ST5,REAL0'])).to.deep.equal({ 'ST5,REAL0': 10 });
  });

  it("a reply that comes after its timeout is never taken for the next request (another station's data passed as good)", async () => {
    // Every reply 150 ms late with a timeout of 100: station 6's reply to a timed-out attempt
    // would arrive while the next request (its retry, then station 7's) waits for its own.
    bus.faults.replyDelayMs = 150;
    const results = await client.readDetailed(['ST6,DWORD0', 'ST7,DWORD0']);
    const expected: Record<string, number> = { 'ST6,DWORD0': 0x12345678, 'ST7,DWORD0': 0 };
    for (const [address, r] of Object.entries(results)) {
      if (r.ok) expect(r.value, address).to.equal(expected[address]);
      else expect(r.error.code, address).to.equal('TIMEOUT');
    }
    bus.faults.replyDelayMs = 0;
    expect(await client.read(['ST7,DWORD0', 'ST5,REAL0'])).to.deep.equal({ 'ST7,DWORD0': 0, 'ST5,REAL0': 10 });
  });

  it('a station not on the bus times out like a silent one', async () => {
    const err = await client.read(['ST30,BYTE0']).then(
      () => undefined,
      (e: unknown) => e,
    );
    expect(err).to.be.instanceOf(TagErrors);
    expect((err as TagErrors).errors['ST30,BYTE0']!.code).to.equal('TIMEOUT');
  });

  it('retries a reply whose checksum fails and never returns corrupted data', async () => {
    bus.faults.corruptNext = 1;
    const corrupt = waitFor(bus, 'request');
    expect(await client.read(['ST6,DWORD0'])).to.deep.equal({ 'ST6,DWORD0': 0x12345678 });
    await corrupt;
    bus.faults.corruptNext = 2; // more than the retries
    const results = await client.readDetailed(['ST6,DWORD0']);
    const r = results['ST6,DWORD0']!;
    expect(r.ok).to.equal(false);
    if (!r.ok) {
      expect(r.error.code).to.equal('PROTOCOL_ERROR');
      expect(r.error.message).to.match(/station 6 .* sent no valid reply .*checksum mismatch/);
    }
    expect(client.state).to.equal('connected');
  });

  it('under random bit flips and dropped characters, every value that arrives is right', async () => {
    await client.close(); // the port is the noisy bus's now
    let seed = 42;
    const random = () => (seed = (seed * 1103515245 + 12345) % 2 ** 31) / 2 ** 31;
    const noisyBus = new FreeportBus({ stations: { 6: Buffer.from([0x12, 0x34, 0x56, 0x78]) }, random });
    const wired = noisyBus.mockBinding(MockBinding);
    const c = new FreeportClient(serialEndpoint({ retries: 6, timeout: 30 }), { binding: wired, ...FAST });
    await c.connect();
    try {
      noisyBus.faults.flipBitRate = 0.3;
      noisyBus.faults.dropCharRate = 0.2;
      let good = 0;
      let failed = 0;
      for (let i = 0; i < 40; i++) {
        const r = (await c.readDetailed(['ST6,DWORD0']))['ST6,DWORD0']!;
        if (r.ok) {
          expect(r.value).to.equal(0x12345678);
          good++;
        } else {
          expect(['TIMEOUT', 'PROTOCOL_ERROR']).to.include(r.error.code);
          failed++;
        }
      }
      expect(good).to.be.greaterThan(30);
      expect(good + failed).to.equal(40);
    } finally {
      await c.close();
      await noisyBus.close();
    }
  });

  it('skips garbage on the line', async () => {
    bus.sendRaw(Buffer.from('\x00\xffqQq12\r\nQQ', 'latin1'));
    expect(await client.read(['ST6,WORD2'])).to.deep.equal({ 'ST6,WORD2': 0x5678 });
  });

  it('keeps one request on the bus at a time, whoever asks', async () => {
    bus.faults.replyDelayMs = 2;
    const reads = Array.from({ length: 12 }, (_, i) => client.read([`ST${5 + (i % 3)},BYTE1`]));
    const values = await Promise.all(reads);
    expect(values.map((v) => Object.values(v)[0])).to.deep.equal(Array.from({ length: 4 }, () => [0x20, 0x34, 0x00]).flat());
    expect(bus.collisions).to.equal(0);
  });

  it('waits the inter-frame gap between a reply and the next request', async () => {
    await client.close();
    const wired = bus.mockBinding(MockBinding);
    const c = new FreeportClient(serialEndpoint({ interFrameGapMs: 40 }), { binding: wired });
    await c.connect();
    try {
      const log = record(bus);
      await c.read(['ST5,BYTE0']);
      await c.read(['ST6,BYTE0']);
      await c.read(['ST7,BYTE0']);
      expect(log.times[1]! - log.times[0]!).to.be.at.least(39);
      expect(log.times[2]! - log.times[1]!).to.be.at.least(39);
    } finally {
      await c.close();
    }
  });

  it('when the serial device disappears: pending requests fail, the link reconnects, values are right again', async () => {
    bus.station(6).silent = true;
    const pending = client.read(['ST6,DWORD0']).then(
      () => undefined,
      (e: unknown) => e,
    );
    await waitFor(bus, 'request');
    const disconnected = waitFor<PlcError>(client, 'disconnected');
    const reconnected = waitFor(client, 'connected', 2000);
    bus.dropConnections();
    const err = (await pending) as PlcError;
    expect(err).to.be.instanceOf(PlcError);
    expect(err.code).to.equal('CONNECTION_LOST');
    expect((await disconnected).message).to.include('the serial port closed');
    await reconnected;
    bus.station(6).silent = false;
    expect(await client.read(['ST6,DWORD0'])).to.deep.equal({ 'ST6,DWORD0': 0x12345678 });
  });

  it('an aborted request settles at once with ABORTED and the bus goes on', async () => {
    bus.station(6).silent = true;
    const controller = new AbortController();
    const started = Date.now();
    const pending = client.readDetailed(['ST6,DWORD0'], { signal: controller.signal });
    await waitFor(bus, 'request');
    controller.abort();
    const r = (await pending)['ST6,DWORD0']!;
    expect(r.ok).to.equal(false);
    if (!r.ok) expect(r.error.code).to.equal('ABORTED');
    expect(Date.now() - started).to.be.below(90); // before the 100 ms timeout
    expect(await client.read(['ST5,REAL0'])).to.deep.equal({ 'ST5,REAL0': 10 });
  });

  it('with a profile whose replies echo DA, ignores a reply from the wrong station', async () => {
    await client.close();
    const profile = { replyEchoesAddress: true };
    const echoBus = new FreeportBus({ stations: { 5: Buffer.from([0, 0, 0, 5]), 6: Buffer.from([0, 0, 0, 6]) }, profile });
    const c = new FreeportClient(serialEndpoint({ retries: 0 }), { binding: echoBus.mockBinding(MockBinding), profile });
    await c.connect();
    try {
      expect(await c.read(['ST5,DINT0', 'ST6,DINT0'])).to.deep.equal({ 'ST5,DINT0': 5, 'ST6,DINT0': 6 });
      echoBus.station(6).answerAs = 5;
      const r = (await c.readDetailed(['ST6,DINT0']))['ST6,DINT0']!;
      expect(r.ok).to.equal(false);
      if (!r.ok) expect(r.error.code).to.equal('TIMEOUT');
    } finally {
      await c.close();
      await echoBus.close();
    }
  });

  it('connect() rejects with CONNECT_FAILED naming a serial port that does not exist', async () => {
    const c = new FreeportClient(
      serialEndpoint({ transport: { kind: 'serial', path: '/dev/ttyNOPE', baudRate: 9600, parity: 'none', dataBits: 8, stopBits: 1 } }),
      { binding: MockBinding },
    );
    const err = (await c.connect().then(
      () => undefined,
      (e: unknown) => e,
    )) as PlcError;
    expect(err.code).to.equal('CONNECT_FAILED');
    expect(err.message).to.include('/dev/ttyNOPE');
    await c.close();
  });

  it('honours a write allow-list of stations ("ST6") and addresses', async () => {
    await client.close();
    const log = record(bus);
    const c = new FreeportClient(serialEndpoint({ allow: ['ST6', 'ST7,BYTE1'] }), { binding: bus.mockBinding(MockBinding) });
    await c.connect();
    try {
      const results = await c.writeDetailed({ 'ST5,BYTE0': 1, 'ST6,BYTE0': 2, 'ST7,BYTE1': 3, 'ST7,BYTE2': 4 });
      expect(codes(results)).to.deep.equal({
        'ST5,BYTE0': 'WRITE_NOT_ALLOWED',
        'ST6,BYTE0': 'ok',
        'ST7,BYTE1': 'ok',
        'ST7,BYTE2': 'WRITE_NOT_ALLOWED',
      });
      expect(log.requests.map((r) => `${r.command}${r.station}`)).to.deep.equal(['write6', 'read7', 'write7']);
    } finally {
      await c.close();
    }
  });
});

describe('freeport master over TCP to a serial device server', () => {
  it('reads, writes, survives the server going away and coming back, and close() leaves no handles', async () => {
    const handles0 = activeHandles();
    let bus = new FreeportBus({ stations: { 5: Buffer.from([0, 0, 0, 42]), 6: Buffer.alloc(4) } });
    const port = await bus.listenTcp({ port: 0 });
    const endpoint: FreeportEndpoint = {
      protocol: 'freeport',
      transport: { kind: 'tcp', host: '127.0.0.1', port },
      timeout: 200,
      retries: 0,
      interFrameGapMs: 1,
    };
    const client = new FreeportClient(endpoint, FAST);
    try {
      await client.connect();
      expect(bus.connectionCount).to.equal(1);
      expect(await client.read(['ST5,DINT0'])).to.deep.equal({ 'ST5,DINT0': 42 });
      await client.write({ 'ST6,REAL0': 1.5, 'ST5,X3.7': true });
      expect(bus.station(6).data.readFloatBE(0)).to.equal(1.5);
      expect(bus.station(5).data).to.deep.equal(Buffer.from([0, 0, 0, 42 | 0x80]));

      bus.station(6).silent = true;
      const r = await client.readDetailed(['ST6,REAL0', 'ST5,BYTE3']);
      expect(r['ST6,REAL0']!.ok).to.equal(false);
      expect(r['ST5,BYTE3']).to.deep.equal({ ok: true, value: 0xaa });
      expect(client.state).to.equal('connected');

      const data = Buffer.from(bus.station(5).data);
      const disconnected = waitFor(client, 'disconnected');
      await bus.close();
      await disconnected;
      const reconnected = waitFor(client, 'connected', 3000);
      bus = new FreeportBus({ stations: { 5: data } });
      await bus.listenTcp({ port });
      await reconnected;
      expect(await client.read(['ST5,DWORD0'])).to.deep.equal({ 'ST5,DWORD0': 0xaa });
    } finally {
      await client.close();
      await bus.close();
    }
    await settle();
    expect(activeHandles()).to.equal(handles0);
  });

  it('reports a refused connection as CONNECT_FAILED and leaves nothing open', async () => {
    const handles0 = activeHandles();
    const bus = new FreeportBus({ stations: [5] });
    const port = await bus.listenTcp();
    await bus.close();
    const client = new FreeportClient({
      protocol: 'freeport',
      transport: { kind: 'tcp', host: '127.0.0.1', port },
      timeout: 200,
      retries: 0,
      interFrameGapMs: 0,
    });
    const err = (await client.connect().then(
      () => undefined,
      (e: unknown) => e,
    )) as PlcError;
    expect(err.code).to.equal('CONNECT_FAILED');
    await client.close();
    await settle();
    expect(activeHandles()).to.equal(handles0);
  });
});
