import { expect } from 'chai';
import * as net from 'node:net';
import { FrameReader } from '../lib/link/framer';
import {
  checkTpkt,
  decodeCotp,
  decodeS7,
  encodeConnectionRequest,
  encodeReadRequest,
  encodeSetupCommunication,
  encodeWriteRequest,
  type CotpMessage,
  type S7Item,
  type S7Message,
  type S7WriteItem,
} from '../lib/s7/codec';
import { PlcError } from '../lib/errors';
import { S7Client } from '../lib/s7/client';
import { decodeUserdata } from '../lib/s7/codec/userdata';
import { headerError, remoteTsapFor } from '../lib/s7/constants';
import { PROFILES, S7Server, refusalLine, type S7Profile, type S7RefusedEvent, type S7RequestEvent } from '../lib/s7/server';
import type { MemoryAccess } from '../lib/sim/memory';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { CAPTURE, DOC, hex, show } from './fixtures/s7';
import { PLC4X } from './fixtures/s7-userdata';
import { decodeModuleIdentification, parseSzl } from '../lib/s7/codec/szl';
import { until, waitFor } from './support/wait';

/** A raw ISO-on-TCP peer built from our own encoders: frames in, frames out, nothing else. */
class RawPeer {
  readonly socket: net.Socket;
  private readonly reader = new FrameReader(checkTpkt);
  private readonly frames: Buffer[] = [];
  private waiter: (() => void) | undefined;
  closed = false;
  readonly closedPromise: Promise<void>;

  constructor(port: number) {
    this.socket = net.connect(port, '127.0.0.1');
    this.socket.setNoDelay(true);
    this.socket.on('data', (chunk) => {
      this.frames.push(...this.reader.push(chunk));
      this.waiter?.();
    });
    this.socket.on('error', () => undefined);
    this.closedPromise = new Promise((resolve) =>
      this.socket.on('close', () => {
        this.closed = true;
        this.waiter?.();
        resolve();
      }),
    );
  }

  send(frame: Buffer): void {
    this.socket.write(frame);
  }

  /** The next frame, or rejects when the peer closes first or after `ms`. */
  async next(ms = 2000): Promise<Buffer> {
    const deadline = Date.now() + ms;
    while (this.frames.length === 0) {
      if (this.closed) throw new Error('connection closed');
      const left = deadline - Date.now();
      if (left <= 0) throw new Error(`no frame within ${ms} ms`);
      await new Promise<void>((resolve) => {
        const t = setTimeout(resolve, left);
        this.waiter = () => {
          clearTimeout(t);
          resolve();
        };
      });
      this.waiter = undefined;
    }
    return this.frames.shift()!;
  }

  async nextS7(ms?: number): Promise<S7Message> {
    return decodeS7(await this.next(ms));
  }

  async closedWithin(ms = 2000): Promise<void> {
    let t: NodeJS.Timeout | undefined;
    await Promise.race([
      this.closedPromise,
      new Promise((_, reject) => (t = setTimeout(() => reject(new Error(`still open after ${ms} ms`)), ms))),
    ]);
    clearTimeout(t);
  }

  destroy(): void {
    this.socket.destroy();
  }
}

interface Handshake {
  peer: RawPeer;
  cc: CotpMessage;
  pduSize: number;
  amq: number;
}

async function connectCotp(
  port: number,
  calledTsap = remoteTsapFor('pg', 0, 1),
  tpduSize = 0x0a,
): Promise<{ peer: RawPeer; cc: CotpMessage }> {
  const peer = new RawPeer(port);
  peer.send(encodeConnectionRequest({ sourceRef: 0x0042, callingTsap: 0x0100, calledTsap, tpduSize }));
  return { peer, cc: decodeCotp(await peer.next()) };
}

async function handshake(port: number, pduSize = 960, amq = 8, calledTsap?: number, tpduSize?: number): Promise<Handshake> {
  const { peer, cc } = await connectCotp(port, calledTsap, tpduSize);
  if (cc.type !== 'CC') throw new Error(`expected CC, got ${cc.type}`);
  peer.send(encodeSetupCommunication(0x1234, { maxAmqCalling: amq, maxAmqCalled: amq, pduSize }));
  const ack = await peer.nextS7();
  if (ack.kind !== 'setup-ack') throw new Error(ack.kind);
  return { peer, cc, pduSize: ack.params.pduSize, amq: ack.params.maxAmqCalling };
}

const db = (dbNumber: number, byte: number, transportSize = 0x02, count = 1, bit = 0): S7Item => ({
  area: 0x84,
  dbNumber,
  transportSize,
  count,
  address: byte * 8 + bit,
});
const write = (item: S7Item, data: Buffer, dataTransportSize = 0x04): S7WriteItem => ({ ...item, dataTransportSize, data });

