/**
 * Sparkplug B against a host nobody here wrote: Eclipse Tahu 1.0.21's decoder
 * and a primary host built on it (test/support/tahu.ts), through a real
 * mosquitto (test/support/mosquitto.ts). Without java, the built Tahu host or
 * mosquitto the suite skips and says why; .ci/run (PLCWIRE_REQUIRE_SPARKPLUG=1)
 * makes a missing peer a failure instead.
 */
import { expect } from 'chai';
import { Mosquitto } from './support/mosquitto';
import { missingMosquitto, sparkplugRequired } from './support/sparkplug-peers';
import { skipBecause } from './support/skip';
import { TahuHost, missingTahu } from './support/tahu';

const mqtt = require('mqtt');

/** Subscribes a plain MQTT.js client to `topic` and resolves with the first message (retained ones too). */
function firstMessage(url: string, topic: string, ms = 20_000): Promise<{ payload: string; retain: boolean; qos: number }> {
  return new Promise((resolve, reject) => {
    const client = mqtt.connect(url, { reconnectPeriod: 0 });
    const timer = setTimeout(() => (client.end(true), reject(new Error(`nothing on ${topic} within ${ms} ms`))), ms);
    client.on('error', (e: Error) => (clearTimeout(timer), client.end(true), reject(e)));
    client.on('connect', () => client.subscribe(topic, { qos: 1 }));
    client.on('message', (_t: string, payload: Buffer, packet: { retain: boolean; qos: number }) => {
      clearTimeout(timer);
      client.end(true);
      resolve({ payload: payload.toString('utf8'), retain: packet.retain, qos: packet.qos });
    });
  });
}

describe('Sparkplug B: the Eclipse Tahu host (test/interop/tahu) and mosquitto', function () {
  this.timeout(120_000);
  const broker = new Mosquitto();

  before(async function () {
    const missing = missingMosquitto() ?? missingTahu();
    if (missing) {
      if (sparkplugRequired()) throw new Error(`PLCWIRE_REQUIRE_SPARKPLUG=1 but ${missing}`);
      skipBecause(this, missing);
    }
    await broker.start();
  });
  after(() => broker.dispose());

  it('publishes its STATE online as Sparkplug 3.0 asks: retained, QoS 1, JSON with a timestamp', async () => {
    const host = new TahuHost(broker.url, 'HarnessHost');
    try {
      await host.ready();
      const state = await firstMessage(broker.url, 'spBv1.0/STATE/HarnessHost');
      expect(state.retain).to.equal(true);
      expect(state.qos).to.equal(1);
      const json = JSON.parse(state.payload);
      expect(json.online).to.equal(true);
      expect(json.timestamp)
        .to.be.a('number')
        .within(Date.now() - 120_000, Date.now());
    } finally {
      await host.close();
    }
    // A clean quit leaves STATE offline retained, with the same birth timestamp.
    const after = JSON.parse((await firstMessage(broker.url, 'spBv1.0/STATE/HarnessHost')).payload);
    expect(after.online).to.equal(false);
  });

  it("leaves STATE offline through its Will when it is killed (the broker's Will delivery)", async () => {
    const host = new TahuHost(broker.url, 'KilledHost');
    await host.ready();
    const online = JSON.parse((await firstMessage(broker.url, 'spBv1.0/STATE/KilledHost')).payload);
    expect(online.online).to.equal(true);
    await host.close(true);
    const deadline = Date.now() + 30_000;
    let state = online;
    while (state.online && Date.now() < deadline) state = JSON.parse((await firstMessage(broker.url, 'spBv1.0/STATE/KilledHost')).payload);
    expect(state).to.deep.equal({ online: false, timestamp: online.timestamp });
  });

  it('encodes NCMD rebirth and DCMD with Tahu and decodes them back with Tahu (the harness itself)', async () => {
    const host = new TahuHost(broker.url, 'EchoHost');
    try {
      await host.ready();
      await host.command('rebirth G1 E1');
      const ncmd = await host.waitFor((l) => l.type === 'NCMD');
      expect(ncmd.topic).to.equal('spBv1.0/G1/NCMD/E1');
      expect(ncmd.metrics![0]).to.include({ name: 'Node Control/Rebirth', datatype: 'Boolean', value: true });
      await host.command('dcmd G1 E1 D1 Counter Int64 9007199254740993');
      const dcmd = await host.waitFor((l) => l.type === 'DCMD');
      expect(dcmd.topic).to.equal('spBv1.0/G1/DCMD/E1/D1');
      expect(dcmd.metrics![0]).to.include({ name: 'Counter', datatype: 'Int64', value: '9007199254740993' });
    } finally {
      await host.close();
    }
  });
});
