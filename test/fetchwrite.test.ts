import { expect } from 'chai';
import fc from 'fast-check';
import * as net from 'node:net';
import { PlcError } from '../lib/errors';
import { FetchWriteClient } from '../lib/fetchwrite/client';
import { OpCode, decodeRequest, decodeResponse, encodeRequest, encodeResponse, errorFor } from '../lib/fetchwrite/codec';
import { FetchWriteServer, type FetchWriteRequestEvent } from '../lib/fetchwrite/server';
import { parseUrl, type FetchWriteEndpoint } from '../lib/url';
import { activeHandles, settle, until, waitFor } from './support/wait';

const hex = (s: string) => Buffer.from(s.replace(/\s+/g, ''), 'hex');
const show = (b: Buffer) => b.toString('hex').toUpperCase();
const FAST = { backoff: { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 } };

describe('FETCH/WRITE codec', () => {
  it("encodes the document's fetch of MB0..MB1 byte for byte", () => {
    const frame = encodeRequest({ op: OpCode.FetchRequest, org: 2, dbNumber: 0, start: 0, length: 2 });
    expect(show(frame)).to.equal(show(hex('53 35 10 01 03 05 03 08 02 00 00 00 00 02 FF 02')));
    expect(decodeRequest(frame)).to.deep.equal({ op: 5, org: 2, dbNumber: 0, start: 0, length: 2 });
  });

  it('encodes a DB write (REAL 22.0 to DB62, data word 1008) and decodes its acknowledgement, as captured from a field device', () => {
    const data = Buffer.alloc(4);
    data.writeFloatBE(22.0);
    const frame = encodeRequest({ op: OpCode.WriteRequest, org: 1, dbNumber: 62, start: 1008, length: 2, data });
    expect(show(frame)).to.equal(show(hex('53 35 10 01 03 03 03 08 01 3E 03 F0 00 02 FF 02 41 B0 00 00')));
    const ack = hex('53 35 10 01 03 04 0F 03 00 FF 07 00 00 00 00 00');
    expect(decodeResponse(ack)).to.deep.equal({ op: 4, error: 0, data: Buffer.alloc(0) });
    expect(show(encodeResponse(OpCode.WriteAck, 0))).to.equal(show(ack));
  });

  it('error responses carry no data and translate to typed errors', () => {
    const r = encodeResponse(OpCode.FetchResponse, 0x02, Buffer.from('ignored'));
    expect(r.length).to.equal(16);
    expect(decodeResponse(r).error).to.equal(2);
    expect(errorFor(0x02, 'fetch').code).to.equal('OBJECT_DOES_NOT_EXIST');
    expect(errorFor(0x03, 'fetch').code).to.equal('ADDRESS_OUT_OF_RANGE');
    expect(errorFor(0x06, 'fetch').message).to.match(/invalid ORG format/);
    expect(errorFor(0x42, 'fetch').message).to.match(/error 42 \(unknown code\)/);
  });

  it('property: any bytes decode or throw a PlcError', () => {
    fc.assert(
      fc.property(fc.uint8Array({ maxLength: 40 }), (a) => {
        for (const f of [decodeResponse, decodeRequest]) {
          try {
            f(Buffer.from(a));
          } catch (err) {
            if (!(err instanceof PlcError)) throw err;
          }
        }
      }),
      { numRuns: 20000 },
    );
  });
});

