/**
 * End to end over a real pseudo-terminal pair (test/support/pty.ts) with the
 * real serialport bindings: the master on one end, the simulated stations on the other.
 */
import type { BindingInterface, BindingPortInterface } from '@serialport/bindings-interface';
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { SerialPort } from 'serialport';
import type { PlcError } from '../lib/errors';
import { FreeportBus } from '../lib/freeport/bus';
import { FreeportClient } from '../lib/freeport/client';
import type { FreeportEndpoint } from '../lib/url';
import { openPtyPair, ptyUnavailable, type PtyPair } from './support/pty';
import { skipBecause } from './support/skip';
import { activeHandles, settle, until, waitFor } from './support/wait';

describe('freeport end to end over a real pseudo-terminal pair (real serialport bindings)', function () {
  this.timeout(20000);
  let dir: string;
  let pty: PtyPair;
  let bus: FreeportBus;
  let handles0: number;

  before(function () {
    const unavailable = ptyUnavailable();
    if (unavailable) skipBecause(this, `pseudo-terminal pair: ${unavailable}`);
  });

  beforeEach(async () => {
    await settle();
    handles0 = activeHandles();
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-pty-'));
    pty = await openPtyPair(dir);
    bus = new FreeportBus({ stations: { 5: Buffer.from([0x41, 0x20, 0, 0]), 6: Buffer.from([1, 2, 3, 4]), 7: Buffer.alloc(4) } });
    await bus.attachSerial(pty.station, { baudRate: 19200 });
  });

  afterEach(async () => {
    await bus?.close();
    await pty?.stop();
    fs.rmSync(dir, { recursive: true, force: true });
  });

  const endpoint = (over: Partial<FreeportEndpoint> = {}): FreeportEndpoint => ({
    protocol: 'freeport',
    transport: { kind: 'serial', path: pty.master, baudRate: 19200, parity: 'none', dataBits: 8, stopBits: 1 },
    timeout: 300,
    retries: 1,
    interFrameGapMs: 2,
    ...over,
  });

  it('reads and writes stations, a silent one times out while the others answer, and close() leaves no handles', async () => {
    const client = new FreeportClient(endpoint());
    try {
      await client.connect();
      expect(await client.read(['ST5,REAL0', 'ST6,DWORD0', 'ST6,B0.4'])).to.deep.equal({
        'ST5,REAL0': 10,
        'ST6,DWORD0': 0x01020304,
        'ST6,B0.4': [1, 2, 3, 4],
      });
      const requests: string[] = [];
      bus.on('request', (r) => requests.push(`${r.command}${r.station}:${r.length}:${r.data.toString('hex')}`));
      await client.write({ 'ST5,DWORD0': 0xe627a1c3 });
      expect(requests).to.deep.equal(['write5:4:e627a1c3']);
      expect(bus.station(5).data).to.deep.equal(Buffer.from([0xe6, 0x27, 0xa1, 0xc3]));
      await client.write({ 'ST7,X1.2': true, 'ST7,INT2': -1 });
      expect(bus.station(7).data).to.deep.equal(Buffer.from([0, 4, 0xff, 0xff]));

      bus.station(6).silent = true;
      const results = await client.readDetailed(['ST6,DWORD0', 'ST7,INT2', 'ST5,BYTE0']);
      expect(results['ST7,INT2']).to.deep.equal({ ok: true, value: -1 });
      expect(results['ST5,BYTE0']).to.deep.equal({ ok: true, value: 0xe6 });
      const silent = results['ST6,DWORD0']!;
      expect(silent.ok).to.equal(false);
      if (!silent.ok) expect(silent.error.message).to.include('station 6').and.include('did not answer');
      expect(client.state).to.equal('connected');
    } finally {
      await client.close();
    }
    await bus.close();
    await pty.stop();
    await settle();
    expect(activeHandles()).to.equal(handles0);
  });

  it('rejects corrupted replies by their checksum and retries', async () => {
    const client = new FreeportClient(endpoint({ retries: 2 }));
    try {
      await client.connect();
      let corrupt = 0;
      bus.faults.corruptNext = 2;
      bus.on('request', () => corrupt++);
      expect(await client.read(['ST6,DWORD0'])).to.deep.equal({ 'ST6,DWORD0': 0x01020304 });
      expect(corrupt).to.equal(3); // two corrupted answers, then a good one
      bus.sendRaw(Buffer.from('garbage\x00\xffqQ', 'latin1'));
      expect(await client.read(['ST5,WORD0'])).to.deep.equal({ 'ST5,WORD0': 0x4120 });
    } finally {
      await client.close();
    }
  });

  it('when the device disappears, pending requests fail and the master reconnects once it is back', async () => {
    const client = new FreeportClient(endpoint(), { backoff: { initialDelay: 50, maxDelay: 200, jitter: 0 } });
    try {
      await client.connect();
      const disconnected = waitFor<PlcError>(client, 'disconnected', 5000);
      await bus.close();
      await pty.stop(); // both ptys vanish, as when a USB adapter is pulled
      const err = await disconnected;
      expect(err.code).to.equal('CONNECTION_LOST');
      expect(client.state).to.equal('reconnecting');

      pty = await openPtyPair(dir);
      bus = new FreeportBus({ stations: { 5: Buffer.from([0, 0, 0, 9]) } });
      await bus.attachSerial(pty.station, { baudRate: 19200 });
      await until(() => client.state === 'connected', 5000, 'reconnected');
      expect(await client.read(['ST5,DINT0'])).to.deep.equal({ 'ST5,DINT0': 9 });
    } finally {
      await client.close();
    }
  });

  it('notices a device that vanished while a read was on its way, closes the port and stops reading it', async () => {
    // A tty that has hung up answers every read with 0 bytes, and the bindings read again at once
    // (https://github.com/serialport/bindings-cpp/issues/162): no error, no 'close', a core kept busy.
    // It happens when the hangup falls between the poll saying "readable" and the read, which load
    // makes likely. Here the real bindings' reads are held until the pair is gone: each runs after the hangup.
    const held = heldReads(SerialPort.binding);
    const client = new FreeportClient(endpoint(), { binding: held.binding, backoff: { initialDelay: 60_000, jitter: 0 } });
    try {
      await client.connect();
      await bus.close();
      await pty.stop();
      const disconnected = waitFor<PlcError>(client, 'disconnected', 3000);
      held.release();
      const err = await disconnected;
      expect(err.code).to.equal('CONNECTION_LOST');
      expect(err.message).to.include(`${pty.master} disappeared`);
      expect(held.ports.map((p) => p.isOpen)).to.deep.equal([false]); // its descriptor closed: nothing reads it any more
      // Measuring windows, not a wait: a read looping on the dead descriptor takes most of a core in every
      // window, while the rest of the process (GC, timers of the suite) may fill one of them: the quietest of three.
      const cpu = Math.min(await cpuShare(300), await cpuShare(300), await cpuShare(300));
      expect(cpu, 'share of one core used by this process after the loss').to.be.below(0.3);
    } finally {
      held.release();
      await client.close();
    }
  });

  it('notices a device path that comes to name another device, and reconnects to the device it names', async () => {
    // As a /dev/serial/by-id/… link does when the adapter is plugged back in and comes up as another ttyUSB.
    const link = path.join(dir, 'adapter');
    fs.symlinkSync(fs.realpathSync(pty.master), link);
    const client = new FreeportClient(
      endpoint({ transport: { kind: 'serial', path: link, baudRate: 19200, parity: 'none', dataBits: 8, stopBits: 1 } }),
      {
        backoff: { initialDelay: 50, maxDelay: 200, jitter: 0 },
      },
    );
    const otherDir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-pty-'));
    const other = await openPtyPair(otherDir);
    const otherBus = new FreeportBus({ stations: { 5: Buffer.from([0, 0, 0, 9]) } });
    try {
      await otherBus.attachSerial(other.station, { baudRate: 19200 });
      await client.connect();
      expect(await client.read(['ST6,DWORD0'])).to.deep.equal({ 'ST6,DWORD0': 0x01020304 });
      const disconnected = waitFor<PlcError>(client, 'disconnected', 3000);
      fs.symlinkSync(fs.realpathSync(other.master), `${link}.new`);
      fs.renameSync(`${link}.new`, link); // re-pointed in one step, as udev does
      const err = await disconnected;
      expect(err.code).to.equal('CONNECTION_LOST');
      expect(err.message).to.include(`${link} now names another device`);
      await until(() => client.state === 'connected', 5000, 'reconnected');
      expect(await client.read(['ST5,DINT0'])).to.deep.equal({ 'ST5,DINT0': 9 });
    } finally {
      await client.close();
      await otherBus.close();
      await other.stop();
      fs.rmSync(otherDir, { recursive: true, force: true });
    }
  });
});

