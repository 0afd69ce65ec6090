/**
 * The s7commplus Python client (PyPI s7commplus 0.3.0, MIT, an independent
 * implementation validated by its authors on real S7-1200/1500 CPUs)
 * against our S7CommPlus simulator over TLS, pinned to the fingerprint the
 * simulator reports (issue #25): connect, list the DBs, browse (names, types
 * and the offsets of standard members equal our compiled table's), CPU
 * state, read and write by name, read by address, a subscription that
 * delivers a change made through `plcwire write`, and a counter jump that
 * resets the connection. Driven through the peer harness
 * (test/support/s7commplus-peer.ts); skipped with the reason when the peer
 * is not installed.
 */
import { expect } from 'chai';
import { spawn } from 'node:child_process';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { S7Client } from '../lib/s7/client';
import { S7Server, type S7RefusedEvent } from '../lib/s7/server';
import { S7PlusService } from '../lib/s7plus/server';
import { generateCertificate } from '../lib/s7plus/transport/cert';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { DB_NUMBERS, S7PLUS_FIXTURES, SOURCES } from './fixtures/s7plus';
import { openS7CommPlusClient, requireS7CommPlus, s7CommPlusClientOk, stopS7CommPlusPeers } from './support/s7commplus-peer';
import { waitFor } from './support/wait';

const BIN = path.join(__dirname, '..', '..', 'bin', 'plcwire.js');

function run(args: string[]): Promise<{ code: number; err: string }> {
  return new Promise((resolve, reject) => {
    const child = spawn(process.execPath, [BIN, ...args], { stdio: ['ignore', 'ignore', 'pipe'] });
    let err = '';
    child.stderr.on('data', (d: Buffer) => (err += d.toString()));
    child.on('error', reject);
    child.on('close', (code) => resolve({ code: code ?? -1, err }));
  });
}

/** `plcwire write` of Tank members by name, over s7:// to the simulator. */
function plcwireWrite(port: number, ...assignments: string[]) {
  const sources = ['Tank.db', 'Valve.udt'].flatMap((f) => ['--symbols', path.join(S7PLUS_FIXTURES, f)]);
  return run(['write', `s7://127.0.0.1:${port}?rack=0&slot=1`, ...sources, '--db', 'Tank=1', ...assignments]);
}

const real = (x: number) => {
  const b = Buffer.alloc(4);
  b.writeFloatBE(x);
  return b.toString('hex');
};

interface Browsed {
  name: string;
  access_sequence: string;
  data_type: string;
  nonopt_address: number;
  nonopt_bitoffset: number;
}

