/**
 * FetchWriteServer: an in-process CP with a "Fetch passive" and a "Write
 * passive" port (or one port for both), serving the shared PlcMemory with the
 * ORG areas and units of docs/protocols.md. Hostile frames close only their connection.
 *
 * connectionCount counts clients the way a CP's connection table does: the
 * most peers on either passive port (a client holding its fetch and its write
 * connection counts once). socketCount counts TCP connections.
 */
import { EventEmitter } from 'node:events';
import * as net from 'node:net';
import { FrameReader } from '../link/framer';
import { PlcMemory, type MemoryLayout } from '../sim/memory';
import { memoryFromSymbols } from '../sim/symbol-memory';
import type { SymbolTable } from '../symbols/model';
import type { AreaName } from '../types';
import { HEADER, MAX_DATA, OpCode, Org, byteLength, checkRequest, decodeRequest, encodeResponse, type FwRequest } from './codec';

export interface FetchWriteServerOptions {
  /** Default 127.0.0.1. */
  host?: string;
  /** Default 2000. */
  fetchPort?: number;
  /** Default 2001. */
  writePort?: number;
  /** One port serving fetch and write jobs. */
  port?: number;
  memory?: PlcMemory;
  layout?: MemoryLayout;
  /** Compiled DB sources: the data blocks are theirs, at their declared lengths with their start values (lib/sim/symbol-memory.ts). */
  symbols?: SymbolTable;
  /** How DB start addresses and lengths are counted (Siemens CPs: words). */
  dbUnit?: 'word' | 'byte';
  /** Initial fault injection; change it later through `server.faults`. */
  faults?: Partial<Omit<FetchWriteFaults, 'dropConnections'>>;
}

export interface FetchWriteFaults {
  /** Answer every job with this error byte (0 = normal). */
  errorCode: number;
  /** Delay before each answer. */
  latencyMs: number;
  /** Stop answering (connections stay open). */
  silent: boolean;
  /** Close new connections at once (a CP whose passive connection is taken). */
  refuseConnections: boolean;
  /** Send only the first half of the next N answers, then reset the connection. */
  truncateAnswers: number;
  /** Drop every client connection now; the ports keep listening. */
  dropConnections(): void;
}

export interface FetchWriteRequestEvent {
  kind: 'fetch' | 'write';
  org: number;
  dbNumber: number;
  /** In the header's units (DB words unless dbUnit is 'byte'; C/T cell numbers). */
  start: number;
  length: number;
}

type PortMode = 'fetch' | 'write' | 'both';

const AREA_BY_ORG: Readonly<Record<number, AreaName>> = {
  [Org.DB]: 'DB',
  [Org.M]: 'M',
  [Org.I]: 'I',
  [Org.Q]: 'Q',
  [Org.PEPA]: 'PE',
  [Org.C]: 'C',
  [Org.T]: 'T',
};

/**
 * Events: `connection` / `disconnect` (connectionCount), `request`
 * (FetchWriteRequestEvent, before it is answered), `error` (listen errors, if
 * listened); the memory emits `read` / `write`.
 */
export class FetchWriteServer extends EventEmitter {
  readonly memory: PlcMemory;
  readonly faults: FetchWriteFaults;
  private readonly host: string;
  private readonly want: { fetch: number; write: number; single: boolean };
  private readonly dbUnit: 'word' | 'byte';
  private readonly servers: net.Server[] = [];
  private readonly sockets = new Map<net.Socket, PortMode>();
  private ports = { fetchPort: 0, writePort: 0 };

  constructor(options: FetchWriteServerOptions = {}) {
    super();
    this.host = options.host ?? '127.0.0.1';
    this.want =
      options.port !== undefined
        ? { fetch: options.port, write: options.port, single: true }
        : { fetch: options.fetchPort ?? 2000, write: options.writePort ?? 2001, single: false };
    this.dbUnit = options.dbUnit ?? 'word';
    this.memory = options.memory ?? (options.symbols ? memoryFromSymbols(options.symbols, options.layout) : new PlcMemory(options.layout));
    this.faults = {
      errorCode: 0,
      latencyMs: 0,
      silent: false,
      refuseConnections: false,
      truncateAnswers: 0,
      ...options.faults,
      dropConnections: () => this.dropConnections(),
    };
  }

