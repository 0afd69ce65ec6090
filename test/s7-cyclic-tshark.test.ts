/**
 * Wireshark's s7comm dissector (tshark, Debian) reads every cyclic-data PDU
 * our client and the S7-300 simulator exchange (issue #33): registrations
 * with their time base, factor and S7ANY items, the CPU's answers with the
 * job id, the pushes as read-response items, change-driven jobs, unsubscribes
 * and a refusal, with no malformed frame and the fields we meant.
 */
import { expect } from 'chai';
import { execFileSync, spawnSync } from 'node:child_process';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { S7Client } from '../lib/s7/client';
import { S7Server } from '../lib/s7/server';
import { parseUrl, type S7Endpoint } from '../lib/url';
import type { SubscriptionNotice } from '../lib/types';
import { RecordingProxy, writePcap } from './support/pcap';
import { waitFor } from './support/wait';

const HAS_TSHARK = spawnSync('tshark', ['--version'], { stdio: 'ignore' }).status === 0;

function tshark(file: string, ...args: string[]): string {
  return execFileSync('tshark', ['-r', file, '-o', 'tcp.check_checksum:TRUE', ...args], {
    encoding: 'utf8',
    stdio: ['ignore', 'pipe', 'ignore'],
  });
}

describe("Wireshark's s7comm dissector reads every cyclic-data PDU (userdata group 2) we and the simulator send", function () {
  this.timeout(30000);
  let dir: string;
  const open: { close(): Promise<void> }[] = [];

  before(function () {
    if (!HAS_TSHARK) {
      console.log('    skipped: tshark is not installed (apt-get install tshark); CI installs it');
      this.skip();
    }
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-tshark-cyclic-'));
  });

  after(async () => {
    for (const x of open.splice(0)) await x.close();
    if (dir) fs.rmSync(dir, { recursive: true, force: true });
  });

  it('an S7-300 session: cyclic and change-driven jobs, their pushes, unsubscribes and a refused cycle', async () => {
    const server = new S7Server({ port: 0, profile: 's7-300', layout: { dataBlocks: { 1: 100 }, flags: 16 } });
    await server.listen();
    const proxy = new RecordingProxy(server.port);
    await proxy.listen();
    open.push(proxy, server);
    const client = new S7Client(parseUrl(`s7://127.0.0.1:${proxy.port}?slot=2&timeout=3000`) as S7Endpoint);
    open.unshift(client);
    await client.connect();
    server.memory.write('DB', 1, 0, Buffer.from([0x12, 0x34, 0x56]));
    // An odd-length item first (a fill byte follows it), a bit, a counter-free byte range.
    const sub = await client.subscribe(['DB1,B0.3', 'M2.5', 'DB1,INT10'], { cycle: 200 });
    await waitFor(sub, 'data', 3000, (d: SubscriptionNotice) => !d.initial);
    const onChange = await client.subscribe(['DB1,DINT20'], { cycle: 1000, onChange: true });
    server.memory.write('DB', 1, 20, Buffer.from([0, 0, 1, 0]));
    await waitFor(onChange, 'data', 5000, (d: SubscriptionNotice) => !d.initial);
    await client.subscribe(['DB1,INT0'], { cycle: 600_000 }).catch(() => undefined);
    await sub.close();
    await onChange.close();
    await client.close();
    const file = path.join(dir, 'cyclic.pcap');
    writePcap(file, proxy.frames);

    expect(tshark(file, '-Y', '_ws.malformed || _ws.expert.severity >= 6291456', '-T', 'fields', '-e', 'frame.number').trim()).to.equal('');
    expect(tshark(file, '-q', '-z', 'expert,warn')).to.not.match(/^(Errors|Warnings) \(/m);
    const rows = tshark(
      file,
      '-Y',
      's7comm.param.userdata.funcgroup == 2',
      '-T',
      'fields',
      '-E',
      'separator=;',
      ...['type', 'subfunc', 'seq_num'].flatMap((f) => ['-e', `s7comm.param.userdata.${f}`]),
      ...[
        '-e',
        's7comm.cyclic.interval_timebase',
        '-e',
        's7comm.cyclic.interval_time',
        '-e',
        's7comm.cyclic.function',
        '-e',
        's7comm.cyclic.job_id',
      ],
      ...['-e', 's7comm.param.errcod', '-e', 's7comm.param.item.db', '-e', 's7comm.param.item.length', '-e', 's7comm.data.length'],
    )
      .trim()
      .split('\n')
      .map((l) => l.split(';'));
    const requests = rows.filter((r) => r[0] === '4');
    const answers = rows.filter((r) => r[0] === '8');
    const pushes = rows.filter((r) => r[0] === '0');
    // Registrations: 200 ms = 2 × 100 ms, 3 items with their DBs and lengths; 1 s change-driven; 600 s = 60 × 10 s.
    expect(requests.slice(0, 3).map((r) => [r[1], r[3], r[4]])).to.deep.equal([
      ['1', '0', '2'],
      ['5', '1', '1'],
      ['1', '2', '60'],
    ]);
    expect(requests[0]![8]).to.equal('1,0,1');
    expect(requests[0]![9]).to.equal('3,1,2');
    // The answers carry the job ids 1 and 2; the 600 s one is refused with 0xd804.
    expect(answers.slice(0, 3).map((r) => [r[2], r[7]])).to.deep.equal([
      ['1', '0x0000'],
      ['2', '0x0000'],
      ['0', '0xd804'],
    ]);
    // Unsubscribes: function 5, the job ids.
    expect(requests.slice(3).map((r) => [r[1], r[5], r[6]])).to.deep.equal([
      ['4', '5', '1'],
      ['4', '5', '2'],
    ]);
    // Pushes of job 1: 22 data bytes (count 2, items of 3 bytes + fill, the byte of M2, 2 bytes), the items' lengths as
    // tshark shows them (bytes), and of the change-driven job 2.
    expect(pushes.length).to.be.greaterThan(1);
    expect(pushes.find((r) => r[1] === '1')![10]).to.equal('22,3,1,2');
    expect(pushes.filter((r) => r[1] === '5').map((r) => r[2])).to.include('2');
  });
});
