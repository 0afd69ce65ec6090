/**
 * The s7commplus Python client (PyPI s7commplus 0.3.0, MIT, an independent
 * implementation validated by its authors on real S7-1200/1500 CPUs)
 * against our S7CommPlus simulator over TLS, pinned to the fingerprint the
 * simulator prints (issue #25): connect, list the DBs, browse (names, types
 * and the offsets of standard members equal our compiled table's), CPU
 * state, read and write by name, read by address, a value written through
 * `plcwire write` read back by name, and a counter jump that resets the
 * connection. Skipped when the peer is not installed (npm test's pretest
 * installs it in test/interop/.venv-s7commplus; S7COMMPLUS_PYTHON names
 * another python).
 */
import { expect } from 'chai';
import { spawn } from 'node:child_process';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { S7Client } from '../lib/s7/client';
import { S7Server } from '../lib/s7/server';
import { S7PlusService } from '../lib/s7plus/server';
import { generateCertificate } from '../lib/s7plus/transport/cert';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { DB_NUMBERS, S7PLUS_FIXTURES, SOURCES } from './fixtures/s7plus';

const ROOT = path.join(__dirname, '..', '..');
const BIN = path.join(ROOT, 'bin', 'plcwire.js');
const PYTHON = process.env.S7COMMPLUS_PYTHON ?? path.join(ROOT, 'test', 'interop', '.venv-s7commplus', 'bin', 'python');

/** The peer's side: one scenario per run, its results as one JSON line. */
const SCRIPT = String.raw`
import json, struct, sys
from s7commplus import Client
port, fp, scenario = int(sys.argv[1]), sys.argv[2], sys.argv[3]
c = Client()
c.connect("127.0.0.1", port, use_tls=True, tls_cert_fingerprint=fp)
out = {}
if scenario == "browse":
    out["dbs"] = [[d["name"], d["number"]] for d in c.list_datablocks()]
    out["vars"] = [[v["name"], v["data_type"], v["nonopt_address"], v["nonopt_bitoffset"]] for v in c.browse()]
    out["state"] = c.get_cpu_state()
elif scenario == "values":
    got = c.read_tags(["Tank.Level", "Tank.Motor.Speed", "Recipe.Target", "Recipe.Inlet.Position", "Tank.Running"])
    out["read"] = [r.value.hex() if r.value is not None else None for r in got]
    c.write_tag("Recipe.Step", struct.pack(">h", -1234))
    c.write_tag("Tank.Count", struct.pack(">h", 4321))
    out["step"] = c.read_tag("Recipe.Step").hex()
    out["db_read"] = c.db_read(1, 0, 8).hex()
elif scenario == "jump":
    c.read_tag("Tank.Level")
    c._connection._integrity_id_read += 3
    try:
        c.read_tag("Tank.Level")
        out["jump"] = "answered"
    except Exception as e:
        out["jump"] = type(e).__name__
print(json.dumps(out))
try:
    c.disconnect()
except Exception:
    pass
`;

