/**
 * Simulated freeport stations on one RS-485 bus. The bus can be reached over
 * a serial device (e.g. one end of a pseudo-terminal pair), over TCP
 * (as through a serial device server), or in-process through a serialport
 * binding such as `@serialport/binding-mock`. Every station hears every frame
 * and answers only its own; frames with a bad checksum or framing get no
 * answer (the master times out and retries): docs/protocols.md, "Frames".
 *
 * Faults for tests: `station(n).silent`, `faults` (bit flips and dropped
 * characters in replies, a reply delay), `sendRaw()` (garbage on the line),
 * `dropConnections()` (the device or the TCP link disappears).
 */
import { EventEmitter } from 'node:events';
import * as net from 'node:net';
import type { BindingInterface, BindingPortInterface } from '@serialport/bindings-interface';
import type { SerialPortStream } from '@serialport/stream';
import { ConnectionError, PlcError } from '../errors';
import { closeSerial, openSerial } from '../link/serial';
import type { Parity } from './url';
import { encodeReply, type FreeportRequest } from './codec';
import { FreeportParser } from './parser';
import { defineProfile, maxStation, type FreeportProfile } from './profile';
import { FreeportStation } from './station';

export interface FreeportBusOptions {
  /** Station addresses, or addresses with their initial data areas. */
  stations: readonly number[] | Readonly<Record<number, Buffer>>;
  /** The frame profile (default: DEFAULT_FREEPORT_PROFILE); a partial profile is completed with defaults. */
  profile?: Partial<FreeportProfile>;
  /** Injected for noise faults. */
  random?: () => number;
}

export interface FreeportBusFaults {
  /** Probability (0–1) that a reply has one bit flipped. */
  flipBitRate: number;
  /** Probability (0–1) that a reply loses one character. */
  dropCharRate: number;
  /** The next N replies have one bit flipped in their data (deterministic corruption). */
  corruptNext: number;
  /** Milliseconds a station takes to answer. */
  replyDelayMs: number;
}

export interface SerialAttachOptions {
  baudRate: number;
  parity?: Parity;
  dataBits?: 7 | 8;
  stopBits?: 1 | 2;
  /** A serialport binding other than the platform's (e.g. a mock). */
  binding?: BindingInterface;
}

interface Link {
  readonly parser: FreeportParser;
  write(bytes: Buffer): void;
  drop(): void;
}

/**
 * Events: 'request' (request, answered: boolean), 'corrupt' (ProtocolError),
 * 'connection' / 'disconnect' (TCP clients).
 */
export class FreeportBus extends EventEmitter {
  readonly profile: FreeportProfile;
  readonly faults: FreeportBusFaults = { flipBitRate: 0, dropCharRate: 0, corruptNext: 0, replyDelayMs: 0 };
  private readonly stationsByAddress = new Map<number, FreeportStation>();
  private readonly links = new Set<Link>();
  private readonly sockets = new Set<net.Socket>();
  private readonly serialPorts = new Set<SerialPortStream>();
  private readonly timers = new Set<NodeJS.Timeout>();
  private readonly random: () => number;
  private server: net.Server | undefined;
  private replying = 0;
  /** Requests that arrived while a station was still answering: on a real RS-485 bus, collisions. */
  collisions = 0;
  private closed = false;

  constructor(options: FreeportBusOptions) {
    super();
    this.profile = defineProfile(options.profile);
    this.random = options.random ?? Math.random;
    const entries: [number, Buffer | undefined][] = Array.isArray(options.stations)
      ? (options.stations as readonly number[]).map((n) => [n, undefined])
      : Object.entries(options.stations as Record<number, Buffer>).map(([n, data]) => [Number(n), data]);
    for (const [address, data] of entries) {
      if (!Number.isInteger(address) || address < 0 || address > maxStation(this.profile)) {
        throw new PlcError('INVALID_VALUE', `station address ${address} is out of range (0–${maxStation(this.profile)})`);
      }
      this.stationsByAddress.set(address, new FreeportStation(address, this.profile.dataBytes, data));
    }
  }

