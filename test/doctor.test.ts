import { expect } from 'chai';
import { spawn, spawnSync, type ChildProcess } from 'node:child_process';
import { once } from 'node:events';
import * as net from 'node:net';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { PlcError } from '../lib/errors';
import { encodeConnectionConfirm, encodeCotpError, encodeErrorAck, encodeSetupAck, encodeWriteResponse } from '../lib/s7/codec';
import { diagnose, type DoctorReport, type DoctorStep } from '../lib/doctor';
import { familyOf } from '../lib/s7/doctor';
import { S7Server, type S7Profile } from '../lib/s7/server';
import { compileSymbols } from '../lib/symbols/compile';
import type { SymbolTable } from '../lib/symbols/model';
import { freePort } from './support/net';
import { skipBecause } from './support/skip';
import { until } from './support/wait';

const SLOT: Record<S7Profile, number> = { 's7-300': 2, 's7-400': 2, 's7-1200': 1, 's7-1500': 1, 's7-200': 1, logo: 1 };
const HANDSHAKE = ['resolve', 'tcp', 'cotp', 'setup'];
const ALL = [...HANDSHAKE, 'identity', 'protection', 'putget'];

/** Every TCP connection the simulator holds, COTP-confirmed or not. */
function openSockets(server: S7Server): number {
  return (server as unknown as { connections: Set<unknown> }).connections.size;
}

/** The demo plant's DB source, as shipped (`npm start` and its Test connection use it), numbered as the demo numbers it. */
const PLANT_DB = fs.readFileSync(path.resolve(__dirname, '../../demo/Plant.db'));
function plant(content: Buffer | string = PLANT_DB): SymbolTable {
  return compileSymbols([{ name: 'Plant.db', content }], { db: { Plant: 1 } });
}

function names(r: DoctorReport): string[] {
  return r.steps.map((s) => s.step);
}

function last(r: DoctorReport): DoctorStep {
  return r.steps[r.steps.length - 1]!;
}

