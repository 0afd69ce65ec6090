/**
 * The edge node's brokers (lib/sparkplug/brokers.ts, issue #34): a plant's broker over TLS with a user and
 * password, a real mosquitto. Births through TLS with the CA given; a certificate the CA did not sign, or a
 * name it was not made for, is CERTIFICATE_UNTRUSTED and nothing is sent (never a fall back to plain text); a
 * wrong password is ACCESS_DENIED; the password shows nowhere (status, errors); a list mixing TLS and plain
 * brokers is refused.
 */
import { expect } from 'chai';
import * as mqtt from 'mqtt';
import { PlcError } from '../lib/errors';
import { S7Server } from '../lib/s7/server';
import { createClient } from '../lib/connect';
import type { GeneratedCertificate } from '../lib/s7plus/transport/cert';
import { brokerName, checkBrokers } from '../lib/sparkplug/brokers';
import { SparkplugEdgeNode, type SparkplugEdgeNodeOptions } from '../lib/sparkplug';
import type { EdgeNodeStatus } from '../lib/sparkplug/options';
import { Mosquitto, testCa, tlsMosquitto } from './support/mosquitto';
import { requirePeers } from './support/sparkplug-peers';
import { until } from './support/wait';

const SECRET = 's3cret-Pa55';

describe('Sparkplug brokers: URLs, TLS and a user and password (issue #34)', function () {
  this.timeout(60000);

  describe('broker URLs', () => {
    it('a password in a broker URL is shown as ***', () => {
      expect(brokerName(`mqtts://edge:${SECRET}@broker.plant:8883`)).to.equal('mqtts://edge:***@broker.plant:8883');
      expect(brokerName('mqtt://broker.plant:1883')).to.equal('mqtt://broker.plant:1883');
    });

    it('a list mixing TLS and plain brokers is refused: moving on would fall back to plain text', () => {
      expect(() => checkBrokers(['mqtts://a:8883', 'mqtt://b:1883']))
        .to.throw(PlcError, /mix TLS and plain text.*fall back to plain text/)
        .with.property('code', 'INVALID_URL');
      expect(() => checkBrokers(['http://a'])).to.throw(PlcError, /scheme must be mqtt/);
      expect(() => checkBrokers([])).to.throw(PlcError, /at least one broker/);
      expect(() => checkBrokers(['mqtts://a:8883', 'wss://b/mqtt'])).to.not.throw();
    });

    it('an error about a broker URL with a password never shows the password', () => {
      const err = (() => {
        try {
          checkBrokers([`mqtts://edge:${SECRET}@a:8883`, 'mqtt://b']);
        } catch (e) {
          return e as PlcError;
        }
        return undefined;
      })();
      expect(err?.message).to.include('mqtts://edge:***@a:8883').and.not.include(SECRET);
    });
  });

  describe('a TLS broker with a password file (mosquitto)', () => {
    let ca: GeneratedCertificate;
    let otherCa: GeneratedCertificate;
    let broker: Mosquitto;
    let server: S7Server;
    let plc: ReturnType<typeof createClient>;
    let node: SparkplugEdgeNode | undefined;

    before(async function () {
      requirePeers(this);
      ca = await testCa('plant CA');
      otherCa = await testCa('another CA');
      broker = await tlsMosquitto(ca, { edge: SECRET, scada: 'host-pw' }, ['localhost', '127.0.0.1']);
      await broker.start();
      server = new S7Server({ port: 0, profile: 's7-1500', layout: { dbs: { 1: 16 } } });
      await server.listen();
      plc = createClient(`s7://127.0.0.1:${server.port}?timeout=2000`);
      await plc.connect();
    });
    afterEach(async () => {
      await node?.stop();
      node = undefined;
    });
    after(async () => {
      await plc?.close();
      await server?.close();
      await broker?.dispose();
    });

    function edge(
      url: string,
      tls: { ca: string; username: string; password: string },
      events: { status: EdgeNodeStatus[]; errors: PlcError[] },
    ) {
      const options: SparkplugEdgeNodeOptions = {
        brokers: [url],
        group: 'Plant',
        node: 'Secure',
        interval: 100,
        reconnectDelay: 200,
        devices: [{ name: 'PLC', client: plc, tags: { Level: 'DB1.DBW0:INT' } }],
        mqtt: { ca: tls.ca, username: tls.username, password: tls.password },
      };
      node = new SparkplugEdgeNode(options);
      node.on('status', (s) => events.status.push(s));
      node.on('error', (e) => events.errors.push(e));
      node.start();
      return node;
    }

    async function host(): Promise<{ client: mqtt.MqttClient; topics: string[] }> {
      const client = await mqtt.connectAsync(broker.url, { ca: ca.cert, username: 'scada', password: 'host-pw', reconnectPeriod: 0 });
      const topics: string[] = [];
      client.on('message', (t) => topics.push(t));
      await client.subscribeAsync('spBv1.0/#', { qos: 1 });
      return { client, topics };
    }

    it('births through TLS with the CA that signed the broker, a user and a password; the status never shows the password', async () => {
      const h = await host();
      try {
        const events = { status: [] as EdgeNodeStatus[], errors: [] as PlcError[] };
        const url = broker.url.replace('mqtts://', `mqtts://edge:${SECRET}@`);
        edge(url, { ca: ca.cert, username: 'edge', password: SECRET }, events);
        await until(() => h.topics.includes('spBv1.0/Plant/DBIRTH/Secure/PLC'), 15000, 'the DBIRTH through TLS');
        expect(events.status.map((s) => s.broker)).to.include(`mqtts://edge:***@127.0.0.1:${broker.port}`);
        expect(JSON.stringify(events)).to.not.include(SECRET);
        expect(events.errors).to.deep.equal([]);
      } finally {
        await h.client.endAsync();
      }
    });

    it('a broker certificate another CA signed is CERTIFICATE_UNTRUSTED, told once however often it is tried, and nothing is published', async () => {
      const h = await host();
      try {
        const events = { status: [] as EdgeNodeStatus[], errors: [] as PlcError[] };
        edge(broker.url, { ca: otherCa.cert, username: 'edge', password: SECRET }, events);
        await until(() => events.errors.length > 0, 15000, 'the refusal');
        expect(events.errors[0]!.code).to.equal('CERTIFICATE_UNTRUSTED');
        expect(events.errors[0]!.message).to.match(/broker mqtts:\/\/127\.0\.0\.1:\d+: its TLS certificate was refused .*nothing was sent/);
        // It goes on trying (the broker may get its certificate right), telling the refusal once, not at each try.
        await until(() => events.status.filter((x) => x.state === 'connecting').length >= 4, 15000, 'three more tries');
        expect(events.errors).to.have.length(1);
        expect(h.topics.filter((t) => t.includes('/Secure'))).to.deep.equal([]);
        expect(node!.stats.state).to.not.equal('online');
      } finally {
        await h.client.endAsync();
      }
    });

    it('the right CA, but a certificate made for another name (broker.plant, reached as 127.0.0.1) is refused too', async () => {
      const other = await tlsMosquitto(ca, { edge: SECRET }, ['broker.plant']);
      await other.start();
      try {
        const events = { status: [] as EdgeNodeStatus[], errors: [] as PlcError[] };
        edge(other.url, { ca: ca.cert, username: 'edge', password: SECRET }, events);
        await until(() => events.errors.length > 0, 15000, 'the refusal');
        expect(events.errors[0]!.code).to.equal('CERTIFICATE_UNTRUSTED');
        expect(events.errors[0]!.message).to.match(
          /made for another name \(Hostname\/IP does not match .*127\.0\.0\.1.*\); nothing was sent/,
        );
        await node!.stop();
        node = undefined;
      } finally {
        await other.dispose();
      }
    });

    it('a wrong password is ACCESS_DENIED, and the error does not show it', async () => {
      const events = { status: [] as EdgeNodeStatus[], errors: [] as PlcError[] };
      edge(broker.url, { ca: ca.cert, username: 'edge', password: 'wrong-Pa55' }, events);
      await until(() => events.errors.length > 0, 15000, 'the refusal');
      expect(events.errors[0]!.code).to.equal('ACCESS_DENIED');
      expect(events.errors[0]!.message).to.match(/refused the edge node's user or password/);
      expect(JSON.stringify(events.errors.map((e) => e.message))).to.not.include('wrong-Pa55');
    });
  });
});