describe('FETCH/WRITE client against the CP simulator', function () {
  this.timeout(10000);
  let server: FetchWriteServer;
  let client: FetchWriteClient;
  let jobs: FetchWriteRequestEvent[];

  async function start(options: { port?: number; dbUnit?: 'word' | 'byte' } = {}) {
    server = new FetchWriteServer(options.port !== undefined ? { port: 0, ...(options.dbUnit ? { dbUnit: options.dbUnit } : {}) } : { fetchPort: 0, writePort: 0, ...(options.dbUnit ? { dbUnit: options.dbUnit } : {}) });
    const ports = await server.listen();
    jobs = [];
    server.on('request', (r: FetchWriteRequestEvent) => jobs.push(r));
    const q = options.port !== undefined ? `port=${ports.fetchPort}` : `fetchPort=${ports.fetchPort}&writePort=${ports.writePort}`;
    client = new FetchWriteClient(parseUrl(`fetchwrite://127.0.0.1?${q}&timeout=1500${options.dbUnit ? `&dbUnit=${options.dbUnit}` : ''}`) as FetchWriteEndpoint, FAST);
    await client.connect();
  }

  afterEach(async () => {
    await client?.close();
    await server?.close();
  });

  it('reads and writes every area and several types', async () => {
    await start();
    const values: Record<string, unknown> = {
      'DB10,INT4': -321,
      'DB10.DBD8:REAL': 1.25,
      'DB10,S20.10': 'abc',
      'DB10.DBB40:LINT': -5n,
      MB0: 0x5a,
      'MW2:INT': -2,
      'I1.5': true,
      QW2: 0xbeef,
      PQW4: 1234,
      C5: 42,
      T3: 2000,
    };
    server.memory.area('DB', 10)![20] = 10;
    await client.write(values);
    // PQW writes the outputs (PA); what is read back from P is the inputs (PE).
    server.memory.area('PE')!.writeUInt16BE(1234, 4);
    expect(await client.read(Object.keys(values))).to.deep.equal(values);
    expect(server.memory.area('PA')!.readUInt16BE(4)).to.equal(1234);
  });

  it('counts DB addresses in words on the wire; an odd byte offset fetches the enclosing words', async () => {
    await start();
    server.memory.area('DB', 1)!.writeUInt8(0x7e, 5);
    expect(await client.read(['DB1.DBB5'])).to.deep.equal({ 'DB1.DBB5': 0x7e });
    expect(jobs).to.deep.equal([{ kind: 'fetch', org: 1, dbNumber: 1, start: 2, length: 1 }]);
  });

  it('dbUnit=byte counts DB addresses in bytes (VIPA and some gateways)', async () => {
    await start({ dbUnit: 'byte' });
    server.memory.area('DB', 1)!.writeUInt8(0x7e, 5);
    expect(await client.read(['DB1.DBB5'])).to.deep.equal({ 'DB1.DBB5': 0x7e });
    expect(jobs).to.deep.equal([{ kind: 'fetch', org: 1, dbNumber: 1, start: 5, length: 1 }]);
  });

  it('writes a bit and an odd byte by read-modify-write of the enclosing unit, keeping the neighbours', async () => {
    await start();
    const db = server.memory.area('DB', 1)!;
    db.writeUInt16BE(0xa5a5, 12);
    await client.write({ 'DB1,X13.1': false, 'DB1.DBB12': 0x11 });
    expect(db.readUInt16BE(12)).to.equal(0x11a5);
    expect(jobs.map((j) => `${j.kind}@${j.start}+${j.length}`)).to.deep.equal(['fetch@6+1', 'write@6+1', 'fetch@6+1', 'write@6+1']);
    server.memory.area('M')![3] = 0xff;
    await client.write({ 'M3.0': false });
    expect(server.memory.area('M')![3]).to.equal(0xfe);
  });

  it('merges several tags into as few fetches as the ranges allow', async () => {
    await start();
    await client.read(['DB1,INT0', 'DB1,INT2', 'DB1,REAL40', 'DB1,INT1000', 'MB0', 'MB10', 'DB2,INT0']);
    expect(jobs.map((j) => `${j.org}/${j.dbNumber}@${j.start}+${j.length}`)).to.deep.equal(['1/1@0+22', '1/1@500+1', '1/2@0+1', '2/0@0+11']);
  });

  it('splits a read beyond the ORG length range into several jobs', async () => {
    await start({ dbUnit: 'byte' });
    server.memory.createDataBlock(5, 8000);
    server.memory.area('DB', 5)!.fill(7);
    const v = (await client.read(['DB5.DBB0:BYTE[6000]']))['DB5.DBB0:BYTE[6000]'] as number[];
    expect(v.length).to.equal(6000);
    expect(v.every((b) => b === 7)).to.equal(true);
    expect(jobs.length).to.be.greaterThan(1);
  });

  it('refuses impossible addresses before sending anything', async () => {
    await start();
    const r = await client.readDetailed(['DB0,INT0', 'DB256,INT0', 'MB256', 'IB200', 'DB1.DBW4096', 'C300']);
    for (const [address, result] of Object.entries(r)) {
      expect(result.ok, address).to.equal(false);
      if (!result.ok) expect(result.error.code, address).to.equal('INVALID_ADDRESS');
    }
    expect(jobs).to.deep.equal([]);
  });

  it('one missing DB fails alone, with the CP error in words', async () => {
    await start();
    const r = await client.readDetailed(['DB99,INT0', 'DB200,INT0']);
    expect(r['DB99,INT0']!.ok).to.equal(true);
    const bad = r['DB200,INT0']!;
    if (bad.ok) throw new Error('expected failure');
    expect(bad.error.code).to.equal('OBJECT_DOES_NOT_EXIST');
    expect(bad.error.message).to.match(/^DB200,INT0: .*area does not exist/);
  });

  it('works with one port serving fetch and write', async () => {
    await start({ port: 0 });
    await client.write({ MW0: 77 });
    expect(await client.read(['MW0'])).to.deep.equal({ MW0: 77 });
    expect(server.connectionCount).to.equal(1);
  });

  it('reconnects after the CP drops the connections, failing fast meanwhile', async () => {
    await start();
    const lost = waitFor(client, 'disconnected');
    server.dropConnections();
    await lost;
    expect(((await client.read(['MW0']).catch((e: unknown) => e)) as PlcError).code).to.equal('NOT_CONNECTED');
    await waitFor(client, 'connected', 3000);
    server.memory.area('M')!.writeUInt16BE(9, 0);
    expect(await client.read(['MW0'])).to.deep.equal({ MW0: 9 });
  });

  it('close() resolves and leaves no handles', async () => {
    await settle();
    const before = activeHandles();
    await start();
    server.faults.silent = true;
    const pending = client.read(['MW0']).catch((e: PlcError) => e);
    await client.close();
    expect(((await pending) as PlcError).code).to.equal('CLOSED');
    await server.close();
    await until(() => server.connectionCount === 0);
    await settle();
    expect(activeHandles()).to.equal(before);
  });
});