describe('connection doctor', function () {
  this.timeout(15000);
  const servers: S7Server[] = [];

  async function sim(profile: S7Profile = 's7-1500', layout?: Record<string, number>): Promise<S7Server> {
    const server = new S7Server({ port: 0, profile, ...(layout ? { layout: { dbs: layout } } : {}) });
    await server.listen();
    servers.push(server);
    return server;
  }

  function url(server: S7Server, query: string): string {
    return `s7://127.0.0.1:${server.port}?${query}&timeout=2000`;
  }

  /** Runs the doctor and checks that the simulator holds no connection afterwards. */
  async function run(server: S7Server, u: string, addresses: string[] = [], options = {}): Promise<DoctorReport> {
    const report = await diagnose(u, addresses, options);
    await until(() => openSockets(server) === 0 && server.connectionCount === 0, 2000, 'no connection left');
    return report;
  }

  afterEach(async () => {
    for (const s of servers.splice(0)) await s.close();
  });

  describe('a healthy connection', () => {
    it('passes every step against an S7-1500 and says what it found', async () => {
      const server = await sim('s7-1500');
      const seen: DoctorStep[] = [];
      const r = await run(server, url(server, 'slot=1'), ['DB1,INT0', 'MW10'], { onStep: (s: DoctorStep) => seen.push(s) });
      expect(r.ok).to.equal(true);
      expect(names(r)).to.deep.equal([...ALL, 'address DB1,INT0', 'address MW10']);
      expect(seen).to.deep.equal(r.steps);
      const by = Object.fromEntries(r.steps.map((s) => [s.step, s]));
      expect(by.resolve!.detail).to.equal('127.0.0.1 is an IP address');
      expect(by.cotp!.detail).to.equal('the CPU accepted the connection request (rack 0, slot 1: called TSAP 0x0101, calling TSAP 0x0100)');
      expect(by.setup!.detail).to.equal('PDU 960 bytes (asked 960), 8 parallel jobs (AmQ)');
      expect(by.identity!.detail)
        .to.contain('CPU 1516-3 PN/DP (6ES7 516-3AN02-0AB0) firmware V3.1.0')
        .and.contain('in RUN')
        .and.contain('family S7-1500');
      expect(by.protection!.detail).to.match(/^level 1: no protection/);
      expect(by.putget!.detail).to.contain('the CPU serves Read Var (PUT/GET): MB0 = 0');
      expect(by['address DB1,INT0']!.detail).to.equal(
        'DB1 exists, its length is not known (this CPU offers no block info over S7comm); DB1,INT0 = 0',
      );
      expect(by['address MW10']!.detail).to.equal('MW10 = 0');
    });

    it('reports each step as { step, ok, detail, hint? } and nothing else', async () => {
      const server = await sim('s7-300');
      server.stop();
      const r = await run(server, url(server, 'slot=2'), ['DB1,INT0']);
      for (const s of r.steps) {
        expect(Object.keys(s).every((k) => ['step', 'ok', 'detail', 'hint'].includes(k))).to.equal(true);
        expect(s.ok).to.be.a('boolean');
        expect(s.detail).to.be.a('string').and.not.equal('');
      }
      expect(JSON.parse(JSON.stringify(r))).to.deep.equal(r);
      // STOP is not a connection failure, but it is worth a hint.
      const identity = r.steps.find((s) => s.step === 'identity')!;
      expect(identity.ok).to.equal(true);
      expect(identity.detail).to.contain('in STOP');
      expect(identity.hint).to.contain('plcwire diag');
      expect(r.steps.find((s) => s.step === 'address DB1,INT0')!.detail).to.equal('DB1 exists, 1024 bytes (block info); DB1,INT0 = 0');
    });

    it('tells the CPU family from the order code or the module type', () => {
      expect(familyOf({ orderCode: '6ES7 214-1AG40-0XB0', moduleTypeName: undefined })).to.equal('S7-1200');
      expect(familyOf({ orderCode: '6ES7 214-2BD23-0XB0', moduleTypeName: undefined })).to.equal('S7-200');
      expect(familyOf({ orderCode: '6ES7 315-2EH14-0AB0', moduleTypeName: undefined })).to.equal('S7-300');
      expect(familyOf({ orderCode: '6ES7 416-3ES07-0AB0', moduleTypeName: undefined })).to.equal('S7-400');
      expect(familyOf({ orderCode: '6ES7 516-3AN02-0AB0', moduleTypeName: undefined })).to.equal('S7-1500');
      expect(familyOf({ orderCode: '6ED1052-1MD08-0BA1', moduleTypeName: undefined })).to.equal('LOGO!');
      expect(familyOf({ orderCode: undefined, moduleTypeName: 'CPU 1212C AC/DC/Rly' })).to.equal('S7-1200');
      expect(familyOf({ orderCode: 'X', moduleTypeName: 'ET 200S' })).to.equal(undefined);
    });
  });

  describe('names, with the symbol table of demo/Plant.db', () => {
    async function plantSim(profile: S7Profile): Promise<S7Server> {
      const server = new S7Server({ port: 0, profile, symbols: plant() });
      await server.listen();
      servers.push(server);
      return server;
    }

    it('resolves each name as a read does and reads it at its address; the step shows the name and the address', async () => {
      const server = await plantSim('s7-300');
      const r = await run(server, url(server, 'slot=2'), ['"Plant".Level', 'Plant.MotorSpeed', '"Plant"', 'DB1,INT0'], {
        symbols: plant(),
      });
      expect(r.ok, JSON.stringify(r.steps)).to.equal(true);
      expect(names(r)).to.deep.equal([...ALL, 'symbol "Plant".Level', 'symbol Plant.MotorSpeed', 'symbol "Plant"', 'address DB1,INT0']);
      const by = Object.fromEntries(r.steps.map((s) => [s.step, s]));
      expect(by['symbol "Plant".Level']!.detail).to.equal(
        '"Plant".Level is DB1.DBD0:REAL; DB1 exists, 20 bytes (block info); "Plant".Level = 20',
      );
      expect(by['symbol Plant.MotorSpeed']!.detail).to.equal(
        'Plant.MotorSpeed is DB1.DBW6:INT; DB1 exists, 20 bytes (block info); Plant.MotorSpeed = 0',
      );
      // The whole block: one read of its bytes, shown member by member.
      expect(by['symbol "Plant"']!.detail).to.match(
        /^"Plant" is DB1\.DBB0:BYTE\[20\]; DB1 exists, 20 bytes \(block info\); "Plant" = \{ Level: 20, MotorRun: false, .*Temperature: 20 \}$/,
      );
    });

    it('on a CPU without block info (S7-1500) a name is read all the same', async () => {
      const server = await plantSim('s7-1500');
      const r = await run(server, url(server, 'slot=1'), ['"Plant".Temperature'], { symbols: plant() });
      expect(r.ok, JSON.stringify(r.steps)).to.equal(true);
      expect(last(r)).to.deep.equal({
        step: 'symbol "Plant".Temperature',
        ok: true,
        detail:
          '"Plant".Temperature is DB1.DBD16:REAL; DB1 exists, its length is not known (this CPU offers no block info over S7comm); "Plant".Temperature = 20',
      });
    });

    it('an unknown name is its own failed step naming it and the closest names; the walk stops there', async () => {
      const server = await plantSim('s7-300');
      const r = await run(server, url(server, 'slot=2'), ['"Plant".Levle', 'DB1,INT0'], { symbols: plant() });
      expect(r.ok).to.equal(false);
      expect(names(r)).to.deep.equal([...ALL, 'symbol "Plant".Levle']);
      expect(last(r).ok).to.equal(false);
      expect(last(r).detail).to.equal('unknown symbol "Plant".Levle; did you mean "Plant".Level?');
      expect(last(r).hint).to.contain('plcwire symbols FILE');
    });

    it('a name without a symbol table: the step says to give the sources (it used to fail as "not an S7 address")', async () => {
      const server = await plantSim('s7-300');
      const r = await run(server, url(server, 'slot=2'), ['"Plant".Level']);
      expect(names(r)).to.deep.equal([...ALL, 'symbol "Plant".Level']);
      expect(last(r).ok).to.equal(false);
      expect(last(r).detail).to.equal(
        '"Plant".Level is a name from the PLC program, and the doctor was given no symbol table to look it up in',
      );
      expect(last(r).hint).to.contain('--symbols FILE').and.contain("the connection node's Symbol sources");
      // Unquoted, it may be a mistyped address or a name: the step says both.
      const u = await run(server, url(server, 'slot=2'), ['Plant.Level']);
      expect(last(u).step).to.equal('address Plant.Level');
      expect(last(u).detail).to.match(/^invalid address "Plant\.Level": .*; no symbol table was given to look it up as a name$/);
      expect(last(u).hint).to.contain('--symbols FILE');
    });

    it('sources that declare the DB longer than the PLC has it: the name step fails before showing a shifted value', async () => {
      const server = await plantSim('s7-300');
      const longer = PLANT_DB.toString('utf8').replace(/END_VAR/, '   Extra : Int;\r\n   END_VAR');
      const r = await run(server, url(server, 'slot=2'), ['"Plant".Level'], { symbols: plant(longer) });
      expect(names(r)).to.deep.equal([...ALL, 'symbol "Plant".Level']);
      expect(last(r).ok).to.equal(false);
      expect(last(r).detail).to.match(/^"Plant"\.Level is DB1\.DBD0:REAL; DB1 "Plant" is 20 bytes in the PLC, the sources declare 22: /);
      expect(last(r).hint).to.contain('Generate source from blocks');
    });
  });

  describe('name and TCP', () => {
    it('stops at a host name that does not resolve', async () => {
      const r = await diagnose('s7://plc.invalid?slot=1&timeout=3000');
      expect(r.ok).to.equal(false);
      expect(names(r)).to.deep.equal(['resolve']);
      expect(last(r).detail).to.match(/^"plc\.invalid" does not resolve|could not be looked up/);
      expect(last(r).hint).to.contain("PLC's IP address");
    });

    it('stops at a closed port: refused, nothing listens', async () => {
      const port = await freePort();
      const r = await diagnose(`s7://127.0.0.1:${port}?slot=1`);
      expect(names(r)).to.deep.equal(['resolve', 'tcp']);
      expect(last(r).ok).to.equal(false);
      expect(last(r).detail).to.equal(
        `127.0.0.1:${port} refused the connection (ECONNREFUSED): the host is up, but nothing listens on port ${port}`,
      );
      expect(last(r).hint).to.contain('S7 uses 102');
    });

    it('stops at a filtered port: the connection attempt gets no reply within the timeout', async function () {
      // A listener with a full backlog (listen(0), never accepting): the kernel drops further SYNs, as a firewall does.
      // Node accepts every connection it is offered, so the listener is a python3 one-liner.
      if (spawnSync('python3', ['-c', '']).status !== 0)
        skipBecause(this, 'python3 is not installed (it holds a listener that never accepts)');
      const py: ChildProcess = spawn(
        'python3',
        [
          '-c',
          'import socket,sys\ns=socket.socket();s.bind(("127.0.0.1",0));s.listen(0)\nprint(s.getsockname()[1],flush=True)\nsys.stdin.read()',
        ],
        {
          stdio: ['pipe', 'pipe', 'inherit'],
        },
      );
      const filler: net.Socket[] = [];
      try {
        const [line] = (await once(py.stdout!, 'data')) as [Buffer];
        const port = Number(line.toString().trim());
        const first = net.connect(port, '127.0.0.1');
        filler.push(first);
        await once(first, 'connect');
        const started = Date.now();
        const r = await diagnose(`s7://127.0.0.1:${port}?slot=1&timeout=400`);
        expect(Date.now() - started).to.be.below(2000);
        expect(names(r)).to.deep.equal(['resolve', 'tcp']);
        expect(last(r).detail).to.equal(
          `no answer from 127.0.0.1:${port} within 400 ms: filtered (the connection attempt got no reply at all)`,
        );
        expect(last(r).hint).to.contain('firewall');
      } finally {
        for (const s of filler) s.destroy();
        py.stdin!.end();
        if (py.exitCode === null) await once(py, 'exit');
      }
    });
  });

  describe('COTP', () => {
    it('stops when something accepts TCP but never answers the connection request', async () => {
      const sockets = new Set<net.Socket>();
      const mute = net.createServer((s) => {
        sockets.add(s);
        s.resume(); // reads (and so sees the doctor's FIN), answers nothing
        s.on('close', () => sockets.delete(s));
      });
      mute.listen(0, '127.0.0.1');
      await once(mute, 'listening');
      try {
        const port = (mute.address() as net.AddressInfo).port;
        const r = await diagnose(`s7://127.0.0.1:${port}?slot=1&timeout=300`);
        expect(names(r)).to.deep.equal(['resolve', 'tcp', 'cotp']);
        expect(last(r).detail).to.equal(`port ${port} accepts TCP but nothing answered the ISO-on-TCP connection request within 300 ms`);
        expect(last(r).hint).to.contain('not an S7 PLC');
        await until(() => sockets.size === 0, 2000, 'the doctor closed its socket');
      } finally {
        await new Promise((r) => mute.close(r));
      }
    });

    it('a deadline that runs out anywhere in the handshake is a failed step, never a rejection, and leaves no socket', async () => {
      const sockets = new Set<net.Socket>();
      const mute = net.createServer((s) => {
        sockets.add(s);
        s.resume();
        s.on('close', () => sockets.delete(s));
      });
      mute.listen(0, '127.0.0.1');
      await once(mute, 'listening');
      try {
        const port = (mute.address() as net.AddressInfo).port;
        for (const timeout of [1, 3, 10, 30, 100]) {
          const r = await diagnose(`s7://127.0.0.1:${port}?slot=1&timeout=5000`, [], { timeout });
          expect(r.ok, `${timeout} ms`).to.equal(false);
          expect(last(r).detail, `${timeout} ms`).to.match(/deadline|nothing answered/);
          await until(() => sockets.size === 0, 2000, 'the doctor closed its socket');
        }
      } finally {
        await new Promise((r) => mute.close(r));
      }
    });

    it('stops when another protocol answers', async () => {
      const http = net.createServer((s) => s.resume().end('HTTP/1.1 400 Bad Request\r\n\r\n'));
      http.listen(0, '127.0.0.1');
      await once(http, 'listening');
      try {
        const port = (http.address() as net.AddressInfo).port;
        const r = await diagnose(`s7://127.0.0.1:${port}?slot=1&timeout=1000`);
        expect(last(r).step).to.equal('cotp');
        expect(last(r).detail).to.match(/^the answer is not an ISO-on-TCP connection confirm: .*TPKT version 72/);
      } finally {
        await new Promise((r) => http.close(r));
      }
    });

    for (const [profile, query, fix, family] of [
      ['s7-300', 'slot=1', '?rack=0&slot=2', 'an S7-300'],
      ['s7-1500', 'slot=3', '?rack=0&slot=1', 'an S7-1200/1500'],
      ['s7-200', 'slot=1', '?localTsap=1000&remoteTsap=1001', 'an S7-200 with a CP 243-1'],
      ['logo', 'slot=2', '?localTsap=0100&remoteTsap=0200', 'a LOGO!'],
    ] as const) {
      it(`names the addressing an ${profile} accepts when the URL's is refused (${query})`, async () => {
        const server = await sim(profile);
        const r = await run(server, url(server, query));
        expect(names(r)).to.deep.equal(['resolve', 'tcp', 'cotp']);
        const step = last(r);
        expect(step.ok).to.equal(false);
        expect(step.detail).to.contain('wrong rack/slot or TSAP');
        expect(step.hint).to.contain(`which points to ${family}`).and.contain(`use ${fix} in the URL`);
        expect(step.hint)
          .to.contain('S7-300 rack 0, slot 2; S7-400 rack 0, slot 3')
          .and.contain('S7-1200/1500 rack 0, slot 1')
          .and.contain('LOGO! localTsap=0100&remoteTsap=0200');
      });
    }

    it('says "no free connection" for a COTP disconnect with reason congestion, without trying other slots', async () => {
      const server = await sim('s7-1500');
      server.faults.refuseConnections = true;
      let refusals = 0;
      server.on('refused', () => refusals++);
      const r = await run(server, url(server, 'slot=1'));
      expect(last(r).step).to.equal('cotp');
      expect(last(r).detail).to.contain('COTP disconnect, reason 1: congestion): no free connection');
      expect(last(r).hint).to.contain('close other clients');
      expect(refusals).to.equal(1);
    });
  });

  describe('each answer of the handshake in its words (a scripted peer)', () => {
    /** A peer that answers the connection request with `cotp` and, after a confirm, setup communication with `setup`. */
    async function scripted(cotp: (s: net.Socket) => void, setup: (s: net.Socket) => void = () => undefined): Promise<DoctorReport> {
      const sockets = new Set<net.Socket>();
      const server = net.createServer((s) => {
        sockets.add(s);
        s.on('error', () => undefined);
        s.on('close', () => sockets.delete(s));
        let frames = 0;
        s.on('data', () => (++frames === 1 ? cotp(s) : frames === 2 ? setup(s) : undefined));
      });
      server.listen(0, '127.0.0.1');
      await once(server, 'listening');
      try {
        const port = (server.address() as net.AddressInfo).port;
        const r = await diagnose(`s7://127.0.0.1:${port}?slot=1&timeout=300`);
        await until(() => sockets.size === 0, 2000, 'the doctor closed its sockets');
        return r;
      } finally {
        await new Promise((r) => server.close(r));
      }
    }
    const confirm = (s: net.Socket) =>
      s.write(encodeConnectionConfirm({ destinationRef: 1, sourceRef: 0x11, callingTsap: 0x0100, calledTsap: 0x0101, tpduSize: 0x0a }));

    it('a COTP TPDU error instead of a confirm: not an ISO-on-TCP connection confirm', async () => {
      const r = await scripted((s) => s.write(encodeCotpError(1, 2)));
      expect(names(r)).to.deep.equal(['resolve', 'tcp', 'cotp']);
      expect(last(r).detail).to.equal('the answer is not an ISO-on-TCP connection confirm: a COTP ER instead of a connection confirm');
      expect(last(r).hint).to.contain('Another protocol listens on this port');
    });

    it('setup communication unanswered: the CPU does not talk S7', async () => {
      const r = await scripted(confirm);
      expect(names(r)).to.deep.equal(HANDSHAKE);
      expect(last(r)).to.deep.include({ ok: false, detail: 'no answer to setup communication within 300 ms' });
      expect(last(r).hint).to.contain('does not talk S7');
    });

    it('the connection closed at setup communication', async () => {
      const r = await scripted(confirm, (s) => s.end());
      expect(last(r)).to.deep.include({ step: 'setup', ok: false, detail: 'the CPU closed the connection at setup communication' });
      expect(last(r).hint).to.contain('not the S7 session');
    });

    it('setup communication refused with a header error, in the PLC error words', async () => {
      const r = await scripted(confirm, (s) => s.write(encodeErrorAck(0, 0x85, 0x00)));
      expect(last(r)).to.deep.include({
        step: 'setup',
        ok: false,
        detail: 'setup communication: the PLC answered 0x8500: PDU too large for the negotiated size',
      });
      expect(last(r).hint).to.contain('refuses the S7 session');
    });

    it('an answer to setup communication of another kind, an unusable PDU size, bytes that are not TPKT', async () => {
      const other = await scripted(confirm, (s) => s.write(encodeWriteResponse(0, [0xff])));
      expect(last(other)).to.deep.include({ step: 'setup', ok: false, detail: 'the answer to setup communication is a write-ack' });
      const small = await scripted(confirm, (s) => s.write(encodeSetupAck(0, { maxAmqCalling: 1, maxAmqCalled: 1, pduSize: 32 })));
      expect(last(small)).to.deep.include({ step: 'setup', ok: false, detail: 'the CPU negotiated an unusable PDU size of 32 bytes' });
      const garbage = await scripted(confirm, (s) => s.write('HTTP/1.1 400 Bad Request\r\n\r\n'));
      expect(last(garbage)).to.deep.include({
        step: 'setup',
        ok: false,
        detail: 'the answer to setup communication is malformed: TPKT version 72, expected 3',
      });
    });

    it('a granted setup: the PDU size and the parallel jobs, at most the 8 asked for', async () => {
      const r = await scripted(confirm, (s) => s.write(encodeSetupAck(0, { maxAmqCalling: 12, maxAmqCalled: 10, pduSize: 480 })));
      const setup = r.steps.find((x) => x.step === 'setup')!;
      expect(setup).to.deep.include({ ok: true, detail: 'PDU 480 bytes (asked 960), 8 parallel jobs (AmQ)' });
    });
  });

  describe('after the handshake', () => {
    it('stops at PUT/GET refused by an S7-1200 and says where to allow it', async () => {
      const server = await sim('s7-1200');
      server.faults.accessDenied = true;
      const r = await run(server, url(server, 'slot=1'), ['DB1,INT0']);
      expect(names(r)).to.deep.equal(ALL);
      expect(last(r).ok).to.equal(false);
      expect(last(r).detail).to.contain('the CPU refuses Read Var as a whole').and.contain('0x8104');
      expect(last(r).hint).to.contain('Permit access with PUT/GET communication from remote partner');
    });

    it('passes protection level 2 with a hint and stops at level 3', async () => {
      const server = await sim('s7-300');
      server.setProtection(2, 'secret');
      let r = await run(server, url(server, 'slot=2'), ['DB1,INT0']);
      expect(r.ok).to.equal(true);
      const p = r.steps.find((s) => s.step === 'protection')!;
      expect(p.detail).to.match(/^level 2: write protection/);
      expect(p.hint).to.contain('setPassword');
      server.setProtection(3, 'secret');
      r = await run(server, url(server, 'slot=2'), ['DB1,INT0']);
      expect(names(r)).to.deep.equal([...HANDSHAKE, 'identity', 'protection']);
      expect(last(r).ok).to.equal(false);
      expect(last(r).detail).to.match(/^level 3: read\/write protection/);
    });

    it('finds a missing DB, by block info on an S7-300 and by the read on an S7-1500', async () => {
      for (const [profile, how] of [
        ['s7-300', 'block info: no such block'],
        ['s7-1500', 'the CPU answered the read'],
      ] as const) {
        const server = await sim(profile, { 1: 100 });
        const r = await run(server, url(server, `slot=${SLOT[profile]}`), ['DB1,INT0', 'DB7,INT0', 'DB1,INT2']);
        expect(names(r)).to.deep.equal([...ALL, 'address DB1,INT0', 'address DB7,INT0']);
        expect(last(r).detail).to.match(new RegExp(`^DB7 does not exist \\(${how.replace(/[()]/g, '\\$&')}`));
        expect(last(r).hint).to.contain('downloaded');
      }
    });

    it('finds a DB too short for the address: its length by block info, or by reading single bytes', async () => {
      let server = await sim('s7-300', { 1: 101 });
      let r = await run(server, url(server, 'slot=2'), ['DB1,INT100']);
      expect(last(r)).to.include({ ok: false, detail: 'DB1 has 101 bytes (block info); DB1,INT100 needs bytes 100..101' });
      server = await sim('s7-1500', { 1: 101 });
      let reads = 0;
      server.on('request', (e: { kind: string }) => (reads += e.kind === 'read' ? 1 : 0));
      r = await run(server, url(server, 'slot=1'), ['DB1,REAL98']);
      expect(last(r)).to.include({
        ok: false,
        detail: 'DB1 has 101 bytes (found by reading single bytes); DB1,REAL98 needs bytes 98..101',
      });
      expect(last(r).hint).to.contain('past the end of DB1');
      expect(reads).to.be.below(12);
    });

    it('says "probably optimized" for an S7-1500 DB that exists but serves not even byte 0', async () => {
      // What an S7-1200/1500 answers for a DB with optimized block access (python-snap7#191); an empty DB answers the same.
      const server = await sim('s7-1500', { 1: 10, 5: 0 });
      const r = await run(server, url(server, 'slot=1'), ['DB5,INT0']);
      expect(last(r).ok).to.equal(false);
      expect(last(r).detail).to.contain('DB5 exists').and.contain('probably an optimized DB').and.contain('an empty DB answers the same');
      expect(last(r).hint).to.contain('Optimized block access');
    });

    it('fails a malformed address on its own step', async () => {
      const server = await sim('s7-1500');
      const r = await run(server, url(server, 'slot=1'), ['DB1,NOPE0']);
      expect(last(r).step).to.equal('address DB1,NOPE0');
      expect(last(r).detail).to.contain('invalid address');
    });

    it('stops at a bad URL or another protocol before any connection', async () => {
      let r = await diagnose('s7://127.0.0.1?slot=99');
      expect(names(r)).to.deep.equal(['url']);
      r = await diagnose('fetchwrite://127.0.0.1');
      expect(last(r).detail).to.contain('this URL is fetchwrite');
    });
  });

  describe('deadline and abort', () => {
    it('keeps its overall deadline against a CPU that stops answering, and leaves no connection', async () => {
      const server = await sim('s7-1500');
      server.faults.silent = true;
      const started = Date.now();
      const r = await run(server, `s7://127.0.0.1:${server.port}?slot=1&timeout=5000`, [], { timeout: 600 });
      expect(Date.now() - started).to.be.below(2000);
      // The identity step fails on the deadline, or the deadline ends the walk between its requests.
      expect(last(r).ok).to.equal(false);
      expect(['identity', 'deadline']).to.include(last(r).step);
      expect(last(r).detail).to.contain('deadline of 600 ms');
    });

    it('rejects with ABORTED when the caller aborts, and leaves no connection', async () => {
      const server = await sim('s7-1500');
      server.faults.silent = true;
      const ac = new AbortController();
      const p = diagnose(url(server, 'slot=1'), [], {
        signal: ac.signal,
        onStep: (s) => s.step === 'setup' && setTimeout(() => ac.abort(), 50),
      });
      const err = await p.then(
        () => undefined,
        (e: unknown) => e,
      );
      expect(err).to.be.instanceOf(PlcError);
      expect((err as PlcError).code).to.equal('ABORTED');
      await until(() => openSockets(server) === 0, 2000, 'no connection left');
    });

    it('rejects at once with an already aborted signal', async () => {
      const server = await sim('s7-1500');
      const err = await diagnose(url(server, 'slot=1'), [], { signal: AbortSignal.abort() }).catch((e: unknown) => e);
      expect((err as PlcError).code).to.equal('ABORTED');
      await until(() => openSockets(server) === 0, 2000, 'no connection left');
    });
  });
});
