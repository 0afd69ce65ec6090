/**
 * client.browse() and reads and writes by name over s7plus:// against our
 * simulator (issue #25): the browsed table gives the names and types the
 * compiled sources give, the PLC's byte and bit of standard members equal
 * our layout's, optimized members have none; names read and write by LID,
 * a struct as an object, an unknown name fails with suggestions.
 */
import { expect } from 'chai';
import { createClient } from '../lib/connect';
import type { PlcError } from '../lib/errors';
import type { S7PlusClient } from '../lib/s7plus/client';
import { S7Server } from '../lib/s7/server';
import { S7PlusService } from '../lib/s7plus/server';
import { generateCertificate } from '../lib/s7plus/transport/cert';
import { compileSymbols } from '../lib/symbols';
import type { SymbolEntry } from '../lib/symbols/model';
import { browseTable } from '../lib/s7plus/client/browse';
import type { Ask, S7PlusSession } from '../lib/s7plus/client/session';
import { encodeExploreResponse, type ExploreRequest } from '../lib/s7plus/codec/explore';
import { newObject, type PObject } from '../lib/s7plus/codec/object';
import { symbolCrc } from '../lib/s7plus/codec/symbol-crc';
import { encodeGetMultiVariablesResponse } from '../lib/s7plus/codec/variables';
import { expectedCrc } from '../lib/s7plus/server/symbol-crc';
import { DataType, dbAccessArea, ElementId, FunctionCode, Ids, SoftDataType } from '../lib/s7plus/constants';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { startPlusSimulator } from './support/s7plus-sim';
import { requireS7CommPlus, startS7CommPlusServer, stopS7CommPlusPeers, type S7CommPlusPeerServer } from './support/s7commplus-peer';

