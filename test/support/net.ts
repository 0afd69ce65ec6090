import * as net from 'node:net';

/** A loopback port that was free a moment ago (for child processes that need a fixed port). */
export async function freePort(): Promise<number> {
  const s = net.createServer().listen(0, '127.0.0.1');
  await new Promise((r) => s.once('listening', r));
  const port = (s.address() as net.AddressInfo).port;
  await new Promise((r) => s.close(r));
  return port;
}

const TPKT_HEADER = 4;
const COTP_DT = 0xf0;
const TLS_HANDSHAKE = 22;
const TLS_APPLICATION_DATA = 23;
const TLS_RECORD_HEADER = 5;

/**
 * A TCP proxy on 127.0.0.1 in front of an S7CommPlus server that counts what the client sends: the TLS
 * application-data records carried in COTP data frames (our client sends each S7CommPlus request as one record,
 * so after the handshake a record is a request) and their sizes. It reads TPKT frames and TLS record headers
 * only: it cannot see inside TLS, as a network tap cannot.
 */
export class RequestCountingProxy {
  /** TLS application-data records from the client since the last reset: its S7CommPlus requests. */
  requests = 0;
  /** The largest such record since the last reset (bytes of ciphertext, header included). */
  largest = 0;
  private readonly server: net.Server;
  private readonly sockets = new Set<net.Socket>();

  constructor(private readonly target: number) {
    this.server = net.createServer((client) => this.pipe(client));
  }

  async listen(): Promise<number> {
    this.server.listen(0, '127.0.0.1');
    await new Promise((r) => this.server.once('listening', r));
    return (this.server.address() as net.AddressInfo).port;
  }

  reset(): void {
    this.requests = 0;
    this.largest = 0;
  }

  async close(): Promise<void> {
    for (const s of this.sockets) s.destroy();
    await new Promise((r) => this.server.close(r));
  }

  private pipe(client: net.Socket): void {
    const upstream = net.connect(this.target, '127.0.0.1');
    for (const s of [client, upstream]) {
      this.sockets.add(s);
      s.on('error', () => undefined);
      s.on('close', () => (this.sockets.delete(s), client.destroy(), upstream.destroy()));
    }
    let frames = Buffer.alloc(0);
    let tls = Buffer.alloc(0);
    let secure = false;
    client.on('data', (chunk: Buffer) => {
      upstream.write(chunk);
      frames = Buffer.concat([frames, chunk]);
      while (frames.length >= TPKT_HEADER && frames.length >= frames.readUInt16BE(2)) {
        const frame = frames.subarray(0, frames.readUInt16BE(2));
        frames = frames.subarray(frame.length);
        if (frame.length < 7 || frame[5] !== COTP_DT) continue;
        const payload = frame.subarray(7);
        // Plain S7CommPlus (InitSSL) until the client's first TLS handshake record.
        if (!secure && payload[0] !== TLS_HANDSHAKE) continue;
        secure = true;
        tls = Buffer.concat([tls, payload]);
        while (tls.length >= TLS_RECORD_HEADER && tls.length >= TLS_RECORD_HEADER + tls.readUInt16BE(3)) {
          const size = TLS_RECORD_HEADER + tls.readUInt16BE(3);
          if (tls[0] === TLS_APPLICATION_DATA) {
            this.requests++;
            this.largest = Math.max(this.largest, size);
          }
          tls = tls.subarray(size);
        }
      }
    });
    upstream.on('data', (chunk: Buffer) => client.write(chunk));
  }
}

/**
 * A TCP proxy on 127.0.0.1 whose path can die without a close, as a pulled cable or a lost host does:
 * cut() drops every byte both ways and leaves the sockets open (neither end sees a FIN or RST); heal()
 * forwards again. A side that gives up closes its socket, and the proxy closes the other.
 */
export class BlackholeProxy {
  private readonly server: net.Server;
  private readonly sockets = new Set<net.Socket>();
  private open = true;

  constructor(private readonly target: number) {
    this.server = net.createServer((client) => {
      const upstream = net.connect(this.target, '127.0.0.1');
      for (const [from, to] of [
        [client, upstream],
        [upstream, client],
      ] as const) {
        this.sockets.add(from);
        from.on('error', () => undefined);
        from.on('data', (chunk: Buffer) => this.open && to.write(chunk));
        from.on('close', () => (this.sockets.delete(from), to.destroy()));
      }
    });
  }

  async listen(): Promise<number> {
    this.server.listen(0, '127.0.0.1');
    await new Promise((r) => this.server.once('listening', r));
    return (this.server.address() as net.AddressInfo).port;
  }

  cut(): void {
    this.open = false;
  }

  heal(): void {
    this.open = true;
  }

  async close(): Promise<void> {
    for (const s of this.sockets) s.destroy();
    await new Promise((r) => this.server.close(r));
  }
}
