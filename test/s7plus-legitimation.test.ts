/**
 * Legitimation (the PLC's password) in the S7CommPlus client (issue #25).
 *
 * The bytes and the crypto against the s7commplus package (PyPI 0.3.0, MIT):
 * the expected values below were printed by its own functions
 * (legitimation.py _build_legitimation_payload, build_new_response,
 * build_legacy_response, decide_legitimation_mode; connection.py
 * _build_get_var_substreamed_payload, _build_set_variable_payload) for the
 * password "hunter2", the challenge 01..14 and the exporter secret 20..3f.
 *
 * Then our client against our simulator protected with a password, over TLS
 * (the new form, keyed by the TLS exporter; the legacy form where the
 * simulated firmware takes it): reads without the password,
 * writes refused per tag with the way to give it, writes with it, a wrong
 * password refused (ACCESS_DENIED, no hammering, nothing left open), a
 * reconnect that gives the password again, and the password in no error.
 * The s7commplus server emulator has no password protection (it answers every
 * GetVarSubStreamed with its challenge): with a password our client is told
 * in words that the PLC reports no protection level, and leaves nothing open
 * (test/s7plus-server-python.test.ts runs its client against our protection).
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import * as util from 'node:util';
import { createClient } from '../lib/connect';
import { PlcError } from '../lib/errors';
import { S7Server } from '../lib/s7/server';
import type { S7PlusClient } from '../lib/s7plus/client';
import { legacyAnswer, newAnswer } from '../lib/s7plus/client/legitimation';
import {
  decodeCredentials,
  decodeSetVariableRequest,
  decodeSetVariableResponse,
  encodeCredentials,
  encodeSetVariableRequest,
  encodeSetVariableResponse,
  legacyAnswerValue,
  legitimateRequest,
  legitimationForm,
  credentialsBlobValue,
  paomString,
  protectionLevelOf,
  challengeOf,
  sessionAttributeRequest,
} from '../lib/s7plus/codec/legitimation';
import { encodeSubStreamedRequest } from '../lib/s7plus/codec/substreamed';
import { DataType, FunctionCode, Ids, LegitimationType, TransportFlags } from '../lib/s7plus/constants';
import { S7PlusService } from '../lib/s7plus/server';
import { generateCertificate } from '../lib/s7plus/transport/cert';
import { createHash } from 'node:crypto';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { requireS7CommPlus, startS7CommPlusServer, stopS7CommPlusPeers } from './support/s7commplus-peer';
import { until, waitFor } from './support/wait';

const SECRET = 'Leg1t-Pa55!not-for-logs';
const CHALLENGE = Buffer.from('0102030405060708090a0b0c0d0e0f1011121314', 'hex');
const EXPORTER = Buffer.from('202122232425262728292a2b2c2d2e2f303132333435363738393a3b3c3d3e3f', 'hex');

/** What the s7commplus package builds (see the file's comment), as hex. */
const THEIRS = {
  credentials: '001700009dd082bb5100040182bb520014000082bb5300140014f3bbbd66a63d4bf1747940578ec3d0103530e21d00',
  newAnswer: 'b75972a2a69b522eb03b4f643b90485750aa2fb02e020b38cb80308b0263d33c7a6951e098d96e786194ffede9cd7e97',
  legacyAnswer: 'f2b9be62a33b4cf97d734b5b83cddf002422f109',
  getProtectionLevel: '000003a02004018e32000004e88969001200000000896a001300896b00040000000100000000',
  setLegitimate:
    '000003a0018e3600140030000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f202122232425262728292a2b2c2d2e2f' +
    '000004e88969001200000000896a001300896b000400000000000000',
  setLegacy: '000003a00182301002140102030405060708090a0b0c0d0e0f1011121314000004e88969001200000000896a001300896b000400000000000000',
};

