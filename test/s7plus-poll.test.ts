/**
 * A poll the PLC can afford (issue #32): our client against our simulator over TLS, through a proxy that counts the
 * requests the client sends (test/support/net.ts RequestCountingProxy: a TLS record each). The client reads the
 * PLC's SystemLimits once per session and sends each browsed name's SymbolCrc; the simulator refuses a stale one
 * (InvalidCRC). So a poll of n names is ceil(n / limit) requests and nothing else, within the negotiated TPDU size,
 * and a download between two polls is seen by the PLC's refusal, never read through.
 */
import { expect } from 'chai';
import fc from 'fast-check';
import { createClient } from '../lib/connect';
import type { PlcError } from '../lib/errors';
import type { S7PlusClient } from '../lib/s7plus/client';
import { cut } from '../lib/s7plus/client/chunks';
import { encodeFrames } from '../lib/s7plus/codec/frame';
import { addressBytes, encodeGetMultiVariablesRequest, readRequest, type ItemAddress } from '../lib/s7plus/codec/variables';
import { ProtocolVersion } from '../lib/s7plus/constants';
import { S7Server, type S7Profile } from '../lib/s7/server';
import { S7PlusService } from '../lib/s7plus/server';
import { generateCertificate } from '../lib/s7plus/transport/cert';
import type { SymbolSource } from '../lib/symbols/model';
import { RequestCountingProxy } from './support/net';

/** An optimized DB of `n` INT members m0 … m(n-1), each started at its index. */
function pollDb(n: number): SymbolSource {
  const members = Array.from({ length: n }, (_, i) => `      m${i} : Int := ${i};`).join('\n');
  return {
    name: 'Poll.db',
    content: `DATA_BLOCK "Poll"\n{ S7_Optimized_Access := 'TRUE' }\nVERSION : 0.1\n   STRUCT\n${members}\n   END_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n`,
  };
}

const names = (n: number) => Array.from({ length: n }, (_, i) => `"Poll".m${i}`);

interface Rig {
  server: S7Server;
  service: S7PlusService;
  proxy: RequestCountingProxy;
  client: S7PlusClient;
}

