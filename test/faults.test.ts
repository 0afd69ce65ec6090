/**
 * The fault matrix of issue #8, over real sockets on 127.0.0.1, for every
 * protocol where a fault applies. Every case checks the same promises:
 * a typed PlcError within the configured timeout, no uncaught exception or
 * unhandled rejection, reconnection on the backoff schedule, correct values
 * after recovery, every write acknowledged or rejected (never dropped; the
 * acknowledged ones are in the PLC's memory), and no leaked handles or timers.
 */
import { expect } from 'chai';
import * as net from 'node:net';
import { createClient, type AnyClient } from '../lib/connect';
import { PlcError } from '../lib/errors';
import { FetchWriteServer } from '../lib/fetchwrite/server';
import { FreeportBus } from '../lib/freeport/bus';
import { FreeportClient } from '../lib/freeport/client';
import { backoffDelay } from '../lib/link/backoff';
import { FrameReader } from '../lib/link/framer';
import { checkTpkt } from '../lib/s7/codec';
import type { S7Client } from '../lib/s7/client';
import { S7Server } from '../lib/s7/server';
import { PlcMemory } from '../lib/sim/memory';
import { parseUrl, type FreeportEndpoint } from '../lib/url';
import { settle, until, waitFor } from './support/wait';

const BACKOFF = { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 };
/** Slack for the event loop and a CI machine on top of a configured deadline. */
const MARGIN = 300;
/** Writes issued while a fault happens. */
const BURST = 8;

// ---------------------------------------------------------------- fault proxy

type ProxyMode = 'pass' | 'silent' | 'reset-mid' | 'drip' | 'garbage';

interface ProxyPair {
  readonly client: net.Socket;
  toClient(bytes: Buffer): void;
  reset(): void;
}

const GARBAGE = Buffer.from('HTTP/1.1 400 Bad Request\r\n\r\n\u00ff\u0000garbage');

/**
 * A TCP proxy between a client and a simulator that injects faults into what
 * the PLC sends back: swallow it, cut it and reset, drip it byte by byte,
 * replace it with garbage, or hand it to a test's own transform.
 */
class FaultProxy {
  mode: ProxyMode = 'pass';
  /** Overrides `mode` when set. */
  downstream: ((chunk: Buffer, pair: ProxyPair) => void) | undefined;
  private server: net.Server | undefined;
  private readonly pairs = new Set<ProxyPair>();
  private readonly timers = new Set<NodeJS.Timeout>();
  port = 0;

  constructor(private readonly targetPort: number) {}

  async listen(): Promise<number> {
    const server = net.createServer((socket) => this.accept(socket));
    this.server = server;
    await new Promise<void>((resolve) => server.listen(0, '127.0.0.1', () => resolve()));
    this.port = (server.address() as net.AddressInfo).port;
    return this.port;
  }

  async close(): Promise<void> {
    for (const t of this.timers) clearTimeout(t);
    this.timers.clear();
    for (const p of this.pairs) p.reset();
    this.pairs.clear();
    const server = this.server;
    this.server = undefined;
    if (server) await new Promise<void>((r) => server.close(() => r()));
  }

  private accept(client: net.Socket): void {
    client.setNoDelay(true);
    const upstream = net.connect({ host: '127.0.0.1', port: this.targetPort, noDelay: true });
    const pair: ProxyPair = {
      client,
      toClient: (bytes) => {
        if (!client.destroyed) client.write(bytes);
      },
      reset: () => {
        if (!client.destroyed) client.resetAndDestroy();
        upstream.destroy();
      },
    };
    this.pairs.add(pair);
    const end = () => {
      this.pairs.delete(pair);
      client.destroy();
      upstream.destroy();
    };
    client.on('error', () => undefined);
    upstream.on('error', () => undefined);
    client.on('close', end);
    upstream.on('close', end);
    client.on('data', (chunk) => upstream.write(chunk));
    upstream.on('data', (chunk: Buffer) => (this.downstream ? this.downstream(chunk, pair) : this.apply(chunk, pair)));
  }

  private readonly dripping = new WeakMap<ProxyPair, Buffer[]>();

  /** One byte per timer tick, in order across chunks (answers to parallel jobs must not interleave). */
  private drip(chunk: Buffer, pair: ProxyPair): void {
    let queue = this.dripping.get(pair);
    if (queue) return void queue.push(chunk);
    queue = [chunk];
    this.dripping.set(pair, queue);
    let i = 0;
    const next = () => {
      const head = queue![0];
      if (!head || pair.client.destroyed) return void this.dripping.delete(pair);
      pair.toClient(head.subarray(i, ++i));
      if (i >= head.length) {
        queue!.shift();
        i = 0;
      }
      const t = setTimeout(() => {
        this.timers.delete(t);
        next();
      }, 0);
      this.timers.add(t);
    };
    next();
  }

  private apply(chunk: Buffer, pair: ProxyPair): void {
    switch (this.mode) {
      case 'pass':
        return pair.toClient(chunk);
      case 'silent':
        return;
      case 'reset-mid':
        pair.client.write(chunk.subarray(0, Math.max(1, chunk.length >> 1)), () => pair.reset());
        return;
      case 'garbage':
        return pair.toClient(GARBAGE);
      case 'drip':
        return this.drip(chunk, pair);
    }
  }
}

// ---------------------------------------------------------------- simulators

