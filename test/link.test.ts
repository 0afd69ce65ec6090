import { expect } from 'chai';
import * as net from 'node:net';
import { EventEmitter } from 'node:events';
import { PlcError, ProtocolError, TimeoutError } from '../lib/errors';
import { backoffDelay } from '../lib/link/backoff';
import { FrameReader, type FrameCheck } from '../lib/link/framer';
import { JobQueue } from '../lib/link/jobs';
import { PendingRequests } from '../lib/link/pending';
import { LinkSupervisor, type DriverSession } from '../lib/link/supervisor';
import { openTcp } from '../lib/link/tcp';
import { collectGarbage } from './support/gc';
import { activeHandles, settle, until, waitFor } from './support/wait';

// A length-prefixed toy framing: first byte = total frame length (0 = bad).
const lengthPrefixed = (buf: Buffer): FrameCheck => {
  if (buf[0] === 0) return { kind: 'bad', error: new ProtocolError('length 0') };
  if (buf[0] === 0xff) return { kind: 'skip', length: 1 };
  return buf.length >= buf[0]! ? { kind: 'frame', length: buf[0]! } : { kind: 'need' };
};

describe('link: FrameReader', () => {
  const stream = Buffer.from([3, 1, 2, 0xff, 2, 9, 4, 7, 7, 7]);
  const expected = ['030102', '0209', '04070707'];

  it('cuts the same frames at every split point', () => {
    for (let split = 0; split <= stream.length; split++) {
      const reader = new FrameReader(lengthPrefixed);
      const frames = [...reader.push(stream.subarray(0, split)), ...reader.push(stream.subarray(split))];
      expect(
        frames.map((f) => f.toString('hex')),
        `split at ${split}`,
      ).to.deep.equal(expected);
      expect(reader.buffered).to.equal(0);
    }
  });

  it('delivers frames byte by byte', () => {
    const reader = new FrameReader(lengthPrefixed);
    const frames: Buffer[] = [];
    for (const byte of stream) frames.push(...reader.push(Buffer.of(byte)));
    expect(frames.map((f) => f.toString('hex'))).to.deep.equal(expected);
  });

  it('throws the framer error on a bad frame and forgets the buffer', () => {
    const reader = new FrameReader(lengthPrefixed);
    expect(() => reader.push(Buffer.from([2, 1, 0, 5]))).to.throw(ProtocolError, 'length 0');
    expect(reader.buffered).to.equal(0);
  });

  it('copies frames by default; with copy: false they share the chunks memory, also across chunks', () => {
    const chunk = Buffer.from(stream);
    const copied = new FrameReader(lengthPrefixed).push(chunk);
    const shared = new FrameReader(lengthPrefixed, undefined, { copy: false }).push(chunk);
    chunk[1] = 0xaa;
    expect(copied[0]!.toString('hex')).to.equal('030102');
    expect(shared[0]!.toString('hex')).to.equal('03aa02');
    expect(shared[2]!.buffer).to.equal(chunk.buffer);
    const reader = new FrameReader(lengthPrefixed, undefined, { copy: false });
    const frames = [...reader.push(stream.subarray(0, 5)), ...reader.push(stream.subarray(5))];
    expect(frames.map((f) => f.toString('hex'))).to.deep.equal(expected);
    expect(reader.buffered).to.equal(0);
  });

  it('refuses to buffer more than its limit (a hostile length field)', () => {
    const reader = new FrameReader(() => ({ kind: 'need' }), 16);
    reader.push(Buffer.alloc(10));
    expect(() => reader.push(Buffer.alloc(10))).to.throw(ProtocolError, 'limit 16');
  });
});

