/**
 * The S7CommPlus simulator on the S7 simulator's port (issue #25), spoken to
 * by a raw peer of this file in plain text (`tls: false`, a CPU configured
 * without secure communication): the object model from the sources, the
 * TSAP that decides the protocol, named reads and writes, optimized DBs
 * refused over PUT/GET, and what resets a connection. The s7commplus Python
 * client over TLS: test/s7plus-server-python.test.ts.
 */
import { expect } from 'chai';
import * as net from 'node:net';
import { FrameReader } from '../lib/link/framer';
import { S7Client } from '../lib/s7/client';
import { checkTpkt, decodeCotp, encodeConnectionRequest } from '../lib/s7/codec';
import { S7Server, type S7RefusedEvent } from '../lib/s7/server';
import { ITEM_ERROR_INVALID_CRC, symbolCrc } from '../lib/s7plus/codec/symbol-crc';
import { encodeSVlq32, encodeUVlq32, encodeUVlq64 } from '../lib/s7plus/codec/vlq';
import { Ids, SoftDataType, SystemLimits } from '../lib/s7plus/constants';
import { resolveLids } from '../lib/s7plus/server/model';
import { S7PlusService } from '../lib/s7plus/server';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { waitFor } from './support/wait';

const HMI = Buffer.from('SIMATIC-ROOT-HMI', 'latin1');

/** A TPKT + COTP CR calling `called` (a 2-byte rack/slot TSAP or an S7CommPlus name). */
function connectionRequest(called: Buffer): Buffer {
  const params = Buffer.concat([Buffer.from([0xc1, 2, 0x06, 0x00, 0xc2, called.length]), called, Buffer.from([0xc0, 1, 0x0a])]);
  const cotp = Buffer.concat([Buffer.from([6 + params.length, 0xe0, 0, 0, 0x00, 0x42, 0]), params]);
  const tpkt = Buffer.from([3, 0, 0, 0]);
  tpkt.writeUInt16BE(4 + cotp.length, 2);
  return Buffer.concat([tpkt, cotp]);
}

function dt(payload: Buffer): Buffer {
  const head = Buffer.from([3, 0, 0, 0, 2, 0xf0, 0x80]);
  head.writeUInt16BE(7 + payload.length, 2);
  return Buffer.concat([head, payload]);
}

/** An S7CommPlus request frame (V1), with its trailer. */
function request(fn: number, seq: number, session: number, body: Buffer): Buffer {
  const head = Buffer.alloc(18);
  head[0] = 0x72;
  head[1] = 0x01;
  head.writeUInt16BE(14 + body.length, 2);
  head[4] = 0x31;
  head.writeUInt16BE(fn, 7);
  head.writeUInt16BE(seq, 11);
  head.writeUInt32BE(session, 13);
  head[17] = 0x34;
  return dt(Buffer.concat([head, body, Buffer.from([0x72, 0x01, 0, 0])]));
}

const v = encodeUVlq32;

/** The item list of a Get/SetMultiVariables: DB items by LID path (SymbolCrc 0 unless given), or any area and sub-area. */
function items(list: readonly { db?: number; area?: number; subArea?: number; lids: number[]; crc?: number }[]): Buffer {
  const parts = [Buffer.alloc(4), v(list.length), v(list.length * 4)];
  for (const it of list)
    parts.push(
      v(it.crc ?? 0),
      v(it.area ?? Ids.DBAccessAreaBase + it.db!),
      v(it.lids.length + 1),
      v(it.subArea ?? Ids.DBValueActual),
      ...it.lids.map((l) => v(l)),
    );
  return Buffer.concat(parts);
}

class Peer {
  readonly socket: net.Socket;
  private readonly reader = new FrameReader(checkTpkt);
  private readonly frames: Buffer[] = [];
  private wake: (() => void) | undefined;
  readonly closed: Promise<void>;
  private seq = 1;
  session = 0;

  constructor(port: number) {
    this.socket = net.connect(port, '127.0.0.1');
    this.socket.on('data', (c) => {
      this.frames.push(...this.reader.push(c));
      this.wake?.();
    });
    this.socket.on('error', () => undefined);
    this.closed = new Promise((resolve) => this.socket.on('close', () => (resolve(), this.wake?.())));
  }

