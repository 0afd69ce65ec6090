import { expect } from 'chai';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { PlcError } from '../lib/errors';
import { BdSeqStore } from '../lib/sparkplug/bdseq';
import { HostStateTracker, parseHostState } from '../lib/sparkplug/host-state';
import { parseTopic, topicOf } from '../lib/sparkplug/topics';
import { SparkplugEdgeNode } from '../lib/sparkplug';

describe('Sparkplug bdSeq, STATE and topics', () => {
  let dir: string;
  beforeEach(() => {
    dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-bdseq-'));
  });
  afterEach(() => fs.rmSync(dir, { recursive: true, force: true }));

  it('tck-id-message-flow-edge-node-birth-publish-will-message-payload-bdSeq: bdSeq counts 0, 1 … 255, then 0, across stores of the same directory', () => {
    const first = new BdSeqStore(dir, 'G', 'E');
    const seen: number[] = [];
    for (let i = 0; i < 256; i++) seen.push(first.next());
    expect(seen[0]).to.equal(0);
    expect(seen[255]).to.equal(255);
    expect(new BdSeqStore(dir, 'G', 'E').next()).to.equal(0);
    expect(new BdSeqStore(dir, 'G', 'Other').next(), 'another edge node has its own').to.equal(0);
  });

  it('a bdSeq file that does not hold 0..255 is an INVALID_VALUE naming the file, not a silent restart at 0', () => {
    fs.writeFileSync(path.join(dir, 'G.E.bdseq.json'), '{"bdSeq": 300}');
    expect(() => new BdSeqStore(dir, 'G', 'E').next())
      .to.throw(PlcError, /G\.E\.bdseq\.json/)
      .with.property('code', 'INVALID_VALUE');
  });

  it('STATE: only the JSON of the specification, and an older timestamp than the last taken is stale', () => {
    expect(parseHostState(Buffer.from('{"online":true,"timestamp":5}'))).to.deep.equal({ online: true, timestamp: 5 });
    expect(parseHostState(Buffer.from('ONLINE'))).to.equal(undefined);
    expect(parseHostState(Buffer.from('{"online":"yes","timestamp":5}'))).to.equal(undefined);
    const t = new HostStateTracker();
    expect(t.take({ online: true, timestamp: 10 })).to.equal('online');
    expect(t.take({ online: false, timestamp: 9 })).to.equal('stale');
    expect(t.online).to.equal(true);
    expect(t.take({ online: false, timestamp: 10 })).to.equal('offline');
  });

  it('topics and ids: the namespace, the message type, ids without "/", "+" or "#"', () => {
    expect(topicOf('DDATA', 'G', 'E', 'D')).to.equal('spBv1.0/G/DDATA/E/D');
    expect(parseTopic('spBv1.0/G/NCMD/E')).to.deep.equal({ type: 'NCMD', group: 'G', node: 'E' });
    expect(parseTopic('spBv1.0/STATE/SCADA')).to.deep.equal({ type: 'STATE', host: 'SCADA' });
    expect(parseTopic('spBv1.0/G/DCMD/E')).to.equal(undefined);
    expect(() => new SparkplugEdgeNode({ brokers: ['mqtt://127.0.0.1:1'], group: 'a/b', node: 'E', devices: [] })).to.throw(
      PlcError,
      /"a\/b"/,
    );
    expect(() => new SparkplugEdgeNode({ brokers: ['mqtt://127.0.0.1:1'], group: 'G', node: 'E#', devices: [] })).to.throw(PlcError, /#/);
  });
});
