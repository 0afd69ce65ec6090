/**
 * FetchWriteServer: an in-process CP with a "Fetch passive" and a "Write
 * passive" port (or one port for both), serving the shared PlcMemory with the
 * document's ORG areas and units. Hostile frames close only their connection.
 */
import { EventEmitter } from 'node:events';
import * as net from 'node:net';
import { ProtocolError, toPlcError } from '../errors';
import { FrameReader, type FrameCheck } from '../link/framer';
import { PlcMemory, type MemoryLayout } from '../sim/memory';
import type { AreaName } from '../types';
import { HEADER, MAX_DATA, OpCode, Org, byteLength, decodeRequest, encodeResponse } from './codec';

export interface FetchWriteServerOptions {
  /** Default 127.0.0.1. */
  host?: string;
  fetchPort?: number;
  writePort?: number;
  /** One port serving fetch and write jobs. */
  port?: number;
  memory?: PlcMemory;
  layout?: MemoryLayout;
  /** How DB start addresses and lengths are counted (Siemens CPs: words). */
  dbUnit?: 'word' | 'byte';
}

export interface FetchWriteFaults {
  /** Answer every job with this error byte (0 = normal). */
  errorCode: number;
  latencyMs: number;
  /** Stop answering (connections stay open). */
  silent: boolean;
}

export interface FetchWriteRequestEvent {
  kind: 'fetch' | 'write';
  org: number;
  dbNumber: number;
  start: number;
  length: number;
}

const AREA_BY_ORG: Readonly<Record<number, AreaName>> = { [Org.DB]: 'DB', [Org.M]: 'M', [Org.I]: 'I', [Org.Q]: 'Q', [Org.PEPA]: 'PE', [Org.C]: 'C', [Org.T]: 'T' };

/** Events: `connection`, `disconnect` (count), `request` (FetchWriteRequestEvent), `error` (if listened). */
export class FetchWriteServer extends EventEmitter {
  readonly memory: PlcMemory;
  readonly faults: FetchWriteFaults = { errorCode: 0, latencyMs: 0, silent: false };
  private readonly host: string;
  private readonly want: { fetch: number; write: number; single: boolean };
  private readonly dbUnit: 'word' | 'byte';
  private readonly servers: net.Server[] = [];
  private readonly sockets = new Set<net.Socket>();
  private readonly modes = new Map<net.Socket, 'fetch' | 'write' | 'both'>();
  private ports = { fetchPort: 0, writePort: 0 };

  constructor(options: FetchWriteServerOptions = {}) {
    super();
    this.host = options.host ?? '127.0.0.1';
    this.want =
      options.port !== undefined
        ? { fetch: options.port, write: options.port, single: true }
        : { fetch: options.fetchPort ?? 2000, write: options.writePort ?? 2001, single: false };
    this.dbUnit = options.dbUnit ?? 'word';
    this.memory = options.memory ?? new PlcMemory(options.layout);
  }

  get fetchPort(): number {
    return this.ports.fetchPort;
  }

  get writePort(): number {
    return this.ports.writePort;
  }

  /**
   * Clients connected: connections on the fetch port (each client holds one
   * there, and one on the write port when the ports differ).
   */
  get connectionCount(): number {
    let n = 0;
    for (const mode of this.modes.values()) if (mode !== 'write') n++;
    return n;
  }

  async listen(): Promise<{ fetchPort: number; writePort: number }> {
    if (this.servers.length > 0) return this.ports;
    try {
      if (this.want.single) {
        const port = await this.open(this.want.fetch, 'both');
        this.ports = { fetchPort: port, writePort: port };
      } else {
        const fetchPort = await this.open(this.want.fetch, 'fetch');
        const writePort = await this.open(this.want.write, 'write');
        this.ports = { fetchPort, writePort };
      }
    } catch (err) {
      await this.close();
      throw err;
    }
    return this.ports;
  }

  private open(port: number, mode: 'fetch' | 'write' | 'both'): Promise<number> {
    const server = net.createServer((socket) => this.accept(socket, mode));
    this.servers.push(server);
    return new Promise((resolve, reject) => {
      server.once('error', reject);
      server.listen(port, this.host, () => {
        server.removeListener('error', reject);
        server.on('error', (err) => this.listenerCount('error') > 0 && this.emit('error', err));
        resolve((server.address() as net.AddressInfo).port);
      });
    });
  }

