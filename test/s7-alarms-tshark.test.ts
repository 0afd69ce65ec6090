/**
 * Wireshark's s7comm dissector (tshark) reads every alarm, diagnostic and mode PDU our client and the S7-300/400
 * simulator exchange — registration, the indications of every kind, the multi-part alarm query, the acknowledgement
 * and its indication, the mode transitions — with no malformed frame, and finds in them the fields we meant.
 */
import { expect } from 'chai';
import { execFileSync, spawnSync } from 'node:child_process';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import type { AlarmDefinition, AlarmEvent } from '../lib/alarms/model';
import { S7Client } from '../lib/s7/client';
import { S7Server } from '../lib/s7/server';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { RecordingProxy, writePcap } from './support/pcap';
import { until } from './support/wait';

const HAS_TSHARK = spawnSync('tshark', ['--version'], { stdio: 'ignore' }).status === 0;

function tshark(file: string, ...args: string[]): string {
  return execFileSync('tshark', ['-r', file, '-o', 'tcp.check_checksum:TRUE', ...args], {
    encoding: 'utf8',
    stdio: ['ignore', 'pipe', 'ignore'],
    maxBuffer: 64 * 1024 * 1024,
  });
}

/** 40 ALARM_SQ (enough for a query answer of several parts at PDU 240), and one of each other kind. */
const DEFINITIONS: AlarmDefinition[] = [
  ...Array.from({ length: 40 }, (_, i) => ({
    id: 0x1000 + i,
    kind: 'ALARM_SQ' as const,
    texts: { 'en-US': `Alarm ${i}` },
    needsAck: true,
    trigger: `DB1.DBX${i >> 3}.${i & 7}`,
    values: ['MW20:INT'],
  })),
  { id: 0x2001, kind: 'ALARM_S', texts: { en: 's' }, needsAck: false, trigger: 'M0.0', values: ['MD24:REAL', 'MB28'] },
  { id: 0x2002, kind: 'ALARM_8', signal: 2, texts: { en: '8' }, needsAck: true, trigger: 'M0.1' },
  { id: 0x2003, kind: 'NOTIFY', texts: { en: 'n' }, needsAck: false, trigger: 'M0.2' },
  { id: 0x2004, kind: 'NOTIFY_8P', signal: 5, texts: { en: 'n8' }, needsAck: false, trigger: 'M0.3' },
];