  /** The simulated station at `address`; throws when there is none. */
  station(address: number): FreeportStation {
    const s = this.stationsByAddress.get(address);
    if (!s) throw new PlcError('INVALID_VALUE', `no simulated station ${address} on this bus`);
    return s;
  }

  get stations(): FreeportStation[] {
    return [...this.stationsByAddress.values()];
  }

  /** TCP clients connected now. */
  get connectionCount(): number {
    return this.sockets.size;
  }

  /** Answers on a serial device (the real bindings unless `binding` is given). Resolves once the port is open. */
  async attachSerial(path: string, options: SerialAttachOptions): Promise<void> {
    this.assertOpen();
    const port = await openSerial({
      path,
      baudRate: options.baudRate,
      parity: options.parity ?? 'none',
      dataBits: options.dataBits ?? 8,
      stopBits: options.stopBits ?? 1,
      ...(options.binding ? { binding: options.binding } : {}),
    });
    if (this.closed) {
      await closeSerial(port);
      this.assertOpen();
    }
    this.serialPorts.add(port);
    const link = this.addLink(
      (bytes) => port.write(bytes),
      () => port.destroy(),
    );
    port.on('data', (chunk: Buffer) => this.receive(link, chunk));
    port.once('close', () => {
      this.links.delete(link);
      this.serialPorts.delete(port);
    });
  }

  /** Answers TCP clients, like stations behind a serial device server. Resolves with the port. */
  listenTcp(options: { host?: string; port?: number } = {}): Promise<number> {
    this.assertOpen();
    if (this.server) return Promise.reject(new PlcError('INVALID_VALUE', 'this bus already listens on TCP'));
    const server = net.createServer((socket) => this.accept(socket));
    this.server = server;
    return new Promise((resolve, reject) => {
      server.once('error', (err) => {
        this.server = undefined;
        reject(new ConnectionError('CONNECT_FAILED', `cannot listen on port ${options.port ?? 0}: ${err.message}`, { cause: err }));
      });
      server.listen(options.port ?? 0, options.host ?? '127.0.0.1', () => resolve(this.port!));
    });
  }

  /** The TCP port listened on, if any. */
  get port(): number | undefined {
    const address = this.server?.address();
    return address && typeof address === 'object' ? address.port : undefined;
  }

  /**
   * In-process bus: wraps a serialport binding (e.g. `MockBinding` from
   * `@serialport/binding-mock`) so that every port opened through the returned
   * binding is wired to these stations. Give it to the master as `binding`.
   */
  mockBinding<T extends BindingPortInterface & { emitData(data: Buffer): void; isOpen: boolean }>(
    base: BindingInterface<T>,
  ): BindingInterface<T> {
    const bus = this;
    return {
      list: () => base.list(),
      async open(options) {
        const port = await base.open(options);
        bus.wireMockPort(port);
        return port;
      },
    };
  }

  /** Writes raw bytes onto every attached line (garbage, noise, a foreign frame). */
  sendRaw(bytes: Buffer): void {
    for (const link of this.links) link.write(bytes);
  }

  /** The line disappears: TCP clients are dropped, serial and in-process ports see a disconnect. */
  dropConnections(): void {
    for (const link of [...this.links]) link.drop();
  }

  /** Stops answering, drops every client and closes every port. Always resolves. */
  async close(): Promise<void> {
    this.closed = true;
    for (const t of this.timers) clearTimeout(t);
    this.timers.clear();
    this.replying = 0;
    for (const socket of this.sockets) socket.destroy();
    this.sockets.clear();
    const ports = [...this.serialPorts];
    this.serialPorts.clear();
    this.links.clear();
    const server = this.server;
    this.server = undefined;
    await Promise.all([
      ...ports.map(closeSerial),
      server ? new Promise<void>((resolve) => server.close(() => resolve())) : Promise.resolve(),
    ]);
  }

