/**
 * What a read node's messages are to the nodes downstream: objects of their
 * own, which a node may change without changing another message or what the
 * read node remembers; and a status that is sent when it changes, not on
 * every poll. Real flows in the test helper against the S7 simulator.
 */
import { expect } from 'chai';
import { s7Sim } from './sims';
import { ALL_NODES, helper, Recorder, type Sim } from './support';

const TAB = { id: 'tab', type: 'tab', label: 'plcwire' };
const at = { z: 'tab', x: 100, y: 100 };
const ARRAY = 'DB1.DBW0:INT[3]';

function flow(sim: Sim, read: Record<string, unknown>, extra: object[] = []): object[] {
  return [
    TAB,
    { id: 'conn', type: 'plcwire-connection', name: 'plc', url: sim.url },
    { id: 'read', type: 'plcwire-read', ...at, name: 'poll', connection: 'conn', interval: 50, deadband: 0, wires: [['out']], ...read },
    { id: 'out', type: 'helper', ...at },
    ...extra,
  ];
}

/** A downstream node that notes what each message held on arrival, then changes it in place. */
function mutating(node: any): { arrived: { msg: any; payload: string }[] } {
  const seen = { arrived: [] as { msg: any; payload: string }[] };
  node.on('input', (msg: any) => {
    seen.arrived.push({ msg, payload: JSON.stringify(msg.payload) });
    if (Array.isArray(msg.payload)) msg.payload[0] = -1;
    msg.quality = 'changed downstream';
  });
  return seen;
}