describe('S7CommPlus poll: SystemLimits, SymbolCrc, no program check per poll (issue #32)', function () {
  this.timeout(30000);
  const rigs: Rig[] = [];

  async function rig(profile: S7Profile, sources: SymbolSource[], db: Record<string, number>, query = '', cpuMax?: number): Promise<Rig> {
    const cert = await generateCertificate();
    const service = new S7PlusService({ sources, db, tls: { cert: cert.cert, key: cert.key }, ...(cpuMax ? { maxItems: cpuMax } : {}) });
    const server = new S7Server({ port: 0, profile, s7plus: service });
    await server.listen();
    const proxy = new RequestCountingProxy(server.port);
    const port = await proxy.listen();
    const client = createClient(`s7plus://127.0.0.1:${port}?fingerprint=${service.fingerprint!}&timeout=10000${query}`) as S7PlusClient;
    const r = { server, service, proxy, client };
    rigs.push(r);
    await client.connect();
    return r;
  }

  afterEach(async () => {
    for (const r of rigs.splice(0)) {
      await r.client.close();
      await r.proxy.close();
      await r.server.close();
    }
  });

  /** Requests of each of `polls` polls of `tags` after a first one (browse, SystemLimits), values checked. */
  async function perPoll(r: Rig, tags: string[], polls = 5): Promise<number> {
    const first = await r.client.read(tags);
    r.proxy.reset();
    for (let i = 0; i < polls; i++) expect(await r.client.read(tags)).to.deep.equal(first);
    return r.proxy.requests / polls;
  }

  it('polls 100 names of an S7-1200 (SystemLimits 50) in ceil(100 / 50) = 2 requests and nothing else', async () => {
    const r = await rig('s7-1200', [pollDb(100)], { Poll: 1 });
    expect(await perPoll(r, names(100))).to.equal(2);
    expect(r.client.maxItems).to.equal(50);
    // Within the negotiated TPDU size (1024 bytes of S7CommPlus frame; the TLS record adds its header and tag).
    expect(r.proxy.largest).to.be.at.most(1024 + 64);
  });

  it('polls 60 names of an S7-1500 (SystemLimits 100) in one request; 100 names in 2, as 100 item addresses pass the 1024-byte frame', async () => {
    const r = await rig('s7-1500', [pollDb(100)], { Poll: 1 });
    expect(await perPoll(r, names(60))).to.equal(1);
    expect(r.client.maxItems).to.equal(100);
    expect(await perPoll(r, names(100))).to.equal(2);
    expect(r.proxy.largest).to.be.at.most(1024 + 64);
  });

  it('takes the URL`s maxItems as an override of SystemLimits: maxItems=25 polls 100 names in 4 requests', async () => {
    const r = await rig('s7-1500', [pollDb(100)], { Poll: 1 }, '&maxItems=25');
    expect(await perPoll(r, names(100))).to.equal(4);
    expect(r.client.maxItems).to.equal(25);
  });

  it('an override above the CPU`s limit: the CPU refuses the request of 60 items as a whole (no reset), the client learns 50 and reads every value', async () => {
    const r = await rig('s7-1200', [pollDb(100)], { Poll: 1 }, '&maxItems=60');
    let drops = 0;
    r.client.on('disconnected', () => drops++);
    const values = await r.client.read(names(60));
    expect(Object.keys(values)).to.have.length(60);
    expect(r.client.maxItems).to.be.at.most(50);
    r.proxy.reset();
    expect(await r.client.read(names(60))).to.deep.equal(values);
    expect(r.proxy.requests).to.equal(2);
    expect(r.client.state).to.equal('connected');
    expect(drops).to.equal(0);
  });

  it('a write by name above the CPU`s limit: refused as a whole, sent again in smaller requests, every member written', async () => {
    // The CPU serves 20 items a request, the URL says 60: the frame alone would cut 60 writes in two requests of about 30.
    const r = await rig('s7-1200', [pollDb(100)], { Poll: 1 }, '&maxItems=60', 20);
    await r.client.read(names(1));
    r.proxy.reset();
    await r.client.write(Object.fromEntries(names(60).map((n, i) => [n, 1000 + i])));
    expect(r.proxy.requests).to.be.at.least(4);
    const written = await r.client.read(names(60));
    expect(names(60).filter((n, i) => written[n] !== 1000 + i)).to.deep.equal([]);
  });

  it('never yields a stale value across a download: a member whose type changed, then one deleted before the others', async () => {
    const line = (body: string): SymbolSource => ({
      name: 'Line.db',
      content: `DATA_BLOCK "Line"\n{ S7_Optimized_Access := 'TRUE' }\nVERSION : 0.1\n   STRUCT\n${body}   END_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n`,
    });
    const r = await rig('s7-1500', [line('      a : Int := 1;\n      b : Int := 2;\n      c : Real := 3.5;\n')], { Line: 4 });
    const tags = ['"Line".a', '"Line".b', '"Line".c'];
    expect(await r.client.read(tags)).to.deep.equal({ '"Line".a': 1, '"Line".b': 2, '"Line".c': 3.5 });
    r.proxy.reset();
    expect(await r.client.read(tags)).to.deep.equal({ '"Line".a': 1, '"Line".b': 2, '"Line".c': 3.5 });
    expect(r.proxy.requests, 'a poll before the download: one read, no program check').to.equal(1);
    // b becomes a REAL at the same LID: its old SymbolCrc (an INT's) no longer matches.
    r.service.reload([line('      a : Int := 1;\n      b : Real := 2.5;\n      c : Real := 3.5;\n')], r.server.memory);
    expect(await r.client.read(tags)).to.deep.equal({ '"Line".a': 1, '"Line".b': 2.5, '"Line".c': 3.5 });
    // a is deleted: b and c move to the LIDs a and b had, each refused for its CRC, read again under its new LID.
    r.service.reload([line('      b : Real := 2.5;\n      c : Real := 4.25;\n')], r.server.memory);
    const after = await r.client.readDetailed(tags);
    expect((after['"Line".a'] as { ok: false; error: PlcError }).error.code).to.equal('INVALID_ADDRESS');
    expect(after['"Line".b']).to.deep.equal({ ok: true, value: 2.5 });
    expect(after['"Line".c']).to.deep.equal({ ok: true, value: 4.25 });
    r.proxy.reset();
    expect(await r.client.read(tags.slice(1))).to.deep.equal({ '"Line".b': 2.5, '"Line".c': 4.25 });
    expect(r.proxy.requests, 'a poll after the new browse: one read again').to.equal(1);
  });

  it('a write by name after a download lands in the member it names, not in the one that took its LID', async () => {
    const line = (body: string): SymbolSource => ({
      name: 'Line.db',
      content: `DATA_BLOCK "Line"\n{ S7_Optimized_Access := 'TRUE' }\nVERSION : 0.1\n   STRUCT\n${body}   END_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n`,
    });
    const r = await rig('s7-1500', [line('      a : Int := 1;\n      b : Int := 2;\n')], { Line: 4 });
    expect(await r.client.read(['"Line".b'])).to.deep.equal({ '"Line".b': 2 });
    r.service.reload([line('      b : Int := 2;\n      x : Int := 9;\n')], r.server.memory);
    r.proxy.reset();
    await r.client.write({ '"Line".b': 7 });
    expect(await r.client.read(['"Line".b', '"Line".x'])).to.deep.equal({ '"Line".b': 7, '"Line".x': 9 });
  });

  it('keeps the program check for a name without a SymbolCrc (a multi-dimensional array`s element) only', async () => {
    const grid: SymbolSource = {
      name: 'Grid.db',
      content: `DATA_BLOCK "Grid"\n{ S7_Optimized_Access := 'TRUE' }\nVERSION : 0.1\n   STRUCT\n      g : Array[1..2, 0..1] of Int;\n      h : Int := 5;\n   END_STRUCT;\nBEGIN\n   g[2,1] := 4;\nEND_DATA_BLOCK\n`,
    };
    const r = await rig('s7-1500', [grid], { Grid: 5 });
    expect(await perPoll(r, ['"Grid".h'])).to.equal(1);
    // One read and the Explore of the type objects' modification times.
    expect(await perPoll(r, ['"Grid".h', '"Grid".g[2,1]'])).to.equal(2);
  });
});