describe('link: PendingRequests', () => {
  it('settles once: a late reply after a timeout is reported as unknown', async () => {
    const pending = new PendingRequests<string>();
    const p = pending.add(7, 20, 'read DB1');
    let err: unknown;
    await p.catch((e) => (err = e));
    expect(err).to.be.instanceOf(TimeoutError);
    expect((err as Error).message).to.equal('read DB1 timed out after 20 ms');
    expect((err as Error).stack).to.include('link.test');
    expect(pending.resolve(7, 'late')).to.equal(false);
    expect(pending.size).to.equal(0);
  });

  it('rejects all on close and on abort', async () => {
    const pending = new PendingRequests<number>();
    const ac = new AbortController();
    const a = pending.add(1, 1000, 'a');
    const b = pending.add(2, 1000, 'b', ac.signal);
    ac.abort();
    const bErr = await b.catch((e: PlcError) => e);
    expect((bErr as PlcError).code).to.equal('ABORTED');
    pending.rejectAll(new PlcError('CLOSED', 'closed'));
    const aErr = await a.catch((e: PlcError) => e);
    expect((aErr as PlcError).code).to.equal('CLOSED');
    expect(pending.size).to.equal(0);
  });

  it('resolves by id regardless of order', async () => {
    const pending = new PendingRequests<string>();
    const a = pending.add(1, 1000, 'a');
    const b = pending.add(2, 1000, 'b');
    expect(pending.resolve(2, 'B')).to.equal(true);
    expect(pending.resolve(1, 'A')).to.equal(true);
    expect(await Promise.all([a, b])).to.deep.equal(['A', 'B']);
  });
});

describe('link: JobQueue', () => {
  it('runs at most `concurrency` jobs at once, in order', async () => {
    const queue = new JobQueue({ concurrency: 3 });
    let running = 0;
    let peak = 0;
    const order: number[] = [];
    const jobs = Array.from({ length: 10 }, (_, i) =>
      queue.run(async () => {
        running++;
        peak = Math.max(peak, running);
        order.push(i);
        await new Promise((r) => setImmediate(r));
        running--;
        return i;
      }),
    );
    expect(await Promise.all(jobs)).to.deep.equal([0, 1, 2, 3, 4, 5, 6, 7, 8, 9]);
    expect(peak).to.equal(3);
    expect(order).to.deep.equal([0, 1, 2, 3, 4, 5, 6, 7, 8, 9]);
  });

  it('refuses work past its bound with QUEUE_FULL instead of growing', async () => {
    const queue = new JobQueue({ concurrency: 1, maxQueued: 2 });
    let release!: () => void;
    const first = queue.run(() => new Promise<void>((r) => (release = r)));
    const queued = [queue.run(async () => 1), queue.run(async () => 2)];
    const err = await queue.run(async () => 3).catch((e: PlcError) => e);
    expect((err as PlcError).code).to.equal('QUEUE_FULL');
    release();
    await first;
    expect(await Promise.all(queued)).to.deep.equal([1, 2]);
  });

  it('rejectAll rejects waiting jobs; a throwing job rejects only itself', async () => {
    const queue = new JobQueue({ concurrency: 1 });
    let release!: () => void;
    const first = queue.run(() => new Promise<void>((r) => (release = r)));
    const waiting = queue.run(async () => 'never');
    queue.rejectAll(new PlcError('CLOSED', 'closed'));
    expect(((await waiting.catch((e) => e)) as PlcError).code).to.equal('CLOSED');
    release();
    await first;
    const bad = queue.run(() => {
      throw new Error('sync throw');
    });
    expect(((await bad.catch((e) => e)) as Error).message).to.equal('sync throw');
    expect(await queue.run(async () => 'ok')).to.equal('ok');
    await queue.idle();
  });

  it('lets go of a job once it started: the queue keeps no reply alive', async () => {
    const queue = new JobQueue({ concurrency: 1 });
    let freed = 0;
    const registry = new FinalizationRegistry(() => freed++);
    for (let i = 0; i < 20; i++) {
      await queue.run(async () => {
        const reply = { i };
        registry.register(reply, i);
        return reply;
      });
    }
    await until(
      () => {
        collectGarbage();
        return freed === 20;
      },
      2000,
      'all 20 replies freed',
    );
  });
});

describe('link: backoff', () => {
  it('grows exponentially and is capped, with bounded jitter', () => {
    const noJitter = { initialDelay: 100, maxDelay: 1000, factor: 2, jitter: 0 };
    expect([1, 2, 3, 4, 5, 6].map((n) => backoffDelay(n, noJitter))).to.deep.equal([100, 200, 400, 800, 1000, 1000]);
    const j = { initialDelay: 1000, maxDelay: 60_000, factor: 2, jitter: 0.2 };
    expect(backoffDelay(1, j, () => 0)).to.equal(800);
    expect(backoffDelay(1, j, () => 0.999999)).to.equal(1200);
  });
});

class FakeSession implements DriverSession {
  destroyed = false;
  destroy(): void {
    this.destroyed = true;
  }
}