/** decide_legitimation_mode of s7commplus for device strings of each series and firmware edge. */
const FORMS: [string, 'new' | 'legacy' | undefined][] = [
  ['1;6ES7 512-1CK01-0AB0;V2.8', undefined],
  ['1;6ES7 512-1CK01-0AB0;V2.9', 'legacy'],
  ['1;6ES7 512-1CK01-0AB0;V3.0', 'legacy'],
  ['1;6ES7 513-1AL02-0AB0;V3.1', 'new'],
  ['1;6ES7 516-3AN02-0AB0;V30.1', 'new'],
  ['1;6ES7 SIM-01500-APLC;S4.1', 'new'],
  ['1;6ES7 215-1AG40-0XB0;V4.2', undefined],
  ['1;6ES7 215-1AG40-0XB0;V4.5', 'legacy'],
  ['1;6ES7 215-1AG40-0XB0;V4.7', 'new'],
  ['1;6ES7 212-1AE50-0XB0;V1.0', 'new'],
  ['1;6ES7 672-7FC01-0YA0;V21.8', undefined],
  ['1;6ES7 672-7FC01-0YA0;V21.9', 'legacy'],
  ['1;6ES7 315-2EH14-0AB0;V3.3', undefined],
  ['garbage', undefined],
];

const header = (functionCode: number) => ({ functionCode, sequence: 7, sessionId: 0x3a0, transportFlags: TransportFlags.Normal });

describe('S7CommPlus legitimation: bytes and crypto as the s7commplus package builds them', () => {
  it('the new form: the credentials (the password as SHA-1, no user) and their AES-256-CBC under the exporter key', () => {
    const credentials = encodeCredentials({
      type: LegitimationType.Legacy,
      username: Buffer.alloc(0),
      password: createHash('sha1').update('hunter2').digest(),
    });
    expect(credentials.toString('hex')).to.equal(THEIRS.credentials);
    expect(decodeCredentials(credentials)).to.deep.equal({
      type: 1,
      username: Buffer.alloc(0),
      password: createHash('sha1').update('hunter2').digest(),
    });
    expect(newAnswer('hunter2', CHALLENGE, EXPORTER).toString('hex')).to.equal(THEIRS.newAnswer);
  });

  it('the legacy form: SHA-1 of the password XOR the challenge', () => {
    expect(legacyAnswer('hunter2', CHALLENGE).toString('hex')).to.equal(THEIRS.legacyAnswer);
  });

  it('the protection level read and both SetVariable answers byte for byte (after the 14-byte request header)', () => {
    const get = encodeSubStreamedRequest({ header: header(FunctionCode.GetVarSubStreamed), body: sessionAttributeRequest(0x3a0, 1842) });
    expect(get.subarray(14).toString('hex')).to.equal(THEIRS.getProtectionLevel);
    const blob = Buffer.from([...Array(48).keys()]);
    const set = legitimateRequest(7, 0x3a0, Ids.Legitimate, credentialsBlobValue(blob));
    const legacy = legitimateRequest(7, 0x3a0, Ids.ServerSessionResponse, legacyAnswerValue(CHALLENGE));
    expect(encodeSetVariableRequest(set).subarray(14).toString('hex')).to.equal(THEIRS.setLegitimate);
    expect(encodeSetVariableRequest(legacy).subarray(14).toString('hex')).to.equal(THEIRS.setLegacy);
    // With an integrity id (over TLS): it goes before the fill, and decodes back.
    const withId = encodeSetVariableRequest({ ...set, integrityId: 3 });
    expect(decodeSetVariableRequest(withId, { integrity: true })).to.deep.equal({ ...set, integrityId: 3 });
    const answer = encodeSetVariableResponse({
      header: { functionCode: FunctionCode.SetVariable, sequence: 7, transportFlags: 0 },
      body: { returnValue: 0x8000n },
      integrityId: 4,
    });
    expect(decodeSetVariableResponse(answer, { integrity: true }).body.returnValue).to.equal(0x8000n);
  });

  it('the firmware decides the form, as decide_legitimation_mode does', () => {
    for (const [paom, form] of FORMS) expect(legitimationForm(paom), paom).to.equal(form);
  });

  it('values of the wrong kind are a ProtocolError, never a crash: level, challenge, credentials, device string', () => {
    expect(protectionLevelOf({ flags: 0, type: DataType.UDInt, value: 2 })).to.equal(2);
    expect(() => protectionLevelOf({ flags: 0x10, type: DataType.USInt, value: [] })).to.throw(PlcError, /not a UDInt/);
    expect(() => protectionLevelOf(undefined)).to.throw(PlcError, /no value/);
    expect(challengeOf({ flags: 0x10, type: DataType.USInt, value: [1, 2] })).to.deep.equal(Buffer.from([1, 2]));
    expect(() => challengeOf({ flags: 0, type: DataType.UDInt, value: 1 })).to.throw(PlcError, /challenge/);
    expect(() => decodeCredentials(Buffer.from('001700009dd000', 'hex'))).to.throw(PlcError, /type/);
    expect(paomString({ flags: 0, type: DataType.UDInt, value: 3 })).to.equal(undefined);
    expect(
      paomString({
        flags: 0,
        type: DataType.Struct,
        value: { id: 314, members: [{ key: 319, value: { flags: 0, type: DataType.WString, value: '1;6ES7 513-1AL02-0AB0;V3.1' } }] },
      }),
    ).to.equal('1;6ES7 513-1AL02-0AB0;V3.1');
  });
});