  get fetchPort(): number {
    return this.ports.fetchPort;
  }

  get writePort(): number {
    return this.ports.writePort;
  }

  /** Clients connected: the most peers on either passive port. */
  get connectionCount(): number {
    let fetch = 0;
    let write = 0;
    for (const mode of this.sockets.values()) {
      if (mode !== 'write') fetch++;
      if (mode !== 'fetch') write++;
    }
    return Math.max(fetch, write);
  }

  /** TCP connections over both ports. */
  get socketCount(): number {
    return this.sockets.size;
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

  private open(port: number, mode: PortMode): Promise<number> {
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

  /** Drops every client connection; the ports keep listening. */
  dropConnections(): void {
    for (const s of this.sockets.keys()) s.destroy();
  }

  /** Stops listening and drops every client; always resolves. */
  close(): Promise<void> {
    this.dropConnections();
    const servers = this.servers.splice(0);
    return Promise.all(servers.map((s) => new Promise<void>((r) => s.close(() => r())))).then(() => undefined);
  }

  private accept(socket: net.Socket, mode: PortMode): void {
    socket.on('error', () => undefined);
    if (this.faults.refuseConnections) {
      socket.destroy();
      return;
    }
    socket.setNoDelay(true);
    this.sockets.set(socket, mode);
    this.emit('connection', this.connectionCount);
    const reader = new FrameReader((buf) => checkRequest(buf, this.dbUnit), MAX_DATA * 2 + HEADER);
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
        busy = busy.then(() => this.serve(socket, mode, frame)).catch(() => void socket.destroy());
      }
    });
    socket.on('close', () => {
      this.sockets.delete(socket);
      this.emit('disconnect', this.connectionCount);
    });
  }

  private async serve(socket: net.Socket, mode: PortMode, frame: Buffer): Promise<void> {
    if (socket.destroyed) return;
    const req = decodeRequest(frame);
    const fetch = req.op === OpCode.FetchRequest;
    // A "Fetch passive" connection takes only fetch jobs, a "Write passive" one only writes.
    if ((mode === 'fetch' && !fetch) || (mode === 'write' && fetch)) {
      socket.destroy();
      return;
    }
    this.emit('request', {
      kind: fetch ? 'fetch' : 'write',
      org: req.org,
      dbNumber: req.dbNumber,
      start: req.start,
      length: req.length,
    } satisfies FetchWriteRequestEvent);
    if (this.faults.latencyMs > 0) await new Promise((r) => setTimeout(r, this.faults.latencyMs));
    if (this.faults.silent || socket.destroyed) return;
    const answer = this.answer(req);
    if (this.faults.truncateAnswers > 0) {
      this.faults.truncateAnswers--;
      socket.write(answer.subarray(0, answer.length >> 1), () => socket.resetAndDestroy());
    } else socket.write(answer);
  }

  private answer({ op: request, org, dbNumber, start, length: units, data }: FwRequest): Buffer {
    const fetch = request === OpCode.FetchRequest;
    const op = fetch ? OpCode.FetchResponse : OpCode.WriteAck;
    if (this.faults.errorCode !== 0) return encodeResponse(op, this.faults.errorCode);
    const area = AREA_BY_ORG[org];
    if (!area || units === 0 || (org === Org.DB && dbNumber === 0)) return encodeResponse(op, 0x06);
    const unitBytes = (org === Org.DB && this.dbUnit === 'word') || org === Org.C || org === Org.T ? 2 : 1;
    const offset = start * unitBytes;
    const length = byteLength(org, units, this.dbUnit);
    // ORG 5 reads the input modules and writes the output modules.
    const target: AreaName = !fetch && area === 'PE' ? 'PA' : area;
    const fault = this.memory.check(target, dbNumber, offset, length);
    if (fault) return encodeResponse(op, fault === 'NO_SUCH_AREA' ? 0x02 : 0x03);
    if (fetch) return encodeResponse(op, 0, this.memory.read(target, dbNumber, offset, length));
    this.memory.write(target, dbNumber, offset, data!);
    return encodeResponse(op, 0);
  }
}