/** Wraps the real bindings so that every read waits until release() (to put a hangup before a read). */
function heldReads(base: BindingInterface): { binding: BindingInterface; ports: BindingPortInterface[]; release(): void } {
  let release!: () => void;
  const gate = new Promise<void>((resolve) => (release = resolve));
  const ports: BindingPortInterface[] = [];
  const binding: BindingInterface = {
    list: () => base.list(),
    async open(options) {
      const port = await base.open(options);
      const read = port.read.bind(port);
      port.read = async (buffer, offset, length) => {
        await gate;
        return read(buffer, offset, length);
      };
      ports.push(port);
      return port;
    },
  };
  return { binding, ports, release };
}

/** CPU time of this process over `ms` of wall time, as a share of one core. */
async function cpuShare(ms: number): Promise<number> {
  const start = process.cpuUsage();
  const t0 = process.hrtime.bigint();
  await new Promise((resolve) => setTimeout(resolve, ms));
  const { user, system } = process.cpuUsage(start);
  return (user + system) / (Number(process.hrtime.bigint() - t0) / 1000);
}

describe('the pseudo-terminal pair under the real serialport bindings', function () {
  this.timeout(20000);

  before(function () {
    const unavailable = ptyUnavailable();
    if (unavailable) skipBecause(this, `pseudo-terminal pair: ${unavailable}`);
  });

  it('carries every byte value both ways unchanged (raw: no CR/LF mapping, no XON/XOFF, no echo)', async () => {
    const { SerialPort } = await import('serialport');
    const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-pty-'));
    const pair = await openPtyPair(dir);
    const open = (p: string) =>
      new Promise<InstanceType<typeof SerialPort>>((resolve, reject) => {
        const port: InstanceType<typeof SerialPort> = new SerialPort({ path: p, baudRate: 19200 }, (err) =>
          err ? reject(err) : resolve(port),
        );
      });
    const received = (port: InstanceType<typeof SerialPort>, length: number) => {
      const chunks: Buffer[] = [];
      let n = 0;
      const all = new Promise<Buffer>((resolve) =>
        port.on('data', (chunk: Buffer) => {
          chunks.push(chunk);
          n += chunk.length;
          if (n >= length) resolve(Buffer.concat(chunks));
        }),
      );
      return Promise.race([
        all,
        new Promise<never>((_, reject) => setTimeout(() => reject(new Error(`got ${n} of ${length} bytes within 3 s`)), 3000).unref()),
      ]);
    };
    const master = await open(pair.master);
    const station = await open(pair.station);
    try {
      const bytes = Buffer.from(Array.from({ length: 256 }, (_, i) => i));
      const reversed = Buffer.from(bytes).reverse();
      const atStation = received(station, bytes.length);
      master.write(bytes);
      expect(await atStation).to.deep.equal(bytes);
      const atMaster = received(master, reversed.length);
      station.write(reversed);
      expect(await atMaster).to.deep.equal(reversed); // and nothing echoed back to the writer
    } finally {
      await Promise.all([master, station].map((p) => new Promise((r) => p.close(r))));
      await pair.stop();
      fs.rmSync(dir, { recursive: true, force: true });
    }
  });
});