describe('S7CommPlus browse and names (our client, our simulator)', function () {
  this.timeout(30000);
  let server: S7Server;
  let service: S7PlusService;
  let client: S7PlusClient;

  before(async () => {
    let url: string;
    ({ server, service, url } = await startPlusSimulator({ sources: SOURCES, db: DB_NUMBERS }));
    client = createClient(url) as S7PlusClient;
    await client.connect();
  });
  after(async () => {
    await client?.close();
    await server?.close();
  });

  it('browses every entry the compiled sources give: names, types, kinds, children; standard offsets equal, optimized null', async () => {
    const browsed = await client.browse();
    const compiled = compileSymbols(SOURCES, { db: DB_NUMBERS });
    expect(browsed.entries.map((e) => e.name)).to.deep.equal(compiled.entries.map((e) => e.name));
    compiled.entries.forEach((c) => {
      const b = browsed.lookup(c.name)!;
      // The type object does not carry the UDT's name: an instance of "Valve" is browsed as STRUCT.
      const type = c.type.replace(/"Valve"/g, 'STRUCT');
      expect({
        name: b.name,
        type: b.type,
        kind: b.kind,
        byte: b.byte,
        bit: b.bit,
        address: b.address,
        children: b.children,
      }).to.deep.equal({
        name: c.name,
        type,
        kind: c.kind,
        byte: c.byte,
        bit: c.bit,
        address: c.address,
        children: c.children,
      });
      expect(b.access!.area).to.equal(0x8a0e0000 + c.db!);
      expect(b.access!.lids.length).to.be.greaterThan(0);
    });
    expect(browsed.lookup('"Recipe".Step')).to.include({ byte: null, bit: null, address: null, type: 'INT' });
    expect(browsed.lookup('"Tank".Count')).to.include({ byte: 4, address: 'DB1.DBW4:INT' });
    expect(browsed.lookup('"Tank".Motor.Speed')!.access!.lids).to.deep.equal([0x0f, 0x0a]);
    expect(browsed.blocks.map((b) => [b.name, b.db, b.optimized === true, b.length])).to.deep.equal(
      compiled.blocks.map((b) => [b.name, b.db, b.optimized === true, b.length]),
    );
    expect(await client.browse()).to.equal(browsed);
  });

  it('reads optimized and standard members by name, a struct as an object', async () => {
    const values = await client.read([
      '"Recipe".Target',
      '"Recipe".Step',
      '"Tank".Level',
      '"Tank".Name',
      '"Tank".Temps',
      '"Tank".Motor',
      '"Tank".Running',
    ]);
    expect(values).to.deep.equal({
      '"Recipe".Target': 80,
      '"Recipe".Step': 3,
      '"Tank".Level': 12.5,
      '"Tank".Name': 'abc',
      '"Tank".Temps': [0, 21.5, 0],
      '"Tank".Motor': { Speed: 1500, On: false },
      '"Tank".Running': true,
    });
    expect(await client.read(['"Recipe".Inlet'])).to.deep.equal({ '"Recipe".Inlet': { Open: false, Position: 0 } });
  });

  it('writes by name (optimized, standard, a BOOL, a struct) and reads the values back', async () => {
    await client.write({ '"Recipe".Step': 9, '"Recipe".Done': true, '"Tank".Name': 'xyz', '"Recipe".Inlet': { Open: true, Position: -4 } });
    expect(await client.read(['"Recipe".Step', '"Recipe".Done', '"Tank".Name', '"Recipe".Inlet.Position', '"Tank".Count'])).to.deep.equal({
      '"Recipe".Step': 9,
      '"Recipe".Done': true,
      '"Tank".Name': 'xyz',
      '"Recipe".Inlet.Position': -4,
      '"Tank".Count': 7,
    });
    // The same bytes by address (the standard DB): the write went where the name is.
    await client.write({ '"Tank".Count': 11 });
    expect(await client.read(['DB1.DBW4'])).to.deep.equal({ 'DB1.DBW4': 11 });
  });

  it('a name the PLC does not have fails with INVALID_ADDRESS naming it and the closest names, never another value', async () => {
    const err = await client.read(['"Recipe".Stepp']).catch((e: Error) => e);
    expect(err).to.include({ code: 'TAG_ERRORS' });
    expect((err as Error).message)
      .to.include('unknown name "Recipe".Stepp')
      .and.include('did you mean "Recipe".Step');
    const detailed = await client.readDetailed(['"Recipe".Step', '"Nope".X']);
    expect(detailed['"Recipe".Step']).to.include({ ok: true });
    const nope = detailed['"Nope".X']!;
    expect(nope.ok).to.equal(false);
    expect(!nope.ok && nope.error).to.include({ code: 'INVALID_ADDRESS' });
  });

  it('an address in the optimized DB (DB2.DBW0) says the block is optimized and which name to use, not "no such item"; a standard DB still reads', async () => {
    for (const r of [await client.readDetailed(['DB2.DBW0:INT', 'DB1.DBW0:INT']), await client.writeDetailed({ 'DB2.DBW0:INT': 1 })]) {
      const refused = r['DB2.DBW0:INT']!;
      expect(refused.ok).to.equal(false);
      const err = (refused as { error: PlcError }).error;
      expect(err.code).to.equal('OPTIMIZED_BLOCK');
      expect(err.plcCode).to.equal(0x8104);
      expect(err.message).to.include('DB2.DBW0:INT: DB2 ("Recipe") has optimized access').and.include('e.g. "Recipe".Target');
    }
    expect((await client.readDetailed(['DB1.DBW0:INT']))['DB1.DBW0:INT']).to.include({ ok: true });
    // A DB the PLC does not have keeps the PLC's own words.
    const missing = (await client.readDetailed(['DB99.DBW0:INT']))['DB99.DBW0:INT']!;
    expect(!missing.ok && missing.error.code).to.equal('OBJECT_DOES_NOT_EXIST');
  });

  it('readOnly and a write allow-list by name hold as for s7://', async () => {
    const ro = createClient(`s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=10000`, {
      readOnly: true,
    }) as S7PlusClient;
    const allow = createClient(`s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=10000`, {
      allow: ['"Recipe".Inlet'],
    }) as S7PlusClient;
    try {
      await ro.connect();
      await allow.connect();
      expect(String(await ro.write({ '"Recipe".Step': 1 }).catch((e: Error) => e))).to.include('the connection is read-only');
      expect(String(await allow.write({ '"Recipe".Step': 1 }).catch((e: Error) => e))).to.include(
        "not in the connection's write allow-list",
      );
      await allow.write({ '"Recipe".Inlet.Position': 5 });
      expect(await allow.read(['"Recipe".Inlet.Position'])).to.deep.equal({ '"Recipe".Inlet.Position': 5 });
    } finally {
      await ro.close();
      await allow.close();
    }
  });

  it('names go in requests of at most maxItems items: a struct of 4 members and 2 more names in 3 requests of 2, and no program check', async () => {
    const small = createClient(
      `s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=10000&maxItems=2`,
    ) as S7PlusClient;
    try {
      await small.connect();
      await small.browse();
      const before = small.stats.requestsSent;
      const values = await small.read(['"Tank".Valves', '"Tank".Count', '"Recipe".Target']);
      expect(values['"Tank".Valves']).to.have.length(2);
      // 3 reads of 2 items and nothing else: each name carries its SymbolCrc, which the PLC checks (issue #32).
      expect(small.stats.requestsSent - before).to.equal(3);
    } finally {
      await small.close();
    }
  });

  it('a given symbols table (the compiled sources) works: its optimized names through the browse, its standard ones by address', async () => {
    const symbols = compileSymbols(SOURCES, { db: DB_NUMBERS });
    const withTable = createClient(`s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=10000`, {
      symbols,
    }) as S7PlusClient;
    try {
      await withTable.connect();
      await withTable.write({ '"Recipe".Target': 42.5, '"Tank".Level': 3.25 });
      expect(await withTable.read(['"Recipe".Target', '"Tank".Level', '"Tank".Motor'])).to.deep.equal({
        '"Recipe".Target': 42.5,
        '"Tank".Level': 3.25,
        '"Tank".Motor': { Speed: 1500, On: false },
      });
    } finally {
      await withTable.close();
    }
  });

  it('the browsed table is kept per connection: a new connection browses again', async () => {
    const first = await client.browse();
    expect(await client.browse()).to.equal(first);
    const back = new Promise<void>((resolve) => client.once('connected', () => resolve()));
    server.dropConnections();
    await back;
    const second = await client.browse();
    expect(second).to.not.equal(first);
    expect(second.entries.map((e) => e.name)).to.deep.equal(first.entries.map((e) => e.name));
  });
});