function run(cmd: string, args: string[]): Promise<{ code: number; out: string; err: string }> {
  return new Promise((resolve, reject) => {
    const child = spawn(cmd, args, { stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    let err = '';
    child.stdout.on('data', (d: Buffer) => (out += d.toString()));
    child.stderr.on('data', (d: Buffer) => (err += d.toString()));
    child.on('error', reject);
    child.on('close', (code) => resolve({ code: code ?? -1, out, err }));
  });
}

describe('S7CommPlus simulator and the s7commplus Python client over TLS (issue #25)', function () {
  this.timeout(60000);
  let server: S7Server;
  let service: S7PlusService;
  let script: string;

  before(async function () {
    if (!fs.existsSync(PYTHON)) this.skip();
    script = path.join(fs.mkdtempSync(path.join(os.tmpdir(), 's7plus-sim-')), 'peer.py');
    fs.writeFileSync(script, SCRIPT);
    const cert = await generateCertificate();
    service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
    expect(service.fingerprint).to.equal(cert.fingerprint);
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await server.listen();
  });
  after(async () => {
    await server?.close();
    if (script) fs.rmSync(path.dirname(script), { recursive: true, force: true });
  });

  async function peer(scenario: string): Promise<Record<string, unknown>> {
    const r = await run(PYTHON, [script, String(server.port), service.fingerprint!, scenario]);
    expect(r.code, r.err).to.equal(0);
    return JSON.parse(r.out.trim().split('\n').pop()!) as Record<string, unknown>;
  }

  it('connects pinned to the printed fingerprint, lists the DBs, browses what our table compiles, and reads RUN', async () => {
    const out = await peer('browse');
    expect(out.dbs).to.deep.equal([
      ['Tank', 1],
      ['Recipe', 2],
    ]);
    expect(out.state).to.equal('RUN');
    const vars = out.vars as [string, string, number, number][];
    // Every elementary member of the standard DB, with the type and the byte/bit of our layout.
    const ours = service.model.table.entries
      .filter((e) => e.db === 1 && e.kind === 'elementary')
      .map((e) => [e.name.replace(/^"Tank"/, 'Tank'), e.dataType, e.byte, e.bit ?? 0]);
    expect(vars.filter((x) => x[0].startsWith('Tank.'))).to.deep.equal(ours);
    // The optimized DB is browsed by name too.
    expect(vars.filter((x) => x[0].startsWith('Recipe.')).map((x) => [x[0], x[1]])).to.deep.equal([
      ['Recipe.Target', 'REAL'],
      ['Recipe.Step', 'INT'],
      ['Recipe.Done', 'BOOL'],
      ['Recipe.Inlet.Open', 'BOOL'],
      ['Recipe.Inlet.Position', 'INT'],
    ]);
  });

  it('reads by name what plcwire write put there over s7://, writes by name what our s7:// client reads, reads by address', async () => {
    const w = await run(process.execPath, [
      BIN,
      'write',
      `s7://127.0.0.1:${server.port}?rack=0&slot=1`,
      '--symbols',
      path.join(S7PLUS_FIXTURES, 'Tank.db'),
      '--symbols',
      path.join(S7PLUS_FIXTURES, 'Valve.udt'),
      '--db',
      'Tank=1',
      '"Tank".Level=99.5',
      '"Tank".Motor.Speed=-70000',
    ]);
    expect(w.code, w.err).to.equal(0);
    server.memory.area('DB', 2)!.writeInt16BE(77, 10); // Recipe.Inlet.Position, through the simulator's memory
    const out = await peer('values');
    const real = (x: number) => {
      const b = Buffer.alloc(4);
      b.writeFloatBE(x);
      return b.toString('hex');
    };
    expect(out.read).to.deep.equal([real(99.5), 'fffeee90', real(80), '004d', '01']);
    expect(out.step).to.equal('fb2e');
    expect(server.memory.area('DB', 2)!.readInt16BE(4)).to.equal(-1234);
    const c = new S7Client(parseUrl(`s7://127.0.0.1:${server.port}?rack=0&slot=1`) as S7Endpoint);
    try {
      await c.connect();
      expect(await c.read(['DB1.DBW4:INT'])).to.deep.equal({ 'DB1.DBW4:INT': 4321 });
    } finally {
      await c.close();
    }
    // Level, Count (4321), Running and Alarm (bits 0 and 1 of byte 6), byte 7.
    expect(out.db_read).to.equal(real(99.5) + '10e1' + '01' + '00');
  });

  it('resets a connection whose integrity id jumps, as a PLC does; the next connection is served', async () => {
    const refused = new Promise<{ message: string }>((resolve) => server.once('refused', resolve));
    const out = await peer('jump');
    expect(out.jump).to.not.equal('answered');
    expect((await refused).message).to.match(/integrity id/);
    expect((await peer('browse')).state).to.equal('RUN');
  });
});