describe('link: LinkSupervisor', () => {
  const fast = { initialDelay: 5, maxDelay: 20, factor: 2, jitter: 0 };

  it('reconnects forever after failures and after a lost session, emitting states in order', async () => {
    const events = new EventEmitter();
    const seen: string[] = [];
    for (const e of ['connecting', 'connected', 'disconnected', 'reconnecting']) events.on(e, () => seen.push(e));
    let attempts = 0;
    const sessions: FakeSession[] = [];
    const sup = new LinkSupervisor<FakeSession>({
      name: 'fake',
      connectTimeout: 100,
      backoff: fast,
      events,
      open: async () => {
        if (++attempts <= 2) throw new PlcError('CONNECT_FAILED', `attempt ${attempts} refused`);
        const s = new FakeSession();
        sessions.push(s);
        return s;
      },
    });
    sup.start();
    await waitFor(events, 'connected');
    expect(seen).to.deep.equal(['connecting', 'reconnecting', 'connecting', 'reconnecting', 'connecting', 'connected']);
    sup.lost(sessions[0]!, new PlcError('CONNECTION_LOST', 'reset'));
    expect(sessions[0]!.destroyed).to.equal(true);
    await waitFor(events, 'connected');
    expect(sup.session).to.equal(sessions[1]);
    await sup.close();
    expect(sessions[1]!.destroyed).to.equal(true);
    expect(sup.state).to.equal('closed');
  });

  it('connectOnce rejects with the first error and stops', async () => {
    const events = new EventEmitter();
    let attempts = 0;
    const sup = new LinkSupervisor<FakeSession>({
      name: 'fake',
      connectTimeout: 100,
      backoff: fast,
      events,
      open: async () => {
        attempts++;
        throw new PlcError('CONNECT_FAILED', 'refused');
      },
    });
    const err = await sup.connectOnce().catch((e: PlcError) => e);
    expect((err as PlcError).code).to.equal('CONNECT_FAILED');
    expect(sup.state).to.equal('closed');
    expect(attempts).to.equal(1);
  });

  it('gives up an attempt that hangs at the connect timeout and destroys it if it opens later', async () => {
    const events = new EventEmitter();
    let finish!: (s: FakeSession) => void;
    const late = new FakeSession();
    const sup = new LinkSupervisor<FakeSession>({
      name: 'hang',
      connectTimeout: 30,
      events,
      open: () => new Promise((r) => (finish = r)),
    });
    const err = await sup.connectOnce().catch((e: PlcError) => e);
    expect((err as PlcError).code).to.equal('TIMEOUT');
    finish(late);
    await settle();
    expect(late.destroyed).to.equal(true);
  });

  it('emits error only when someone listens (an unheard error never crashes)', async () => {
    const events = new EventEmitter();
    const sup = new LinkSupervisor<FakeSession>({
      name: 'x',
      connectTimeout: 50,
      backoff: fast,
      events,
      open: async () => {
        throw new PlcError('CONNECT_FAILED', 'no');
      },
    });
    sup.start();
    await waitFor(events, 'reconnecting');
    const errors: PlcError[] = [];
    events.on('error', (e) => errors.push(e));
    await waitFor(events, 'reconnecting');
    await sup.close();
    expect(errors.length).to.be.greaterThan(0);
    expect(errors[0]!.code).to.equal('CONNECT_FAILED');
  });
});

describe('link: openTcp', () => {
  it('connects with no-delay and leaves nothing behind on refusal', async () => {
    const server = net.createServer((s) => s.end());
    await new Promise<void>((r) => server.listen(0, '127.0.0.1', r));
    const { port } = server.address() as net.AddressInfo;
    const socket = await openTcp({ host: '127.0.0.1', port, timeout: 1000 });
    expect(socket.remotePort).to.equal(port);
    socket.destroy();
    await new Promise<void>((r) => server.close(() => r()));
    await settle();
    const before = activeHandles();
    const err = await openTcp({ host: '127.0.0.1', port, timeout: 1000 }).catch((e: PlcError) => e);
    expect((err as PlcError).code).to.equal('CONNECT_FAILED');
    expect((err as PlcError).message)
      .to.include(`127.0.0.1:${port}`)
      .and.include('ECONNREFUSED');
    await settle();
    expect(activeHandles()).to.equal(before);
  });

  it('honours an abort signal', async () => {
    const ac = new AbortController();
    ac.abort();
    const err = await openTcp({ host: '127.0.0.1', port: 1, timeout: 1000, signal: ac.signal }).catch((e) => e);
    expect((err as PlcError).code).to.equal('ABORTED');
  });
});