  dropConnections(): void {
    for (const s of this.sockets) s.destroy();
  }

  close(): Promise<void> {
    this.dropConnections();
    const servers = this.servers.splice(0);
    return Promise.all(servers.map((s) => new Promise<void>((r) => s.close(() => r())))).then(() => undefined);
  }

  private accept(socket: net.Socket, mode: 'fetch' | 'write' | 'both'): void {
    socket.setNoDelay(true);
    this.sockets.add(socket);
    this.modes.set(socket, mode);
    this.emit('connection', this.connectionCount);
    const reader = new FrameReader((buf) => this.check(buf, mode), MAX_DATA * 2 + HEADER);
    let busy = Promise.resolve();
    socket.on('data', (chunk: Buffer) => {
      let frames: Buffer[];
      try {
        frames = reader.push(chunk);
      } catch {
        socket.destroy();
        return;
      }
      for (const frame of frames) {
        // One job at a time per connection, in order, as a CP does.
        busy = busy.then(() => this.serve(socket, frame)).catch(() => void socket.destroy());
      }
    });
    socket.on('error', () => undefined);
    socket.on('close', () => {
      this.sockets.delete(socket);
      this.modes.delete(socket);
      this.emit('disconnect', this.connectionCount);
    });
  }

  /** Requests: 16 bytes, plus the data of a write (its length from the header's units). */
  private check(buf: Buffer, mode: 'fetch' | 'write' | 'both'): FrameCheck {
    if (buf.length < HEADER) return { kind: 'need' };
    let req;
    try {
      req = decodeRequest(buf.subarray(0, HEADER));
    } catch (err) {
      return { kind: 'bad', error: toPlcError(err, 'PROTOCOL_ERROR') as ProtocolError };
    }
    if ((mode === 'fetch' && req.op !== OpCode.FetchRequest) || (mode === 'write' && req.op !== OpCode.WriteRequest)) {
      return { kind: 'bad', error: new ProtocolError('job on the wrong passive connection') };
    }
    const length = req.op === OpCode.WriteRequest ? HEADER + byteLength(req.org, req.length, this.dbUnit) : HEADER;
    return buf.length >= length ? { kind: 'frame', length } : { kind: 'need' };
  }

  private async serve(socket: net.Socket, frame: Buffer): Promise<void> {
    const req = decodeRequest(frame);
    const fetch = req.op === OpCode.FetchRequest;
    this.emit('request', { kind: fetch ? 'fetch' : 'write', org: req.org, dbNumber: req.dbNumber, start: req.start, length: req.length } satisfies FetchWriteRequestEvent);
    if (this.faults.latencyMs > 0) await new Promise((r) => setTimeout(r, this.faults.latencyMs));
    if (this.faults.silent || socket.destroyed) return;
    const op = fetch ? OpCode.FetchResponse : OpCode.WriteAck;
    if (this.faults.errorCode !== 0) {
      socket.write(encodeResponse(op, this.faults.errorCode));
      return;
    }
    const area = AREA_BY_ORG[req.org];
    if (!area || req.length === 0 || (req.org === Org.DB && req.dbNumber === 0)) {
      socket.write(encodeResponse(op, 0x06));
      return;
    }
    const unitBytes = (req.org === Org.DB && this.dbUnit === 'word') || req.org === Org.C || req.org === Org.T ? 2 : 1;
    const offset = req.start * unitBytes;
    const length = byteLength(req.org, req.length, this.dbUnit);
    const target: AreaName = !fetch && area === 'PE' ? 'PA' : area;
    const fault = this.memory.check(target, req.dbNumber, offset, length);
    if (fault) {
      socket.write(encodeResponse(op, fault === 'NO_SUCH_AREA' ? 0x02 : 0x03));
      return;
    }
    if (fetch) socket.write(encodeResponse(op, 0, this.memory.read(target, req.dbNumber, offset, length)));
    else {
      this.memory.write(target, req.dbNumber, offset, req.data!);
      socket.write(encodeResponse(op, 0));
    }
  }
}
