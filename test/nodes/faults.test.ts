/**
 * Issue #8 through Node-RED: the read, write and heartbeat nodes report a
 * fault on Status and Catch and recover without a redeploy; nothing sensitive
 * is logged at info level; the nodes' admin endpoints need a permission.
 */
import { expect } from 'chai';
import { spawn, type ChildProcess } from 'node:child_process';
import * as fs from 'node:fs';
import * as http from 'node:http';
import * as os from 'node:os';
import * as path from 'node:path';
import { S7Server } from '../../lib/s7/server';
import { PlcMemory } from '../../lib/sim/memory';
import { fetchWriteSim, freeportSim } from './sims';
import { ALL_NODES, helper, Recorder, ROOT, until, type Sim } from './support';

const TAB = { id: 'tab', type: 'tab', label: 'faults' };
const at = (n: object[]) => n.map((x: any) => (x.z ? { x: 100, y: 100, ...x } : x));
const rec = (id: string) => new Recorder(helper.getNode(id));

/** Waits for a message matching `match` among those `r` received from index `from` on (in any order). */
async function seen(r: Recorder, from: number, match: (m: any) => boolean, ms: number, what: string): Promise<any> {
  await until(() => r.messages.slice(from).some(match), ms, what).catch(() => {
    throw new Error(
      `no ${what} within ${ms} ms; got ${r.messages
        .slice(from)
        .map((m) => JSON.stringify(m.status ?? m.error ?? m.payload).slice(0, 120))
        .join(' | ')}`,
    );
  });
  return r.messages.slice(from).find(match);
}

/** Read, write and heartbeat nodes on one connection, with a Catch and a Status node watching all of them. */
function flow(url: string, addr: (i: number) => string) {
  return at([
    TAB,
    { id: 'conn', type: 'plcwire-connection', name: 'plc', url },
    {
      id: 'read',
      type: 'plcwire-read',
      z: 'tab',
      name: 'poll',
      connection: 'conn',
      interval: 100,
      output: 'object',
      deadband: 0,
      tags: [{ name: 'a', address: addr(0) }],
      wires: [['out']],
    },
    {
      id: 'write',
      type: 'plcwire-write',
      z: 'tab',
      name: 'w',
      connection: 'conn',
      tags: [{ name: 'sp', address: addr(1) }],
      wires: [['written']],
    },
    {
      id: 'hb',
      type: 'plcwire-heartbeat',
      z: 'tab',
      name: 'hb',
      connection: 'conn',
      writeAddress: addr(5),
      writeMode: 'counter',
      interval: 100,
      watchAddress: addr(5),
      timeout: 700,
      wires: [['beats']],
    },
    { id: 'catcher', type: 'catch', z: 'tab', scope: null, uncaught: false, wires: [['caught']] },
    { id: 'watcher', type: 'status', z: 'tab', scope: null, wires: [['statuses']] },
    ...['out', 'written', 'beats', 'caught', 'statuses'].map((id) => ({ id, type: 'helper', z: 'tab' })),
  ]);
}

interface Fault {
  name: string;
  /** Codes the nodes may report for it. */
  codes: string[];
  /** Does the link state show it (red status), or only the tags (access denied)? */
  linkDown: boolean;
  on(ctx: Ctx): Promise<void>;
  off(ctx: Ctx): Promise<void>;
}

interface Ctx {
  sim: Sim;
  server?: () => S7Server;
}

/** An S7 simulator whose server is reachable for its faults. */
async function s7(): Promise<Ctx> {
  const memory = new PlcMemory();
  let server = new S7Server({ port: 0, memory, profile: 's7-1500' });
  const port = await server.listen();
  const db = () => memory.area('DB', 1)!;
  const sim: Sim = {
    protocol: 's7',
    url: `s7://127.0.0.1:${port}?timeout=400`,
    addr: (i) => `DB1.DBW${2 * i}:INT`,
    set: (i, v) => void db().writeInt16BE(v, 2 * i),
    get: (i) => db().readInt16BE(2 * i),
    missing: 'DB999.DBW0:INT',
    connectionCount: () => server.connectionCount,
    stop: () => server.close(),
    restart: async () => {
      server = new S7Server({ port, memory, profile: 's7-1500' });
      await server.listen();
    },
    close: () => server.close(),
  };
  return { sim, server: () => server };
}

const STOPPED: Fault = {
  name: 'the simulator stopped',
  codes: ['CONNECT_FAILED', 'CONNECTION_LOST', 'NOT_CONNECTED', 'TIMEOUT'],
  linkDown: true,
  on: (c) => c.sim.stop(),
  off: (c) => c.sim.restart(),
};