/** An optimized DB "Line" whose members are declared in `order`, each with its start value. */
function lineSource(order: readonly [name: string, value: number][]): { name: string; content: string }[] {
  const members = order.map(([name, value]) => `      ${name} : Int := ${value};`).join('\n');
  const content = `DATA_BLOCK "Line"\n{ S7_Optimized_Access := 'TRUE' }\nVERSION : 0.1\nNON_RETAIN\n   STRUCT\n${members}\n   END_STRUCT;\nBEGIN\nEND_DATA_BLOCK\n`;
  return [{ name: 'Line.db', content }];
}

describe('S7CommPlus names polled as one list (the read plan)', function () {
  this.timeout(30000);
  const servers: S7Server[] = [];
  after(async () => {
    for (const s of servers) await s.close();
  });

  it('a list read again after a reconnect to a changed program reads by the new LIDs, never the old plan', async () => {
    const cert = await generateCertificate();
    const tls = { cert: cert.cert, key: cert.key };
    const serve = async (order: readonly [string, number][], port = 0) => {
      const s = new S7Server({ port, profile: 's7-1500', s7plus: new S7PlusService({ sources: lineSource(order), db: { Line: 3 }, tls }) });
      servers.push(s);
      await s.listen();
      return s;
    };
    const first = await serve([
      ['Speed', 10],
      ['Count', 20],
    ]);
    const client = createClient(`s7plus://127.0.0.1:${first.port}?fingerprint=${cert.fingerprint}&timeout=5000`) as S7PlusClient;
    client.on('error', () => undefined);
    try {
      await client.connect();
      const list = ['"Line".Count', '"Line".Speed'];
      expect(await client.read(list)).to.deep.equal({ '"Line".Count': 20, '"Line".Speed': 10 });
      expect(await client.read(list)).to.deep.equal({ '"Line".Count': 20, '"Line".Speed': 10 });
      // A download in between: the same names, declared the other way round (Count now has Speed's LID) and a new value.
      const back = new Promise<void>((resolve) => client.once('connected', () => resolve()));
      await first.close();
      await serve(
        [
          ['Count', 21],
          ['Speed', 11],
        ],
        first.port,
      );
      await back;
      expect(await client.read(list)).to.deep.equal({ '"Line".Count': 21, '"Line".Speed': 11 });
    } finally {
      await client.close();
    }
  });
});

