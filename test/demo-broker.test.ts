/**
 * The demo's in-process MQTT broker (demo/broker.js, `npm start`'s port 1883 here
 * a free one): it carries a message between two clients, a second demo on the
 * same port uses the broker already there, and close() frees the port.
 */
import { expect } from 'chai';
import * as net from 'node:net';
import * as path from 'node:path';
import { freePort } from './support/net';

const ROOT = path.resolve(__dirname, '../..');
const { startDemoBroker } = require(path.join(ROOT, 'demo/broker.js')) as {
  startDemoBroker(port: number): Promise<{ url?: string; note: string; close(): Promise<void> }>;
};
const mqtt = require('mqtt');

const accepts = (port: number) =>
  new Promise<boolean>((resolve) => {
    const s = net.connect(port, '127.0.0.1');
    s.once('connect', () => (s.destroy(), resolve(true)));
    s.once('error', () => (s.destroy(), resolve(false)));
  });

describe('demo: the in-process MQTT broker (demo/broker.js)', function () {
  this.timeout(20_000);

  it('carries a retained QoS 1 message, leaves a broker already on its port alone, and frees the port on close', async () => {
    const port = await freePort();
    const broker = await startDemoBroker(port);
    expect(broker.url).to.equal(`mqtt://127.0.0.1:${port}`);
    expect(broker.note).to.match(/aedes/);
    const second = await startDemoBroker(port);
    expect(second.note).to.equal(`a broker is already on port ${port}: the demo uses it`);
    await second.close();
    const pub = await mqtt.connectAsync(broker.url, { reconnectPeriod: 0 });
    await pub.publishAsync('spBv1.0/STATE/Demo', '{"online":true,"timestamp":1}', { qos: 1, retain: true });
    const sub = await mqtt.connectAsync(broker.url, { reconnectPeriod: 0 });
    const got = new Promise<string>((resolve) => sub.on('message', (_t: string, p: Buffer) => resolve(p.toString())));
    await sub.subscribeAsync('spBv1.0/STATE/#', { qos: 1 });
    const deadline = new Promise<never>((_, reject) =>
      setTimeout(() => reject(new Error('no retained message within 10 s')), 10_000).unref(),
    );
    expect(await Promise.race([got, deadline])).to.equal('{"online":true,"timestamp":1}');
    await pub.endAsync(true);
    await sub.endAsync(true);
    await broker.close();
    expect(await accepts(port)).to.equal(false);
  });
});