  async next(ms = 3000): Promise<Buffer> {
    const deadline = Date.now() + ms;
    while (this.frames.length === 0) {
      if (this.socket.destroyed) throw new Error('connection closed');
      if (Date.now() > deadline) throw new Error(`no frame within ${ms} ms`);
      await new Promise<void>((r) => {
        const t = setTimeout(r, 50);
        this.wake = () => (clearTimeout(t), r());
      });
    }
    return this.frames.shift()!;
  }

  /** Sends a request and gives the response's body (after the 10-byte response header). */
  async ask(fn: number, body: Buffer, session = this.session): Promise<{ fn: number; body: Buffer }> {
    this.socket.write(request(fn, this.seq++, session, body));
    const frame = await this.next();
    const data = frame.subarray(7 + 4, 7 + 4 + frame.readUInt16BE(7 + 2));
    return { fn: data.readUInt16BE(3), body: data.subarray(10) };
  }

  /** CR, InitSSL, CreateObject and the setup write, as the s7commplus client does them in plain text. */
  async open(): Promise<void> {
    this.socket.write(connectionRequest(HMI));
    expect(decodeCotp(await this.next()).type).to.equal('CC');
    await this.ask(0x05b3, Buffer.alloc(4), 0);
    const created = await this.ask(0x04ca, Buffer.alloc(4), 288);
    // ReturnValue 0, two object ids: the session and its subscription container.
    expect(created.body[0]).to.equal(0);
    expect(created.body[1]).to.equal(2);
    this.session = created.body[2]! & 0x80 ? ((created.body[2]! & 0x7f) << 7) | created.body[3]! : created.body[2]!;
    const setup = await this.ask(
      0x0542,
      Buffer.concat([Buffer.alloc(4), v(1), v(1), v(306), v(1), Buffer.from([0, 4, 1, 0]), Buffer.alloc(4)]),
    );
    expect(setup.body[0]).to.equal(0);
  }
}