describe('S7CommPlus browse against the s7commplus emulator (its browse offers nothing)', function () {
  this.timeout(60_000);
  let peer: S7CommPlusPeerServer;
  before(async function () {
    const python = requireS7CommPlus(this);
    peer = await startS7CommPlusServer(python, { dbs: [{ number: 1, size: 64, variables: { count: ['DInt', 4] } }], version: 1 });
  });
  after(async () => {
    await peer?.stop();
    await stopS7CommPlusPeers();
  });

  it('gives a table without error; a name then fails with INVALID_ADDRESS, addresses still read', async () => {
    const client = createClient(`s7plus://127.0.0.1:${peer.port}?tls=false&timeout=5000`) as S7PlusClient;
    try {
      await client.connect();
      const table = await client.browse();
      expect(table.entries).to.deep.equal([]);
      expect(table.blocks).to.deep.equal([]);
      const detailed = await client.readDetailed(['"Nothing".Here', 'DB1.DBD4:DINT']);
      const missing = detailed['"Nothing".Here']!;
      expect(missing.ok).to.equal(false);
      expect(!missing.ok && missing.error).to.include({ code: 'INVALID_ADDRESS' });
      expect(detailed['DB1.DBD4:DINT']).to.include({ ok: true });
    } finally {
      await client.close();
    }
  });
});

/** A session that answers an Explore of the program with one DB, LID 1 with RID 0x92000001, and the type info with `vartype` (raw list bytes). */
function hostileSession(vartype: Buffer, varname: Buffer): S7PlusSession {
  const header = { functionCode: 0, sequence: 1, transportFlags: 0 };
  const db = newObject({ relationId: dbAccessArea(1), classId: Ids.DBClassRID }, [
    [Ids.ObjectVariableTypeName, { flags: 0, type: DataType.WString, value: 'Evil' }],
    [Ids.BlockBlockNumber, { flags: 0, type: DataType.UDInt, value: 1 }],
  ]);
  const type: PObject = {
    ...newObject({ relationId: 0x92000001, classId: 0 }),
    members: [
      { kind: 'list', tag: ElementId.VartypeList, raw: vartype },
      { kind: 'list', tag: ElementId.VarnameList, raw: varname },
    ],
  };
  const fake = {
    alive: true,
    request(ask: Ask<unknown, unknown>): Promise<unknown> {
      const answer = (data: Buffer) => Promise.resolve(ask.decode(data, { integrity: false }).body);
      if (ask.functionCode === FunctionCode.GetMultiVariables)
        return answer(
          encodeGetMultiVariablesResponse({
            header,
            body: { returnValue: 0n, values: new Map([[1, { flags: 0, type: DataType.RID, value: 0x92000001 }]]), errors: new Map() },
          }),
        );
      const { exploreId } = ask.body as ExploreRequest;
      const objects = exploreId === Ids.ObjectOmsTypeInfoContainer ? [type] : [db];
      return answer(encodeExploreResponse({ header, body: { returnValue: 0n, objects } }));
    },
  };
  return fake as unknown as S7PlusSession;
}

/** A vartype list of one element (LID 0xA, an INT at offset 0 of a standard block, or what `element` gives) and its name list. */
function lists(element: Buffer, name = 'X'): [Buffer, Buffer] {
  const block = Buffer.concat([Buffer.alloc(4), element]);
  const len = Buffer.alloc(2);
  len.writeUInt16BE(block.length);
  const n = Buffer.concat([Buffer.from([name.length]), Buffer.from(name), Buffer.from([0])]);
  const nlen = Buffer.alloc(2);
  nlen.writeUInt16BE(n.length);
  return [Buffer.concat([len, block, Buffer.alloc(2)]), Buffer.concat([nlen, n, Buffer.alloc(2)])];
}

function element(soft: number, oi: number, info: Buffer, classic = true): Buffer {
  const head = Buffer.alloc(12);
  head.writeUInt32LE(0xa, 0);
  head[8] = soft;
  head.writeUInt16BE(oi << 12, 9);
  head[11] = classic ? 0x08 : 0;
  return Buffer.concat([head, info]);
}

