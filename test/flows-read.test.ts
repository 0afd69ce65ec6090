/** A read node's queue and messages without Node-RED: one read at a time, bounded; one builder for both ways a read ends. */
import { expect } from 'chai';
import { ChangeFilter, PolledTable, outcomes, type TagOutcome } from '../lib';
import { ReadMessages, readOutput, type FlowMessage, type ReadOutput } from '../lib/flows/read-messages';
import { MAX_WAITING_READS, ReadQueue } from '../lib/flows/read-queue';

/** A promise and its resolve, to finish a job when the test says so. */
function later<T>() {
  let resolve!: (v: T) => void;
  const promise = new Promise<T>((r) => (resolve = r));
  return { promise, resolve };
}

describe('flows: read queue', () => {
  it('runs one job at a time, in order, also after a job failed', async () => {
    const q = new ReadQueue();
    const log: string[] = [];
    const first = later<string>();
    const a = q.run(async () => {
      log.push('a start');
      const v = await first.promise;
      log.push('a end');
      return v;
    });
    const b = q.run(() => {
      log.push('b');
      throw new Error('b failed');
    });
    const c = q.run(() => (log.push('c'), 3));
    expect(q.waiting).to.equal(3);
    await Promise.resolve();
    expect(log).to.deep.equal(['a start']);
    first.resolve('A');
    expect(await a).to.equal('A');
    await b.then(
      () => expect.fail('b resolved'),
      (err: Error) => expect(err.message).to.equal('b failed'),
    );
    expect(await c).to.equal(3);
    expect(log).to.deep.equal(['a start', 'a end', 'b', 'c']);
    expect(q.waiting).to.equal(0);
  });

  it('refuses a job beyond the limit with QUEUE_FULL, and takes jobs again once the queue moves', async () => {
    expect(MAX_WAITING_READS).to.equal(100);
    const q = new ReadQueue(2);
    const gate = later<void>();
    const running = q.run(() => gate.promise);
    const waiting = q.run(() => 'second');
    let err: (Error & { code?: string }) | undefined;
    await q.run(() => 'third').catch((e: Error & { code?: string }) => (err = e));
    expect(err?.code).to.equal('QUEUE_FULL');
    expect(err?.message).to.equal('more than 2 reads waiting; the PLC answers slower than messages arrive');
    gate.resolve();
    await running;
    expect(await waiting).to.equal('second');
    expect(await q.run(() => 'again')).to.equal('again');
  });
});