const S7_FAULTS: Fault[] = [
  STOPPED,
  {
    name: 'a silent peer (jobs never answered)',
    codes: ['TIMEOUT', 'CONNECTION_LOST', 'NOT_CONNECTED'],
    linkDown: true,
    on: async (c) => void (c.server!().faults.silent = true),
    off: async (c) => void (c.server!().faults.silent = false),
  },
  {
    name: 'access denied (PUT/GET off)',
    codes: ['ACCESS_DENIED'],
    linkDown: false,
    on: async (c) => void (c.server!().faults.accessDenied = true),
    off: async (c) => void (c.server!().faults.accessDenied = false),
  },
];

const CASES: [string, () => Promise<Ctx>, Fault[]][] = [
  ['S7comm', s7, S7_FAULTS],
  ['FETCH/WRITE', async () => ({ sim: await fetchWriteSim() }), [STOPPED]],
  ['freeport', async () => ({ sim: await freeportSim() }), [STOPPED]],
];

describe('nodes under faults: Status and Catch report them, values flow again without a redeploy', function () {
  this.timeout(20000);
  let ctx: Ctx | undefined;

  beforeEach(() => helper.startServer());
  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
    await ctx?.sim.close();
    ctx = undefined;
  });

  for (const [protocol, make, faults] of CASES) {
    for (const fault of faults) {
      it(`${protocol}, ${fault.name}: Status and Catch show it on read, write and heartbeat; values flow again without a redeploy`, async () => {
        ctx = await make();
        const { sim } = ctx;
        for (let i = 0; i < 6; i++) sim.set(i, 0);
        sim.set(0, 11);
        await helper.load(ALL_NODES, flow(sim.url, sim.addr));
        const out = rec('out');
        const caught = rec('caught');
        const statuses = rec('statuses');
        const beats = rec('beats');
        const written = rec('written');
        await out.next((m) => m.payload.a === 11, 4000, 'a first poll');
        await beats.next((m) => m.payload.event === 'alive', 4000, 'alive');
        const c0 = caught.messages.length;
        const s0 = statuses.messages.length;

        await fault.on(ctx);
        const lost = await beats.next((m) => m.payload.event === 'lost', 5000, 'heartbeat lost');
        expect(lost.payload.losses).to.equal(1);
        // A write during the fault is rejected to Catch (done(err)), never sent on as if acknowledged.
        helper.getNode('write').receive({ payload: { sp: 4321 } });
        const writeErr = await seen(caught, c0, (m) => m.error.source.id === 'write', 4000, 'the write error at Catch');
        expect(writeErr.error.code).to.be.oneOf([...fault.codes, 'TAG_ERRORS']);
        // It names the tag as the flow names it, whether the write was refused as a whole or per tag (issue #26).
        expect(writeErr.error.message).to.match(/^\w*Error: write "sp" \(/);
        if (fault.linkDown) {
          await seen(statuses, s0, (m) => m.status.source.id === 'read' && m.status.fill === 'red', 4000, 'a red status on the read node');
          await seen(
            statuses,
            s0,
            (m) => m.status.source.id === 'write' && m.status.fill === 'red',
            4000,
            'a red status on the write node',
          );
          const linkErr = await seen(
            caught,
            c0,
            (m) => m.error.source.type === 'plcwire-connection' || m.error.source.id === 'read',
            4000,
            'the link error at Catch',
          );
          expect(linkErr.error.code).to.be.oneOf(fault.codes);
          // Each link error once, however many nodes of the tab use the connection (read, write, heartbeat here; issue #26).
          const fromConnection = caught.messages
            .slice(c0)
            .filter((m) => m.error.source.type === 'plcwire-connection')
            .map((m) => m.error.message as string);
          expect(fromConnection.length, fromConnection.join(' | ')).to.equal(new Set(fromConnection).size);
          // The connection reports the link's loss; the read node whose poll timed out with it does not report it again.
          const fromRead = caught.messages.slice(c0).filter((m) => m.error.source.id === 'read');
          expect(fromRead.map((m) => `${m.error.code} ${m.error.message}`)).to.deep.equal([]);
        } else {
          const readErr = await seen(caught, c0, (m) => m.error.source.id === 'read', 4000, 'the read error at Catch');
          expect(readErr.error.code).to.be.oneOf(fault.codes);
          await seen(
            statuses,
            s0,
            (m) => m.status.source.id === 'read' && m.status.fill === 'yellow',
            4000,
            'tag errors on the read status',
          );
          await seen(caught, c0, (m) => m.error.source.id === 'hb', 4000, 'the heartbeat error at Catch');
        }
        await seen(statuses, s0, (m) => m.status.source.id === 'hb' && m.status.fill === 'red', 4000, 'a red status on the heartbeat');
        expect(written.messages).to.deep.equal([]);
        const s1 = statuses.messages.length;

        if (fault.linkDown) {
          // Let the link fail again while the fault lasts: a refused or unanswered reconnect, in other words than the loss.
          await seen(statuses, s1, (m) => m.status.source.id === 'read' && m.status.fill === 'red', 6000, 'a failed reconnect');
        }
        await fault.off(ctx);
        sim.set(0, 22);
        await out.next((m) => m.payload.a === 22 && m.quality.a === 'good', 8000, 'values flowing again');
        if (fault.linkDown) {
          // One outage, one message from the connection at Catch, whatever the reconnects said (issue #26).
          const outage = caught.messages.slice(c0).filter((m) => m.error.source.type === 'plcwire-connection');
          expect(
            outage.map((m) => m.error.message),
            "the connection's Catch messages of the outage",
          ).to.have.length(1);
        }
        await beats.next((m) => m.payload.event === 'restored', 8000, 'heartbeat restored');
        await seen(statuses, s1, (m) => m.status.source.id === 'read' && m.status.fill === 'green', 4000, 'the read node green again');
        written.skip();
        helper.getNode('write').receive({ payload: { sp: 1234 } });
        const ok = await written.next(() => true, 4000, 'a write acknowledged after recovery');
        expect(ok.results.sp.ok).to.equal(true);
        expect(sim.get(1)).to.equal(1234);
        expect(sim.connectionCount()).to.equal(1);
      });
    }
  }

  it('logs neither tag values nor URL credentials at info level or above, also when things fail', async () => {
    ctx = await s7();
    const { sim } = ctx;
    sim.set(0, 31337);
    await helper.load(ALL_NODES, flow(sim.url, sim.addr));
    const spy = helper.log();
    const caught = rec('caught');
    await rec('out').next((m) => m.payload.a === 31337, 4000, 'a poll');
    helper.getNode('write').receive({ payload: { sp: 27183 } });
    await rec('written').next(() => true, 4000, 'a write');
    helper.getNode('write').receive({ payload: { sp: 'bogus-value-77' } });
    await caught.next((m) => m.error.source.id === 'write', 4000, 'the bad value at Catch');
    await ctx.server!().close();
    await caught.next((m) => m.error.source.type === 'plcwire-connection', 4000, 'a link error');
    await new Promise((r) => setTimeout(r, 200));
    const visible = spy
      .getCalls()
      .map((c: any) => c.args[0])
      .filter((e: any) => e && typeof e.level === 'number' && e.level <= 40);
    expect(visible.length, 'something was logged').to.be.greaterThan(0);
    const text = visible.map((e: any) => (typeof e.msg === 'string' ? e.msg : JSON.stringify(e.msg))).join('\n');
    for (const secret of ['hunter2', 'operator', '31337', '27183', 'bogus-value-77'])
      expect(text, `log at info level or above`).not.to.include(secret);
    // The credentials do not reach Catch messages either (they go to debug sidebars and files).
    const caughtText = JSON.stringify(caught.messages.map((m) => ({ ...m, error: { message: m.error.message } })));
    expect(caughtText).not.to.include('hunter2');
  });

  it('refuses a URL with credentials (PLC protocols have none) without logging or passing them on', async () => {
    ctx = await s7();
    const { sim } = ctx;
    const spy = helper.log();
    await helper.load(ALL_NODES, flow(sim.url.replace('s7://', 's7://operator:hunter2@'), sim.addr));
    const caught = rec('caught');
    helper.getNode('write').receive({ payload: { sp: 1 } });
    const refused = await caught.next(() => true, 4000, 'an error at Catch');
    expect(JSON.stringify({ ...refused, error: { message: refused.error.message } })).not.to.include('hunter2');
    const text = spy
      .getCalls()
      .map((c: any) => c.args[0])
      .filter((e: any) => e && typeof e.level === 'number')
      .map((e: any) => (typeof e.msg === 'string' ? e.msg : JSON.stringify(e.msg)))
      .join('\n');
    expect(text).not.to.include('hunter2');
    expect(sim.connectionCount()).to.equal(0);
  });
});

