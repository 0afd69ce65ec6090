/**
 * S7CommPlus over TLS when the PLC's TLS misbehaves in mid-session (issue
 * #26, the chaos run's TLS faults, one at a time): a fatal alert from the
 * PLC's own TLS, and a certificate that changes when the PLC restarts. Our
 * S7-1500 simulator behind a small TCP proxy on 127.0.0.1.
 */
import { expect } from 'chai';
import * as net from 'node:net';
import { createClient } from '../lib/connect';
import { PlcError } from '../lib/errors';
import type { S7PlusClient } from '../lib/s7plus/client';
import { S7PlusService } from '../lib/s7plus/server';
import { generateCertificate, type GeneratedCertificate } from '../lib/s7plus/transport/cert';
import { S7Server } from '../lib/s7/server';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { until, waitFor } from './support/wait';

const BACKOFF = { initialDelay: 20, maxDelay: 100, factor: 2, jitter: 0 };

/** A TCP proxy to `target` (changeable, as a PLC restarted elsewhere) that can flip the last byte of the client's next chunk. */
class Proxy {
  port = 0;
  target: number;
  corruptNext = false;
  private readonly server: net.Server;
  private readonly sockets = new Set<net.Socket>();

  constructor(target: number) {
    this.target = target;
    this.server = net.createServer((client) => {
      const upstream = net.connect({ host: '127.0.0.1', port: this.target });
      for (const s of [client, upstream]) {
        this.sockets.add(s);
        s.on('error', () => undefined);
        s.on('close', () => {
          this.sockets.delete(s);
          client.destroy();
          upstream.destroy();
        });
      }
      client.on('data', (chunk: Buffer) => {
        if (this.corruptNext) {
          this.corruptNext = false;
          chunk = Buffer.from(chunk);
          chunk[chunk.length - 1]! ^= 0xff;
        }
        upstream.write(chunk);
      });
      upstream.on('data', (chunk: Buffer) => client.write(chunk));
    });
  }

  async listen(): Promise<number> {
    await new Promise<void>((resolve) => this.server.listen(0, '127.0.0.1', resolve));
    this.port = (this.server.address() as net.AddressInfo).port;
    return this.port;
  }

  /** Every connection reset (the PLC restarting). */
  reset(): void {
    for (const s of this.sockets) s.resetAndDestroy();
  }

  async close(): Promise<void> {
    this.reset();
    await new Promise<void>((resolve) => this.server.close(() => resolve()));
  }
}

async function plc(cert: GeneratedCertificate): Promise<{ server: S7Server; service: S7PlusService; port: number }> {
  const service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
  const server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
  return { server, service, port: await server.listen() };
}

describe('S7CommPlus over TLS: faults of the PLC in mid-session (issue #26)', function () {
  this.timeout(30_000);
  let cert: GeneratedCertificate;
  let other: GeneratedCertificate;
  const cleanup: (() => Promise<unknown>)[] = [];

  before(async () => {
    [cert, other] = await Promise.all([generateCertificate(), generateCertificate({ commonName: 'another PLC' })]);
  });

  afterEach(async () => {
    for (const c of cleanup.splice(0).reverse()) await c().catch(() => undefined);
  });

  it("a fatal TLS alert from the PLC's TLS: CONNECTION_LOST saying the PLC's alert in words, and the link comes back", async () => {
    const real = await plc(cert);
    cleanup.push(() => real.server.close());
    const proxy = new Proxy(real.port);
    cleanup.push(() => proxy.close());
    await proxy.listen();
    const client = createClient(`s7plus://127.0.0.1:${proxy.port}?fingerprint=${real.service.fingerprint!}&timeout=3000`, {
      backoff: BACKOFF,
    }) as S7PlusClient;
    cleanup.push(() => client.close());
    client.on('error', () => undefined);
    await client.connect();
    // The request's TLS record arrives with a broken authentication tag: the PLC's TLS answers bad_record_mac and closes.
    proxy.corruptNext = true;
    const lost = waitFor<PlcError>(client, 'disconnected', 5000);
    await client.read(['"Tank".Level']).catch(() => undefined);
    const err = await lost;
    expect(err).to.be.instanceOf(PlcError);
    expect(err.code).to.equal('CONNECTION_LOST');
    expect(err.message).to.include(`the TLS session with ${client.name} ended with an alert from the PLC`);
    expect(err.message).to.match(/bad record mac/i);
    // OpenSSL's own words (its error queue, source file and line) stay in `cause`.
    expect(err.message).to.not.include('SSL routines');
    await waitFor(client, 'connected', 5000);
    expect(await client.read(['"Tank".Level'])).to.have.property('"Tank".Level');
  });

  it('a certificate that changes when the PLC restarts: refused with CERTIFICATE_UNTRUSTED at every attempt, never trusted; the pinned one back, the link is back', async () => {
    const real = await plc(cert);
    cleanup.push(() => real.server.close());
    const impostor = await plc(other);
    cleanup.push(() => impostor.server.close());
    const proxy = new Proxy(real.port);
    cleanup.push(() => proxy.close());
    await proxy.listen();
    const client = createClient(`s7plus://127.0.0.1:${proxy.port}?fingerprint=${real.service.fingerprint!}&timeout=3000`, {
      backoff: BACKOFF,
    }) as S7PlusClient;
    cleanup.push(() => client.close());
    const refusals: PlcError[] = [];
    client.on('error', (e: PlcError) => {
      if (e.code === 'CERTIFICATE_UNTRUSTED') refusals.push(e);
    });
    let connected = 0;
    client.on('connected', () => connected++);
    await client.connect();
    proxy.target = impostor.port;
    proxy.reset();
    await until(() => refusals.length >= 3, 5000, 'three refusals of the other certificate');
    expect(connected, 'never connected to the PLC with the other certificate').to.equal(1);
    expect(client.state).to.not.equal('connected');
    for (const r of refusals) expect(r.message).to.include(other.fingerprint);
    const refused = await client.read(['"Tank".Level']).catch((e: PlcError) => e);
    expect(refused).to.be.instanceOf(PlcError);
    expect((refused as PlcError).code).to.equal('NOT_CONNECTED');
    expect(impostor.server.connectionCount, 'the other PLC never keeps a session').to.be.at.most(1);
    proxy.target = real.port;
    await waitFor(client, 'connected', 5000);
    expect(client.certificate?.fingerprint).to.equal(cert.fingerprint);
    expect(await client.read(['"Tank".Level'])).to.have.property('"Tank".Level');
  });
});