describe('flows: read messages', () => {
  const tags = [
    { name: 'speed', address: 'DB1,INT0' },
    { name: 'list', address: 'MW10:INT[2]' },
    { name: 'again', address: 'MW10:INT[2]' },
  ];
  const values = { 'DB1,INT0': 7, 'MW10:INT[2]': [1, 2] };
  const good = outcomes(tags, { 'DB1,INT0': { ok: true, value: 7 }, 'MW10:INT[2]': { ok: true, value: [1, 2] } });
  const error = { code: 'ADDRESS_OUT_OF_RANGE', message: 'no such DB', address: 'DB1,INT0' };
  const mixed: TagOutcome[] = [{ name: 'speed', address: 'DB1,INT0', ok: false, error }, good[1]!, good[2]!];

  function setup(output: ReadOutput) {
    let ids = 0;
    const sent: FlowMessage[] = [];
    const runtime = { clone: (m: FlowMessage) => structuredClone(m), newId: () => `id${++ids}` };
    const m = new ReadMessages(new PolledTable(tags), output, 'poller', new ChangeFilter(0), runtime);
    return { m, sent, send: (msg: FlowMessage) => sent.push(msg) };
  }

  it('the output mode a node configures; anything else is object', () => {
    expect(readOutput('per-tag')).to.equal('per-tag');
    expect(readOutput('changes')).to.equal('changes');
    expect(readOutput('csv')).to.equal('object');
    expect(readOutput(undefined)).to.equal('object');
  });

  it('object output: a good read sends the same message from values as from outcomes', () => {
    const fast = setup('object');
    fast.m.sendGood(fast.send, values);
    const slow = setup('object');
    slow.m.sendOutcomes(slow.send, good);
    expect(fast.sent).to.deep.equal(slow.sent);
    expect(Object.keys(fast.sent[0]!)).to.deep.equal(Object.keys(slow.sent[0]!));
    expect(fast.sent[0]).to.deep.equal({
      payload: { speed: 7, list: [1, 2], again: [1, 2] },
      quality: { speed: 'good', list: 'good', again: 'good' },
      addresses: { speed: 'DB1,INT0', list: 'MW10:INT[2]', again: 'MW10:INT[2]' },
      topic: 'poller',
    });
  });

  it('object output with a failed tag: its quality bad, its error by name, no payload for it; on the input message its own topic stays', () => {
    const { m, sent, send } = setup('object');
    const input: FlowMessage = { topic: 'mine', errors: 'stale', _msgid: 'in' };
    m.sendOutcomes(send, mixed, input);
    expect(sent).to.have.length(1);
    expect(sent[0]).to.equal(input);
    expect(input).to.deep.equal({
      topic: 'mine',
      _msgid: 'in',
      errors: { speed: error },
      payload: { list: [1, 2], again: [1, 2] },
      quality: { speed: 'bad', list: 'good', again: 'good' },
      addresses: { speed: 'DB1,INT0', list: 'MW10:INT[2]', again: 'MW10:INT[2]' },
    });
    m.sendGood(send, values, input);
    expect(input).to.not.have.property('errors');
  });

  it('per-tag output: the same messages from values as from outcomes, one id per read, each a fresh object', () => {
    const fast = setup('per-tag');
    fast.m.sendGood(fast.send, values);
    const slow = setup('per-tag');
    slow.m.sendOutcomes(slow.send, good);
    expect(fast.sent).to.deep.equal(slow.sent);
    expect(fast.sent.map((s) => [s.topic, s.payload, s.quality, s._msgid])).to.deep.equal([
      ['speed', 7, 'good', 'id1'],
      ['list', [1, 2], 'good', 'id1'],
      ['again', [1, 2], 'good', 'id1'],
    ]);
    // Two rows of one address: the later one's value is its own copy.
    expect(fast.sent[2]!.payload).to.not.equal(fast.sent[1]!.payload);
  });

  it('per-tag output on the input message: copies for all but the last, which is the input itself', () => {
    const { m, sent, send } = setup('per-tag');
    const input: FlowMessage = { _msgid: 'in', extra: { a: 1 } };
    m.sendOutcomes(send, mixed.slice(0, 2), input);
    expect(sent).to.have.length(2);
    expect(sent[1]).to.equal(input);
    expect(sent[0]).to.not.equal(input);
    expect(sent[0]).to.deep.include({ topic: 'speed', payload: null, quality: 'bad', errors: { speed: error }, _msgid: 'in' });
    expect(sent[0]!.extra).to.not.equal(input.extra);
    expect(sent[1]).to.not.have.property('errors');
  });

  it('per-tag output of outcomes: two rows of one address get their own copies of the value, as from values', () => {
    const { m, sent, send } = setup('per-tag');
    m.sendOutcomes(send, mixed);
    expect(sent[2]!.payload).to.deep.equal([1, 2]);
    expect(sent[2]!.payload).to.not.equal(sent[1]!.payload);
  });

  it('changes output: only what changed, from values or outcomes alike; on-demand lists are sent whole', () => {
    const { m, sent, send } = setup('changes');
    m.sendGood(send, values);
    expect(sent).to.have.length(3);
    m.sendOutcomes(send, good);
    expect(sent).to.have.length(3);
    m.sendGood(send, { ...values, 'DB1,INT0': 8 });
    expect(sent.slice(3).map((s) => [s.topic, s.payload])).to.deep.equal([['speed', 8]]);
    // A single message of a read of outcomes gets no id of its own (the runtime gives it one).
    m.sendOutcomes(send, mixed);
    expect(sent.slice(4).map((s) => [s.topic, s.quality, s._msgid])).to.deep.equal([['speed', 'bad', undefined]]);
    m.sendOutcomes(send, good, undefined, true);
    expect(sent.slice(5).map((s) => s.topic)).to.deep.equal(['speed', 'list', 'again']);
  });
});