describe('S7CommPlus request frames within the negotiated TPDU size (issue #32)', () => {
  const u32 = fc.integer({ min: 0, max: 0xffffffff });
  const address = fc.record({
    symbolCrc: u32,
    accessArea: u32,
    accessSubArea: u32,
    lids: fc.array(u32, { minLength: 1, maxLength: 6 }),
  });

  it('cuts items so that each request frame (header to trailer, integrity id included) stays within the frame', () => {
    fc.assert(
      fc.property(
        fc.array(address, { minLength: 1, maxLength: 150 }),
        fc.integer({ min: 128, max: 2048 }),
        fc.integer({ min: 1, max: 120 }),
        (items, frame, max) => {
          const chunks = cut<ItemAddress>(items, { maxItems: () => max, refused: () => undefined, maxFrame: () => frame }, addressBytes);
          expect(chunks.flat()).to.deep.equal(items);
          for (const chunk of chunks) {
            expect(chunk.length).to.be.at.most(max);
            const data = encodeGetMultiVariablesRequest({ ...readRequest(0xffff, 0xffffffff, chunk), integrityId: 0xffffffff });
            // One item alone over the frame still goes (alone): the PLC's answer is its result.
            if (chunk.length > 1) expect(encodeFrames(ProtocolVersion.V2, data).length).to.be.at.most(frame);
          }
        },
      ),
    );
  });

  it('without a frame, cuts by the item limit alone', () => {
    const items = Array.from({ length: 7 }, (_, i) => i);
    expect(cut(items, { maxItems: () => 3, refused: () => undefined })).to.deep.equal([[0, 1, 2], [3, 4, 5], [6]]);
  });
});