describe('S7CommPlus browse of a hostile PLC', () => {
  it('a well-formed type object browses (the fake PLC is right), one too short or an array of 2^32-1 elements is a PROTOCOL_ERROR', async () => {
    const table = await browseTable(hostileSession(...lists(element(SoftDataType.Int, 8, Buffer.from([0, 0, 0, 0])))));
    expect(table.entries.map((e) => [e.name, e.type, e.address, e.access?.lids])).to.deep.equal([
      ['"Evil".X', 'INT', 'DB1.DBW0:INT', [0xa]],
    ]);
    // The PLC's own offset wins over our layout rules (which would place the only member at 0).
    const moved = await browseTable(hostileSession(...lists(element(SoftDataType.Int, 8, Buffer.from([0, 0, 6, 0])))));
    expect(moved.lookup('"Evil".X')).to.include({ byte: 6, address: 'DB1.DBW6:INT' });
    const short = await browseTable(hostileSession(...lists(element(SoftDataType.Int, 9, Buffer.from([0, 0]))))).catch((e: Error) => e);
    expect(short).to.include({ code: 'PROTOCOL_ERROR' });
    const info = Buffer.alloc(20);
    info.writeUInt32LE(0xffffffff, 16);
    const huge = await browseTable(hostileSession(...lists(element(SoftDataType.Int, 10, info)))).catch((e: Error) => e);
    expect(huge).to.include({ code: 'PROTOCOL_ERROR' });
    expect((huge as Error).message).to.include('4294967295 elements');
  });
});

const ALL_TYPES = `DATA_BLOCK "All"
{ S7_Optimized_Access := 'TRUE' }
VERSION : 0.1
NON_RETAIN
   STRUCT
      b : Bool; by : Byte; c : Char; w : Word; i : Int; dw : DWord; di : DInt; r : Real; d : Date; tod : Time_Of_Day;
      t : Time; s5 : S5Time; dt : Date_And_Time; s : String[8]; lr : LReal; uli : ULInt; li : LInt; lw : LWord;
      usi : USInt; ui : UInt; udi : UDInt; si : SInt; wc : WChar; ws : WString[6]; lt : LTime; dtl : DTL;
      grid : Array[1..2, 0..2] of Int;
      flags : Array[0..9] of Bool;
      steps : Array[1..2] of Struct
         temp : Real;
         names : Array[0..1] of String[4];
      END_STRUCT;
   END_STRUCT;
BEGIN
END_DATA_BLOCK
`;