describe('FETCH/WRITE client against hostile peers', function () {
  this.timeout(10000);
  const servers: net.Server[] = [];
  afterEach(async () => Promise.all(servers.splice(0).map((s) => new Promise((r) => s.close(r)))));

  async function peer(answer: (socket: net.Socket, job: Buffer) => void): Promise<number> {
    const server = net.createServer((socket) => {
      socket.on('error', () => undefined);
      socket.on('data', (job) => answer(socket, job));
    });
    servers.push(server);
    await new Promise<void>((r) => server.listen(0, '127.0.0.1', r));
    return (server.address() as net.AddressInfo).port;
  }

  async function readFrom(port: number): Promise<unknown> {
    const client = new FetchWriteClient(parseUrl(`fetchwrite://127.0.0.1?port=${port}&timeout=800`) as FetchWriteEndpoint, FAST);
    try {
      await client.connect();
      return await client.read(['MW0']).catch((e: unknown) => e);
    } finally {
      await client.close();
    }
  }

  it('a response dripped one byte at a time, and two responses coalesced, are cut correctly', async () => {
    const reply = encodeResponse(OpCode.FetchResponse, 0, hex('1234'));
    const port = await peer((socket) => {
      let i = 0;
      const drip = () => {
        if (i < reply.length && !socket.destroyed) {
          socket.write(reply.subarray(i, ++i));
          setImmediate(drip);
        }
      };
      drip();
    });
    expect(await readFrom(port)).to.deep.equal({ MW0: 0x1234 });
  });

  it('a silent CP: TIMEOUT within the timeout', async () => {
    const port = await peer(() => undefined);
    const started = Date.now();
    const err = (await readFrom(port)) as PlcError;
    expect(err.code).to.equal('TIMEOUT');
    expect(Date.now() - started).to.be.below(2000);
  });

  it('garbage instead of a response: a connection error, no crash', async () => {
    const port = await peer((socket) => socket.write(Buffer.from('HTTP/1.1 400 Bad Request\r\n\r\n')));
    const err = (await readFrom(port)) as PlcError;
    expect(err).to.be.instanceOf(PlcError);
    expect(err.code).to.match(/PROTOCOL_ERROR|CONNECTION_LOST/);
  });

  it('a write ack where a fetch response is due: a protocol error', async () => {
    const port = await peer((socket) => socket.write(encodeResponse(OpCode.WriteAck, 0)));
    const err = (await readFrom(port)) as PlcError;
    expect(err.code).to.match(/PROTOCOL_ERROR|CONNECTION_LOST/);
  });
});