describe('nodes: read messages downstream', function () {
  this.timeout(20000);
  let sim: Sim;

  beforeEach(async () => {
    sim = await s7Sim();
    for (let i = 0; i < 6; i++) sim.set(i, i + 1);
    await helper.startServer();
  });

  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
    await sim.close();
  });

  it('per-tag: a node that changes one message changes no other, also for two rows of one address', async () => {
    const tags = [
      { name: 'first', address: ARRAY },
      { name: 'again', address: ARRAY },
      { name: 'word', address: sim.addr(4) },
    ];
    await helper.load(ALL_NODES, flow(sim, { output: 'per-tag', tags }));
    const out = helper.getNode('out');
    const rec = new Recorder(out);
    const seen = mutating(out);
    await rec.next((m) => m.topic === 'word');
    const poll = seen.arrived.slice(0, 3);
    expect(poll.map((a) => [a.msg.topic, a.payload])).to.deep.equal([
      ['first', '[1,2,3]'],
      ['again', '[1,2,3]'],
      ['word', '5'],
    ]);
    expect(new Set(poll.map((a) => a.msg)).size).to.equal(3);
    expect(poll[0]!.msg.payload).not.to.equal(poll[1]!.msg.payload);
    const next = await rec.next((m) => m.topic === 'again');
    expect(seen.arrived.find((a) => a.msg === next)!.payload).to.equal('[1,2,3]');
  });

  it('per-tag: the messages of one poll share one _msgid, as the messages of one send() call do', async () => {
    const tags = [0, 1, 2].map((i) => ({ name: `t${i}`, address: sim.addr(i) }));
    await helper.load(ALL_NODES, flow(sim, { output: 'per-tag', tags }));
    const rec = new Recorder(helper.getNode('out'));
    const polls = [];
    for (let p = 0; p < 2; p++) polls.push([await rec.next(), await rec.next(), await rec.next()]);
    for (const poll of polls) {
      expect(poll.map((m) => m.topic)).to.deep.equal(['t0', 't1', 't2']);
      expect(new Set(poll.map((m) => m._msgid)).size).to.equal(1);
    }
    expect(polls[0]![0]._msgid).not.to.equal(polls[1]![0]._msgid);
  });

  it('object mode: every poll sends new objects, so a node that changes one message changes no later one', async () => {
    await helper.load(
      ALL_NODES,
      flow(sim, {
        output: 'object',
        tags: [
          { name: 'list', address: ARRAY },
          { name: 'word', address: sim.addr(4) },
        ],
      }),
    );
    const rec = new Recorder(helper.getNode('out'));
    const one = await rec.next();
    one.payload.list[0] = -1;
    one.payload.word = 99;
    one.quality.word = 'bad';
    one.addresses.word = 'changed';
    const two = await rec.next();
    expect(two.payload).to.deep.equal({ list: [1, 2, 3], word: 5 });
    expect(two.quality).to.deep.equal({ list: 'good', word: 'good' });
    expect(two.addresses).to.deep.equal({ list: ARRAY, word: sim.addr(4) });
    expect(two).not.to.equal(one);
  });

  it('changes: a node that changes a reported array in place neither fakes a change nor hides the next one', async () => {
    const tags = [
      { name: 'list', address: ARRAY },
      { name: 'tick', address: sim.addr(5) },
    ];
    await helper.load(ALL_NODES, flow(sim, { output: 'changes', tags }));
    const out = helper.getNode('out');
    const rec = new Recorder(out);
    const seen = mutating(out);
    await rec.next((m) => m.topic === 'tick');
    expect(seen.arrived.map((a) => [a.msg.topic, a.payload])).to.deep.equal([
      ['list', '[1,2,3]'],
      ['tick', '6'],
    ]);
    // The array went out as [-1, 2, 3] downstream; the PLC still holds [1, 2, 3]: no change to report.
    sim.set(5, 60);
    await rec.next((m) => m.topic === 'tick' && m.payload === 60);
    expect(seen.arrived.map((a) => a.msg.topic)).to.deep.equal(['list', 'tick', 'tick']);
    sim.set(1, 20);
    const changed = await rec.next((m) => m.topic === 'list');
    expect(seen.arrived.find((a) => a.msg === changed)!.payload).to.equal('[1,20,3]');
  });

  it('a REAL is sent with the digits TIA shows (40.4, not 40.400001525878906), whole table or beside a failing tag', async () => {
    // 40.4 as float32 is 0x4221999A: the two words of DB1.DBD20.
    const bits = Buffer.alloc(4);
    bits.writeFloatBE(40.4);
    sim.set(10, bits.readInt16BE(0));
    sim.set(11, bits.readInt16BE(2));
    const tags = [
      { name: 'level', address: 'DB1.DBD20:REAL' },
      { name: 'word', address: sim.addr(4) },
    ];
    await helper.load(ALL_NODES, flow(sim, { output: 'object', tags }));
    const rec = new Recorder(helper.getNode('out'));
    const good = await rec.next();
    expect(good.payload).to.deep.equal({ level: 40.4, word: 5 });
    await helper.unload();
    await helper.load(ALL_NODES, flow(sim, { output: 'per-tag', tags: [...tags, { name: 'gone', address: sim.missing }] }));
    const rec2 = new Recorder(helper.getNode('out'));
    const level = await rec2.next((m) => m.topic === 'level');
    expect(level.payload).to.equal(40.4);
    expect(String(level.payload)).to.equal('40.4');
  });

  it('sends its status when it changes, not on every poll', async () => {
    const watcher = { id: 'watcher', type: 'status', ...at, scope: ['read'], wires: [['statuses']] };
    await helper.load(
      ALL_NODES,
      flow(sim, { output: 'object', tags: [{ name: 'word', address: sim.addr(4) }] }, [watcher, { id: 'statuses', type: 'helper', ...at }]),
    );
    const rec = new Recorder(helper.getNode('out'));
    const statuses = new Recorder(helper.getNode('statuses'));
    for (let i = 0; i < 3; i++) await rec.next();
    statuses.skip();
    const before = statuses.messages.length;
    for (let i = 0; i < 5; i++) await rec.next();
    expect(statuses.messages.slice(before).map((m) => m.status.text)).to.deep.equal([]);
    // The link going down and coming back are changes: each is shown once.
    const mark = statuses.messages.length;
    await sim.stop();
    await statuses.next((m) => m.status.text === 'plcwire.status.retryIn', 6000, 'the retry status');
    await sim.restart();
    await statuses.next((m) => m.status.text === 'plcwire.status.connected', 6000, 'the connected status');
    for (let i = 0; i < 5; i++) await rec.next();
    expect(statuses.messages.slice(mark).filter((m) => m.status.text === 'plcwire.status.connected').length).to.equal(1);
  });
});