/** A simulated PLC with INT slots 0..15 at distinct addresses, restartable on the same port and memory. */
interface Rig {
  readonly protocol: 's7' | 'fetchwrite' | 'freeport';
  /** The request timeout in the URL, ms. */
  readonly timeout: number;
  /** Does a request timeout drop the link? (Not on a freeport bus: a silent station is normal there.) */
  readonly timeoutDropsLink: boolean;
  /** The URL of the simulator itself. */
  url(): string;
  /** The URL through fault proxies (created on the first call); `proxies` are then set. */
  proxied(): Promise<string>;
  proxies: FaultProxy[];
  addr(i: number): string;
  peek(i: number): number;
  poke(i: number, value: number): void;
  stop(): Promise<void>;
  restart(): Promise<void>;
  close(): Promise<void>;
}

async function proxiesFor(ports: number[]): Promise<FaultProxy[]> {
  const proxies = ports.map((p) => new FaultProxy(p));
  await Promise.all(proxies.map((p) => p.listen()));
  return proxies;
}

async function s7Rig(profile: 's7-1200' | 's7-1500' = 's7-1200'): Promise<Rig & { server(): S7Server }> {
  const memory = new PlcMemory();
  let server = new S7Server({ port: 0, memory, profile });
  const port = await server.listen();
  const timeout = 500;
  const rig = {
    protocol: 's7' as const,
    timeout,
    timeoutDropsLink: true,
    proxies: [] as FaultProxy[],
    server: () => server,
    url: () => `s7://127.0.0.1:${port}?timeout=${timeout}`,
    async proxied() {
      rig.proxies = await proxiesFor([port]);
      return `s7://127.0.0.1:${rig.proxies[0]!.port}?timeout=${timeout}`;
    },
    addr: (i: number) => `DB1.DBW${2 * i}:INT`,
    peek: (i: number) => memory.area('DB', 1)!.readInt16BE(2 * i),
    poke: (i: number, v: number) => void memory.area('DB', 1)!.writeInt16BE(v, 2 * i),
    stop: () => server.close(),
    async restart() {
      server = new S7Server({ port, memory, profile });
      await server.listen();
    },
    async close() {
      await Promise.all(rig.proxies.map((p) => p.close()));
      await server.close();
    },
  };
  return rig;
}

async function fetchWriteRig(): Promise<Rig> {
  const memory = new PlcMemory();
  let server = new FetchWriteServer({ fetchPort: 0, writePort: 0, memory });
  const { fetchPort, writePort } = await server.listen();
  const timeout = 500;
  const rig: Rig = {
    protocol: 'fetchwrite',
    timeout,
    timeoutDropsLink: true,
    proxies: [],
    url: () => `fetchwrite://127.0.0.1?fetchPort=${fetchPort}&writePort=${writePort}&timeout=${timeout}`,
    async proxied() {
      rig.proxies = await proxiesFor([fetchPort, writePort]);
      return `fetchwrite://127.0.0.1?fetchPort=${rig.proxies[0]!.port}&writePort=${rig.proxies[1]!.port}&timeout=${timeout}`;
    },
    addr: (i) => `DB1,INT${2 * i}`,
    peek: (i) => memory.area('DB', 1)!.readInt16BE(2 * i),
    poke: (i, v) => void memory.area('DB', 1)!.writeInt16BE(v, 2 * i),
    stop: () => server.close(),
    async restart() {
      server = new FetchWriteServer({ fetchPort, writePort, memory });
      await server.listen();
    },
    async close() {
      await Promise.all(rig.proxies.map((p) => p.close()));
      await server.close();
    },
  };
  return rig;
}

/** Stations 1..8, two INT slots each, behind a serial device server (freeport+tcp). */
async function freeportRig(): Promise<Rig & { bus(): FreeportBus }> {
  const STATIONS = [1, 2, 3, 4, 5, 6, 7, 8];
  let bus = new FreeportBus({ stations: STATIONS });
  const port = await bus.listenTcp({ port: 0 });
  const timeout = 150;
  const where = (i: number) => ({ station: STATIONS[Math.floor(i / 2)]!, offset: 2 * (i % 2) });
  const rig = {
    protocol: 'freeport' as const,
    timeout,
    timeoutDropsLink: false,
    proxies: [] as FaultProxy[],
    bus: () => bus,
    url: () => `freeport+tcp://127.0.0.1:${port}?timeout=${timeout}&retries=0&gap=0`,
    async proxied() {
      rig.proxies = await proxiesFor([port]);
      return `freeport+tcp://127.0.0.1:${rig.proxies[0]!.port}?timeout=${timeout}&retries=0&gap=0`;
    },
    addr: (i: number) => `ST${where(i).station},INT${where(i).offset}`,
    peek: (i: number) => bus.station(where(i).station).data.readInt16BE(where(i).offset),
    poke: (i: number, v: number) => void bus.station(where(i).station).data.writeInt16BE(v, where(i).offset),
    async stop() {
      await bus.close();
    },
    async restart() {
      const data = Object.fromEntries(STATIONS.map((s) => [s, Buffer.from(bus.station(s).data)]));
      bus = new FreeportBus({ stations: data });
      await bus.listenTcp({ port });
    },
    async close() {
      await Promise.all(rig.proxies.map((p) => p.close()));
      await bus.close();
    },
  };
  return rig;
}

const RIGS: [string, () => Promise<Rig>][] = [
  ['S7comm', () => s7Rig()],
  ['FETCH/WRITE', fetchWriteRig],
  ['freeport (serial device server)', freeportRig],
];

// ---------------------------------------------------------------- invariants

/** A client with the small backoff; records the delays it announced, to check them against the schedule. */
function client(url: string): AnyClient & { delays: { attempt: number; delay: number }[] } {
  const c = createClient(url, { backoff: BACKOFF }) as AnyClient & { delays: { attempt: number; delay: number }[] };
  c.delays = [];
  c.on('reconnecting', (r: { delay: number; attempt: number }) => c.delays.push({ attempt: r.attempt, delay: r.delay }));
  return c;
}

