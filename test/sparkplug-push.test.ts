import { expect } from 'chai';
import type { S7PlusClient } from '../lib';
import { createClient } from '../lib/connect';
import { S7Server } from '../lib/s7/server';
import { S7PlusService } from '../lib/s7plus/server';
import { generateCertificate } from '../lib/s7plus/transport/cert';
import { SparkplugEdgeNode } from '../lib/sparkplug';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { Mosquitto } from './support/mosquitto';
import { requirePeers } from './support/sparkplug-peers';
import { TestHost } from './support/sparkplug-host';

describe('Sparkplug edge node fed by the PLC pushes (S7CommPlus subscription)', function () {
  this.timeout(30000);
  let broker: Mosquitto;
  let server: S7Server;
  let client: S7PlusClient;
  let writer: S7PlusClient;
  let host: TestHost;
  let node: SparkplugEdgeNode | undefined;

  before(function () {
    requirePeers(this);
  });

  beforeEach(async () => {
    broker = new Mosquitto();
    await broker.start();
    const cert = await generateCertificate();
    const service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    await server.listen();
    const url = `s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=5000`;
    client = createClient(url) as S7PlusClient;
    writer = createClient(url) as S7PlusClient;
    await client.connect();
    await writer.connect();
    host = new TestHost(broker.url);
    await host.connect();
  });

  afterEach(async () => {
    await node?.stop();
    node = undefined;
    await host.close();
    await client.close();
    await writer.close();
    await server.close();
    await broker.dispose();
  });

  it('a change the PLC pushes is a DDATA long before the next poll (interval 60 s)', async () => {
    node = new SparkplugEdgeNode({
      brokers: [broker.url],
      group: 'G',
      node: 'E',
      interval: 60_000,
      devices: [{ name: 'S1500', client, tags: { Count: '"Tank".Count' } }],
    });
    node.on('error', () => undefined);
    node.start();
    await host.nextOf('DBIRTH', 'S1500');
    await writer.write({ '"Tank".Count': 42 });
    const ddata = await host.nextOf('DDATA', 'S1500', 10000);
    expect(ddata.payload!.metrics[0]!.value).to.equal(42);
  });
});
