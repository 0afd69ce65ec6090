import { expect } from 'chai';
import { PlcError, TagErrors } from '../lib/errors';
import { S7Client } from '../lib/s7/client';
import { cyclicInterval, planCyclic, type S7CyclicSubscription } from '../lib/s7/client/cyclic';
import { S7Server, type S7Profile } from '../lib/s7/server';
import { encodeCyclicSubscribe, CyclicSubfunction } from '../lib/s7/codec/cyclic';
import { decodeUserdata } from '../lib/s7/codec/userdata';
import { parseUrl, type S7Endpoint } from '../lib/url';
import type { SubscriptionNotice } from '../lib/types';
import { waitFor } from './support/wait';

const SLOT: Record<S7Profile, number> = { 's7-300': 2, 's7-400': 2, 's7-1200': 1, 's7-1500': 1, 's7-200': 1, logo: 1 };
const LOGO_TSAPS = '&localTsap=0100&remoteTsap=0200';
const S7_200_TSAPS = '&localTsap=1000&remoteTsap=1001';

describe('S7 cyclic data (userdata group 2): client against the simulator', function () {
  this.timeout(15000);
  const open: { close(): Promise<void> }[] = [];

  async function start(profile: S7Profile = 's7-300', query = ''): Promise<{ server: S7Server; client: S7Client }> {
    const server = new S7Server({ port: 0, profile, layout: { dataBlocks: { 1: 1000, 2: 64 }, flags: 64 } });
    await server.listen();
    open.push(server);
    const at = profile === 'logo' ? LOGO_TSAPS : profile === 's7-200' ? S7_200_TSAPS : `&slot=${SLOT[profile]}`;
    const client = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?timeout=3000${at}${query}`) as S7Endpoint);
    open.unshift(client);
    await client.connect();
    return { server, client };
  }

  async function subscribe(client: S7Client, tags: string[], options = {}): Promise<S7CyclicSubscription> {
    const sub = await client.subscribe(tags, options);
    open.unshift(sub);
    return sub;
  }

  afterEach(async () => {
    for (const x of open.splice(0)) await x.close();
  });

  it('maps a cycle to the nearest time base × factor the CPU can do', () => {
    expect(cyclicInterval(100)).to.deep.equal({ timeBase: 0, factor: 1, ms: 100 });
    expect(cyclicInterval(250)).to.deep.equal({ timeBase: 0, factor: 3, ms: 300 });
    expect(cyclicInterval(1000)).to.deep.equal({ timeBase: 1, factor: 1, ms: 1000 });
    expect(cyclicInterval(30_000)).to.deep.equal({ timeBase: 2, factor: 3, ms: 30_000 });
    expect(cyclicInterval(10)).to.deep.equal({ timeBase: 0, factor: 1, ms: 100 });
    expect(cyclicInterval(10_000_000)).to.deep.equal({ timeBase: 2, factor: 255, ms: 2_550_000 });
  });

  it('an S7-300 sends the tags every cycle, decoded as a read decodes them, first values in the answer', async () => {
    const { server, client } = await start();
    server.memory.write('DB', 1, 0, Buffer.from([0x00, 0x2a, 0x41, 0x20, 0x00, 0x00]));
    server.memory.writeBit('M', 0, 3, 1, true);
    const sub = await subscribe(client, ['DB1,INT0', 'DB1,REAL2', 'M3.1', 'DB1,STRING100.10'], { cycle: 100 });
    expect(sub.cycle).to.equal(100);
    const first = await waitFor<SubscriptionNotice>(sub, 'data', 3000);
    // The first values (the CPU's answer) reach a listener added after subscribe() resolved.
    expect(first.initial).to.equal(true);
    expect(first.changed).to.have.length(4);
    expect(first.results['DB1,INT0']).to.deep.equal({ ok: true, value: 42 });
    expect(first.results['DB1,REAL2']).to.deep.equal({ ok: true, value: 10 });
    expect(first.results['M3.1']).to.deep.equal({ ok: true, value: true });
    const read = await client.read(['DB1,STRING100.10']);
    expect(first.results['DB1,STRING100.10']).to.deep.equal({ ok: true, value: read['DB1,STRING100.10'] });
    server.memory.write('DB', 1, 0, Buffer.from([0x01, 0x00]));
    const next = await waitFor<SubscriptionNotice>(sub, 'data', 3000, (d: SubscriptionNotice) => d.changed.includes('DB1,INT0'));
    expect(next.results['DB1,INT0']).to.deep.equal({ ok: true, value: 256 });
    expect(next.initial).to.equal(false);
  });

  it('change-driven: the CPU sends only when a value changed', async () => {
    const { server, client } = await start('s7-400');
    const sub = await subscribe(client, ['DB2,DINT4'], { cycle: 100, onChange: true });
    let pushes = 0;
    sub.on('data', (d: SubscriptionNotice) => !d.initial && pushes++);
    // A cycle without a change (the read of its check): no push; then a change: one.
    const pushed = new Promise<void>((resolve) => server.memory.once('read', () => resolve()));
    await pushed;
    expect(pushes).to.equal(0);
    server.memory.write('DB', 2, 4, Buffer.from([0, 0, 0, 7]));
    const d = await waitFor<SubscriptionNotice>(sub, 'data', 3000);
    expect(d.results['DB2,DINT4']).to.deep.equal({ ok: true, value: 7 });
  });

  it('more items than one job carries become several jobs, each pushed', async () => {
    const { server, client } = await start('s7-300', '&maxItems=5');
    const tags = Array.from({ length: 12 }, (_, i) => `DB1,INT${i * 10}`);
    for (let i = 0; i < 12; i++) server.memory.write('DB', 1, i * 10, Buffer.from([0, i]));
    const sub = await subscribe(client, tags, { cycle: 100 });
    const seen = new Set<string>();
    await new Promise<void>((resolve) =>
      sub.on('data', (d: SubscriptionNotice) => {
        if (d.initial) return;
        for (const t of d.changed) seen.add(t);
        if (tags.every((t) => d.results[t]?.ok)) resolve();
      }),
    );
    const last = await waitFor<SubscriptionNotice>(sub, 'data', 3000);
    tags.forEach((t, i) => expect(last.results[t]).to.deep.equal({ ok: true, value: i }));
    expect(
      planCyclic(
        tags.map((t) => client.tag(t)),
        240,
        5,
      ).jobs.map((j) => j.items.length),
    ).to.deep.equal([5, 5, 2]);
  });

  it('a DB that does not exist fails its tag only, with the read error', async () => {
    const { client } = await start();
    const sub = await subscribe(client, ['DB1,INT0', 'DB9,INT0'], { cycle: 100 });
    const d = await waitFor<SubscriptionNotice>(sub, 'data', 3000, (x: SubscriptionNotice) => 'DB9,INT0' in x.results);
    expect(d.results['DB1,INT0']!.ok).to.equal(true);
    const bad = d.results['DB9,INT0']!;
    expect(bad.ok).to.equal(false);
    if (!bad.ok) expect(bad.error.code).to.equal('OBJECT_DOES_NOT_EXIST');
  });

  it('registered again after a reconnect (the CPU forgot the jobs of the closed connection)', async () => {
    const { server, client } = await start();
    const sub = await subscribe(client, ['DB1,INT0'], { cycle: 100 });
    await waitFor(sub, 'data', 3000);
    const lost = waitFor(sub, 'lost', 3000);
    server.dropConnections();
    await lost;
    await waitFor(sub, 'active', 10000);
    server.memory.write('DB', 1, 0, Buffer.from([0, 99]));
    const d = await waitFor<SubscriptionNotice>(
      sub,
      'data',
      5000,
      (x: SubscriptionNotice) => x.results['DB1,INT0']?.ok === true && x.results['DB1,INT0'].value === 99,
    );
    expect(d.results['DB1,INT0']).to.deep.equal({ ok: true, value: 99 });
  });

  it('close() ends the jobs on the CPU; a closed connection ends its jobs too', async () => {
    const { server, client } = await start();
    const sub = await subscribe(client, ['DB1,INT0'], { cycle: 100 });
    const cyclic = (server as unknown as { cyclic: { jobCount: number } }).cyclic;
    expect(cyclic.jobCount).to.equal(1);
    await sub.close();
    expect(cyclic.jobCount).to.equal(0);
    await subscribe(client, ['DB1,INT0'], { cycle: 100 });
    expect(cyclic.jobCount).to.equal(1);
    await client.close();
    await waitFor(server, 'disconnect', 3000);
    expect(cyclic.jobCount).to.equal(0);
  });

  it("beyond the CPU's 16 jobs: 0xD805; a cycle outside 100 ms … 52.1 s: 0xD804", async () => {
    const { client } = await start();
    for (let i = 0; i < 16; i++) await subscribe(client, [`DB1,INT${i * 2}`], { cycle: 1000 });
    const err = await client.subscribe(['DB1,INT40'], { cycle: 1000 }).then(
      () => undefined,
      (e: PlcError) => e,
    );
    expect(err).to.be.instanceOf(PlcError);
    expect(err!.plcCode).to.equal(0xd805);
    expect(err!.message).to.match(/no more cyclic read jobs/i);
    const long = await client.subscribe(['DB1,INT40'], { cycle: 60_000 }).then(
      () => undefined,
      (e: PlcError) => e,
    );
    expect(long!.plcCode).to.equal(0xd804);
  });

  for (const profile of ['s7-1200', 's7-1500', 's7-200', 'logo'] as const) {
    it(`${profile} refuses cyclic data as its CPU does (0x8104); the error names the way on`, async () => {
      const { client } = await start(profile);
      const err = await client.subscribe(['DB1,INT0'], { cycle: 100 }).then(
        () => undefined,
        (e: unknown) => e,
      );
      expect(err).to.be.instanceOf(TagErrors);
      const one = (err as TagErrors).errors['DB1,INT0']!;
      expect(one.code).to.equal('NOT_SUPPORTED');
      expect(one.message).to.include('0x8104');
      expect(one.message).to.include('s7plus://');
    });
  }

  it('the simulator answers a registration with the job id as sequence number', async () => {
    const { client } = await start();
    const session = (client as unknown as { session: { exchange(f: Buffer, w: string): Promise<Buffer> } }).session;
    const frame = encodeCyclicSubscribe({
      subfunction: CyclicSubfunction.Memory,
      timeBase: 1,
      factor: 1,
      items: [{ area: 0x84, dbNumber: 1, transportSize: 2, count: 2, address: 0 }],
    });
    const a = decodeUserdata(await session.exchange(frame, 'test'));
    const b = decodeUserdata(await session.exchange(frame, 'test'));
    expect([a.params.sequence, b.params.sequence]).to.deep.equal([1, 2]);
    expect(a.params.errorCode).to.equal(0);
  });
});