describe('S7CommPlus names of every elementary type (an optimized DB)', function () {
  this.timeout(30000);
  let server: S7Server;
  let service: S7PlusService;
  let client: S7PlusClient;
  before(async () => {
    const cert = await generateCertificate();
    service = new S7PlusService({
      sources: [{ name: 'All.db', content: ALL_TYPES }],
      db: { All: 3 },
      tls: { cert: cert.cert, key: cert.key },
    });
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await server.listen();
    client = createClient(`s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=10000`) as S7PlusClient;
    await client.connect();
  });
  after(async () => {
    await client?.close();
    await server?.close();
  });

  it('each written by name reads back by name with its JS value; a value of the wrong kind is refused, nothing written', async () => {
    const values: Record<string, unknown> = {
      b: true,
      by: 0xab,
      c: 'Z',
      w: 0x1234,
      i: -1234,
      dw: 0xdeadbeef,
      di: -123456,
      r: 1.5,
      d: new Date(Date.UTC(2024, 0, 2)),
      tod: 3600000,
      t: -5000,
      s5: 2000,
      dt: new Date(Date.UTC(2024, 5, 7, 8, 9, 10, 120)),
      s: 'hello',
      lr: 3.14159,
      uli: 2n ** 63n,
      li: -(2n ** 40n),
      lw: 0x0123456789abcdefn,
      usi: 200,
      ui: 60000,
      udi: 4000000000,
      si: -100,
      wc: 'é',
      ws: 'grüße',
      lt: 1234567890123n,
      dtl: new Date(Date.UTC(2024, 1, 29, 23, 59, 58, 500)),
    };
    const table = await client.browse();
    expect(Object.keys(values).map((k) => table.lookup(`"All".${k}`)?.type)).to.deep.equal([
      'BOOL',
      'BYTE',
      'CHAR',
      'WORD',
      'INT',
      'DWORD',
      'DINT',
      'REAL',
      'DATE',
      'TIME_OF_DAY',
      'TIME',
      'S5TIME',
      'DATE_AND_TIME',
      'STRING[8]',
      'LREAL',
      'ULINT',
      'LINT',
      'LWORD',
      'USINT',
      'UINT',
      'UDINT',
      'SINT',
      'WCHAR',
      'WSTRING[6]',
      'LTIME',
      'DTL',
    ]);
    const named = Object.fromEntries(Object.entries(values).map(([k, v]) => [`"All".${k}`, v]));
    await client.write(named);
    expect(await client.read(Object.keys(named))).to.deep.equal(named);
    const compiled = compileSymbols([{ name: 'All.db', content: ALL_TYPES }], { db: { All: 3 } });
    expect(table.entries.map((e) => [e.name, e.type, e.children])).to.deep.equal(compiled.entries.map((e) => [e.name, e.type, e.children]));
    expect(table.lookup('"All".grid[2,1]')!.access!.lids).to.deep.equal([0xa + 26, 4]);
    expect(table.lookup('"All".steps[2].names[1]')!.access!.lids).to.deep.equal([0xa + 28, 1, 1, 0xb, 1]);
    // Every name with the SymbolCrc the CPU checks, an element with its array's (issue #32); a multi-dimensional
    // array's none (no public rule gives its bound in the CRC).
    const db = service.model.dbs.find((d) => d.name === 'All')!;
    for (const e of table.entries.filter((x) => x.access!.lids.length > 0))
      expect(e.access!.symbolCrc, e.name).to.equal(expectedCrc(db, e.access!.lids));
    expect(table.lookup('"All".grid[2,1]')!.access!.symbolCrc).to.equal(undefined);
    expect(table.lookup('"All".steps[2].names[1]')!.access!.symbolCrc).to.equal(
      symbolCrc([
        { name: 'steps', soft: SoftDataType.Struct, low: 1 },
        { name: 'names', soft: SoftDataType.String, low: 0 },
      ]),
    );
    expect(table.lookup('"All".flags[9]')!.access!.symbolCrc).to.equal(table.lookup('"All".flags[0]')!.access!.symbolCrc);
    const arrays = {
      '"All".grid': [1, 2, 3, 4, 5, 6],
      '"All".flags': [true, false, true, false, false, false, false, false, false, true],
      '"All".steps': [
        { temp: 1.5, names: ['ab', 'cd'] },
        { temp: -2, names: ['', 'wxyz'] },
      ],
    };
    await client.write(arrays);
    expect(await client.read(Object.keys(arrays))).to.deep.equal(arrays);
    expect(await client.read(['"All".grid[2,1]', '"All".flags[9]', '"All".steps[2].names[1]'])).to.deep.equal({
      '"All".grid[2,1]': 5,
      '"All".flags[9]': true,
      '"All".steps[2].names[1]': 'wxyz',
    });
    const wrong = await client.writeDetailed({ '"All".i': 'abc', '"All".b': 1 });
    expect(Object.values(wrong).map((r) => (r.ok ? 'ok' : r.error.code))).to.deep.equal(['INVALID_VALUE', 'INVALID_VALUE']);
    expect(await client.read(['"All".i', '"All".b'])).to.deep.equal({ '"All".i': -1234, '"All".b': true });
  });

  it('the same block with standard access: the byte, bit and address as the PLC gives them of every entry equal the compiled ones', async () => {
    const source = [{ name: 'All.db', content: ALL_TYPES.replace("'TRUE'", "'FALSE'") }];
    const cert = await generateCertificate();
    const service = new S7PlusService({ sources: source, db: { All: 3 }, tls: { cert: cert.cert, key: cert.key } });
    const standard = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await standard.listen();
    const c = createClient(`s7plus://127.0.0.1:${standard.port}?fingerprint=${service.fingerprint!}&timeout=10000`) as S7PlusClient;
    try {
      await c.connect();
      const table = await c.browse();
      const compiled = compileSymbols(source, { db: { All: 3 } });
      const shape = (e: SymbolEntry) => [e.name, e.type, e.byte, e.bit, e.address];
      expect(table.entries.map(shape)).to.deep.equal(compiled.entries.map(shape));
      expect(table.lookup('"All".dtl')).to.include({ address: compiled.lookup('"All".dtl')!.address });
      expect(table.blocks[0]).to.include({ length: compiled.blocks[0]!.length });
    } finally {
      await c.close();
      await standard.close();
    }
  });
});
