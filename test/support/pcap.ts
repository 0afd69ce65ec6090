/**
 * Recording what a client and a server send each other, and writing it as a
 * pcap file (Ethernet, IPv4, TCP port 102, one TPKT frame per segment after
 * a three-way handshake) for Wireshark's dissectors.
 */
import * as net from 'node:net';
import { writeFileSync } from 'node:fs';
import { FrameReader } from '../../lib/link/framer';
import { checkTpkt } from '../../lib/s7/codec';

export interface RecordedFrame {
  fromClient: boolean;
  bytes: Buffer;
}

/** A TCP proxy on 127.0.0.1 that records every whole TPKT frame in the order it passes. */
export class RecordingProxy {
  readonly frames: RecordedFrame[] = [];
  private server: net.Server | undefined;
  private readonly sockets = new Set<net.Socket>();
  port = 0;

  constructor(private readonly targetPort: number) {}

  async listen(): Promise<number> {
    const server = net.createServer((client) => {
      const upstream = net.connect({ host: '127.0.0.1', port: this.targetPort });
      this.sockets.add(client).add(upstream);
      const up = new FrameReader(checkTpkt, 0x10010);
      const down = new FrameReader(checkTpkt, 0x10010);
      client.on('data', (chunk: Buffer) => {
        for (const f of up.push(chunk)) this.frames.push({ fromClient: true, bytes: Buffer.from(f) });
        upstream.write(chunk);
      });
      upstream.on('data', (chunk: Buffer) => {
        for (const f of down.push(chunk)) this.frames.push({ fromClient: false, bytes: Buffer.from(f) });
        client.write(chunk);
      });
      const end = () => {
        client.destroy();
        upstream.destroy();
      };
      for (const s of [client, upstream]) {
        s.on('error', () => undefined);
        s.on('close', () => {
          this.sockets.delete(s);
          end();
        });
      }
    });
    this.server = server;
    await new Promise<void>((resolve) => server.listen(0, '127.0.0.1', () => resolve()));
    this.port = (server.address() as net.AddressInfo).port;
    return this.port;
  }

  async close(): Promise<void> {
    for (const s of this.sockets) s.destroy();
    const server = this.server;
    this.server = undefined;
    if (server) await new Promise<void>((r) => server.close(() => r()));
  }
}

function checksum(b: Buffer): number {
  let sum = 0;
  for (let i = 0; i + 1 < b.length; i += 2) sum += b.readUInt16BE(i);
  if (b.length & 1) sum += b[b.length - 1]! << 8;
  while (sum >> 16) sum = (sum & 0xffff) + (sum >> 16);
  return ~sum & 0xffff;
}

const CLIENT = { ip: [10, 0, 0, 1], port: 49152, mac: Buffer.from('020000000001', 'hex') };
const PLC = { ip: [10, 0, 0, 2], port: 102, mac: Buffer.from('020000000002', 'hex') };

function packet(fromClient: boolean, seq: number, ack: number, flags: number, payload: Buffer): Buffer {
  const [src, dst] = fromClient ? [CLIENT, PLC] : [PLC, CLIENT];
  const tcp = Buffer.alloc(20);
  tcp.writeUInt16BE(src.port, 0);
  tcp.writeUInt16BE(dst.port, 2);
  tcp.writeUInt32BE(seq >>> 0, 4);
  tcp.writeUInt32BE(ack >>> 0, 8);
  tcp[12] = 5 << 4;
  tcp[13] = flags;
  tcp.writeUInt16BE(65535, 14);
  const pseudo = Buffer.concat([
    Buffer.from(src.ip),
    Buffer.from(dst.ip),
    Buffer.of(0, 6, (20 + payload.length) >> 8, (20 + payload.length) & 0xff),
    tcp,
    payload,
  ]);
  tcp.writeUInt16BE(checksum(pseudo), 16);
  const ip = Buffer.alloc(20);
  ip[0] = 0x45;
  ip.writeUInt16BE(20 + 20 + payload.length, 2);
  ip[6] = 0x40;
  ip[8] = 64;
  ip[9] = 6;
  Buffer.from(src.ip).copy(ip, 12);
  Buffer.from(dst.ip).copy(ip, 16);
  ip.writeUInt16BE(checksum(ip), 10);
  const eth = Buffer.concat([dst.mac, src.mac, Buffer.of(0x08, 0x00)]);
  return Buffer.concat([eth, ip, tcp, payload]);
}

/** Writes the frames as one TCP connection (handshake, then one segment per frame, each acknowledging the other side). */
export function writePcap(path: string, frames: readonly RecordedFrame[]): void {
  const packets: Buffer[] = [];
  let cseq = 1000;
  let pseq = 5000;
  const SYN = 0x02;
  const ACK = 0x10;
  const PSH = 0x18;
  packets.push(packet(true, cseq, 0, SYN, Buffer.alloc(0)));
  packets.push(packet(false, pseq, cseq + 1, SYN | ACK, Buffer.alloc(0)));
  cseq++;
  pseq++;
  packets.push(packet(true, cseq, pseq, ACK, Buffer.alloc(0)));
  for (const f of frames) {
    if (f.fromClient) {
      packets.push(packet(true, cseq, pseq, PSH, f.bytes));
      cseq += f.bytes.length;
    } else {
      packets.push(packet(false, pseq, cseq, PSH, f.bytes));
      pseq += f.bytes.length;
    }
  }
  const head = Buffer.alloc(24);
  head.writeUInt32LE(0xa1b2c3d4, 0);
  head.writeUInt16LE(2, 4);
  head.writeUInt16LE(4, 6);
  head.writeUInt32LE(65535, 16);
  head.writeUInt32LE(1, 20);
  const records = packets.map((p, i) => {
    const h = Buffer.alloc(16);
    h.writeUInt32LE(1_700_000_000 + Math.floor(i / 1000), 0);
    h.writeUInt32LE((i % 1000) * 1000, 4);
    h.writeUInt32LE(p.length, 8);
    h.writeUInt32LE(p.length, 12);
    return Buffer.concat([h, p]);
  });
  writeFileSync(path, Buffer.concat([head, ...records]));
}