describe('S7Server', () => {
  const servers: S7Server[] = [];
  const peers: RawPeer[] = [];
  async function start(profile: S7Profile = 's7-1500', extra: ConstructorParameters<typeof S7Server>[0] = {}): Promise<S7Server> {
    const server = new S7Server({ port: 0, profile, ...extra });
    servers.push(server);
    await server.listen();
    return server;
  }
  async function open(
    server: S7Server,
    ...args: Parameters<typeof handshake> extends [number, ...infer R] ? R : never
  ): Promise<Handshake> {
    const h = await handshake(server.port, ...args);
    peers.push(h.peer);
    return h;
  }

  afterEach(async () => {
    for (const p of peers.splice(0)) p.destroy();
    await Promise.all(servers.splice(0).map((s) => s.close()));
  });

  describe('connection and negotiation', () => {
    it('confirms a CR with its own reference, echoing TSAPs and TPDU size, and counts the connection', async () => {
      const server = await start('s7-1200');
      const counted = waitFor<number>(server, 'connection');
      const { peer, cc } = await connectCotp(server.port);
      peers.push(peer);
      expect(cc).to.deep.equal({
        type: 'CC',
        destinationRef: 0x0042,
        sourceRef: 1,
        callingTsap: 0x0100,
        calledTsap: 0x0101,
        tpduSize: 0x0a,
      });
      expect(await counted).to.equal(1);
      expect(server.connectionCount).to.equal(1);
    });

    it('answers the circulated setup communication frame like the PLC it was captured from: PDU 240, AmQ 1', async () => {
      const server = await start('s7-1200');
      const peer = new RawPeer(server.port);
      peers.push(peer);
      peer.send(DOC.connectionRequest);
      expect(show(await peer.next())).to.equal('0300001611D000010001' + '00C0010AC1021000C2020301');
      peer.send(DOC.setup);
      expect(show(await peer.next())).to.equal(show(DOC.setupAck));
    });

    it('answers the real S7-1200 negotiation capture byte for byte', async () => {
      const server = await start('s7-1200');
      const { peer } = await connectCotp(server.port);
      peers.push(peer);
      peer.send(CAPTURE.setup1200Request);
      expect(show(await peer.next())).to.equal(show(CAPTURE.setup1200Ack));
    });

    const cases: [S7Profile, number, number, number, number][] = [
      ['s7-300', 960, 8, 240, 1],
      ['s7-400', 960, 16, 480, 8],
      ['s7-1200', 960, 8, 240, 3],
      ['s7-1500', 960, 16, 960, 8],
      ['s7-1500', 480, 2, 480, 2],
      ['s7-1200', 200, 1, 200, 1],
    ];
    for (const [profile, askPdu, askAmq, pdu, amq] of cases) {
      it(`${profile}: asked PDU ${askPdu} / AmQ ${askAmq}, answers min(asked, offered) = ${pdu} / ${amq}`, async () => {
        const server = await start(profile);
        const slot = profile === 's7-300' || profile === 's7-400' ? 2 : 1;
        const h = await open(server, askPdu, askAmq, remoteTsapFor('basic', 0, slot));
        expect([h.pduSize, h.amq]).to.deep.equal([pdu, amq]);
      });
    }

    it('s7-1500 offers 480 when the client asks for TPDUs of 512 bytes (960 does not fit)', async () => {
      const server = await start('s7-1500');
      const h = await open(server, 960, 1, remoteTsapFor('pg', 0, 1), 0x09);
      expect(h.cc).to.include({ tpduSize: 0x09 });
      expect(h.pduSize).to.equal(480);
    });

    it('refuses a wrong rack/slot with a COTP DR (address unknown) and closes, like a CPU', async () => {
      const server = await start('s7-300');
      const refused = waitFor<S7RefusedEvent>(server, 'refused');
      const { peer, cc } = await connectCotp(server.port, remoteTsapFor('pg', 0, 1));
      peers.push(peer);
      expect(cc).to.deep.include({ type: 'DR', destinationRef: 0x42, reason: 3 });
      await peer.closedWithin();
      expect((await refused).reason).to.equal('wrong-tsap');
      expect(server.connectionCount).to.equal(0);
      // slot 2 is the S7-300 CPU
      const ok = await open(server, 240, 1, remoteTsapFor('pg', 0, 2));
      expect(ok.pduSize).to.equal(240);
    });

    it('accepts TSAPs outside the rack/slot form (S7-200 / LOGO pairs)', async () => {
      const server = await start('s7-1200');
      const h = await open(server, 240, 1, 0x0200);
      expect(h.cc.type).to.equal('CC');
    });

    it('s7-1200 refuses the 9th connection with a DR and accepts again once one closes', async () => {
      const server = await start('s7-1200');
      const eight = await Promise.all(Array.from({ length: 8 }, () => open(server, 240, 3)));
      expect(server.connectionCount).to.equal(8);
      const refused = waitFor<S7RefusedEvent>(server, 'refused');
      const { peer, cc } = await connectCotp(server.port);
      peers.push(peer);
      expect(cc).to.deep.include({ type: 'DR', reason: 1 });
      await peer.closedWithin();
      expect((await refused).reason).to.equal('connection-limit');
      expect(server.connectionCount).to.equal(8);
      const gone = waitFor<number>(server, 'disconnect');
      eight[0]!.peer.destroy();
      expect(await gone).to.equal(7);
      const again = await open(server, 240, 3);
      expect(again.cc.type).to.equal('CC');
      expect(server.connectionCount).to.equal(8);
    });
  });

  describe('TSAP-addressed CPUs: s7-200 (CP 243-1) and logo', () => {
    // The TSAP pair each profile accepts, as a client URL gives it (local = calling, remote = called).
    const cases = [
      {
        profile: 's7-200',
        tsaps: 'localTsap=1000&remoteTsap=1001',
        called: 0x1001,
        calling: 0x4d57,
        wrong: ['localTsap=1000&remoteTsap=0301', 'localTsap=1000&remoteTsap=1801'],
        vBytes: 10240,
      },
      {
        profile: 'logo',
        tsaps: 'localTsap=0100&remoteTsap=0200',
        called: 0x0200,
        calling: 0x0100,
        wrong: ['localTsap=0100&remoteTsap=0201', 'localTsap=1000&remoteTsap=0200'],
        vBytes: 1470,
      },
    ] as const;
    const clients: S7Client[] = [];
    const client = (port: number, query: string) => {
      const c = new S7Client(parseUrl(`s7://127.0.0.1:${port}?timeout=1500&${query}`) as S7Endpoint);
      clients.push(c);
      return c;
    };
    afterEach(async () => {
      await Promise.all(clients.splice(0).map((c) => c.close()));
    });

    it("a LOGO! profile object with a project's own TSAP pair (snap7's 10.00 / 20.00) accepts that pair only", async () => {
      const own = { ...PROFILES.logo, tsaps: { called: { value: 0x2000, mask: 0xffff }, calling: { value: 0x1000, mask: 0xffff } } };
      const server = new S7Server({ port: 0, profile: own });
      servers.push(server);
      await server.listen();
      await client(server.port, 'localTsap=1000&remoteTsap=2000').connect();
      const err = await client(server.port, 'localTsap=0100&remoteTsap=0200')
        .connect()
        .then(
          () => undefined,
          (e: unknown) => e,
        );
      expect((err as PlcError).code).to.equal('CONNECT_FAILED');
      expect(server.memory.area('DB', 1)!.length).to.equal(1470);
    });

    for (const { profile, tsaps, called, calling, wrong, vBytes } of cases) {
      describe(profile, () => {
        it('the client reaches it with its TSAP URL and reads and writes V memory (= DB1) at PDU 240', async () => {
          const server = await start(profile);
          const c = client(server.port, tsaps);
          await c.connect();
          expect(c.pduSize).to.equal(240);
          await c.write({ VW10: 64302, 'V20.3': true, VD30: 0xdeadbeef });
          const v = server.memory.area('DB', 1)!;
          expect(v.length).to.equal(vBytes);
          expect([v.readUInt16BE(10), v[20], v.readUInt32BE(30)]).to.deep.equal([64302, 0b1000, 0xdeadbeef]);
          v.writeUInt16BE(4321, vBytes - 2);
          expect(await c.read([`VW${vBytes - 2}`, 'VW10', 'V20.3'])).to.deep.equal({
            [`VW${vBytes - 2}`]: 4321,
            VW10: 64302,
            'V20.3': true,
          });
        });

        it('has V as its only DB and refuses the S5 counters and timers (0x03)', async () => {
          const server = await start(profile);
          const c = client(server.port, tsaps);
          await c.connect();
          const r = await c.readDetailed(['DB2,INT0', `VB${vBytes}`, 'C0', 'T0', 'VB0']);
          const code = (a: string) => {
            const x = r[a]!;
            return x.ok ? 'ok' : x.error.code;
          };
          expect(['DB2,INT0', `VB${vBytes}`, 'C0', 'T0', 'VB0'].map(code)).to.deep.equal([
            'OBJECT_DOES_NOT_EXIST',
            'ADDRESS_OUT_OF_RANGE',
            'ACCESS_DENIED',
            'ACCESS_DENIED',
            'ok',
          ]);
        });

        it('refuses a connection request with other TSAPs (rack/slot ones too) with a COTP DR, address unknown', async () => {
          const server = await start(profile);
          const reasons: S7RefusedEvent['reason'][] = [];
          server.on('refused', (e: S7RefusedEvent) => reasons.push(e.reason));
          for (const query of [...wrong, 'rack=0&slot=1', 'rack=0&slot=2']) {
            const err = await client(server.port, query)
              .connect()
              .then(
                () => undefined,
                (e: unknown) => e,
              );
            expect(err, query).to.be.instanceOf(PlcError);
            expect((err as PlcError).code, query).to.equal('CONNECT_FAILED');
          }
          const { peer, cc } = await connectCotp(server.port, remoteTsapFor('pg', 0, 1));
          peers.push(peer);
          expect(cc).to.deep.include({ type: 'DR', destinationRef: 0x42, reason: 3 });
          await peer.closedWithin();
          expect(reasons).to.deep.equal(Array(wrong.length + 3).fill('wrong-tsap'));
          expect(server.connectionCount).to.equal(0);
        });

        it('serves 8 connections, refuses the 9th with a DR (congestion), and asked for PDU 960 offers 240', async () => {
          const server = await start(profile);
          const eight: RawPeer[] = [];
          for (let i = 0; i < 8; i++) {
            const peer = new RawPeer(server.port);
            peers.push(peer);
            peer.send(encodeConnectionRequest({ sourceRef: 0x0042, callingTsap: calling, calledTsap: called, tpduSize: 0x0a }));
            expect(decodeCotp(await peer.next())).to.include({ type: 'CC', calledTsap: called, callingTsap: calling });
            peer.send(encodeSetupCommunication(i, { maxAmqCalling: 8, maxAmqCalled: 8, pduSize: 960 }));
            const ack = await peer.nextS7();
            expect(ack).to.deep.include({ kind: 'setup-ack', params: { maxAmqCalling: 1, maxAmqCalled: 1, pduSize: 240 } });
            eight.push(peer);
          }
          const ninth = new RawPeer(server.port);
          peers.push(ninth);
          ninth.send(encodeConnectionRequest({ sourceRef: 0x0042, callingTsap: calling, calledTsap: called, tpduSize: 0x0a }));
          expect(decodeCotp(await ninth.next())).to.deep.include({ type: 'DR', reason: 1 });
          await ninth.closedWithin();
          expect(server.connectionCount).to.equal(8);
          const gone = waitFor<number>(server, 'disconnect');
          eight[0]!.destroy();
          expect(await gone).to.equal(7);
          const again = client(server.port, tsaps);
          await again.connect();
          expect(server.connectionCount).to.equal(8);
        });
      });
    }
  });

  describe('Read Var and Write Var', () => {
    it('reads bytes, words, bits, REAL, counters and timers with fill bytes after odd items', async () => {
      const server = await start('s7-1500');
      const mem = server.memory;
      mem.area('DB', 1)!.set([0xaa, 0xbb, 0xcc], 10);
      mem.area('DB', 1)!.writeInt16BE(-2, 20);
      mem.area('DB', 1)!.writeFloatBE(1.5, 24);
      mem.area('M', 0)![3] = 0b0000_0100;
      mem.area('C', 0)!.writeUInt16BE(0x0123, 2 * 5);
      mem.area('T', 0)!.writeUInt16BE(0x2100, 2 * 3);
      const { peer } = await open(server);
      peer.send(
        encodeReadRequest(7, [
          db(1, 10, 0x02, 3), // 3 bytes: odd → fill
          db(1, 20, 0x05, 1), // INT
          { area: 0x83, dbNumber: 0, transportSize: 0x01, count: 1, address: 3 * 8 + 2 }, // M3.2
          db(1, 24, 0x08, 1), // REAL
          { area: 0x1c, dbNumber: 0, transportSize: 0x1c, count: 1, address: 5 }, // C5
          { area: 0x1d, dbNumber: 0, transportSize: 0x1d, count: 1, address: 3 }, // T3
        ]),
      );
      const reply = await peer.next();
      const data = reply.subarray(7 + 12 + 2);
      expect(show(data)).to.equal(
        ['FF040018AABBCC00', 'FF050010FFFE', 'FF0300010100', 'FF0700043FC00000', 'FF0900020123', 'FF0900022100'].join(''),
      );
      const ack = decodeS7(reply);
      expect(ack).to.have.property('kind', 'read-ack');
      expect(ack).to.have.property('pduRef', 7);
    });

    it('answers per item: missing DB, out of range, unsupported and inconsistent types, next to good items', async () => {
      const server = await start('s7-1500');
      const { peer } = await open(server);
      peer.send(
        encodeReadRequest(8, [
          db(500, 0), // DB500 does not exist
          db(1, 1023, 0x04, 1), // WORD at the last byte of 1024
          db(1, 0, 0x42, 1), // unknown transport size
          db(1, 0, 0x01, 2), // two bits at once
          { area: 0x99, dbNumber: 0, transportSize: 0x02, count: 1, address: 0 }, // unknown area
          db(1, 0, 0x02, 1),
        ]),
      );
      const ack = await peer.nextS7();
      if (ack.kind !== 'read-ack') throw new Error(ack.kind);
      expect(ack.items.map((i) => i.returnCode)).to.deep.equal([0x0a, 0x05, 0x06, 0x07, 0x05, 0xff]);
      expect(ack.items.map((i) => i.data.length)).to.deep.equal([0, 0, 0, 0, 0, 1]);
    });

    it('serves every ANY-pointer data type code a CPU accepts: DATE, TIME_OF_DAY, TIME, S5TIME, DATE_AND_TIME, and 0x13 as PLC4X sends WCHAR', async () => {
      const server = await start('s7-1500');
      server.memory.area('DB', 1)!.set(Buffer.from('0102030405060708', 'hex'), 0);
      const { peer } = await open(server);
      // Codes 09 DATE, 0A TIME_OF_DAY, 0B TIME, 0C S5TIME, 0E DATE_AND_TIME, 13 (one 2-byte WCHAR), each count 1.
      peer.send(
        encodeReadRequest(
          8,
          [0x09, 0x0a, 0x0b, 0x0c, 0x0e, 0x13].map((ts) => db(1, 0, ts, 1)),
        ),
      );
      const ack = await peer.nextS7();
      if (ack.kind !== 'read-ack') throw new Error(ack.kind);
      expect(ack.items.map((i) => i.returnCode)).to.deep.equal([0xff, 0xff, 0xff, 0xff, 0xff, 0xff]);
      expect(ack.items.map((i) => i.data.toString('hex'))).to.deep.equal([
        '0102',
        '01020304',
        '01020304',
        '0102',
        '0102030405060708',
        '0102',
      ]);
    });

    it("answers Apache PLC4X's identification request (SZL 0x0011; its item announces 12 bytes, carries 4) with the list, not a closed connection", async () => {
      const server = await start('s7-1500');
      const { peer } = await open(server);
      peer.send(PLC4X.szlRequest);
      const u = decodeUserdata(await peer.next());
      expect(u.params.errorCode).to.equal(0);
      const list = parseSzl(u.data);
      expect(list.id).to.equal(0x0011);
      expect(decodeModuleIdentification(list).orderCode).to.equal(server.cpu.identity.orderCode);
    });

    it('writes bytes and single bits without touching neighbouring bits, and reports each item', async () => {
      const server = await start('s7-1200');
      const buf = server.memory.area('DB', 2)!;
      buf[12] = 0b1111_0000;
      const writes: MemoryAccess[] = [];
      server.memory.on('write', (w: MemoryAccess) => writes.push(w));
      const { peer } = await open(server, 240, 3);
      peer.send(
        encodeWriteRequest(9, [
          write(db(2, 0, 0x02, 3), hex('010203')),
          write(db(2, 12, 0x01, 1, 1), hex('01'), 0x03),
          write(db(2, 12, 0x01, 1, 7), hex('00'), 0x03),
          write(db(2, 4, 0x04, 1), hex('01')), // WORD with one byte of data
          write(db(777, 0, 0x02, 1), hex('01')), // missing DB (default: DB1–DB100)
          write(db(2, 1024, 0x02, 1), hex('01')), // out of range
        ]),
      );
      const ack = await peer.nextS7();
      expect(ack).to.deep.equal({ kind: 'write-ack', pduRef: 9, returnCodes: [0xff, 0xff, 0xff, 0x07, 0x0a, 0x05] });
      expect(show(buf.subarray(0, 3))).to.equal('010203');
      expect(buf[12]).to.equal(0b0111_0010);
      expect(writes.map((w) => [w.area, w.dbNumber, w.offset, w.length])).to.deep.equal([
        ['DB', 2, 0, 3],
        ['DB', 2, 12, 1],
        ['DB', 2, 12, 1],
      ]);
      expect(show(writes[0]!.data!)).to.equal('010203');
    });

    it('reads what the circulated frames ask for (unaligned BYTE addresses read the byte, bit part ignored)', async () => {
      const server = await start('s7-1200', { layout: { dbs: { '200': 16 } } });
      server.memory.area('DB', 200)!.set([0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88, 0x99, 0xaa, 0xbb, 0xcc]);
      const { peer } = await open(server, 240, 1);
      peer.send(DOC.read);
      const ack = await peer.nextS7();
      if (ack.kind !== 'read-ack') throw new Error(ack.kind);
      expect(ack.pduRef).to.equal(1);
      expect(ack.items.map((i) => show(i.data))).to.deep.equal(['11', '33', 'BB', 'CC']);
      peer.send(DOC.write);
      expect(await peer.nextS7()).to.deep.equal({ kind: 'write-ack', pduRef: 9, returnCodes: [0xff] });
      expect(server.memory.area('DB', 200)![1]).to.equal(9);
    });

    // Counters and timers as other clients ask for them (each item's origin in its comment; the CPU's rules
    // and their sources are in lib/s7/server/jobs.ts). Address field: the counter/timer number.
    it('serves C and T items of their own transport size and answers 0x05 to any other, as a CPU does', async () => {
      const server = await start('s7-300');
      const c = server.memory.area('C', 0)!;
      const t = server.memory.area('T', 0)!;
      c.writeUInt16BE(0x0123, 5 * 2);
      c.writeUInt16BE(0x0040, 40 * 2);
      t.writeUInt16BE(0x2100, 3 * 2);
      t.writeUInt16BE(0x0010, 4 * 2);
      const { peer } = await open(server, 240, 1, remoteTsapFor('pg', 0, 2));
      peer.send(
        hex(
          '03 00 00 4F | 02 F0 80 | 32 01 00 00 00 05 00 3E 00 00 | 04 05' +
            '12 0A 10 1C 00 01 00 00 1C 00 00 05' + // snap7 CTRead(5, 1): COUNTER ×1, C5
            '12 0A 10 1D 00 02 00 00 1D 00 00 03' + // snap7 TMRead(3, 2): TIMER ×2, T3 and T4
            '12 0A 10 02 00 02 00 00 1D 00 00 68' + // python-snap7 before #121 read_area(TM, 0, 13, 2): BYTE ×2 at bit address 13 × 8
            '12 0A 10 09 00 02 00 00 1C 00 00 28' + // @st-one-io/nodes7 1.1.2 "C5": transport size 0x09, 2 bytes, bit address 5 × 8
            '12 0A 10 1C 00 01 00 00 1C 00 00 28', // nodes7 0.3.18 "C5": COUNTER ×1 but the number × 8, so C40
        ),
      );
      expect(show(await peer.next())).to.equal(
        '03000031' +
          '02F080' +
          '320300000005000200' +
          '1C0000' +
          '0405' +
          'FF0900020123' +
          'FF09000421000010' +
          '05000000' +
          '05000000' +
          'FF0900020040',
      );
      peer.send(
        hex(
          '03 00 00 49 | 02 F0 80 | 32 01 00 00 00 06 00 26 00 12 | 05 03' +
            '12 0A 10 1C 00 01 00 00 1C 00 00 05' + // snap7 CTWrite(5, 1)
            '12 0A 10 1C 00 01 00 00 1C 00 00 07' + // nodes7 0.3.18 writing C7 the same way (its data: 0x09, 2 bytes)
            '12 0A 10 02 00 02 00 00 1C 00 00 30' + // BYTE ×2 at bit address 6 × 8
            '00 09 00 02 02 34 | 00 09 00 02 00 07 | 00 04 00 10 AA BB',
        ),
      );
      expect(show(await peer.next())).to.equal('03000018' + '02F080' + '320300000006000200030000' + '0503' + 'FFFF05');
      expect([c.readUInt16BE(5 * 2), c.readUInt16BE(7 * 2), c.readUInt16BE(6 * 2)]).to.deep.equal([0x0234, 0x0007, 0]);
    });

    it('uses a JSON layout: only the DBs listed exist, with their sizes', async () => {
      const server = await start('s7-1500', { layout: { dbs: { '1': 16, '7': 4 }, areas: { M: 8 } } });
      const { peer } = await open(server);
      peer.send(
        encodeReadRequest(1, [
          db(1, 15),
          db(2, 0),
          db(7, 3),
          db(7, 4),
          { area: 0x83, dbNumber: 0, transportSize: 0x02, count: 1, address: 8 * 8 },
        ]),
      );
      const ack = await peer.nextS7();
      if (ack.kind !== 'read-ack') throw new Error(ack.kind);
      expect(ack.items.map((i) => i.returnCode)).to.deep.equal([0xff, 0x0a, 0xff, 0x05, 0x05]);
    });

    it('refuses a request larger than the negotiated PDU, and one whose answer would be, with 0x8500', async () => {
      const server = await start('s7-1200');
      const { peer } = await open(server, 240, 3);
      const many = Array.from({ length: 20 }, (_, i) => db(1, i)); // 10 + 2 + 240 > 240
      peer.send(encodeReadRequest(1, many));
      const big = await peer.nextS7();
      expect(big).to.deep.include({ kind: 'error', pduRef: 1, errorClass: 0x85, errorCode: 0x00 });
      expect(headerError(0x85, 0, 'read').code).to.equal('PDU_TOO_LARGE');
      peer.send(encodeReadRequest(2, [db(1, 0, 0x02, 230)])); // 14 + 4 + 230 > 240
      expect(await peer.nextS7()).to.deep.include({ kind: 'error', pduRef: 2, errorClass: 0x85 });
      peer.send(encodeReadRequest(3, [db(1, 0, 0x02, 222)])); // 14 + 4 + 222 = 240 fits exactly
      const ok = await peer.nextS7();
      if (ok.kind !== 'read-ack') throw new Error(ok.kind);
      expect(ok.items[0]!.data.length).to.equal(222);
      peer.send(encodeWriteRequest(4, [write(db(1, 0, 0x02, 220), Buffer.alloc(220))])); // 10 + 14 + 4 + 220 > 240
      expect(await peer.nextS7()).to.deep.include({ kind: 'error', pduRef: 4, errorClass: 0x85 });
    });

    it('emits request events and memory read events', async () => {
      const server = await start('s7-1500');
      const requests: S7RequestEvent[] = [];
      server.on('request', (r: S7RequestEvent) => requests.push(r));
      const reads: MemoryAccess[] = [];
      server.memory.on('read', (r: MemoryAccess) => reads.push(r));
      const { peer } = await open(server);
      const frame = encodeReadRequest(5, [db(3, 4, 0x04, 2)]);
      peer.send(frame);
      await peer.next();
      expect(requests).to.deep.equal([{ kind: 'read', pduRef: 5, items: 1, bytes: frame.length }]);
      expect(reads).to.deep.equal([{ area: 'DB', dbNumber: 3, offset: 4, length: 4 }]);
    });
  });

  describe('streams', () => {
    it('serves a request dripped one byte at a time', async () => {
      const server = await start('s7-1500');
      const { peer } = await open(server);
      server.memory.area('DB', 1)![0] = 0x5a;
      const frame = encodeReadRequest(0x77, [db(1, 0)]);
      for (const byte of frame) peer.socket.write(Buffer.of(byte));
      const ack = await peer.nextS7();
      if (ack.kind !== 'read-ack') throw new Error(ack.kind);
      expect([ack.pduRef, show(ack.items[0]!.data)]).to.deep.equal([0x77, '5A']);
    });

    it('serves coalesced requests (handshake and three jobs in one segment) in order', async () => {
      const server = await start('s7-1500');
      const peer = new RawPeer(server.port);
      peers.push(peer);
      peer.send(
        Buffer.concat([
          encodeConnectionRequest({ sourceRef: 1, callingTsap: 0x100, calledTsap: 0x101, tpduSize: 0x0a }),
          encodeSetupCommunication(1, { maxAmqCalling: 3, maxAmqCalled: 3, pduSize: 480 }),
          encodeReadRequest(10, [db(1, 0)]),
          encodeWriteRequest(11, [write(db(1, 0), hex('42'))]),
          encodeReadRequest(12, [db(1, 0)]),
        ]),
      );
      expect(decodeCotp(await peer.next()).type).to.equal('CC');
      expect((await peer.nextS7()).kind).to.equal('setup-ack');
      const answers = [await peer.nextS7(), await peer.nextS7(), await peer.nextS7()];
      expect(answers.map((a) => [a.kind, a.pduRef])).to.deep.equal([
        ['read-ack', 10],
        ['write-ack', 11],
        ['read-ack', 12],
      ]);
      const last = answers[2]!;
      if (last.kind !== 'read-ack') throw new Error(last.kind);
      expect(show(last.items[0]!.data)).to.equal('42');
    });
  });

  describe('faults', () => {
    it('accessDenied: every job gets header error 0x8104 (PUT/GET off), the connection stays', async () => {
      const server = await start('s7-1200');
      const { peer } = await open(server, 240, 3);
      server.faults.accessDenied = true;
      peer.send(encodeReadRequest(3, [db(1, 0)]));
      const denied = await peer.nextS7();
      expect(denied).to.deep.equal({ kind: 'error', pduRef: 3, errorClass: 0x81, errorCode: 0x04, rosctr: 2 });
      expect(headerError(0x81, 0x04, 'read').message).to.include('PUT/GET access is not enabled on this S7-1200/1500');
      server.faults.accessDenied = false;
      peer.send(encodeReadRequest(4, [db(1, 0)]));
      expect((await peer.nextS7()).kind).to.equal('read-ack');
    });

    it('missingDb: the named DBs answer 0x0A although they exist', async () => {
      const server = await start('s7-1500');
      server.faults.missingDb = [2, 3];
      const { peer } = await open(server);
      peer.send(encodeReadRequest(1, [db(1, 0), db(2, 0), db(3, 0)]));
      const ack = await peer.nextS7();
      if (ack.kind !== 'read-ack') throw new Error(ack.kind);
      expect(ack.items.map((i) => i.returnCode)).to.deep.equal([0xff, 0x0a, 0x0a]);
      server.faults.missingDb = 1;
      peer.send(encodeWriteRequest(2, [write(db(1, 0), hex('01')), write(db(2, 0), hex('01'))]));
      expect(await peer.nextS7()).to.deep.include({ returnCodes: [0x0a, 0xff] });
    });

    it('refuseConnections: a CR gets a DR and the socket closes', async () => {
      const server = await start('s7-1500');
      server.faults.refuseConnections = true;
      const { peer, cc } = await connectCotp(server.port);
      peers.push(peer);
      expect(cc.type).to.equal('DR');
      await peer.closedWithin();
    });

    it('dropConnections(): every client socket closes and the count returns to 0', async () => {
      const server = await start('s7-1500');
      const a = await open(server);
      const b = await open(server);
      expect(server.connectionCount).to.equal(2);
      server.faults.dropConnections();
      await Promise.all([a.peer.closedWithin(), b.peer.closedWithin()]);
      await until(() => server.connectionCount === 0, 2000, 'count back to 0');
    });

    it('latencyMs: serves up to AmQ jobs of a connection at once, the rest after them', async () => {
      const server = await start('s7-1200');
      const { peer, amq } = await open(server, 240, 3);
      expect(amq).to.equal(3);
      const latency = 80;
      server.faults.latencyMs = latency;
      const t0 = Date.now();
      for (let ref = 1; ref <= 6; ref++) peer.send(encodeReadRequest(ref, [db(1, 0)]));
      const at: number[] = [];
      const refs: number[] = [];
      for (let i = 0; i < 6; i++) {
        refs.push((await peer.nextS7(3000)).pduRef);
        at.push(Date.now() - t0);
      }
      expect(refs).to.deep.equal([1, 2, 3, 4, 5, 6]);
      expect(at[0]).to.be.at.least(latency - 5);
      // the first three ran together, the fourth waited for a free job slot and its own latency
      expect(at[2]! - at[0]!).to.be.below(latency * 0.75);
      expect(at[3]! - at[0]!).to.be.at.least(latency - 5);
    });

    it('silent: jobs are not answered but the connection stays open', async () => {
      const server = await start('s7-1500');
      const { peer } = await open(server);
      server.faults.silent = true;
      peer.send(encodeReadRequest(1, [db(1, 0)]));
      let error: unknown;
      await peer.next(150).catch((e) => (error = e));
      expect(String(error)).to.match(/no frame within 150 ms/);
      expect(peer.closed).to.equal(false);
    });
  });

  describe('hostile peers', () => {
    const hostile: [string, (h: Handshake) => Buffer][] = [
      ['a TPKT version 4', () => hex('04 00 00 10 02 F0 80 32 01 00 00 00 01 00 00 00 00')],
      ['a TPKT length below a COTP header', () => hex('03 00 00 03')],
      [
        'an S7 protocol id that is not 0x32',
        () => {
          const f = encodeReadRequest(1, [db(1, 0)]);
          f[7] = 0x72;
          return f;
        },
      ],
      [
        'parameter lengths that do not add up',
        () => {
          const f = encodeReadRequest(1, [db(1, 0)]);
          f.writeUInt16BE(40, 13);
          return f;
        },
      ],
      [
        'an item that is not S7ANY',
        () => {
          const f = encodeReadRequest(1, [db(1, 0)]);
          f[19] = 0x11;
          return f;
        },
      ],
      [
        'a write whose data item is truncated',
        () => {
          const f = encodeWriteRequest(1, [write(db(1, 0, 0x02, 2), hex('0102'))]);
          f.writeUInt16BE(0x0100, f.length - 4); // announces 32 bytes
          return f;
        },
      ],
      [
        'a second connection request',
        () => encodeConnectionRequest({ sourceRef: 1, callingTsap: 0x100, calledTsap: 0x101, tpduSize: 0x0a }),
      ],
      ['a second setup communication', () => encodeSetupCommunication(1, { maxAmqCalling: 1, maxAmqCalled: 1, pduSize: 240 })],
    ];
    for (const [what, frame] of hostile) {
      it(`closes only the connection that sends ${what}`, async () => {
        const server = await start('s7-1500');
        const bad = await open(server);
        const good = await open(server);
        const refused = waitFor<S7RefusedEvent>(server, 'refused');
        const sent = frame(bad);
        bad.peer.send(sent);
        await bad.peer.closedWithin();
        // Never silently: the event names the client and the frame (issue #31).
        const e = await refused;
        expect(e.reason).to.equal('protocol-error');
        expect(e.peer).to.match(/^127\.0\.0\.1:\d+$/);
        expect(e.frame).to.be.a('string').and.not.equal('');
        expect(refusalLine(e)).to.match(/^refused 127\.0\.0\.1:\d+ \(protocol-error\): .+ — frame [0-9a-f]+/);
        if (sent.length <= 64) expect(e.frame).to.equal(sent.toString('hex'));
        good.peer.send(encodeReadRequest(1, [db(1, 0)]));
        expect((await good.peer.nextS7()).kind).to.equal('read-ack');
        expect(server.connectionCount).to.equal(1);
      });
    }

    it('closes a connection that sends a job before setup communication', async () => {
      const server = await start('s7-1500');
      const { peer } = await connectCotp(server.port);
      peers.push(peer);
      peer.send(encodeReadRequest(1, [db(1, 0)]));
      await peer.closedWithin();
    });

    it('closes a connection whose first frame is not a CR, and one that sends garbage', async () => {
      const server = await start('s7-1500');
      const a = new RawPeer(server.port);
      const b = new RawPeer(server.port);
      peers.push(a, b);
      a.send(DOC.setup);
      b.send(Buffer.from('GET / HTTP/1.1\r\n\r\n'));
      await Promise.all([a.closedWithin(), b.closedWithin()]);
      const ok = await open(server);
      expect(ok.cc.type).to.equal('CC');
    });

    it('answers a userdata function it does not have with the CPU error 0x8104 in the parameters, and keeps the connection', async () => {
      const server = await start('s7-1500');
      const { peer } = await open(server);
      // userdata (ROSCTR 7), group 1 (programmer commands), which the simulator does not offer
      peer.send(hex('03 00 00 1D | 02 F0 80 | 32 07 00 00 00 05 00 08 00 04 | 00 01 12 04 11 41 01 00 | 0A 00 00 00'));
      const answer = decodeUserdata(await peer.next());
      expect(answer.params).to.deep.include({ type: 8, group: 1, subfunction: 1, errorCode: 0x8104 });
      peer.send(DOC.read);
      expect(await peer.nextS7()).to.deep.include({ kind: 'read-ack', pduRef: 1 });
    });
  });

  it('close() destroys every client socket and resolves; listen() can be called again on a new server', async () => {
    const server = new S7Server({ port: 0 });
    await server.listen();
    const h = await handshake(server.port);
    await server.close();
    await h.peer.closedWithin();
    expect(server.connectionCount).to.equal(0);
    await server.close(); // idempotent
  });
});