  private accept(socket: net.Socket): void {
    if (this.closed) return void socket.destroy();
    this.sockets.add(socket);
    socket.setNoDelay(true);
    const link = this.addLink(
      (bytes) => socket.write(bytes),
      () => socket.destroy(),
    );
    socket.on('data', (chunk) => this.receive(link, chunk));
    socket.on('error', () => {});
    socket.once('close', () => {
      this.links.delete(link);
      if (this.sockets.delete(socket)) this.emit('disconnect', this.sockets.size);
    });
    this.emit('connection', this.sockets.size);
  }

  private wireMockPort(port: BindingPortInterface & { emitData(data: Buffer): void; isOpen: boolean }): void {
    let vanish: (err: Error) => void = () => {};
    const vanished = new Promise<never>((_, reject) => (vanish = reject));
    vanished.catch(() => {});
    const link = this.addLink(
      (bytes) => {
        if (port.isOpen) port.emitData(bytes);
      },
      () => {
        this.links.delete(link);
        vanish(Object.assign(new Error('device disconnected'), { disconnect: true }));
      },
    );
    const write = port.write.bind(port);
    const read = port.read.bind(port);
    const close = port.close.bind(port);
    port.write = async (bytes: Buffer) => {
      await write(bytes);
      this.receive(link, Buffer.from(bytes));
    };
    // The stream treats a failed read as the device going away (SerialPortStream → 'close' with a DisconnectedError).
    port.read = (buffer, offset, length) => Promise.race([read(buffer, offset, length), vanished]);
    port.close = async () => {
      this.links.delete(link);
      await close();
    };
  }

  private addLink(write: (bytes: Buffer) => void, drop: () => void): Link {
    const link: Link = { parser: new FreeportParser(this.profile, 'request'), write, drop };
    this.links.add(link);
    return link;
  }

  private receive(link: Link, chunk: Buffer): void {
    if (this.closed || !this.links.has(link)) return;
    for (const frame of link.parser.push(chunk)) {
      if (frame.kind === 'corrupt') this.emit('corrupt', frame.error);
      else if (frame.kind === 'request') this.answer(link, frame.request);
    }
  }

  private answer(link: Link, request: FreeportRequest): void {
    if (this.replying > 0) this.collisions++;
    const station = this.stationsByAddress.get(request.station);
    const reply = station?.handle(request, this.profile.replyEchoesAddress);
    this.emit('request', request, reply !== undefined);
    if (!reply) return;
    const bytes = this.applyNoise(encodeReply(reply, this.profile));
    const send = () => {
      if (!this.closed && this.links.has(link)) link.write(bytes);
    };
    if (this.faults.replyDelayMs <= 0) return send();
    this.replying++;
    const timer = setTimeout(() => {
      this.timers.delete(timer);
      this.replying--;
      send();
    }, this.faults.replyDelayMs);
    this.timers.add(timer);
  }

  private applyNoise(frame: Buffer): Buffer {
    const f = this.faults;
    let bytes = frame;
    const inner = () => 1 + Math.floor(this.random() * (bytes.length - 2));
    if (f.corruptNext > 0) {
      f.corruptNext--;
      bytes = Buffer.from(bytes);
      // Bit 0 of the first DU character: a digit stays a digit, so only the checksum can tell.
      bytes[1 + (this.profile.replyEchoesAddress ? this.profile.addressWidth : 0)]! ^= 0x01;
    }
    if (f.flipBitRate > 0 && this.random() < f.flipBitRate) {
      bytes = Buffer.from(bytes);
      bytes[inner()]! ^= 1 << Math.floor(this.random() * 7);
    }
    if (f.dropCharRate > 0 && this.random() < f.dropCharRate) {
      const at = inner();
      bytes = Buffer.concat([bytes.subarray(0, at), bytes.subarray(at + 1)]);
    }
    return bytes;
  }

  private assertOpen(): void {
    if (this.closed) throw new PlcError('CLOSED', 'this freeport bus was closed');
  }
}
