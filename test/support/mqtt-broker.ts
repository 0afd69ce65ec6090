/**
 * A real MQTT broker for the tests: aedes on 127.0.0.1 over TCP, which can be
 * stopped (every client connection dropped, the port closed) and started
 * again on the same port. Its persistence store (sessions, subscriptions,
 * queued QoS 1 messages, retained messages) outlives a restart, as a broker
 * that keeps its state on disk does (Mosquitto with `persistence true`).
 *
 * `hold(clientId)` keeps that client's CONNECT waiting until `release`: a
 * gateway that is away for as long as a test needs, with no refused CONNACK
 * (after which an MQTT.js client would stop reconnecting).
 */
import * as net from 'node:net';

const { Aedes } = require('aedes');
const memory = require('aedes-persistence');

export class TestBroker {
  port = 0;
  private readonly persistence = memory();
  private broker: any;
  private server: net.Server | undefined;
  private readonly sockets = new Set<net.Socket>();
  private readonly held = new Set<string>();
  private waiting: { clientId: string; go: () => void }[] = [];

  get url(): string {
    return `mqtt://127.0.0.1:${this.port}`;
  }

  async start(): Promise<void> {
    const broker = await Aedes.createBroker({ persistence: this.persistence, heartbeatInterval: 3_600_000 });
    broker.preConnect = (client: any, packet: any, callback: (err: Error | null, ok: boolean) => void) => {
      const go = () => callback(null, true);
      if (this.held.has(packet.clientId)) this.waiting.push({ clientId: packet.clientId, go });
      else go();
    };
    this.broker = broker;
    const server = net.createServer((socket) => {
      this.sockets.add(socket);
      socket.on('close', () => this.sockets.delete(socket));
      broker.handle(socket);
    });
    await new Promise<void>((resolve, reject) => {
      server.once('error', reject);
      server.listen(this.port, '127.0.0.1', () => resolve());
    });
    this.port = (server.address() as net.AddressInfo).port;
    this.server = server;
  }

  /** Drops every connection and closes the port; the persistence store stays. */
  async stop(): Promise<void> {
    const { broker, server } = this;
    this.broker = undefined;
    this.server = undefined;
    this.waiting = [];
    if (broker) await new Promise<void>((resolve) => broker.close(() => resolve()));
    for (const s of this.sockets) s.destroy();
    if (server) await new Promise<void>((resolve) => server.close(() => resolve()));
  }

  async restart(): Promise<void> {
    await this.stop();
    await this.start();
  }

  /** True while a client with this id has a session open on the broker. */
  connected(clientId: string): boolean {
    return !!this.broker && !!this.broker.clients[clientId];
  }

  hold(clientId: string): void {
    this.held.add(clientId);
  }

  release(clientId: string): void {
    this.held.delete(clientId);
    const go = this.waiting.filter((w) => w.clientId === clientId);
    this.waiting = this.waiting.filter((w) => w.clientId !== clientId);
    go.forEach((w) => w.go());
  }

  /** True while a CONNECT of this client waits in hold(). */
  waitingFor(clientId: string): boolean {
    return this.waiting.some((w) => w.clientId === clientId);
  }
}