describe('S7CommPlus legitimation: our client against our simulator protected with a password (TLS)', function () {
  this.timeout(60000);
  let server: S7Server;
  let service: S7PlusService;
  let url: string;
  const clients: S7PlusClient[] = [];
  /** Everything an error could show: message, inspect() with its causes, JSON. */
  const shown: string[] = [];
  const show = (err: unknown) => {
    shown.push(util.inspect(err, { depth: 8, showHidden: true }), JSON.stringify(err), String((err as Error).message));
  };
  const client = (options: Parameters<typeof createClient>[1] = {}) => {
    const c = createClient(url, options) as S7PlusClient;
    clients.push(c);
    return c;
  };
  const count = () => server.memory.area('DB', 1)!.readInt16BE(4);

  before(async () => {
    const cert = await generateCertificate();
    service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key }, password: SECRET });
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await server.listen();
    url = `s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=10000`;
  });
  afterEach(async () => {
    await Promise.all(clients.splice(0).map((c) => c.close()));
  });
  after(async () => {
    await server?.close();
    for (const text of shown) expect(text).not.to.include(SECRET);
  });

  it('the simulator keeps its password out of sight too: protected, but no inspect() or JSON of the service shows it', () => {
    expect(service.protected).to.equal(true);
    expect(util.inspect(service, { depth: 6, showHidden: true }) + JSON.stringify(service)).not.to.include(SECRET);
  });

  it('without the password: reads work; each write is refused with ACCESS_DENIED saying read access only and how to give it; nothing changes', async () => {
    const c = client();
    await c.connect();
    // Without a password, the level the PLC grants (read access).
    expect(c.protection).to.deep.equal({ level: 2, legitimated: false });
    expect(await c.read(['DB1.DBW4:INT', '"Recipe".Step'])).to.deep.equal({ 'DB1.DBW4:INT': 7, '"Recipe".Step': 3 });
    const results = await c.writeDetailed({ 'DB1.DBW4:INT': 99, '"Recipe".Step': 5 });
    for (const [tag, r] of Object.entries(results)) {
      expect(r.ok, tag).to.equal(false);
      const err = (r as { error: PlcError }).error;
      show(err);
      expect(err.code, tag).to.equal('ACCESS_DENIED');
      expect(err.tag).to.equal(tag);
      // The PLC's own code, by address and by name alike (one mapper of item errors keeps it).
      expect(err.plcCode, tag).to.equal(0x8104);
      expect(err.message).to.include(
        `${tag}: the PLC refused the write: s7plus://127.0.0.1:${server.port} gives this connection read access only`,
      );
      expect(err.message).to.include('protection level 2 (read access)');
      for (const way of ['connect(url, { password })', 'PLCWIRE_PASSWORD', '--password-file', "the connection node's password"])
        expect(err.message).to.include(way);
    }
    expect(count()).to.equal(7);
    expect(await c.read(['"Recipe".Step'])).to.deep.equal({ '"Recipe".Step': 3 });
  });

  it('with the right password: the session legitimates (the new form) and writes by address and by name go through', async () => {
    const c = client({ password: SECRET });
    await c.connect();
    expect(c.protection).to.deep.equal({ level: 1, legitimated: true, form: 'new' });
    await c.write({ 'DB1.DBW4:INT': 1234, '"Recipe".Step': 8 });
    expect(count()).to.equal(1234);
    expect(await c.read(['DB1.DBW4:INT', '"Recipe".Step'])).to.deep.equal({ 'DB1.DBW4:INT': 1234, '"Recipe".Step': 8 });
    for (const text of [util.inspect(c, { depth: 8, showHidden: true }), JSON.stringify(c)]) expect(text).not.to.include(SECRET);
  });

  it('a wrong password: connect() fails with ACCESS_DENIED naming the PLC, never the password, and leaves no connection', async () => {
    const wrong = `${SECRET}-wrong`;
    const c = client({ password: wrong });
    const err = await c.connect().then(
      () => undefined,
      (e: unknown) => e as PlcError,
    );
    expect(err).to.be.instanceOf(PlcError);
    show(err);
    expect(err!.code).to.equal('ACCESS_DENIED');
    expect(err!.message).to.include(`s7plus://127.0.0.1:${server.port} refused the password (wrong password`);
    expect(util.inspect(err, { depth: 8, showHidden: true })).not.to.include(wrong);
    expect(c.state).to.equal('closed');
    await until(() => server.connectionCount === 0, 5000, `no connection left (have ${server.connectionCount})`);
    expect(count()).to.equal(1234);
  });

  it('a wrong password is no transient fault: the client waits its longest backoff delay before asking again', async () => {
    const c = client({ password: 'nope', backoff: { initialDelay: 10, maxDelay: 20_000 } });
    const reconnecting = waitFor<{ delay: number; error: PlcError }>(c, 'reconnecting', 15000);
    c.on('error', () => {});
    c.start();
    const r = await reconnecting;
    show(r.error);
    expect(r.error.code).to.equal('ACCESS_DENIED');
    // 20 s ± the jitter (20 %), where a transient fault would wait 10 ms.
    expect(r.delay).to.be.at.least(16_000);
    await c.close();
    await until(() => server.connectionCount === 0, 5000, 'no connection left');
  });

  it('a reconnect (the PLC drops the connection) gives the password again: writes still work', async () => {
    const c = client({ password: SECRET, backoff: { initialDelay: 10, maxDelay: 200 } });
    await c.connect();
    await c.write({ 'DB1.DBW4:INT': 21 });
    const again = waitFor(c, 'connected', 15000);
    server.dropConnections();
    await again;
    expect(c.protection).to.deep.equal({ level: 1, legitimated: true, form: 'new' });
    await c.write({ 'DB1.DBW4:INT': 22 });
    expect(count()).to.equal(22);
  });

  it('a password for a PLC that wants none connects with full access (legitimated: false), and writes', async () => {
    const cert = await generateCertificate();
    const open = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
    const plain = new S7Server({ port: 0, profile: 's7-1500', s7plus: open });
    await plain.listen();
    try {
      const c = createClient(`s7plus://127.0.0.1:${plain.port}?fingerprint=${open.fingerprint!}&timeout=10000`, {
        password: SECRET,
      }) as S7PlusClient;
      try {
        await c.connect();
        expect(c.protection).to.deep.equal({ level: 1, legitimated: false });
        await c.write({ 'DB1.DBW4:INT': 5 });
        expect(plain.memory.area('DB', 1)!.readInt16BE(4)).to.equal(5);
      } finally {
        await c.close();
      }
    } finally {
      await plain.close();
    }
  });

  it('the legacy form on a CPU whose firmware takes it (S7-1500 V2.9): the right password legitimates, a wrong one is refused; V2.8 takes none', async () => {
    const serve = async (device: string) => {
      const cert = await generateCertificate();
      const plus = new S7PlusService({
        sources: SOURCES,
        db: DB_NUMBERS,
        tls: { cert: cert.cert, key: cert.key },
        password: SECRET,
        device,
      });
      const sim = new S7Server({ port: 0, profile: 's7-1500', s7plus: plus });
      await sim.listen();
      return { sim, url: `s7plus://127.0.0.1:${sim.port}?fingerprint=${plus.fingerprint!}&timeout=10000` };
    };
    const failure = async (c: S7PlusClient) => {
      const err = await c.connect().then(
        () => undefined,
        (e: unknown) => e as PlcError,
      );
      await c.close();
      show(err);
      return err;
    };
    const legacy = await serve('1;6ES7 512-1CK01-0AB0;V2.9');
    try {
      const c = createClient(legacy.url, { password: SECRET }) as S7PlusClient;
      try {
        await c.connect();
        expect(c.protection).to.deep.equal({ level: 1, legitimated: true, form: 'legacy' });
        await c.write({ 'DB1.DBW4:INT': 29 });
        expect(legacy.sim.memory.area('DB', 1)!.readInt16BE(4)).to.equal(29);
      } finally {
        await c.close();
      }
      const wrong = await failure(createClient(legacy.url, { password: 'nope' }) as S7PlusClient);
      expect(wrong?.code).to.equal('ACCESS_DENIED');
      await until(() => legacy.sim.connectionCount === 0, 5000, 'no connection left');
    } finally {
      await legacy.sim.close();
    }
    const old = await serve('1;6ES7 512-1CK01-0AB0;V2.8');
    try {
      const none = await failure(createClient(old.url, { password: SECRET }) as S7PlusClient);
      expect(none?.code).to.equal('NOT_SUPPORTED');
      expect(none?.message).to.include(`the PLC's firmware ("1;6ES7 512-1CK01-0AB0;V2.8") takes no form of legitimation plcwire knows`);
    } finally {
      await old.sim.close();
    }
  });

  it('tls=false with a password: NOT_SUPPORTED, saying legitimation needs TLS (never the password in plain text)', async () => {
    const open = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: false, password: SECRET });
    const plain = new S7Server({ port: 0, profile: 's7-1500', s7plus: open });
    await plain.listen();
    try {
      const c = createClient(`s7plus://127.0.0.1:${plain.port}?tls=false&timeout=10000`, { password: SECRET });
      const err = await c.connect().then(
        () => undefined,
        (e: unknown) => e as PlcError,
      );
      await c.close();
      show(err);
      expect(err?.code).to.equal('NOT_SUPPORTED');
      expect(err?.message).to.include('legitimation needs TLS');
      await until(() => plain.connectionCount === 0, 5000, 'no connection left');
    } finally {
      await plain.close();
    }
  });
});