describe('S7CommPlus simulator (issue #25)', function () {
  this.timeout(15000);
  let server: S7Server;
  let service: S7PlusService;
  const peers: Peer[] = [];
  const clients: S7Client[] = [];
  const peer = () => {
    const p = new Peer(server.port);
    peers.push(p);
    return p;
  };
  const s7 = async () => {
    const c = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?rack=0&slot=1&timeout=2000`) as S7Endpoint);
    clients.push(c);
    await c.connect();
    return c;
  };

  beforeEach(async () => {
    service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: false, maxItems: 4, maxRequestBytes: 400 });
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await server.listen();
  });
  afterEach(async () => {
    for (const p of peers.splice(0)) p.socket.destroy();
    await Promise.all(clients.splice(0).map((c) => c.close()));
    await server.close();
  });

  describe('the object model from the sources', () => {
    it('numbers members from LID 0xA in declaration order, per struct, a UDT sharing one type object', () => {
      const tank = service.model.dbs.find((d) => d.name === 'Tank')!;
      const recipe = service.model.dbs.find((d) => d.name === 'Recipe')!;
      expect(tank.type.members.map((m) => [m.name, m.lid])).to.deep.equal([
        ['Level', 0xa],
        ['Count', 0xb],
        ['Running', 0xc],
        ['Alarm', 0xd],
        ['Name', 0xe],
        ['Motor', 0xf],
        ['Temps', 0x10],
        ['Valves', 0x11],
      ]);
      expect(recipe.optimized).to.equal(true);
      expect(tank.optimized).to.equal(false);
      expect([...service.model.optimizedDbs]).to.deep.equal([2]);
      const inlet = recipe.type.members.find((m) => m.name === 'Inlet')!;
      const valves = tank.type.members.find((m) => m.name === 'Valves')!;
      expect(inlet.type).to.equal(valves.type);
    });

    it('resolves LID paths as a browse builds them: member, element index, and the 1 before a struct element`s member', () => {
      const tank = service.model.dbs.find((d) => d.name === 'Tank')!;
      const at = (lids: number[]) => {
        const n = resolveLids(tank, lids);
        return n && [n.byte, n.bit];
      };
      expect(at([0xf, 0xb])).to.deep.equal([24, 0]); // Motor.On
      expect(at([0x10, 1])).to.deep.equal([30, null]); // Temps[2]
      expect(at([0x11, 1, 1, 0xb])).to.deep.equal([44, null]); // Valves[1].Position
      expect(at([0x11, 1, 2, 0xb])).to.equal(undefined);
      expect(at([0x12])).to.equal(undefined);
      expect(at([0x10, 3])).to.equal(undefined);
      // The LID gives the member's index (no search): below the first LID or past the last names nothing.
      expect(at([0x9])).to.equal(undefined);
      expect(at([0])).to.equal(undefined);
      expect(at([0xf, 0x9])).to.equal(undefined);
      expect(at([0xf, 0xc])).to.equal(undefined);
    });
  });

  describe('on the S7 port: the called TSAP decides', () => {
    it('PUT/GET reads a standard DB and refuses the optimized one as a CPU does: address out of range (0x05)', async () => {
      const c = await s7();
      const r = await c.readDetailed(['DB1.DBD0:REAL', 'DB2.DBD0:REAL', 'DB2.DBW4:INT']);
      expect(r['DB1.DBD0:REAL']).to.deep.include({ ok: true, value: 12.5 });
      for (const a of ['DB2.DBD0:REAL', 'DB2.DBW4:INT']) {
        const x = r[a]!;
        expect(x.ok ? 'ok' : x.error.code, a).to.equal('ADDRESS_OUT_OF_RANGE');
      }
      const w = await c.writeDetailed({ 'DB2.DBW4:INT': 9 });
      expect(w['DB2.DBW4:INT']!.ok).to.equal(false);
      expect(server.memory.area('DB', 2)!.readInt16BE(4)).to.equal(3);
    });

    it('confirms a CR calling SIMATIC-ROOT-HMI with the TSAPs echoed; without S7CommPlus its InitSSL is a protocol error there', async () => {
      const p = peer();
      p.socket.write(connectionRequest(HMI));
      const cc = await p.next();
      expect(decodeCotp(cc).type).to.equal('CC');
      expect(cc.includes(HMI)).to.equal(true);
      const plain = new S7Server({ port: 0, profile: 's7-1500' });
      await plain.listen();
      try {
        const q = new Peer(plain.port);
        peers.push(q);
        q.socket.write(connectionRequest(HMI));
        await q.next();
        const refused = waitFor<S7RefusedEvent>(plain, 'refused');
        q.socket.write(request(0x05b3, 1, 0, Buffer.alloc(4)));
        expect((await refused).reason).to.equal('protocol-error');
        await q.closed;
      } finally {
        await plain.close();
      }
      // A PUT/GET CR on the S7CommPlus simulator's port still gets the S7 side.
      const s = new Peer(server.port);
      peers.push(s);
      s.socket.write(encodeConnectionRequest({ sourceRef: 1, callingTsap: 0x0100, calledTsap: 0x0101, tpduSize: 0x0a }));
      expect(decodeCotp(await s.next()).type).to.equal('CC');
    });
  });

  describe('a session', () => {
    it('reads members of the optimized DB by LID with their own wire types (REAL, INT, BOOL) and a whole UDT as a BLOB', async () => {
      const p = peer();
      await p.open();
      const r = await p.ask(
        0x054c,
        Buffer.concat([
          items([
            { db: 2, lids: [0xa] },
            { db: 2, lids: [0xb] },
            { db: 2, lids: [0xc] },
            { db: 2, lids: [0xd] },
          ]),
          Buffer.alloc(4),
        ]),
      );
      expect(r.fn).to.equal(0x054c);
      // ReturnValue 0; item 1: REAL 80.0; item 2: INT 3; item 3: BOOL false; item 4: BLOB of 4 bytes; end of values; end of errors.
      expect(r.body.toString('hex')).to.equal('00' + '01000e42a00000' + '0200070003' + '03000100' + '040014000400000000' + '00' + '00');
    });

    it('reads a member of a UDT at its own instance: Recipe.Inlet.Position, Tank.Valves[1].Position (one shared type object)', async () => {
      server.memory.area('DB', 2)!.writeInt16BE(258, 10);
      server.memory.area('DB', 1)!.writeInt16BE(-2, 44);
      const p = peer();
      await p.open();
      const r = await p.ask(
        0x054c,
        Buffer.concat([
          items([
            { db: 2, lids: [0xd, 0xb] },
            { db: 1, lids: [0x11, 1, 1, 0xb] },
          ]),
          Buffer.alloc(4),
        ]),
      );
      expect(r.body.toString('hex')).to.equal('00' + '0100070102' + '020007fffe' + '00' + '00');
    });

    it('writes a member of the optimized DB by LID (the simulator sees it) and a standard member seen over s7:// and back', async () => {
      const p = peer();
      await p.open();
      const write = Buffer.concat([
        items([
          { db: 2, lids: [0xb] },
          { db: 1, lids: [0xf, 0xa] },
        ]),
        v(1),
        Buffer.from([0, 0x07, 0x01, 0x2c]),
        v(2),
        Buffer.from([0, 0x08]),
        Buffer.from([0x8f, 0x50]),
        Buffer.from([0]),
        Buffer.alloc(4),
      ]);
      const w = await p.ask(0x0542, write);
      expect(w.body.toString('hex')).to.equal('0000'); // ReturnValue 0, no item errors
      expect(server.memory.area('DB', 2)!.readInt16BE(4)).to.equal(300);
      const c = await s7();
      expect(await c.read(['DB1.DBD20:DINT'])).to.deep.equal({ 'DB1.DBD20:DINT': 2000 });
      await c.write({ 'DB1.DBD20:DINT': -5 });
      const r = await p.ask(0x054c, Buffer.concat([items([{ db: 1, lids: [0xf, 0xa] }]), Buffer.alloc(4)]));
      expect(r.body.toString('hex')).to.equal('00' + '0100087b' + '00' + '00'); // DINT -5 as a signed VLQ
    });

    it('answers an item it cannot serve with its error, the others with values (an unknown LID, a classic read of the optimized DB)', async () => {
      const p = peer();
      await p.open();
      const classic = Buffer.concat([
        Buffer.alloc(4),
        v(2),
        v(8),
        v(0),
        v(Ids.DBAccessAreaBase + 2),
        v(4),
        v(Ids.DBValueActual),
        v(3),
        v(0),
        v(4),
        v(0),
        v(Ids.DBAccessAreaBase + 1),
        v(4),
        v(Ids.DBValueActual),
        v(3),
        v(0),
        v(4),
        Buffer.alloc(4),
      ]);
      const r = await p.ask(0x054c, classic);
      // Item 2 (DB1 bytes 0..3) as a BLOB; item 1 (optimized DB2 by address) an error 0x8104.
      expect(r.body.toString('hex')).to.equal('00' + '0200140004' + '41480000' + '00' + '01' + '828204' + '00');
      const unknown = await p.ask(0x054c, Buffer.concat([items([{ db: 2, lids: [0x30] }]), Buffer.alloc(4)]));
      expect(unknown.body.toString('hex')).to.equal('00' + '00' + '01828204' + '00');
    });

    it('refuses a read or write of more items than the CPU serves as a 1215C does (ReturnValue 0xA027A6000054FFFC, no item), the connection kept', async () => {
      const p = peer();
      await p.open();
      const five = items([1, 2, 3, 4, 5].map(() => ({ db: 1, lids: [0xa] })));
      const read = await p.ask(0x054c, Buffer.concat([five, Buffer.alloc(4)]));
      // ReturnValue as a VLQ64 (d0 89 f4 e0 80 81 a9 ff fc), no value, no error.
      expect(read.body.toString('hex')).to.equal('d089f4e08081a9fffc' + '00' + '00');
      const write = await p.ask(0x0542, Buffer.concat([five, Buffer.from([1, 0x00, 0x04, 0x07, 0]), Buffer.alloc(4)]));
      expect(write.body.toString('hex')).to.equal('d089f4e08081a9fffc' + '00');
      const r = await p.ask(0x054c, Buffer.concat([items([{ db: 1, lids: [0xb] }]), Buffer.alloc(4)]));
      expect(r.body.toString('hex')).to.equal('00' + '0100070007' + '00' + '00');
    });

    it('resets the connection on a request too long; others go on', async () => {
      for (const body of [Buffer.concat([items([{ db: 1, lids: [0xa] }]), Buffer.alloc(400)])]) {
        const p = peer();
        await p.open();
        const refused = waitFor<S7RefusedEvent>(server, 'refused');
        p.socket.write(request(0x054c, 9, p.session, body));
        expect((await refused).reason).to.equal('protocol-error');
        await p.closed;
      }
      const q = peer();
      await q.open();
      const r = await q.ask(0x054c, Buffer.concat([items([{ db: 1, lids: [0xb] }]), Buffer.alloc(4)]));
      expect(r.body.toString('hex')).to.equal('00' + '0100070007' + '00' + '00');
    });

    it('a hostile frame (garbage after the CC, a request before InitSSL, a wrong session id) is a typed refused event and a closed connection, never a crash', async () => {
      const garbage = [
        dt(Buffer.from('not s7commplus at all')),
        request(0x054c, 1, 0, Buffer.alloc(8)),
        Buffer.from([3, 0, 0, 9, 2, 0xe0, 0, 0, 0]),
      ];
      for (const frame of garbage) {
        const p = peer();
        p.socket.write(connectionRequest(HMI));
        await p.next();
        const refused = waitFor<S7RefusedEvent>(server, 'refused');
        p.socket.write(frame);
        const e = await refused;
        expect(e.reason).to.equal('protocol-error');
        expect(e.message).to.be.a('string').and.not.equal('');
        await p.closed;
      }
      const p = peer();
      await p.open();
      const refused = waitFor<S7RefusedEvent>(server, 'refused');
      p.socket.write(request(0x054c, 5, p.session + 1, Buffer.concat([items([{ db: 1, lids: [0xa] }]), Buffer.alloc(4)])));
      expect((await refused).message).to.match(/session/);
      await p.closed;
      expect(server.connectionCount).to.be.at.most(1);
    });

    it('a subscription sends the values at once and a notification when one changes, none while nothing does; a malformed one resets', async () => {
      const p = peer();
      const frames: Buffer[] = [];
      await p.open();
      const container = 0x3a0 + 1 + (p.session - 0x3a0);
      const list = [0x80010000, 0, 1, 0x80040002, 7, 0, Ids.DBAccessAreaBase + 2, 0, Ids.DBValueActual, 0xb];
      const refs = Buffer.concat([Buffer.from([0x20, 0x04]), v(list.length), ...list.map((x) => v(x))]);
      const object = Buffer.concat([
        Buffer.from([0xa1, 0x7f, 0xff, 0xc0, 0x01]),
        v(1001),
        v(0),
        v(0),
        Buffer.from([0xa3]),
        v(1048),
        refs,
        Buffer.from([0xa3]),
        v(1049),
        Buffer.from([0, 4]),
        v(20),
        Buffer.from([0xa2]),
        Buffer.alloc(4),
      ]);
      const head = Buffer.alloc(4);
      head.writeUInt32BE(container);
      const created = await p.ask(0x04ca, Buffer.concat([head, Buffer.from([0, 4, 0]), Buffer.alloc(4), object]));
      expect(created.body.subarray(0, 2).toString('hex')).to.equal('0001');
      const notification = async () => {
        const f = await p.next();
        frames.push(f);
        return f.subarray(7 + 4);
      };
      // Opcode 0x33, subscription id, 6 reserved, credit tick 1, sequence 1, change counter 1, value record of reference 7: INT 3, end.
      const first = await notification();
      expect(first[0]).to.equal(0x33);
      expect(first.subarray(11).toString('hex')).to.equal('010101' + '92' + '00000007' + '00070003' + '00' + '72010000');
      server.memory.write('DB', 2, 4, Buffer.from([0x01, 0x00]));
      const second = await notification();
      expect(second.subarray(11).toString('hex')).to.equal('020201' + '92' + '00000007' + '00070100' + '00' + '72010000');
      // A read in between is answered as usual (no notification queued before it: the value did not change).
      const r = await p.ask(0x054c, Buffer.concat([items([{ db: 2, lids: [0xb] }]), Buffer.alloc(4)]));
      expect(r.body.toString('hex')).to.equal('00' + '0100070100' + '00' + '00');
      const refused = waitFor<S7RefusedEvent>(server, 'refused');
      p.socket.write(
        request(
          0x04ca,
          50,
          p.session,
          Buffer.concat([
            head,
            Buffer.from([0, 4, 0]),
            Buffer.alloc(4),
            Buffer.from([0xa1, 0, 0, 0, 1]),
            v(1001),
            v(0),
            v(0),
            Buffer.from([0xa3]),
            v(1048),
            Buffer.from([0x20, 0x04, 0x05, 1, 2]),
          ]),
        ),
      );
      expect((await refused).reason).to.equal('protocol-error');
      await p.closed;
    });

    it('survives 3000 mutated requests after a session: each answered or refused with a typed event, the simulator still serving', async () => {
      let seed = 25;
      const rand = (n: number) => {
        seed = (seed * 1103515245 + 12345) & 0x7fffffff;
        return seed % n;
      };
      const templates = [
        Buffer.concat([
          items([
            { db: 2, lids: [0xa] },
            { db: 1, lids: [0x11, 1, 1, 0xb] },
          ]),
          Buffer.alloc(4),
        ]),
        Buffer.concat([items([{ db: 2, lids: [0xb] }]), v(1), Buffer.from([0, 0x07, 0x01, 0x2c]), Buffer.from([0]), Buffer.alloc(4)]),
        Buffer.concat([Buffer.from([0, 0, 0x02, 0x19]), v(0), Buffer.from([1, 1, 0, 0]), v(0), Buffer.alloc(5)]),
      ];
      const fns = [0x054c, 0x0542, 0x04bb, 0x04ca, 0x04d4, 0x04f2, 0x0586, 0x1234];
      let refused = 0;
      server.on('refused', () => refused++);
      let p = peer();
      await p.open();
      for (let i = 0; i < 3000; i++) {
        if (p.socket.destroyed || p.socket.readyState !== 'open') {
          p = peer();
          await p.open();
        }
        const body = Buffer.from(templates[rand(templates.length)]!);
        for (let k = rand(4); k >= 0; k--) body[rand(body.length)] = rand(256);
        const cut = rand(3) === 0 ? body.subarray(0, rand(body.length)) : body;
        p.socket.write(request(fns[rand(fns.length)]!, i & 0xffff, p.session, cut));
        // Each request is answered or its connection reset; wait for either before the next.
        await Promise.race([p.next(3000).catch(() => undefined), p.closed]);
      }
      expect(refused).to.be.greaterThan(0);
      const q = peer();
      await q.open();
      const r = await q.ask(0x054c, Buffer.concat([items([{ db: 1, lids: [0xb] }]), Buffer.alloc(4)]));
      expect(r.body.toString('hex')).to.equal('00' + '0100070007' + '00' + '00');
    });

    it('DeleteObject of the session answers and closes the connection', async () => {
      const p = peer();
      await p.open();
      const r = await p.ask(0x04d4, Buffer.alloc(4));
      expect(r.body[0]).to.equal(0);
      await p.closed;
    });
  });

  describe('SymbolCrc, SystemLimits and the frame limit (issue #32)', () => {
    const limitsOf = async (port: number) => {
      const p = new Peer(port);
      peers.push(p);
      await p.open();
      const area = SystemLimits.ObjectRoot;
      const subArea = SystemLimits.SubArea;
      const r = await p.ask(
        0x054c,
        Buffer.concat([
          items([
            { area, subArea, lids: [SystemLimits.TagsPerReadRequest] },
            { area, subArea, lids: [SystemLimits.TagsPerWriteRequest] },
          ]),
          Buffer.alloc(4),
        ]),
      );
      // ReturnValue 0; items 1 and 2 as DInt (type 0x08, a signed VLQ); no errors.
      return r.body.toString('hex');
    };
    const dint = (n: number) => '0008' + encodeSVlq32(n).toString('hex');

    it('reports SystemLimits (ObjectRoot 201, sub-area 1037, LIDs 1000 and 1001) per profile: an S7-1500 100, an S7-1200 50; maxItems overrides', async () => {
      expect(await limitsOf(server.port)).to.equal('00' + '01' + dint(4) + '02' + dint(4) + '00' + '00');
      for (const [profile, limit] of [
        ['s7-1500', 100],
        ['s7-1200', 50],
      ] as const) {
        const own = new S7Server({ port: 0, profile, s7plus: new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: false }) });
        await own.listen();
        try {
          expect(await limitsOf(own.port), profile).to.equal('00' + '01' + dint(limit) + '02' + dint(limit) + '00' + '00');
        } finally {
          await own.close();
        }
      }
    });

    it('refuses an item whose SymbolCrc is not its path`s alone with InvalidCRC (0x8009890012CBFFEF); a matching CRC and 0 are served', async () => {
      const level = symbolCrc([{ name: 'Level', soft: SoftDataType.Real }]);
      const position = symbolCrc([
        { name: 'Valves', soft: SoftDataType.Struct, low: 0 },
        { name: 'Position', soft: SoftDataType.Int },
      ]);
      server.memory.area('DB', 1)!.writeInt16BE(-2, 44);
      const p = peer();
      await p.open();
      const r = await p.ask(
        0x054c,
        Buffer.concat([
          items([
            { db: 1, lids: [0xa], crc: level },
            { db: 1, lids: [0xa], crc: (level ^ 1) >>> 0 },
            { db: 1, lids: [0x11, 1, 1, 0xb], crc: position },
            { db: 1, lids: [0xb], crc: level },
          ]),
          Buffer.alloc(4),
        ]),
      );
      const invalid = encodeUVlq64(ITEM_ERROR_INVALID_CRC).toString('hex');
      // Item 1: REAL 12.5; item 3: INT -2; items 2 and 4 (Count read with Level's CRC): InvalidCRC.
      expect(r.body.toString('hex')).to.equal('00' + '01000e41480000' + '030007fffe' + '00' + '02' + invalid + '04' + invalid + '00');
      // A write with a stale CRC writes nothing; the other item of the request is written.
      const w = await p.ask(
        0x0542,
        Buffer.concat([
          items([
            { db: 1, lids: [0xb], crc: level },
            { db: 1, lids: [0xa], crc: level },
          ]),
          v(1),
          Buffer.from([0, 0x07, 0x00, 0x09]),
          v(2),
          Buffer.from([0, 0x0e, 0x40, 0x00, 0x00, 0x00]),
          Buffer.from([0]),
          Buffer.alloc(4),
        ]),
      );
      expect(w.body.toString('hex')).to.equal('00' + '01' + invalid + '00');
      expect(server.memory.area('DB', 1)!.readInt16BE(4)).to.equal(7);
      expect(server.memory.area('DB', 1)!.readFloatBE(0)).to.equal(2);
    });

    it('refuses a request frame past the negotiated TPDU size (1024 bytes) by default, and serves one within it', async () => {
      const own = new S7Server({
        port: 0,
        profile: 's7-1500',
        s7plus: new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: false }),
      });
      await own.listen();
      try {
        // Header 4 + request header 14 + items + fill + trailer 4: pad the fill to reach the size wanted.
        const body = (frame: number) => {
          const list = items([{ db: 1, lids: [0xb] }]);
          return Buffer.concat([list, Buffer.alloc(frame - 4 - 14 - list.length - 4)]);
        };
        const p = new Peer(own.port);
        peers.push(p);
        await p.open();
        const r = await p.ask(0x054c, body(1024));
        expect(r.body.toString('hex')).to.equal('00' + '0100070007' + '00' + '00');
        const refused = waitFor<S7RefusedEvent>(own, 'refused');
        p.socket.write(request(0x054c, 9, p.session, body(1025)));
        expect((await refused).message).to.contain('a request of 1025 bytes, more than the 1024');
        await p.closed;
      } finally {
        await own.close();
      }
    });
  });
});