/** Every announced delay is the schedule's, attempt by attempt (jitter 0). */
function expectOnSchedule(c: { delays: { attempt: number; delay: number }[] }): void {
  for (const d of c.delays) expect(d.delay, `delay of attempt ${d.attempt}`).to.equal(backoffDelay(d.attempt, BACKOFF));
}

/**
 * What a request that times out costs the requests queued behind it: its
 * timeout, and on a freeport line one more (the line is drained before the
 * next request, so a late reply is not taken for the next request's).
 */
function failedAttemptMs(rig: Rig): number {
  return rig.protocol === 'freeport' ? 2 * rig.timeout : rig.timeout;
}

/** Waits until the client is connected again, at most `ms` after now. */
async function reconnected(c: AnyClient, ms: number): Promise<number> {
  const t0 = Date.now();
  if (c.state !== 'connected') await waitFor(c, 'connected', ms);
  return Date.now() - t0;
}

/** The rejection of `p` as a PlcError (fails the test when it resolves or throws anything else). */
async function failure(p: Promise<unknown>): Promise<PlcError> {
  const outcome = await p.then(
    () => new Error('expected a rejection, got a value'),
    (e: unknown) => e,
  );
  if (!(outcome instanceof PlcError)) throw new Error(`expected a PlcError, got ${String(outcome)}`);
  return outcome;
}

/** A typed error within `ms` (+ margin), never a hang. */
async function typedWithin(p: Promise<unknown>, ms: number, codes: string[]): Promise<PlcError> {
  const t0 = Date.now();
  const err = await failure(p);
  const took = Date.now() - t0;
  expect(err.code, err.message).to.be.oneOf(codes);
  expect(took, `${err.code} after ${took} ms`).to.be.at.most(ms + MARGIN);
  return err;
}

interface Burst {
  acked: number[];
  rejected: PlcError[];
  /** Settles with every outcome once all writes settled; rejects if any hangs past `ms`. */
  settled(ms: number): Promise<void>;
}

/** Issues writes value(i) to slots `from`..`from+count-1`, one every `spacing` ms, recording each outcome. */
function burst(c: AnyClient, rig: Rig, from: number, count: number, value: (i: number) => number, spacing = 2): Burst {
  const acked: number[] = [];
  const rejected: PlcError[] = [];
  const all: Promise<void>[] = [];
  let launched = Promise.resolve();
  for (let k = 0; k < count; k++) {
    const i = from + k;
    launched = launched.then(() => new Promise((r) => setTimeout(r, spacing)));
    all.push(
      launched
        .then(() => c.write({ [rig.addr(i)]: value(i) }))
        .then(
          () => void acked.push(i),
          (e: unknown) => {
            if (!(e instanceof PlcError)) throw new Error(`write ${i} rejected with a non-PlcError: ${String(e)}`);
            // Writes rejected while the link is down name their tag too (issue #26): a gateway's log must say which write failed.
            expect(e.message, `the rejection of write ${i} (${e.code}) names its tag`).to.include(rig.addr(i));
            expect(e.tag, `the rejection of write ${i} (${e.code}) carries its tag`).to.equal(rig.addr(i));
            rejected.push(e);
          },
        ),
    );
  }
  return {
    acked,
    rejected,
    async settled(ms: number) {
      let timer: NodeJS.Timeout | undefined;
      const deadline = new Promise<never>(
        (_, reject) => (timer = setTimeout(() => reject(new Error(`writes still pending after ${ms} ms: a hang`)), ms)),
      );
      try {
        await Promise.race([Promise.all(all), deadline]);
      } finally {
        clearTimeout(timer);
      }
      expect(acked.length + rejected.length, 'every write resolved or rejected').to.equal(count);
    },
  };
}

/** Acknowledged writes are in the PLC's memory. */
function expectAckedInMemory(rig: Rig, b: Burst, value: (i: number) => number): void {
  for (const i of b.acked) expect(rig.peek(i), `acknowledged write to ${rig.addr(i)}`).to.equal(value(i));
}

/** Correct values after recovery: what the PLC holds now is what the client reads. */
async function expectFreshValues(c: AnyClient, rig: Rig): Promise<void> {
  const v = 1000 + Math.floor(Math.random() * 1000);
  rig.poke(15, v);
  expect(await c.read([rig.addr(15)])).to.deep.equal({ [rig.addr(15)]: v });
  await c.write({ [rig.addr(14)]: -v });
  expect(rig.peek(14)).to.equal(-v);
}

/** Active handles and timers of the process, by type (process.getActiveResourcesInfo). */
function resources(): Map<string, number> {
  const counts = new Map<string, number>();
  for (const r of process.getActiveResourcesInfo()) if (r !== 'TTYWrap') counts.set(r, (counts.get(r) ?? 0) + 1);
  return counts;
}

function describeResources(m: Map<string, number>): string {
  return [...m]
    .sort()
    .map(([k, n]) => `${k}×${n}`)
    .join(', ');
}

async function expectNoLeaks(before: Map<string, number>): Promise<void> {
  await settle();
  const same = () => describeResources(resources()) === describeResources(before);
  await until(same, 1500, 'resources back to where they were').catch(() => undefined);
  expect(describeResources(resources()), 'active handles and timers').to.equal(describeResources(before));
}

// ---------------------------------------------------------------- the suite