describe('admin endpoints of the nodes (Node-RED with adminAuth, in a child process)', function () {
  this.timeout(30000);
  let child: ChildProcess | undefined;
  let port = 0;
  let dir = '';

  before(async () => {
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-auth-'));
    const script = path.join(dir, 'start.js');
    const red = require.resolve(process.env.PLCWIRE_NODE_RED || 'node-red');
    fs.mkdirSync(path.join(dir, 'node_modules', '@plcwire'), { recursive: true });
    fs.symlinkSync(ROOT, path.join(dir, 'node_modules', '@plcwire', 'node-red-siemens'), 'dir');
    fs.writeFileSync(
      path.join(dir, 'package.json'),
      JSON.stringify({ name: 'auth-test', dependencies: { '@plcwire/node-red-siemens': '*' } }),
    );
    fs.writeFileSync(
      script,
      `
const http = require('http');
const path = require('path');
const RED = require(${JSON.stringify(red)});
const express = require(require.resolve('express', { paths: [path.dirname(${JSON.stringify(red)})] }));
const bcrypt = require(require.resolve('bcryptjs', { paths: [path.dirname(require.resolve('@node-red/editor-api/package.json', { paths: [path.dirname(${JSON.stringify(red)})] }))] }));
const app = express();
const server = http.createServer(app);
RED.init(server, {
  userDir: ${JSON.stringify(dir)},
  httpAdminRoot: '/admin',
  uiHost: '127.0.0.1',
  logging: { console: { level: 'off' } },
  credentialSecret: 'x',
  adminAuth: { type: 'credentials', users: [{ username: 'admin', password: bcrypt.hashSync('pw', 4), permissions: '*' }] },
});
app.use('/admin', RED.httpAdmin);
server.listen(0, '127.0.0.1', () => RED.start().then(() => console.log('PORT ' + server.address().port)));
process.on('SIGTERM', () => RED.stop().then(() => process.exit(0)));
`,
    );
    child = spawn(process.execPath, [script], { cwd: dir, stdio: ['ignore', 'pipe', 'pipe'] });
    let output = '';
    port = await new Promise<number>((resolve, reject) => {
      const timer = setTimeout(() => reject(new Error(`Node-RED did not start: ${output}`)), 20000);
      const onData = (b: Buffer) => {
        output += b.toString();
        const m = /PORT (\d+)/.exec(output);
        if (m) {
          clearTimeout(timer);
          resolve(Number(m[1]));
        }
      };
      child!.stdout!.on('data', onData);
      child!.stderr!.on('data', (b: Buffer) => (output += b.toString()));
      child!.once('exit', (code) => reject(new Error(`Node-RED exited with ${code}: ${output}`)));
    });
  });

  after(async () => {
    if (child && child.exitCode === null) {
      const exited = new Promise((r) => child!.once('exit', r));
      child.kill('SIGTERM');
      await Promise.race([exited, new Promise((r) => setTimeout(r, 3000))]);
      if (child.exitCode === null) child.kill('SIGKILL');
    }
    fs.rmSync(dir, { recursive: true, force: true });
  });

  function call(method: string, url: string, body?: object, token?: string): Promise<{ status: number; body: string }> {
    return new Promise((resolve, reject) => {
      const data = body ? JSON.stringify(body) : undefined;
      const req = http.request(
        {
          host: '127.0.0.1',
          port,
          method,
          path: url,
          headers: { ...(data ? { 'content-type': 'application/json' } : {}), ...(token ? { authorization: `Bearer ${token}` } : {}) },
        },
        (res) => {
          let text = '';
          res.on('data', (c) => (text += c));
          res.on('end', () => resolve({ status: res.statusCode ?? 0, body: text }));
        },
      );
      req.on('error', reject);
      req.end(data);
    });
  }

  const ENDPOINTS: [string, string, object | undefined][] = [
    ['POST', '/admin/plcwire/validate', { addresses: ['DB1,INT0'] }],
    ['POST', '/admin/plcwire/url', { url: 's7://127.0.0.1' }],
    ['POST', '/admin/plcwire/csv', { text: 'MW2' }],
    ['GET', '/admin/plcwire/serialports', undefined],
  ];

  it('our nodes are loaded (the editor lists plcwire-connection)', async () => {
    const token = await login();
    const nodes = await call('GET', '/admin/nodes', undefined, token);
    expect(nodes.status).to.equal(200);
    expect(nodes.body).to.include('plcwire-connection');
  });

  for (const [method, url, body] of ENDPOINTS) {
    it(`${method} ${url}: 401 without a login, 200 with one`, async () => {
      expect((await call(method, url, body)).status).to.equal(401);
      expect((await call(method, url, body, 'not-a-token')).status).to.equal(401);
      const ok = await call(method, url, body, await login());
      expect(ok.status).to.equal(200);
    });
  }

  async function login(): Promise<string> {
    const r = await call('POST', '/admin/auth/token', {
      client_id: 'node-red-admin',
      grant_type: 'password',
      scope: '*',
      username: 'admin',
      password: 'pw',
    });
    expect(r.status).to.equal(200);
    return JSON.parse(r.body).access_token as string;
  }
});