describe('S7CommPlus legitimation against the s7commplus emulator (no protection level there)', function () {
  this.timeout(60000);
  let python: string;
  before(function () {
    python = requireS7CommPlus(this);
  });
  after(() => stopS7CommPlusPeers());

  it('a password is NOT_SUPPORTED in words (the PLC reports no protection level), the session ended, nothing left open', async () => {
    const cert = await generateCertificate();
    const dir = fs.mkdtempSync(path.join(os.tmpdir(), 's7plus-legit-'));
    const files = { cert: path.join(dir, 'cert.pem'), key: path.join(dir, 'key.pem') };
    fs.writeFileSync(files.cert, cert.cert);
    fs.writeFileSync(files.key, cert.key);
    const peer = await startS7CommPlusServer(python, { dbs: [{ number: 1, size: 8, variables: {} }], tls: files, version: 1 });
    try {
      const c = createClient(`s7plus://127.0.0.1:${peer.port}?fingerprint=${cert.fingerprint}&timeout=5000`, { password: SECRET });
      const err = await c.connect().then(
        () => undefined,
        (e: unknown) => e as PlcError,
      );
      await c.close();
      expect(err?.code).to.equal('NOT_SUPPORTED');
      expect(err?.message).to.include('the password cannot be given: the PLC reports no protection level');
      expect(util.inspect(err, { depth: 8, showHidden: true })).not.to.include(SECRET);
      await peer.waitForEvent((e) => e.event === 'deleteObject');
      await peer.waitForNoClients(10_000);
      // Without the password the same emulator serves.
      const plain = createClient(`s7plus://127.0.0.1:${peer.port}?fingerprint=${cert.fingerprint}&timeout=5000`);
      await plain.connect();
      await plain.close();
    } finally {
      await peer.stop();
      fs.rmSync(dir, { recursive: true, force: true });
    }
  });
});