describe("Wireshark's s7comm dissector reads every alarm, diagnostic and mode PDU we and the simulator send (issue #33)", function () {
  this.timeout(60000);
  let dir: string;
  const open: { close(): Promise<void> }[] = [];

  before(function () {
    if (!HAS_TSHARK) {
      console.log('    skipped: tshark is not installed (apt-get install tshark); CI installs it');
      this.skip();
    }
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-alarms-tshark-'));
  });

  after(async () => {
    for (const x of open.splice(0)) await x.close();
    if (dir && !process.env.KEEP_PCAP) fs.rmSync(dir, { recursive: true, force: true });
  });

  it('an S7-300 session: registration, every indication kind, the query in parts, ack and ack indication, STOP/RUN', async () => {
    const server = new S7Server({ port: 0, profile: 's7-300', alarms: DEFINITIONS, layout: { dbs: { 1: 16 } } });
    await server.listen();
    const proxy = new RecordingProxy(server.port);
    await proxy.listen();
    open.push(proxy, server);
    const client = new S7Client(parseUrl(`s7://127.0.0.1:${proxy.port}?slot=2&pdu=240&timeout=3000`) as S7Endpoint);
    open.unshift(client);
    await client.connect();
    const events: AlarmEvent[] = [];
    const sub = await client.subscribeAlarms({ mode: true, diagnostics: true }, (e) => events.push(e));
    for (let i = 0; i < 40; i++) server.memory.writeBit('DB', 1, i >> 3, i & 7, true);
    for (let bit = 0; bit < 4; bit++) server.memory.writeBit('M', 0, 0, bit, true);
    await until(() => events.length === 44, 5000, '44 coming events');
    const listed = await client.alarms();
    expect(listed).to.have.length(44); // every one is coming
    await client.acknowledge(0x1000);
    await until(() => events.some((e) => e.type === 'alarm' && e.change === 'acknowledged'), 3000, 'the ack indication');
    server.stop();
    server.start();
    await until(() => events.filter((e) => e.type === 'mode').length === 2, 3000, 'STOP and RUN');
    await sub.close();
    await client.close();
    await until(() => proxy.frames.length > 0 && proxy.frames.at(-1)!.fromClient === false, 3000, 'the last answer');
    const file = path.join(dir, 's7-300-alarms.pcap');
    writePcap(file, proxy.frames);

    // Clean: every frame after COTP CR/CC is s7comm, none malformed, no warning.
    const s7 = tshark(file, '-Y', 's7comm', '-T', 'fields', '-e', 's7comm.header.rosctr').trim().split('\n');
    expect(s7.length).to.equal(proxy.frames.length - 2);
    expect(tshark(file, '-Y', '_ws.malformed || _ws.expert.severity >= 6291456', '-T', 'fields', '-e', 'frame.number').trim()).to.equal('');
    expect(tshark(file, '-q', '-z', 'expert,warn')).to.not.match(/^(Errors|Warnings) \(/m);

    // The fields we meant.
    const fields = (filter: string, ...names: string[]) =>
      tshark(file, '-Y', filter, '-T', 'fields', '-E', 'separator=|', ...names.flatMap((n) => ['-e', n]))
        .trim()
        .split('\n')
        .filter((l) => l !== '');
    const subfuncs = fields('s7comm.param.userdata.subfunc', 's7comm.param.userdata.funcgroup', 's7comm.param.userdata.subfunc');
    const count = (s: string) => subfuncs.filter((l) => l === s).length;
    expect(count('4|2'), 'message service requests and answers').to.equal(8); // 2 to register, 2 to abort, each answered
    expect(count('4|18'), 'ALARM_S indication').to.equal(1);
    expect(count('4|17'), 'ALARM_SQ indications').to.equal(40);
    expect(count('4|5'), 'ALARM_8 indication').to.equal(1);
    expect(count('4|6'), 'NOTIFY indication').to.equal(1);
    expect(count('4|22'), 'NOTIFY_8 indication').to.equal(1);
    expect(count('4|12'), 'ack indication').to.equal(1);
    expect(count('4|11'), 'ack and its answer').to.equal(2);
    expect(count('4|3'), 'diagnostic messages').to.be.greaterThan(2);
    const modes = fields('s7comm.param.userdata.funcgroup == 0', 's7comm.param.modetrans.subfunc');
    expect(modes, 'mode transitions: STOP, then RUN').to.deep.equal(['0', '2']);
    const queryParts = count('4|19');
    expect(queryParts, 'the query of two families, the ALARM_S one in several parts').to.be.greaterThan(4);
    const ids = fields('s7comm.param.userdata.subfunc == 17', 's7comm.alarm.event_id').map((x) => Number(x));
    expect(ids).to.deep.equal(Array.from({ length: 40 }, (_, i) => 0x1000 + i));
    const alarm8 = fields('s7comm.param.userdata.subfunc == 5', 's7comm.alarm.event_id', 's7comm.alarm.eventstate');
    expect(alarm8).to.deep.equal([`0x00002002|0x02`]);
    const s = fields('s7comm.param.userdata.subfunc == 18', 's7comm.alarm.nr_add_values');
    expect(s).to.deep.equal(['2']);
    const acked = fields('s7comm.param.userdata.subfunc == 12', 's7comm.alarm.event_id');
    expect(acked).to.deep.equal(['0x00001000']);
    const diag = fields('s7comm.param.userdata.subfunc == 3', 's7comm.cpu.diag_msg.eventid');
    expect(diag).to.include('0x4304');
    const registered = fields('s7comm.param.userdata.subfunc == 2 && s7comm.param.userdata.type == 4', 's7comm.cpu.msg.events');
    expect(registered[0]).to.equal('0x83');
  });
});
