import { expect } from 'chai';
import { execFileSync, spawnSync } from 'node:child_process';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { S7Client } from '../lib/s7/client';
import { S7Server, type S7Profile } from '../lib/s7/server';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { RecordingProxy, writePcap, type RecordedFrame } from './support/pcap';

const HAS_TSHARK = spawnSync('tshark', ['--version'], { stdio: 'ignore' }).status === 0;

/** Runs tshark on a capture; returns stdout (stderr's "running as root" notice is dropped). */
function tshark(file: string, ...args: string[]): string {
  return execFileSync('tshark', ['-r', file, '-o', 'tcp.check_checksum:TRUE', ...args], {
    encoding: 'utf8',
    stdio: ['ignore', 'pipe', 'ignore'],
  });
}

describe("Wireshark's s7comm dissector reads every system-service frame we and the simulator send", function () {
  this.timeout(30000);
  let dir: string;
  const open: { close(): Promise<void> }[] = [];

  before(function () {
    if (!HAS_TSHARK) {
      console.log('    skipped: tshark is not installed (apt-get install tshark); CI installs it');
      this.skip();
    }
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-tshark-'));
  });

  after(async () => {
    for (const x of open.splice(0)) await x.close();
    if (dir && !process.env.KEEP_PCAP) fs.rmSync(dir, { recursive: true, force: true });
    else if (dir) console.log(`    pcaps kept in ${dir}`);
  });

  /** A simulator, a recording proxy in front of it, our client through the proxy; `session` runs the services. */
  async function capture(
    profile: S7Profile,
    slot: number,
    session: (c: S7Client, s: S7Server) => Promise<void>,
  ): Promise<{ file: string; frames: RecordedFrame[] }> {
    const server = new S7Server({
      port: 0,
      profile,
      layout: { dbs: Object.fromEntries(Array.from({ length: 80 }, (_, i) => [String(i + 1), 200 + i])) },
    });
    await server.listen();
    const proxy = new RecordingProxy(server.port);
    await proxy.listen();
    open.push(proxy, server);
    const client = new S7Client(parseUrl(`s7://127.0.0.1:${proxy.port}?slot=${slot}&pdu=240&control=true&timeout=3000`) as S7Endpoint);
    open.unshift(client);
    await client.connect();
    await session(client, server);
    await client.close();
    const file = path.join(dir, `${profile}.pcap`);
    writePcap(file, proxy.frames);
    return { file, frames: proxy.frames };
  }

  function expectClean(file: string, frames: RecordedFrame[]): void {
    // One S7 PDU per frame after COTP CR/CC: every one of them dissected as s7comm.
    const s7 = tshark(file, '-Y', 's7comm', '-T', 'fields', '-e', 's7comm.header.rosctr').trim().split('\n');
    expect(s7.length).to.equal(frames.length - 2);
    expect(s7.filter((r) => r === '7').length).to.equal(frames.filter((f) => f.bytes[8] === 7 && f.bytes[5] === 0xf0).length);
    expect(tshark(file, '-Y', '_ws.malformed || _ws.expert.severity >= 6291456', '-T', 'fields', '-e', 'frame.number').trim()).to.equal('');
    const expert = tshark(file, '-q', '-z', 'expert,warn');
    expect(expert).to.not.match(/^(Errors|Warnings) \(/m);
  }

  it('an S7-300 session: every SZL, multi-part diagnostic buffer and block list, clock, stop/start, block info, upload, password, errors', async () => {
    const { file, frames } = await capture('s7-300', 2, async (c, s) => {
      for (let i = 0; i < 5; i++) {
        s.stop();
        s.start(i % 2 ? 'cold' : 'warm');
      }
      await c.info();
      for (const [id, index] of [
        [0, 0],
        [0x0011, 0],
        [0x0111, 7],
        [0x001c, 0],
        [0x011c, 5],
        [0x0131, 1],
        [0x0232, 4],
        [0x0424, 0],
        [0x0074, 0],
        [0x0f11, 0],
        [0x01a0, 3],
      ] as const)
        await c.readSzl(id, index);
      expect((await c.diagnosticBuffer()).length).to.equal(23);
      await c.readSzl(0x0d91, 0).catch(() => undefined);
      await c.setClock(new Date());
      await c.readClock();
      await c.stop();
      await c.stop();
      await c.hotStart();
      await c.hotStart();
      await c.stop();
      await c.coldStart();
      await c.listBlocks();
      expect((await c.listBlocksOfType('DB')).length).to.equal(80);
      await c.listBlocksOfType('SFB');
      await c.blockInfo('DB', 1);
      await c.blockInfo('OB', 1);
      await c.blockInfo('DB', 999).catch(() => undefined);
      expect((await c.uploadBlock('DB', 70)).code.length).to.equal(269);
      await c.readDb(3);
      await c.setPassword('wrong').catch(() => undefined);
      s.setProtection(2, 'secret');
      await c.stop().catch(() => undefined);
      await c.setPassword('secret');
      await c.clearPassword();
    });
    expect(frames.length).to.be.above(70);
    expectClean(file, frames);
    // The dissector sees the multi-part answers as such: parts that say more follow (last data unit "no").
    const last = tshark(file, '-Y', 's7comm.param.userdata.lastdataunit == 1', '-T', 'fields', '-e', 'frame.number').trim().split('\n');
    // The diagnostic buffer (23 entries: 468 bytes in parts of 214) two, the DB list (320 bytes in parts of 212) one.
    expect(last.length).to.equal(3);
  });

  it('an S7-1500 session: the refusals of a CPU without block and password functions', async () => {
    const { file, frames } = await capture('s7-1500', 1, async (c) => {
      await c.info();
      await c.listBlocks().catch(() => undefined);
      await c.blockInfo('DB', 1).catch(() => undefined);
      await c.uploadBlock('DB', 1).catch(() => undefined);
      await c.setPassword('abc').catch(() => undefined);
      await c.diagnosticBuffer({ max: 1 });
    });
    expectClean(file, frames);
  });
});