describe('S7CommPlus simulator and the s7commplus Python client over TLS (issue #25)', function () {
  this.timeout(60000);
  let python: string;
  let server: S7Server;
  let service: S7PlusService;
  const connect = () => ({ op: 'connect' as const, port: server.port, tls: true, fingerprint: service.fingerprint! });

  before(async function () {
    python = requireS7CommPlus(this);
    const cert = await generateCertificate();
    service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
    expect(service.fingerprint).to.equal(cert.fingerprint);
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await server.listen();
  });
  after(async () => {
    await stopS7CommPlusPeers();
    await server?.close();
  });

  it('connects over TLS pinned to the fingerprint, lists the DBs, browses what our table compiles, and reads RUN', async () => {
    const [connected, dbs, browsed, state] = (await s7CommPlusClientOk(python, [
      connect(),
      { op: 'list_datablocks' },
      { op: 'browse' },
      { op: 'get_cpu_state' },
    ])) as [{ tls: boolean; fingerprint: string; protocolVersion: number }, { name: string; number: number }[], Browsed[], string];
    expect(connected).to.deep.include({ tls: true, protocolVersion: 2 });
    expect(connected.fingerprint.toUpperCase()).to.equal(service.fingerprint);
    expect(dbs.map((d) => [d.name, d.number])).to.deep.equal([
      ['Tank', 1],
      ['Recipe', 2],
    ]);
    expect(state).to.equal('RUN');
    // Every elementary member of the standard DB, with the type and the byte/bit of our layout.
    const ours = service.model.table.entries
      .filter((e) => e.db === 1 && e.kind === 'elementary')
      .map((e) => [e.name.replace(/^"Tank"/, 'Tank'), e.dataType, e.byte, e.bit ?? 0]);
    const tank = browsed.filter((x) => x.name.startsWith('Tank.')).map((x) => [x.name, x.data_type, x.nonopt_address, x.nonopt_bitoffset]);
    expect(tank).to.deep.equal(ours);
    // The optimized DB is browsed by name too.
    expect(browsed.filter((x) => x.name.startsWith('Recipe.')).map((x) => [x.name, x.data_type])).to.deep.equal([
      ['Recipe.Target', 'REAL'],
      ['Recipe.Step', 'INT'],
      ['Recipe.Done', 'BOOL'],
      ['Recipe.Inlet.Open', 'BOOL'],
      ['Recipe.Inlet.Position', 'INT'],
    ]);
  });

  it('reads by name what plcwire write put there over s7://, writes by name what our s7:// client reads, reads by address', async () => {
    const w = await plcwireWrite(server.port, '"Tank".Level=99.5', '"Tank".Motor.Speed=-70000');
    expect(w.code, w.err).to.equal(0);
    server.memory.area('DB', 2)!.writeInt16BE(77, 10); // Recipe.Inlet.Position, through the simulator's memory
    const [, read, , , step, bytes] = (await s7CommPlusClientOk(python, [
      connect(),
      { op: 'read_tags', names: ['Tank.Level', 'Tank.Motor.Speed', 'Recipe.Target', 'Recipe.Inlet.Position', 'Tank.Running'] },
      { op: 'write_tag', name: 'Recipe.Step', value: 'fb2e' },
      { op: 'write_tag', name: 'Tank.Count', value: '10e1' },
      { op: 'read_tags', names: ['Recipe.Step'] },
      { op: 'db_read', db: 1, offset: 0, size: 8 },
    ])) as [unknown, { value: string; decoded: unknown }[], unknown, unknown, { value: string }[], string];
    expect(read.map((r) => r.value)).to.deep.equal([real(99.5), 'fffeee90', real(80), '004d', '01']);
    expect(read.map((r) => r.decoded)).to.deep.equal([99.5, -70000, 80, 77, true]);
    expect(step[0]!.value).to.equal('fb2e');
    expect(server.memory.area('DB', 2)!.readInt16BE(4)).to.equal(-1234);
    // Level, Count (4321), Running and Alarm (bits 0 and 1 of byte 6), byte 7.
    expect(bytes).to.equal(real(99.5) + '10e1' + '01' + '00');
    const c = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?rack=0&slot=1`) as S7Endpoint);
    try {
      await c.connect();
      expect(await c.read(['DB1.DBW4:INT'])).to.deep.equal({ 'DB1.DBW4:INT': 4321 });
    } finally {
      await c.close();
    }
  });

  it('its browse gives the tag table under IArea/QArea/MArea with their addresses and reads them; it notices our reload as a program change', async () => {
    const cert = await generateCertificate();
    const tags = { name: 'PLC tags.csv', content: fs.readFileSync(path.join(S7PLUS_FIXTURES, 'PLC tags.csv'), 'utf8') };
    const plus = new S7PlusService({ sources: [...SOURCES, tags], db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
    const sim = new S7Server({ port: 0, profile: 's7-1500', s7plus: plus });
    await sim.listen();
    const peer = openS7CommPlusClient(python);
    try {
      sim.memory.writeBit('I', 0, 0, 0, true);
      sim.memory.write('M', 0, 10, Buffer.from([0x04, 0xd2])); // 1234
      await peer.ok({ op: 'connect', port: sim.port, tls: true, fingerprint: plus.fingerprint! });
      const browsed = (await peer.ok({ op: 'browse' })) as Browsed[];
      const areaTags = browsed
        .filter((b) => /^(IArea|QArea|MArea)\./.test(b.name))
        .map((b) => [b.name, b.access_sequence, b.data_type, b.nonopt_address, b.nonopt_bitoffset]);
      expect(areaTags).to.deep.equal([
        ['IArea.Start_Button', '50.A', 'BOOL', 0, 0],
        ['QArea.Motor on', '51.A', 'BOOL', 0, 1],
        ['MArea.Speed setpoint', '52.A', 'INT', 10, 0],
        ['MArea.Temperature', '52.B', 'REAL', 20, 0],
      ]);
      const read = (await peer.ok({ op: 'read_tags', names: ['IArea.Start_Button', 'MArea.Speed setpoint'] })) as { decoded: unknown }[];
      expect(read.map((r) => r.decoded)).to.deep.equal([true, 1234]);
      expect(await peer.ok({ op: 'refresh_if_changed' })).to.equal(false);
      plus.reload(
        [
          ...SOURCES.map((f) =>
            f.name === 'Recipe.db' ? { ...f, content: f.content.replace('Step : Int := 3;', 'Step : DInt := 3;') } : f,
          ),
          tags,
        ],
        sim.memory,
      );
      expect(await peer.ok({ op: 'refresh_if_changed' })).to.equal(true);
      const after = (await peer.ok({ op: 'browse' })) as Browsed[];
      expect(after.find((b) => b.name === 'Recipe.Step')!.data_type).to.equal('DINT');
    } finally {
      await peer.close();
      await sim.close();
    }
  });

  it('a subscription delivers the initial values, then a change made through plcwire write', async () => {
    await plcwireWrite(server.port, '"Tank".Level=1.5');
    const peer = openS7CommPlusClient(python);
    try {
      await peer.ok(connect());
      const browsed = (await peer.ok({ op: 'browse' })) as Browsed[];
      const seq = (name: string) => browsed.find((b) => b.name === name)!.access_sequence;
      const id = (await peer.ok({ op: 'subscribe', items: [seq('Tank.Level'), seq('Recipe.Step')], cycleMs: 50 })) as number;
      const first = (await peer.ok({ op: 'notification', subscription: id })) as { values: Record<string, string> };
      expect(first.values).to.deep.equal({ 1: real(1.5), 2: 'fb2e' });
      const w = await plcwireWrite(server.port, '"Tank".Level=42.5');
      expect(w.code, w.err).to.equal(0);
      const second = (await peer.ok({ op: 'notification', subscription: id })) as { values: Record<string, string> };
      expect(second.values).to.deep.equal({ 1: real(42.5), 2: 'fb2e' });
    } finally {
      await peer.close();
    }
  });

  it('with a password: read access until the session legitimates (the new AES legitimation over the TLS exporter); a wrong password refused', async () => {
    const cert = await generateCertificate();
    const locked = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key }, password: 'hunter2' });
    const guarded = new S7Server({ port: 0, profile: 's7-1500', s7plus: locked });
    await guarded.listen();
    try {
      // The harness has no legitimation operation: the package's own authenticate() is called.
      const script = [
        'import sys, struct',
        'from s7commplus import Client',
        'c = Client()',
        'c.connect("127.0.0.1", int(sys.argv[1]), use_tls=True, tls_cert_fingerprint=sys.argv[2])',
        'out = [c.protection_level]',
        'def write():',
        '    try:',
        '        c.write_tag("Tank.Count", struct.pack(">h", 555))',
        '        return "written"',
        '    except Exception as e:',
        '        return "refused"',
        'out.append(write())',
        'try:',
        '    c._connection.authenticate(sys.argv[3])',
        '    out.append(c._connection.protection_level)',
        'except Exception as e:',
        '    out.append(type(e).__name__)',
        'out.append(write())',
        'print(" ".join(map(str, out)))',
      ].join('\n');
      const attempt = (password: string) =>
        new Promise<string>((resolve, reject) => {
          const child = spawn(python, ['-c', script, String(guarded.port), locked.fingerprint!, password], {
            stdio: ['ignore', 'pipe', 'pipe'],
          });
          let text = '';
          child.stdout.on('data', (d: Buffer) => (text += d.toString()));
          child.on('error', reject);
          child.on('close', () => resolve(text.trim()));
        });
      expect(await attempt('wrong')).to.equal('2 refused S7ConnectionError refused');
      expect(guarded.memory.area('DB', 1)!.readInt16BE(4)).to.equal(7);
      expect(await attempt('hunter2')).to.equal('2 refused 1 written');
      expect(guarded.memory.area('DB', 1)!.readInt16BE(4)).to.equal(555);
    } finally {
      await guarded.close();
    }
  });

  it('resets a connection whose integrity id jumps, as a PLC does; the next connection is served', async () => {
    // The harness has no operation that makes the client's counter jump: a few lines of the package's own client do.
    const script = [
      'import sys',
      'from s7commplus import Client',
      'c = Client()',
      'c.connect("127.0.0.1", int(sys.argv[1]), use_tls=True, tls_cert_fingerprint=sys.argv[2])',
      'c.read_tag("Tank.Level")',
      'c._connection._integrity_id_read += 3',
      'try:',
      '    c.read_tag("Tank.Level")',
      '    print("answered")',
      'except Exception as e:',
      '    print(type(e).__name__)',
    ].join('\n');
    const refused = waitFor<S7RefusedEvent>(server, 'refused', 30000);
    const out = await new Promise<string>((resolve, reject) => {
      const child = spawn(python, ['-c', script, String(server.port), service.fingerprint!], { stdio: ['ignore', 'pipe', 'pipe'] });
      let text = '';
      child.stdout.on('data', (d: Buffer) => (text += d.toString()));
      child.on('error', reject);
      child.on('close', () => resolve(text.trim()));
    });
    expect(out).to.not.equal('answered');
    expect(out).to.not.equal('');
    expect((await refused).message).to.match(/integrity id/);
    const [, state] = await s7CommPlusClientOk(python, [connect(), { op: 'get_cpu_state' }]);
    expect(state).to.equal('RUN');
  });
});