describe('faults over real sockets: a typed error in time, no write dropped, recovery, no leak', function () {
  this.timeout(15000);
  const crashes: unknown[] = [];
  const onCrash = (e: unknown) => crashes.push(e);
  let baseline: Map<string, number>;
  const cleanups: (() => Promise<void>)[] = [];

  before(() => {
    process.on('uncaughtException', onCrash);
    process.on('unhandledRejection', onCrash);
  });
  after(() => {
    process.removeListener('uncaughtException', onCrash);
    process.removeListener('unhandledRejection', onCrash);
  });

  beforeEach(async () => {
    await settle();
    baseline = resources();
  });

  afterEach(async function () {
    for (const c of cleanups.splice(0).reverse()) await c();
    // Rejections nobody handled surface a tick later.
    await new Promise((r) => setTimeout(r, 5));
    expect(crashes.map(String), 'uncaught exceptions / unhandled rejections').to.deep.equal([]);
    if (this.currentTest?.state === 'passed') await expectNoLeaks(baseline);
  });

  async function open<R extends Rig>(make: () => Promise<R>): Promise<R> {
    const rig = await make();
    cleanups.push(() => rig.close());
    return rig;
  }

  function track<C extends AnyClient>(c: C): C {
    cleanups.push(() => c.close());
    return c;
  }

  for (const [title, make] of RIGS) {
    describe(title, () => {
      it('connection refused: CONNECT_FAILED at once, writes rejected while down, connects on the backoff schedule once the PLC listens', async () => {
        const rig = await open(make);
        await rig.stop();
        const first = track(client(rig.url()));
        await typedWithin(first.connect(), rig.timeout, ['CONNECT_FAILED']);
        const c = track(client(rig.url()));
        c.start();
        await until(() => c.delays.length >= 3, 2000, 'three refused attempts');
        const b = burst(c, rig, 0, BURST, (i) => 100 + i);
        await b.settled(2000);
        expect(b.rejected.map((e) => e.code)).to.deep.equal(Array(BURST).fill('NOT_CONNECTED'));
        await rig.restart();
        const took = await reconnected(c, BACKOFF.maxDelay + MARGIN + 200);
        expect(took).to.be.at.most(BACKOFF.maxDelay + MARGIN);
        expectOnSchedule(c);
        await expectFreshValues(c, rig);
      });

      it('the simulator killed and restarted mid-poll: typed errors meanwhile, no write dropped, the poll sees new values', async () => {
        const rig = await open(make);
        for (let i = 0; i < BURST; i++) rig.poke(i, 0);
        const c = track(client(rig.url()));
        await c.connect();
        const outcomes: (number | PlcError)[] = [];
        let polling = true;
        const poller = (async () => {
          // eslint-disable-next-line no-unmodified-loop-condition -- cleared by the test once the restart is done; each pass awaits a read
          while (polling) {
            try {
              outcomes.push((await c.read([rig.addr(15)]))[rig.addr(15)] as number);
            } catch (e) {
              if (!(e instanceof PlcError)) throw e;
              outcomes.push(e);
              await new Promise((r) => setTimeout(r, 5));
            }
          }
        })();
        try {
          rig.poke(15, 1);
          await until(() => outcomes.filter((o) => o === 1).length >= 3, 2000, 'polls');
          const b = burst(c, rig, 0, BURST, (i) => 200 + i, 1);
          await new Promise((r) => setTimeout(r, 4));
          await rig.stop();
          await b.settled(rig.timeout * 3 + 1000);
          await until(() => outcomes.some((o) => o instanceof PlcError), 2000, 'a typed error at the poller');
          rig.poke(15, 2);
          await rig.restart();
          await reconnected(c, BACKOFF.maxDelay + MARGIN + rig.timeout);
          await until(() => outcomes.includes(2), 2000, 'the poll reads the value set while it was down');
          expectAckedInMemory(rig, b, (i) => 200 + i);
          for (const o of outcomes) {
            if (o instanceof PlcError) expect(o.code).to.be.oneOf(['NOT_CONNECTED', 'CONNECTION_LOST', 'TIMEOUT', 'CLOSED', 'TAG_ERRORS']);
            else expect(o).to.be.oneOf([1, 2]);
          }
          expectOnSchedule(c);
        } finally {
          polling = false;
          await poller;
        }
        await expectFreshValues(c, rig);
      });

      it('a peer that accepts and then stays silent: TIMEOUT within the timeout, every write settled, recovery after', async () => {
        const rig = await open(make);
        const c = track(client(await rig.proxied()));
        await c.connect();
        rig.proxies.forEach((p) => (p.mode = 'silent'));
        const b = burst(c, rig, 0, BURST, (i) => 300 + i);
        const err = await typedWithin(c.read([rig.addr(15)]), rig.timeout, ['TIMEOUT', 'TAG_ERRORS']);
        if (err.code === 'TAG_ERRORS') expect((err.cause as PlcError).code).to.equal('TIMEOUT');
        await b.settled(failedAttemptMs(rig) * (BURST + 1) + 1000);
        // Nothing came back, so nothing may be reported as acknowledged.
        expect(b.acked).to.deep.equal([]);
        rig.proxies.forEach((p) => (p.mode = 'pass'));
        await reconnected(c, rig.timeout + BACKOFF.maxDelay + MARGIN);
        expectOnSchedule(c);
        await expectFreshValues(c, rig);
      });

      it('a reset in the middle of a response: CONNECTION_LOST at once, every write settled, reconnects', async () => {
        const rig = await open(make);
        const c = track(client(await rig.proxied()));
        await c.connect();
        rig.proxies.forEach((p) => (p.mode = 'reset-mid'));
        const lost = waitFor(c, 'disconnected', 2000);
        const b = burst(c, rig, 0, BURST, (i) => 400 + i);
        const err = await typedWithin(c.read([rig.addr(15)]), rig.timeout, ['CONNECTION_LOST', 'NOT_CONNECTED', 'TAG_ERRORS']);
        if (err.code === 'TAG_ERRORS') expect((err.cause as PlcError).code).to.equal('CONNECTION_LOST');
        await lost;
        await b.settled(2000);
        rig.proxies.forEach((p) => (p.mode = 'pass'));
        await reconnected(c, BACKOFF.maxDelay + MARGIN);
        expectAckedInMemory(rig, b, (i) => 400 + i);
        expectOnSchedule(c);
        await expectFreshValues(c, rig);
      });

      it('garbage where a response is due: a typed error, every write settled, recovery after', async () => {
        const rig = await open(make);
        const c = track(client(await rig.proxied()));
        await c.connect();
        rig.proxies.forEach((p) => (p.mode = 'garbage'));
        const b = burst(c, rig, 0, BURST, (i) => 500 + i);
        // A bus skips noise it cannot frame, so there the answer is simply missing.
        const codes =
          rig.protocol === 'freeport'
            ? ['TIMEOUT', 'PROTOCOL_ERROR', 'TAG_ERRORS']
            : ['PROTOCOL_ERROR', 'CONNECTION_LOST', 'NOT_CONNECTED', 'TAG_ERRORS'];
        await typedWithin(c.read([rig.addr(15)]), rig.timeout, codes);
        await b.settled(failedAttemptMs(rig) * (BURST + 1) + 1000);
        expect(b.acked).to.deep.equal([]);
        rig.proxies.forEach((p) => (p.mode = 'pass'));
        await reconnected(c, rig.timeout + BACKOFF.maxDelay + MARGIN);
        expectOnSchedule(c);
        await expectFreshValues(c, rig);
      });

      it('every answer dripped one byte at a time (handshake included): correct values, every write acknowledged', async () => {
        const rig = await open(make);
        const url = await rig.proxied();
        rig.proxies.forEach((p) => (p.mode = 'drip'));
        const c = track(client(url));
        await c.connect();
        rig.poke(15, 4321);
        expect(await c.read([rig.addr(15)])).to.deep.equal({ [rig.addr(15)]: 4321 });
        const b = burst(c, rig, 0, BURST, (i) => 600 + i);
        await b.settled(5000);
        expect(b.rejected.map(String)).to.deep.equal([]);
        expectAckedInMemory(rig, b, (i) => 600 + i);
        expect(c.delays).to.deep.equal([]);
      });
    });
  }

  describe('S7comm frames', () => {
    /** Hands the test each whole TPKT frame the PLC sends after the handshake (CC and setup ack pass). */
    function onResponse(proxy: FaultProxy, transform: (frame: Buffer, pair: ProxyPair) => void): void {
      const readers = new WeakMap<ProxyPair, { reader: FrameReader; seen: number }>();
      proxy.downstream = (chunk, pair) => {
        let r = readers.get(pair);
        if (!r) readers.set(pair, (r = { reader: new FrameReader(checkTpkt), seen: 0 }));
        for (const frame of r.reader.push(chunk)) {
          if (r.seen++ < 2) pair.toClient(frame);
          else transform(frame, pair);
        }
      };
    }

    /** The first response of the session is replaced by `bad`; writes issued with it all settle; then it recovers. */
    async function badFirstResponse(bad: Buffer, codes: string[]): Promise<PlcError> {
      const rig = await open(() => s7Rig());
      const c = track(client(await rig.proxied()));
      let injected = false;
      onResponse(rig.proxies[0]!, (frame, pair) => {
        if (injected) return pair.toClient(frame);
        injected = true;
        pair.toClient(bad);
      });
      await c.connect();
      const read = c.read([rig.addr(15)]);
      const b = burst(c, rig, 0, BURST, (i) => 700 + i, 0);
      const err = await typedWithin(read, rig.timeout, codes);
      await b.settled(rig.timeout * 2 + 1000);
      await reconnected(c, rig.timeout + BACKOFF.maxDelay + MARGIN);
      expectAckedInMemory(rig, b, (i) => 700 + i);
      expectOnSchedule(c);
      await expectFreshValues(c, rig);
      return err;
    }

    it('TPKT length 0: PROTOCOL_ERROR, the link is dropped and comes back', async () => {
      await badFirstResponse(Buffer.from('03000000', 'hex'), ['PROTOCOL_ERROR']);
    });

    it('TPKT length 3, shorter than its own header: PROTOCOL_ERROR, the link comes back', async () => {
      await badFirstResponse(Buffer.from('03000003', 'hex'), ['PROTOCOL_ERROR']);
    });

    it('TPKT length 65535 with a few bytes only: TIMEOUT within the timeout, no hang, the link comes back', async () => {
      await badFirstResponse(Buffer.from('0300ffff02f080320300', 'hex'), ['TIMEOUT']);
    });

    it('an answer with the wrong PDU reference: TIMEOUT (never matched to the job), the link comes back', async () => {
      const rig = await open(() => s7Rig());
      const c = track(client(await rig.proxied()));
      let injected = false;
      onResponse(rig.proxies[0]!, (frame, pair) => {
        if (!injected) {
          injected = true;
          frame = Buffer.from(frame);
          frame.writeUInt16BE((frame.readUInt16BE(11) + 7) & 0xffff, 11);
        }
        pair.toClient(frame);
      });
      await c.connect();
      rig.poke(15, 99);
      await typedWithin(c.read([rig.addr(15)]), rig.timeout, ['TIMEOUT']);
      await reconnected(c, BACKOFF.maxDelay + MARGIN);
      expect(await c.read([rig.addr(15)])).to.deep.equal({ [rig.addr(15)]: 99 });
    });

    it('every response duplicated: values right, every write acknowledged once, the link never drops', async () => {
      const rig = await open(() => s7Rig());
      const c = track(client(await rig.proxied()));
      onResponse(rig.proxies[0]!, (frame, pair) => {
        pair.toClient(frame);
        pair.toClient(frame);
      });
      await c.connect();
      let drops = 0;
      c.on('disconnected', () => drops++);
      for (let n = 0; n < 20; n++) {
        rig.poke(15, n);
        expect(await c.read([rig.addr(15)])).to.deep.equal({ [rig.addr(15)]: n });
      }
      const b = burst(c, rig, 0, BURST, (i) => 800 + i, 0);
      await b.settled(3000);
      expect(b.acked.length).to.equal(BURST);
      expectAckedInMemory(rig, b, (i) => 800 + i);
      expect(drops).to.equal(0);
    });

    it('responses out of order (AmQ 3): each job gets its own answer by PDU reference', async () => {
      const rig = await open(() => s7Rig('s7-1200'));
      const c = track(client(await rig.proxied()));
      let held: { frame: Buffer; pair: ProxyPair }[] = [];
      let reversed = 0;
      onResponse(rig.proxies[0]!, (frame, pair) => {
        held.push({ frame, pair });
        if (held.length < 3) return;
        const out = held.reverse();
        held = [];
        reversed++;
        for (const h of out) h.pair.toClient(h.frame);
      });
      await c.connect();
      expect((c as { maxJobs?: number }).maxJobs).to.equal(3);
      for (let round = 0; round < 5; round++) {
        [0, 1, 2].forEach((i) => rig.poke(i, 10 * round + i));
        // Three separate requests in flight at once (different DBs never merge).
        const reads = await Promise.all([0, 1, 2].map((i) => c.read([rig.addr(i)])));
        expect(reads).to.deep.equal([0, 1, 2].map((i) => ({ [rig.addr(i)]: 10 * round + i })));
      }
      expect(reversed).to.equal(5);
    });

    it("the PLC's connection limit (S7-1200, 9th connection): refused with CONNECT_FAILED, retried on schedule, in once a slot frees", async () => {
      const rig = await open(() => s7Rig('s7-1200'));
      const eight = Array.from({ length: 8 }, () => track(client(rig.url())));
      await Promise.all(eight.map((c) => c.connect()));
      const ninth = track(client(rig.url()));
      const errors: PlcError[] = [];
      ninth.on('error', (e: PlcError) => errors.push(e));
      ninth.start();
      await until(() => ninth.delays.length >= 3, 3000, 'three refused attempts');
      expect(errors[0]!.code).to.equal('CONNECT_FAILED');
      expect(errors[0]!.message).to.match(/connection limit/);
      const b = burst(ninth, rig, 0, BURST, (i) => 900 + i);
      await b.settled(2000);
      expect(b.rejected.map((e) => e.code)).to.deep.equal(Array(BURST).fill('NOT_CONNECTED'));
      await eight[0]!.close();
      await reconnected(ninth, BACKOFF.maxDelay + MARGIN);
      expectOnSchedule(ninth);
      expect(rig.server().connectionCount).to.equal(8);
      await expectFreshValues(ninth, rig);
    });

    it('COTP disconnect instead of a confirm: CONNECT_FAILED, retried on schedule, in once the PLC accepts', async () => {
      const rig = await open(() => s7Rig());
      rig.server().faults.refuseConnections = true;
      const c = track(client(rig.url()));
      c.start();
      await until(() => c.delays.length >= 2, 3000, 'two refused attempts');
      rig.server().faults.refuseConnections = false;
      await reconnected(c, BACKOFF.maxDelay + MARGIN);
      expectOnSchedule(c);
      await expectFreshValues(c, rig);
    });

    describe('userdata (system services)', () => {
      /** A client with the services (S7Client) through the proxy; `transform` sees every userdata answer (ROSCTR 7). */
      async function servicesRig(
        transform: (frame: Buffer, pair: ProxyPair, n: number) => void,
        profile: 's7-1200' | 's7-1500' = 's7-1200',
      ) {
        const rig = await open(() => s7Rig(profile));
        const url = await rig.proxied();
        let n = 0;
        onResponse(rig.proxies[0]!, (frame, pair) => (frame[8] === 7 ? transform(frame, pair, n++) : pair.toClient(frame)));
        const c = track(client(url)) as S7Client & { delays: { attempt: number; delay: number }[] };
        await c.connect();
        return { rig, c };
      }

      /** A frame with its S7 data part replaced (every length field kept consistent unless `lengths` is false). */
      function withData(frame: Buffer, data: Buffer, lengths = true): Buffer {
        const plen = frame.readUInt16BE(13);
        const head = frame.subarray(0, 17 + plen);
        const out = Buffer.concat([head, data]);
        if (lengths) {
          out.writeUInt16BE(out.length, 2);
          out.writeUInt16BE(data.length, 15);
        }
        return out;
      }

      const HOSTILE: [string, (f: Buffer) => Buffer][] = [
        ['its S7 data length one byte longer than the frame', (f) => (f.writeUInt16BE(f.readUInt16BE(15) + 1, 15), f)],
        [
          'its item announcing more bytes than follow',
          (f) => (f.writeUInt16BE(f.readUInt16BE(f.readUInt16BE(13) + 19) + 9, f.readUInt16BE(13) + 19), f),
        ],
        [
          'an 8-byte parameter part (no error field)',
          (f) => {
            const p = Buffer.from(f.subarray(17, 25));
            p[3] = 4;
            const out = Buffer.concat([f.subarray(0, 17), p, f.subarray(29)]);
            out.writeUInt16BE(out.length, 2);
            out.writeUInt16BE(8, 13);
            return out;
          },
        ],
        ['the answer of another function group', (f) => ((f[22] = 0x87), f)],
        // The SZL header (N_DR at byte 39 of the frame) announcing one record more than the answer carries.
        ['an SZL header counting one record more than it carries', (f) => (f.writeUInt16BE(f.readUInt16BE(39) + 1, 39), f)],
        ['its data part cut to the item header (lengths kept consistent)', (f) => withData(f, Buffer.from(f.subarray(29, 33)).fill(0, 2))],
        ['a truncated parameter head (00 01 13)', (f) => ((f[19] = 0x13), f)],
      ];

      for (const [what, corrupt] of HOSTILE) {
        it(`a userdata answer with ${what}: PROTOCOL_ERROR, writes settled, the link comes back and serves again`, async () => {
          const { rig, c } = await servicesRig((frame, pair, n) => pair.toClient(n === 0 ? corrupt(Buffer.from(frame)) : frame));
          const info = c.readSzl(0x0011, 0);
          const b = burst(c, rig, 0, BURST, (i) => 300 + i, 0);
          await typedWithin(info, rig.timeout, ['PROTOCOL_ERROR']);
          await b.settled(rig.timeout * 2 + 1000);
          await reconnected(c, rig.timeout + BACKOFF.maxDelay + MARGIN);
          expectAckedInMemory(rig, b, (i) => 300 + i);
          expect((await c.info()).orderCode).to.equal('6ES7 214-1AG40-0XB0');
          await expectFreshValues(c, rig);
        });
      }

      it('a multi-part answer whose connection drops between parts: CONNECTION_LOST, and the next read of it is whole', async () => {
        const rig0 = await open(() => s7Rig());
        for (let i = 0; i < 20; i++) {
          rig0.server().stop();
          rig0.server().start();
        }
        const url = await rig0.proxied();
        let parts = 0;
        let cut = false;
        onResponse(rig0.proxies[0]!, (frame, pair) => {
          if (frame[8] === 7 && !cut && ++parts === 2) {
            cut = true;
            return pair.reset();
          }
          pair.toClient(frame);
        });
        const c = track(client(`${url}&pdu=240`)) as S7Client & { delays: { attempt: number; delay: number }[] };
        await c.connect();
        await typedWithin(c.diagnosticBuffer(), rig0.timeout, ['CONNECTION_LOST']);
        await reconnected(c, BACKOFF.maxDelay + MARGIN);
        expect((await c.diagnosticBuffer()).length).to.equal(3 + 20 * 4);
      });

      it('a userdata answer dripped one byte at a time: every service answers right', async () => {
        const { c } = await servicesRig((frame, pair) => {
          for (const byte of frame) pair.toClient(Buffer.of(byte));
        });
        expect(await c.info()).to.deep.include({ orderCode: '6ES7 214-1AG40-0XB0', state: 'RUN' });
        expect((await c.diagnosticBuffer()).length).to.equal(3);
      });

      it('a userdata answer that never comes: TIMEOUT within the timeout, the link comes back', async () => {
        const { rig, c } = await servicesRig((frame, pair, n) => (n === 0 ? undefined : pair.toClient(frame)));
        await typedWithin(c.readClock(), rig.timeout, ['TIMEOUT']);
        await reconnected(c, rig.timeout + BACKOFF.maxDelay + MARGIN);
        expect((await c.cpuState()).mode).to.equal('RUN');
      });

      it('an unknown userdata function: the CPU error answer (NOT_SUPPORTED), the link stays up', async () => {
        const { rig, c } = await servicesRig((frame, pair) => pair.toClient(frame), 's7-1500');
        let drops = 0;
        c.on('disconnected', () => drops++);
        expect((await failure(c.listBlocks())).code).to.equal('NOT_SUPPORTED');
        expect((await failure(c.setPassword('abc'))).code).to.equal('NOT_SUPPORTED');
        await expectFreshValues(c, rig);
        expect(drops).to.equal(0);
      });
    });

    it('access denied (PUT/GET off): every write rejected with ACCESS_DENIED, the link stays up', async () => {
      const rig = await open(() => s7Rig());
      const c = track(client(rig.url()));
      await c.connect();
      rig.server().faults.accessDenied = true;
      for (let i = 0; i < BURST; i++) rig.poke(i, 0);
      const b = burst(c, rig, 0, BURST, (i) => 950 + i, 0);
      await b.settled(2000);
      expect(b.rejected.map((e) => (e.cause as PlcError | undefined)?.code ?? e.code)).to.deep.equal(Array(BURST).fill('ACCESS_DENIED'));
      for (let i = 0; i < BURST; i++) expect(rig.peek(i)).to.equal(0);
      rig.server().faults.accessDenied = false;
      expect(c.state).to.equal('connected');
      await expectFreshValues(c, rig);
    });
  });

  describe('freeport bus', () => {
    async function busClient(rig: Awaited<ReturnType<typeof freeportRig>>, query = '', profile?: { replyEchoesAddress: boolean }) {
      const endpoint = parseUrl(query ? rig.url().replace('retries=0', query) : rig.url()) as FreeportEndpoint;
      const c = track(new FreeportClient(endpoint, { backoff: BACKOFF, ...(profile ? { profile } : {}) })) as FreeportClient & {
        delays: unknown[];
      };
      c.delays = [];
      c.on('reconnecting', (r: unknown) => c.delays.push(r));
      await c.connect();
      return c;
    }

    it('noise on the line between and inside frames: every value that arrives is right, every error typed', async () => {
      const rig = await open(freeportRig);
      const c = await busClient(rig, 'retries=3');
      const noise = setInterval(() => rig.bus().sendRaw(Buffer.from('\u0000zz\u00ff7q1', 'latin1')), 2);
      cleanups.push(async () => clearInterval(noise));
      let good = 0;
      for (let n = 0; n < 30; n++) {
        rig.poke(3, n);
        try {
          expect(await c.read([rig.addr(3)])).to.deep.equal({ [rig.addr(3)]: n });
          good++;
        } catch (e) {
          expect(e).to.be.instanceOf(PlcError);
          expect((e as PlcError).code).to.be.oneOf(['TAG_ERRORS', 'TIMEOUT', 'PROTOCOL_ERROR']);
        }
      }
      clearInterval(noise);
      expect(good).to.be.greaterThan(15);
      expect(c.state).to.equal('connected');
    });

    it('checksum errors: a typed error without retries, the right value with one retry; a corrupted write acknowledgement is never taken as one', async () => {
      const rig = await open(freeportRig);
      const c = await busClient(rig);
      rig.poke(2, 77);
      rig.bus().faults.corruptNext = 1;
      const err = await typedWithin(c.read([rig.addr(2)]), rig.timeout, ['TAG_ERRORS']);
      expect((err.cause as PlcError).code).to.equal('PROTOCOL_ERROR');
      rig.bus().faults.corruptNext = 1;
      const w = await failure(c.write({ [rig.addr(4)]: 5 }));
      expect((w.cause as PlcError).code).to.equal('PROTOCOL_ERROR');
      const retrying = await busClient(rig, 'retries=1');
      rig.bus().faults.corruptNext = 1;
      expect(await retrying.read([rig.addr(2)])).to.deep.equal({ [rig.addr(2)]: 77 });
    });

    it('truncated replies: typed errors within retries × timeout, every write settled, right values once whole', async () => {
      const rig = await open(freeportRig);
      const c = await busClient(rig, 'retries=1');
      rig.bus().faults.dropCharRate = 1;
      await typedWithin(c.read([rig.addr(1)]), 2 * rig.timeout, ['TAG_ERRORS']);
      const b = burst(c, rig, 0, BURST, (i) => 100 + i, 0);
      await b.settled(2 * failedAttemptMs(rig) * BURST + 1000);
      expect(b.acked).to.deep.equal([]);
      rig.bus().faults.dropCharRate = 0;
      await expectFreshValues(c, rig);
      expect(c.delays).to.deep.equal([]);
    });

    it('a silent station fails alone within the timeout; writes to it are rejected, to the others acknowledged', async () => {
      const rig = await open(freeportRig);
      const c = await busClient(rig);
      rig.bus().station(2).silent = true; // slots 2 and 3
      rig.poke(0, 11);
      const t0 = Date.now();
      const r = await c.readDetailed([rig.addr(2), rig.addr(0)]);
      expect(Date.now() - t0).to.be.at.most(rig.timeout + MARGIN);
      expect(r[rig.addr(0)]).to.deep.equal({ ok: true, value: 11 });
      const silent = r[rig.addr(2)]!;
      expect(silent.ok || silent.error.code).to.equal('TIMEOUT');
      const b = burst(c, rig, 0, 6, (i) => 40 + i, 0);
      await b.settled(rig.timeout * 6 + 1000);
      expect(b.acked.sort()).to.deep.equal([0, 1, 4, 5]);
      expectAckedInMemory(rig, b, (i) => 40 + i);
      rig.bus().station(2).silent = false;
      await expectFreshValues(c, rig);
    });

    it('a station answering for another address (replies echo DA): the answer is not taken, the request times out', async () => {
      const bus = new FreeportBus({
        stations: { 5: Buffer.from([0, 5, 0, 0]), 6: Buffer.from([0, 6, 0, 0]) },
        profile: { replyEchoesAddress: true },
      });
      const port = await bus.listenTcp({ port: 0 });
      cleanups.push(() => bus.close());
      const endpoint = parseUrl(`freeport+tcp://127.0.0.1:${port}?timeout=150&retries=0`) as FreeportEndpoint;
      const c = track(new FreeportClient(endpoint, { backoff: BACKOFF, profile: { replyEchoesAddress: true } }));
      await c.connect();
      bus.station(6).answerAs = 5;
      const r = await c.readDetailed(['ST6,INT0', 'ST5,INT0']);
      expect(r['ST5,INT0']).to.deep.equal({ ok: true, value: 5 });
      const wrong = r['ST6,INT0']!;
      expect(wrong.ok || wrong.error.code).to.equal('TIMEOUT');
      // INT2 is a read-modify-write: its read is not answered, so nothing is written and the write is rejected.
      const w = await c.writeDetailed({ 'ST6,INT2': 9 });
      expect(w['ST6,INT2']!.ok || (w['ST6,INT2'] as { error: PlcError }).error.code).to.equal('TIMEOUT');
      expect(bus.station(6).data.readInt16BE(2)).to.equal(0);
      bus.station(6).answerAs = undefined;
      await c.write({ 'ST6,INT2': 9 });
      expect(await c.read(['ST6,INT0', 'ST6,INT2'])).to.deep.equal({ 'ST6,INT0': 6, 'ST6,INT2': 9 });
    });
  });
});
